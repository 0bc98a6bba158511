//! The SocketCAN adapter at the trait level (the build machines have no AF_CAN): frame
//! conversion both ways, error-frame decoding from the kernel's bit definitions, and a
//! clean error when the interface cannot be opened.

use klar_drivers::can::socketcan::{
    SocketCanBus, decode_error_frame, from_socketcan, to_socketcan,
};
use klar_drivers::can::{BusErrorKind, CanError, CanEvent, CanFrame, CanId};
use socketcan::EmbeddedFrame;

#[test]
fn frames_convert_both_ways() {
    let cases = [
        CanFrame::standard(0x181, &[0x27, 0x06, 0x10, 0x27, 0, 0]).expect("frame"),
        CanFrame::new(CanId::Extended(0x1234_5678), &[1, 2, 3, 4, 5, 6, 7, 8]).expect("frame"),
        CanFrame::remote(CanId::Standard(0x701), 1).expect("frame"),
        CanFrame::standard(0x080, &[]).expect("frame"),
    ];
    for f in cases {
        let sc = to_socketcan(&f).expect("representable");
        assert_eq!(sc.is_remote_frame(), f.is_remote());
        assert_eq!(sc.dlc(), usize::from(f.dlc()));
        match from_socketcan(&sc, 1.5).as_slice() {
            [CanEvent::Frame { frame, timestamp }] => {
                assert_eq!(frame, &f);
                assert_eq!(*timestamp, 1.5);
            }
            other => panic!("{other:?}"),
        }
    }
}

#[test]
fn error_frames_decode_to_bus_conditions() {
    // linux/can/error.h: class 0x040 bus-off; 0x004 controller problem with byte 1
    // 0x10/0x20 error passive, 0x04/0x08 warning, 0x01/0x02 overflow; 0x020 no ACK.
    assert_eq!(
        decode_error_frame(0x040, &[0; 8]),
        vec![BusErrorKind::BusOff]
    );
    assert_eq!(
        decode_error_frame(0x004, &[0, 0x20, 0, 0, 0, 0, 0, 0]),
        vec![BusErrorKind::ErrorPassive]
    );
    assert_eq!(
        decode_error_frame(0x004, &[0, 0x08, 0, 0, 0, 0, 0, 0]),
        vec![BusErrorKind::ErrorWarning]
    );
    assert_eq!(
        decode_error_frame(0x004, &[0, 0x01, 0, 0, 0, 0, 0, 0]),
        vec![BusErrorKind::Overrun]
    );
    assert!(
        matches!(decode_error_frame(0x020, &[0; 8]).as_slice(), [BusErrorKind::Protocol(m)] if m.contains("acknowledge"))
    );
    let both = decode_error_frame(0x044, &[0, 0x10, 0, 0, 0, 0, 0, 0]);
    assert_eq!(both, vec![BusErrorKind::BusOff, BusErrorKind::ErrorPassive]);
    // A short error frame does not panic.
    assert_eq!(decode_error_frame(0x004, &[]), Vec::<BusErrorKind>::new());
    // And a real socketcan error frame goes the same way.
    let ef = socketcan::CanErrorFrame::new_error(0x040, &[0; 8]).expect("error frame");
    let events = from_socketcan(&socketcan::CanFrame::Error(ef), 0.0);
    assert_eq!(events, vec![CanEvent::Error(BusErrorKind::BusOff)]);
}

#[test]
fn a_missing_interface_is_an_error() {
    match SocketCanBus::open("klarcan9") {
        Err(CanError::Io(msg)) => assert!(msg.contains("klarcan9"), "{msg}"),
        Err(e) => panic!("unexpected error {e}"),
        Ok(_) => panic!("no such interface on this machine"),
    }
}
