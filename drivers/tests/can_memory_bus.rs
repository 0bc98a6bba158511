//! The in-memory bus: delivery to everyone but the sender, synchronous device answers,
//! fault injection and bus-off.

use std::time::Duration;

use klar_drivers::can::memory::{BusDevice, FrameFate, MemoryBus};
use klar_drivers::can::{BusErrorKind, CanBus, CanError, CanEvent, CanFrame};

fn frame(id: u16, data: &[u8]) -> CanFrame {
    CanFrame::standard(id, data).expect("frame")
}

fn frames(ep: &mut dyn CanBus) -> Vec<CanFrame> {
    let mut out = Vec::new();
    while let Some(ev) = ep.try_recv().expect("open") {
        if let CanEvent::Frame { frame, .. } = ev {
            out.push(frame);
        }
    }
    out
}

/// Answers every frame with id + 1 and the same data, and says hello when attached.
struct Echo;

impl BusDevice for Echo {
    fn start(&mut self, out: &mut Vec<CanFrame>) {
        out.push(CanFrame::standard(0x700, &[0]).expect("frame"));
    }
    fn on_frame(&mut self, f: &CanFrame, out: &mut Vec<CanFrame>) {
        if let Some(id) = f.id().standard().filter(|&id| id < 0x700) {
            out.push(CanFrame::standard(id + 1, f.data()).expect("frame"));
        }
    }
}

#[test]
fn endpoints_see_each_other_but_not_themselves() {
    let bus = MemoryBus::new();
    let mut a = bus.endpoint();
    let mut b = bus.endpoint();
    let mut c = bus.endpoint();
    a.send(&frame(0x10, &[1])).expect("send");
    b.send(&frame(0x20, &[2])).expect("send");
    assert_eq!(frames(&mut a), vec![frame(0x20, &[2])]);
    assert_eq!(frames(&mut b), vec![frame(0x10, &[1])]);
    assert_eq!(frames(&mut c), vec![frame(0x10, &[1]), frame(0x20, &[2])]);
    assert_eq!(bus.frames_carried(), 2);
}

#[test]
fn devices_answer_before_send_returns() {
    let bus = MemoryBus::new();
    let mut a = bus.endpoint();
    bus.attach(Box::new(Echo));
    a.send(&frame(0x100, &[9, 8])).expect("send");
    assert_eq!(
        frames(&mut a),
        vec![frame(0x700, &[0]), frame(0x101, &[9, 8])]
    );
}

#[test]
fn injector_drops_and_truncates() {
    let bus = MemoryBus::new();
    let mut a = bus.endpoint();
    let mut b = bus.endpoint();
    bus.set_injector(|f| match f.id().raw() {
        0x1 => FrameFate::Drop,
        0x2 => FrameFate::Truncate,
        _ => FrameFate::Deliver,
    });
    a.send(&frame(0x1, &[1, 2])).expect("send");
    a.send(&frame(0x2, &[1, 2])).expect("send");
    a.send(&frame(0x3, &[1, 2])).expect("send");
    assert_eq!(frames(&mut b), vec![frame(0x2, &[1]), frame(0x3, &[1, 2])]);
    bus.clear_injector();
    a.send(&frame(0x1, &[])).expect("send");
    assert_eq!(frames(&mut b), vec![frame(0x1, &[])]);
}

#[test]
fn bus_off_refuses_sends_and_tells_everyone() {
    let bus = MemoryBus::new();
    let mut a = bus.endpoint();
    let mut b = bus.endpoint();
    bus.set_bus_off(true);
    assert_eq!(a.send(&frame(0x1, &[])), Err(CanError::BusOff));
    assert_eq!(
        b.try_recv().expect("open"),
        Some(CanEvent::Error(BusErrorKind::BusOff))
    );
    bus.set_bus_off(false);
    a.send(&frame(0x1, &[])).expect("recovered");
    assert_eq!(frames(&mut b), vec![frame(0x1, &[])]);
}

#[test]
fn recv_waits_for_another_thread() {
    let bus = MemoryBus::new();
    let mut a = bus.endpoint();
    let mut b = bus.endpoint();
    let sender = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(20));
        a.send(&frame(0x42, &[])).expect("send");
    });
    let got = b.recv_timeout(Duration::from_secs(5)).expect("open");
    assert!(matches!(got, Some(CanEvent::Frame { frame: f, .. }) if f == frame(0x42, &[])));
    sender.join().expect("sender");
    assert_eq!(
        b.recv_timeout(Duration::from_millis(10)).expect("open"),
        None
    );
}
