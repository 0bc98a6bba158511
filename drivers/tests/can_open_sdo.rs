//! The SDO client and PDO configuration against a scripted server that expects the exact
//! bytes CiA 301 prescribes for each request (written out by hand here) and answers with
//! hand-written bytes.

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use klar_drivers::can::CanFrame;
use klar_drivers::can::memory::{BusDevice, MemoryBus};
use klar_drivers::canopen::pdo::{PdoConfig, PdoEntry, PdoKind};
use klar_drivers::canopen::{CanOpenError, Master};

type Step = ([u8; 8], Option<[u8; 8]>);

/// What the script saw: mismatches, and the steps not yet played.
#[derive(Default)]
struct Log {
    errors: Vec<String>,
    steps: VecDeque<Step>,
}

/// A server for one node that plays back a script of (expected request, answer).
struct Script {
    node: u16,
    log: Arc<Mutex<Log>>,
}

impl BusDevice for Script {
    fn start(&mut self, _out: &mut Vec<CanFrame>) {}
    fn on_frame(&mut self, f: &CanFrame, out: &mut Vec<CanFrame>) {
        if f.id().standard() != Some(0x600 + self.node) {
            return;
        }
        let mut log = self.log.lock().expect("lock");
        match log.steps.pop_front() {
            Some((expected, answer)) => {
                if f.data() != expected {
                    log.errors
                        .push(format!("expected {expected:02X?}, got {:02X?}", f.data()));
                }
                if let Some(a) = answer {
                    out.push(CanFrame::standard(0x580 + self.node, &a).expect("frame"));
                }
            }
            None => log
                .errors
                .push(format!("unexpected request {:02X?}", f.data())),
        }
    }
}

/// A master talking to a script for `node`; returns the master and the script's log.
fn scripted(node: u8, steps: Vec<Step>) -> (Master, Arc<Mutex<Log>>) {
    let bus = MemoryBus::new();
    let master = Master::new(Box::new(bus.endpoint()), Duration::from_millis(50));
    let log = Arc::new(Mutex::new(Log {
        errors: Vec::new(),
        steps: steps.into(),
    }));
    bus.attach(Box::new(Script {
        node: u16::from(node),
        log: Arc::clone(&log),
    }));
    (master, log)
}

/// Every request was the expected one and the whole script was played.
fn clean(log: &Arc<Mutex<Log>>) {
    let log = log.lock().expect("lock");
    assert!(log.errors.is_empty(), "{:?}", log.errors);
    assert!(log.steps.is_empty(), "{} steps not played", log.steps.len());
}

#[test]
fn expedited_writes_encode_the_size() {
    let (mut m, errors) = scripted(
        5,
        vec![
            (
                [0x2B, 0x40, 0x60, 0x00, 0x34, 0x12, 0, 0],
                Some([0x60, 0x40, 0x60, 0x00, 0, 0, 0, 0]),
            ),
            (
                [0x2F, 0x60, 0x60, 0x00, 0x08, 0, 0, 0],
                Some([0x60, 0x60, 0x60, 0x00, 0, 0, 0, 0]),
            ),
            (
                [0x27, 0x00, 0x20, 0x07, 1, 2, 3, 0],
                Some([0x60, 0x00, 0x20, 0x07, 0, 0, 0, 0]),
            ),
            (
                [0x23, 0x7A, 0x60, 0x00, 0xFF, 0xFF, 0xFF, 0xFF],
                Some([0x60, 0x7A, 0x60, 0x00, 0, 0, 0, 0]),
            ),
        ],
    );
    m.sdo_write(5, 0x6040, 0, &0x1234u16.to_le_bytes())
        .expect("u16");
    m.sdo_write(5, 0x6060, 0, &[8]).expect("u8");
    m.sdo_write(5, 0x2000, 7, &[1, 2, 3]).expect("3 bytes");
    m.sdo_write(5, 0x607A, 0, &(-1i32).to_le_bytes())
        .expect("i32");
    clean(&errors);
}

#[test]
fn expedited_read_takes_the_indicated_size() {
    let (mut m, errors) = scripted(
        1,
        vec![
            (
                [0x40, 0x41, 0x60, 0x00, 0, 0, 0, 0],
                Some([0x4B, 0x41, 0x60, 0x00, 0x37, 0x06, 0xEE, 0xEE]),
            ),
            (
                [0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0],
                Some([0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x02, 0x00]),
            ),
        ],
    );
    assert_eq!(m.sdo_read(1, 0x6041, 0).expect("read"), vec![0x37, 0x06]);
    assert_eq!(m.sdo_read_u32(1, 0x1000, 0).expect("read"), 0x0002_0192);
    clean(&errors);
}

#[test]
fn segmented_read_follows_the_toggle() {
    // "klar drive 12345": 16 bytes in segments of 7, 7 and 2.
    let name = b"klar drive 12345";
    let (mut m, errors) = scripted(
        3,
        vec![
            (
                [0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0],
                Some([0x41, 0x08, 0x10, 0x00, 16, 0, 0, 0]),
            ),
            (
                [0x60, 0, 0, 0, 0, 0, 0, 0],
                Some([0x00, b'k', b'l', b'a', b'r', b' ', b'd', b'r']),
            ),
            (
                [0x70, 0, 0, 0, 0, 0, 0, 0],
                Some([0x10, b'i', b'v', b'e', b' ', b'1', b'2', b'3']),
            ),
            (
                [0x60, 0, 0, 0, 0, 0, 0, 0],
                Some([0x0B, b'4', b'5', 0, 0, 0, 0, 0]),
            ),
        ],
    );
    assert_eq!(m.sdo_read(3, 0x1008, 0).expect("read"), name.to_vec());
    clean(&errors);
}

#[test]
fn segmented_write_splits_in_sevens() {
    let (mut m, errors) = scripted(
        2,
        vec![
            (
                [0x21, 0x00, 0x20, 0x01, 10, 0, 0, 0],
                Some([0x60, 0x00, 0x20, 0x01, 0, 0, 0, 0]),
            ),
            (
                [0x00, 0, 1, 2, 3, 4, 5, 6],
                Some([0x20, 0, 0, 0, 0, 0, 0, 0]),
            ),
            (
                [0x19, 7, 8, 9, 0, 0, 0, 0],
                Some([0x30, 0, 0, 0, 0, 0, 0, 0]),
            ),
        ],
    );
    m.sdo_write(2, 0x2000, 1, &[0, 1, 2, 3, 4, 5, 6, 7, 8, 9])
        .expect("write");
    clean(&errors);
}

#[test]
fn server_abort_is_decoded_to_its_name() {
    let (mut m, errors) = scripted(
        7,
        vec![(
            [0x40, 0x34, 0x12, 0x00, 0, 0, 0, 0],
            Some([0x80, 0x34, 0x12, 0x00, 0x00, 0x00, 0x02, 0x06]),
        )],
    );
    match m.sdo_read(7, 0x1234, 0) {
        Err(CanOpenError::SdoAbort {
            node,
            index,
            sub,
            code,
            name,
        }) => {
            assert_eq!((node, index, sub, code), (7, 0x1234, 0, 0x0602_0000));
            assert_eq!(name, "object does not exist in the object dictionary");
        }
        other => panic!("{other:?}"),
    }
    let msg = m
        .sdo_read(7, 0x1234, 0)
        .map(|_| ())
        .expect_err("script is used up");
    assert!(matches!(msg, CanOpenError::SdoTimeout { .. }));
    let log = errors.lock().expect("lock");
    assert_eq!(
        log.errors.len(),
        2,
        "the second read and its timeout abort were unscripted: {:?}",
        log.errors
    );
}

#[test]
fn wrong_toggle_is_aborted_by_the_client() {
    let (mut m, errors) = scripted(
        4,
        vec![
            (
                [0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0],
                Some([0x41, 0x08, 0x10, 0x00, 9, 0, 0, 0]),
            ),
            (
                [0x60, 0, 0, 0, 0, 0, 0, 0],
                Some([0x10, 1, 2, 3, 4, 5, 6, 7]),
            ),
            // The client must abort with 0x05030000 "toggle bit not alternated".
            ([0x80, 0x08, 0x10, 0x00, 0x00, 0x00, 0x03, 0x05], None),
        ],
    );
    match m.sdo_read(4, 0x1008, 0) {
        Err(CanOpenError::SdoProtocol { node: 4, what, .. }) => {
            assert!(what.contains("toggle"), "{what}")
        }
        other => panic!("{other:?}"),
    }
    clean(&errors);
}

#[test]
fn silence_times_out_with_an_abort() {
    let (mut m, errors) = scripted(
        9,
        vec![
            ([0x40, 0x41, 0x60, 0x00, 0, 0, 0, 0], None),
            // 0x05040000 "SDO protocol timed out".
            ([0x80, 0x41, 0x60, 0x00, 0x00, 0x00, 0x04, 0x05], None),
        ],
    );
    match m.sdo_read(9, 0x6041, 0) {
        Err(CanOpenError::SdoTimeout {
            node: 9,
            index: 0x6041,
            sub: 0,
            timeout_ms: 50,
        }) => {}
        other => panic!("{other:?}"),
    }
    clean(&errors);
}

#[test]
fn answer_for_another_object_is_refused() {
    let (mut m, _errors) = scripted(
        1,
        vec![(
            [0x40, 0x41, 0x60, 0x00, 0, 0, 0, 0],
            Some([0x4B, 0x40, 0x60, 0x00, 0, 0, 0, 0]),
        )],
    );
    match m.sdo_read(1, 0x6041, 0) {
        Err(CanOpenError::SdoProtocol { what, .. }) => assert!(what.contains("0x6040"), "{what}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn pdo_configuration_follows_the_cia301_procedure() {
    let ok = |i0: u8, i1: u8, sub: u8| Some([0x60, i0, i1, sub, 0, 0, 0, 0]);
    let (mut m, errors) = scripted(
        2,
        vec![
            // Disable: COB-ID with bit 31 set.
            (
                [0x23, 0x00, 0x14, 0x01, 0x02, 0x02, 0x00, 0x80],
                ok(0x00, 0x14, 1),
            ),
            // Transmission type 1.
            ([0x2F, 0x00, 0x14, 0x02, 0x01, 0, 0, 0], ok(0x00, 0x14, 2)),
            // Mapping count 0, two entries, count 2.
            ([0x2F, 0x00, 0x16, 0x00, 0x00, 0, 0, 0], ok(0x00, 0x16, 0)),
            (
                [0x23, 0x00, 0x16, 0x01, 0x10, 0x00, 0x40, 0x60],
                ok(0x00, 0x16, 1),
            ),
            (
                [0x23, 0x00, 0x16, 0x02, 0x20, 0x00, 0x7A, 0x60],
                ok(0x00, 0x16, 2),
            ),
            ([0x2F, 0x00, 0x16, 0x00, 0x02, 0, 0, 0], ok(0x00, 0x16, 0)),
            // Enable: COB-ID without bit 31.
            (
                [0x23, 0x00, 0x14, 0x01, 0x02, 0x02, 0x00, 0x00],
                ok(0x00, 0x14, 1),
            ),
        ],
    );
    m.configure_pdo(
        2,
        &PdoConfig {
            kind: PdoKind::Receive,
            number: 1,
            cob_id: 0x202,
            transmission: 1,
            entries: vec![PdoEntry::new(0x6040, 0, 16), PdoEntry::new(0x607A, 0, 32)],
        },
    )
    .expect("configured");
    clean(&errors);
}
