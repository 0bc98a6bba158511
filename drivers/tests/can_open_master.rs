//! The CANopen master's NMT, SYNC, boot-up, heartbeat and EMCY handling, checked against
//! frames laid out by hand from CiA 301.

use std::time::Duration;

use klar_drivers::can::memory::MemoryBus;
use klar_drivers::can::{CanBus, CanEvent, CanFrame};
use klar_drivers::canopen::emcy::{error_code_name, register_bit_names};
use klar_drivers::canopen::pdo::{PdoEntry, PdoKind, default_cob_id, pack, unpack};
use klar_drivers::canopen::{Emergency, Master, NmtCommand, NmtState, NodeEvent};

fn setup() -> (Master, klar_drivers::can::memory::MemoryEndpoint) {
    let bus = MemoryBus::new();
    let master = Master::new(Box::new(bus.endpoint()), Duration::from_millis(20));
    (master, bus.endpoint())
}

fn sent(ep: &mut dyn CanBus) -> Vec<CanFrame> {
    let mut out = Vec::new();
    while let Some(CanEvent::Frame { frame, .. }) = ep.try_recv().expect("open") {
        out.push(frame);
    }
    out
}

fn f(id: u16, data: &[u8]) -> CanFrame {
    CanFrame::standard(id, data).expect("frame")
}

#[test]
fn nmt_and_sync_frames() {
    let (mut m, mut node) = setup();
    m.nmt(NmtCommand::Start, 3).expect("nmt");
    m.nmt(NmtCommand::Stop, 3).expect("nmt");
    m.nmt(NmtCommand::PreOperational, 0).expect("nmt");
    m.nmt(NmtCommand::ResetNode, 127).expect("nmt");
    m.nmt(NmtCommand::ResetCommunication, 0).expect("nmt");
    m.sync().expect("sync");
    assert!(m.nmt(NmtCommand::Start, 128).is_err());
    assert_eq!(
        sent(&mut node),
        vec![
            f(0, &[0x01, 3]),
            f(0, &[0x02, 3]),
            f(0, &[0x80, 0]),
            f(0, &[0x81, 127]),
            f(0, &[0x82, 0]),
            f(0x080, &[])
        ]
    );
    assert_eq!(m.sync_count(), 1);
}

#[test]
fn boot_up_and_state_changes_become_events() {
    let (mut m, mut node) = setup();
    node.send(&f(0x705, &[0x00])).expect("send");
    node.send(&f(0x705, &[0x05])).expect("send");
    node.send(&f(0x705, &[0x05])).expect("send");
    node.send(&f(0x705, &[0x7F])).expect("send");
    node.send(&f(0x705, &[0x05, 0x00])).expect("send");
    m.poll().expect("poll");
    assert_eq!(m.next_event(), Some(NodeEvent::BootUp(5)));
    assert_eq!(
        m.next_event(),
        Some(NodeEvent::StateChanged(5, NmtState::Operational))
    );
    assert_eq!(
        m.next_event(),
        Some(NodeEvent::StateChanged(5, NmtState::PreOperational))
    );
    assert!(matches!(
        m.next_event(),
        Some(NodeEvent::Malformed { node: Some(5), .. })
    ));
    assert_eq!(m.next_event(), None);
    assert_eq!(m.node_state(5), Some(NmtState::PreOperational));
}

#[test]
fn heartbeat_supervision_uses_the_given_clock() {
    let (mut m, mut node) = setup();
    m.set_time(0.1);
    m.watch_heartbeat(4, 0.3);
    node.send(&f(0x704, &[0x05])).expect("send");
    m.set_time(0.15);
    m.poll().expect("poll");
    while m.next_event().is_some() {}
    m.set_time(0.44);
    assert_eq!(m.next_event(), None, "0.29 s of silence is within 0.3 s");
    m.set_time(0.5);
    match m.next_event() {
        Some(NodeEvent::HeartbeatLost {
            node: 4,
            silent_for,
        }) => assert!((silent_for - 0.35).abs() < 1e-12),
        other => panic!("{other:?}"),
    }
    m.set_time(0.9);
    assert_eq!(m.next_event(), None, "reported once");
}

#[test]
fn emergencies_are_decoded() {
    let (mut m, mut node) = setup();
    node.send(&f(0x085, &[0x10, 0x23, 0x03, 1, 2, 3, 4, 5]))
        .expect("send");
    m.poll().expect("poll");
    let e = match m.next_event() {
        Some(NodeEvent::Emergency(e)) => e,
        other => panic!("{other:?}"),
    };
    assert_eq!(
        e,
        Emergency {
            node: 5,
            code: 0x2310,
            register: 0x03,
            manufacturer: [1, 2, 3, 4, 5]
        }
    );
    let text = e.to_string();
    assert!(
        text.contains("node 5")
            && text.contains("0x2310")
            && text.contains("continuous over-current"),
        "{text}"
    );
    assert!(text.contains("generic, current"), "{text}");
    // The class of 0x23xx (CiA 301: current on the device's output side) follows the name.
    assert_eq!(
        text,
        "node 5: EMCY 0x2310 continuous over-current (current, device output side; \
         error register 0x03: generic, current)"
    );
    // A code known only by its class is named once, by the class.
    let classed = Emergency {
        node: 1,
        code: 0x2399,
        register: 0x03,
        manufacturer: [0; 5],
    };
    assert_eq!(
        classed.to_string(),
        "node 1: EMCY 0x2399 current, device output side (error register 0x03: generic, current)"
    );
    assert_eq!(e.encode(), [0x10, 0x23, 0x03, 1, 2, 3, 4, 5]);
    assert!(Emergency::decode(1, &[0; 7]).is_none());
}

#[test]
fn error_codes_are_named_by_entry_or_class() {
    assert_eq!(error_code_name(0x0000), "error reset or no error");
    assert_eq!(error_code_name(0x8611), "following error");
    assert_eq!(
        error_code_name(0x8130),
        "life guard error or heartbeat error"
    );
    assert_eq!(error_code_name(0x3211), "voltage inside the device");
    assert_eq!(error_code_name(0x4234), "device temperature");
    assert_eq!(error_code_name(0x5001), "device hardware");
    assert_eq!(error_code_name(0xFF42), "device specific");
    assert_eq!(
        register_bit_names(0x91),
        vec!["generic", "communication", "manufacturer specific"]
    );
}

#[test]
fn pdo_samples_are_fresh_only_after_sync() {
    let (mut m, mut node) = setup();
    node.send(&f(0x181, &[1, 2])).expect("send");
    m.sync().expect("sync");
    let missing = m
        .await_pdos(&[0x181, 0x182], Duration::ZERO)
        .expect("await");
    assert_eq!(
        missing,
        vec![0x181, 0x182],
        "a PDO from before the SYNC is stale"
    );
    node.send(&f(0x181, &[3, 4])).expect("send");
    let missing = m
        .await_pdos(&[0x181, 0x182], Duration::from_millis(5))
        .expect("await");
    assert_eq!(missing, vec![0x182]);
    assert_eq!(
        m.pdo(0x181).map(|s| s.frame.data().to_vec()),
        Some(vec![3, 4])
    );
}

#[test]
fn pdo_payloads_pack_little_endian() {
    let entries = [PdoEntry::new(0x6041, 0, 16), PdoEntry::new(0x6064, 0, 32)];
    assert_eq!(
        pack(&entries, &[0x0637, (-2i32) as u32]),
        vec![0x37, 0x06, 0xFE, 0xFF, 0xFF, 0xFF]
    );
    assert_eq!(
        unpack(&entries, &[0x37, 0x06, 0xFE, 0xFF, 0xFF, 0xFF]),
        Some(vec![0x0637, 0xFFFF_FFFE])
    );
    assert_eq!(unpack(&entries, &[0x37, 0x06, 0xFE, 0xFF, 0xFF]), None);
    assert_eq!(PdoEntry::new(0x607A, 0, 32).mapping_value(), 0x607A_0020);
    assert_eq!(
        PdoEntry::from_mapping_value(0x6040_0010),
        PdoEntry::new(0x6040, 0, 16)
    );
    assert_eq!(default_cob_id(PdoKind::Transmit, 1, 5), Some(0x185));
    assert_eq!(default_cob_id(PdoKind::Receive, 4, 5), Some(0x505));
    assert_eq!(default_cob_id(PdoKind::Receive, 5, 5), None);
}
