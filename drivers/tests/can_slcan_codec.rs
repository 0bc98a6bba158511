//! The slcan (Lawicel) codec against messages written out by hand from the protocol
//! description, plus round trips over random frames.

use klar_drivers::can::slcan::{
    SlcanDecoder, SlcanMessage, adapter_answer, bitrate_command, decode_line, encode_frame,
};
use klar_drivers::can::{CanError, CanFrame, CanId};
use proptest::prelude::*;

fn encoded(frame: &CanFrame) -> String {
    let mut out = Vec::new();
    encode_frame(frame, &mut out);
    String::from_utf8(out).expect("ascii")
}

#[test]
fn frames_encode_as_the_protocol_spells_them() {
    let f = CanFrame::standard(0x123, &[0x11, 0x22, 0x33]).expect("frame");
    assert_eq!(encoded(&f), "t123311 2233\r".replace(' ', ""));
    assert_eq!(
        encoded(&CanFrame::standard(0x080, &[]).expect("frame")),
        "t0800\r"
    );
    let ext = CanFrame::new(
        CanId::Extended(0x0ABC_DEF1),
        &[0xDE, 0xAD, 0xBE, 0xEF, 0, 1, 2, 0xFF],
    )
    .expect("frame");
    assert_eq!(encoded(&ext), "T0ABCDEF18DEADBEEF000102FF\r");
    assert_eq!(
        encoded(&CanFrame::remote(CanId::Standard(0x7FF), 2).expect("frame")),
        "r7FF2\r"
    );
    assert_eq!(
        encoded(&CanFrame::remote(CanId::Extended(1), 0).expect("frame")),
        "R000000010\r"
    );
}

#[test]
fn lines_decode_with_and_without_timestamps() {
    let f = CanFrame::standard(0x5A1, &[0x43, 0x41, 0x60, 0x00]).expect("frame");
    assert_eq!(
        decode_line(b"t5A1443416000"),
        SlcanMessage::Frame {
            frame: f,
            adapter_ms: None
        }
    );
    assert_eq!(
        decode_line(b"t5A14434160001F40"),
        SlcanMessage::Frame {
            frame: f,
            adapter_ms: Some(8000)
        }
    );
    // Lower-case hexadecimal is accepted.
    assert_eq!(
        decode_line(b"t5a1443416000"),
        SlcanMessage::Frame {
            frame: f,
            adapter_ms: None
        }
    );
    assert_eq!(decode_line(b""), SlcanMessage::Ok);
    assert_eq!(decode_line(b"V1013"), SlcanMessage::Other("V1013".into()));
}

#[test]
fn malformed_lines_are_reported_not_panicked() {
    for bad in [
        &b"t12"[..],
        b"t1239AA",
        b"t12G0",
        b"t8001",
        b"t12320",
        b"t1232AABBC",
        b"T1FFFFFFFF0",
        b"T123",
    ] {
        match decode_line(bad) {
            SlcanMessage::Malformed(m) => {
                assert!(m.contains(&String::from_utf8_lossy(bad).to_string()), "{m}")
            }
            other => panic!("{} decoded as {other:?}", String::from_utf8_lossy(bad)),
        }
    }
}

#[test]
fn the_decoder_splits_a_byte_stream() {
    let mut d = SlcanDecoder::new();
    let mut out = Vec::new();
    d.feed(b"\rt1000\r\x07t2", &mut out);
    d.feed(b"0111A\r", &mut out);
    assert_eq!(
        out,
        vec![
            SlcanMessage::Ok,
            SlcanMessage::Frame {
                frame: CanFrame::standard(0x100, &[]).expect("frame"),
                adapter_ms: None
            },
            SlcanMessage::Error,
            SlcanMessage::Frame {
                frame: CanFrame::standard(0x201, &[0x1A]).expect("frame"),
                adapter_ms: None
            },
        ]
    );
    // An endless line is cut and reported once.
    out.clear();
    d.feed(&[b'7'; 500], &mut out);
    d.feed(b"\rt0000\r", &mut out);
    assert!(matches!(out[0], SlcanMessage::Malformed(_)));
    assert!(matches!(out[1], SlcanMessage::Frame { .. }));
    assert_eq!(out.len(), 2);
}

#[test]
fn bitrate_commands_follow_the_lawicel_table() {
    let table = [
        (10_000, "S0"),
        (20_000, "S1"),
        (50_000, "S2"),
        (100_000, "S3"),
        (125_000, "S4"),
        (250_000, "S5"),
        (500_000, "S6"),
        (800_000, "S7"),
        (1_000_000, "S8"),
    ];
    for (rate, cmd) in table {
        assert_eq!(bitrate_command(rate).expect("known"), cmd);
    }
    assert_eq!(
        bitrate_command(83_333),
        Err(CanError::UnsupportedBitrate(83_333))
    );
}

#[test]
fn the_adapter_end_answers_like_an_adapter() {
    assert_eq!(adapter_answer("O"), b"\r");
    assert_eq!(adapter_answer("C"), b"\r");
    assert_eq!(adapter_answer("S8"), b"\r");
    assert_eq!(adapter_answer("S9"), b"\x07");
    assert_eq!(adapter_answer("Q"), b"\x07");
}

proptest! {
    #[test]
    fn any_frame_survives_encode_then_decode(
        extended in any::<bool>(),
        raw in 0u32..0x2000_0000,
        remote in any::<bool>(),
        data in proptest::collection::vec(any::<u8>(), 0..=8),
    ) {
        let id = if extended { CanId::Extended(raw) } else { CanId::Standard((raw & 0x7FF) as u16) };
        let frame = if remote { CanFrame::remote(id, data.len() as u8) } else { CanFrame::new(id, &data) }.expect("valid");
        let mut bytes = Vec::new();
        encode_frame(&frame, &mut bytes);
        prop_assert_eq!(bytes.last(), Some(&b'\r'));
        let mut out = Vec::new();
        SlcanDecoder::new().feed(&bytes, &mut out);
        prop_assert_eq!(out, vec![SlcanMessage::Frame { frame, adapter_ms: None }]);
    }

    #[test]
    fn arbitrary_bytes_never_panic_the_decoder(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
        let mut out = Vec::new();
        SlcanDecoder::new().feed(&bytes, &mut out);
    }
}
