//! `klar run` with a Modbus spindle against the independent Delta VFD of ../shared/peers
//! (pymodbus RTU behind a null modem that can cut or garble the line): every way a run ends
//! commands the VFD to stop and confirms it, or says loudly that it could not; a change of
//! direction stops first; a port that cannot keep the configured parity is refused.
//! The server's JSON log is the witness of what reached the device.

mod common;

use common::vfd_peer::{
    COMMAND, RUN_FORWARD, RUN_REVERSE, STOP, VfdPeer, command_writes, output_frequency_is,
};
use serde_json::Value;
use std::time::Duration;

/// M3 at 6000 rpm (100 Hz at 60 rpm/Hz) during a 6 s move, then M5.
const LONG_CUT: &str = "0 BEGIN PGM P MM\n1 TOOL CALL 1 Z S6000\n2 L X+0 F200 M3\n\
                        3 L X+20\n4 L X+0 M5\n5 END PGM P MM\n";

/// Starts klar on the long cut and waits until the VFD runs forward at speed.
fn running(peer: &VfdPeer) -> common::vfd_peer::Klar {
    let machine = peer.machine("none");
    let program = peer.program("long.h", LONG_CUT);
    let klar = peer.klar(&program, &machine);
    peer.wait_log("the VFD commanded to run forward", |e| {
        e["addr"].as_u64() == Some(COMMAND)
            && e["values"][0].as_u64() == Some(RUN_FORWARD)
            && e.get("exc").is_none()
    });
    peer.wait_log("the VFD at 100 Hz", |e| {
        output_frequency_is(e, |f| f == 10_000)
    });
    klar
}

/// Index of the first entry at or after `from` that `pred` accepts.
fn find(log: &[Value], from: usize, pred: impl Fn(&Value) -> bool) -> Option<usize> {
    log.iter().skip(from).position(pred).map(|k| k + from)
}

/// The stop (0x2000 = 0x01) was written after entry `from`, and a status read answered after
/// it shows the VFD out of the run state: the stop klar confirmed. The server may lag behind
/// klar on a loaded machine, so its log is read again for a few seconds.
fn assert_stop_confirmed_after(peer: &VfdPeer, from: usize, stderr: &str) {
    let confirmed = |log: &[Value]| {
        let stop = command_writes(log)
            .into_iter()
            .find(|&(i, w)| i > from && w == STOP)
            .map(|(i, _)| i)?;
        find(log, stop + 1, |e| {
            e["addr"].as_u64() == Some(0x2100)
                && e["reply"]
                    .as_array()
                    .and_then(|r| r.get(1))
                    .and_then(Value::as_u64)
                    .is_some_and(|status| status & 0b11 != 0b11)
        })
    };
    let deadline = std::time::Instant::now() + Duration::from_secs(5);
    loop {
        let log = peer.log();
        if confirmed(&log).is_some() {
            return;
        }
        assert!(
            std::time::Instant::now() < deadline,
            "no stop written after entry {from}, or no status read after it shows the VFD out \
             of the run state: {log:?}\n{stderr}"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn a_vfd_exception_ends_in_a_controlled_stop_with_the_spindle_stopped() {
    let mut peer = VfdPeer::start("exception", 2000.0);
    let klar = running(&peer);
    peer.vfd_control("exception 4 1");
    let run = klar.wait();
    let log = peer.log();
    let exc = find(&log, 0, |e| e["exc"].as_u64() == Some(4)).expect("the exception was sent");
    assert_stop_confirmed_after(&peer, exc, &run.stderr);
    assert!(!run.status.success(), "{run:?}");
    let device = format!("spindle VFD (Modbus unit 1 on {})", peer.port);
    assert!(
        run.stderr.contains(&device) && run.stderr.contains("device exception 0x04"),
        "the stop names the device and the exception as its own fault kind: {}",
        run.stderr
    );
    assert!(
        !run.stderr.contains("communication lost"),
        "a device that answers with an exception is not a lost link: {}",
        run.stderr
    );
    assert!(!run.stderr.contains("may still turn"), "{}", run.stderr);
    let exit = peer.stop_server();
    assert_eq!(exit["run"], false, "the VFD is left stopped: {exit}");
}

#[test]
fn bad_crcs_end_in_a_controlled_stop_with_the_spindle_stopped() {
    let mut peer = VfdPeer::start("garble", 2000.0);
    let klar = running(&peer);
    let before = peer.log().len();
    // Three answers in a row with a bad CRC: the first try and both retries of one request.
    peer.relay_control("garble 3");
    let run = klar.wait();
    assert!(
        peer.relay_log().contains("garbled"),
        "the relay garbled answers"
    );
    assert_stop_confirmed_after(&peer, before, &run.stderr);
    assert!(!run.status.success(), "{run:?}");
    let device = format!("spindle VFD (Modbus unit 1 on {})", peer.port);
    assert!(
        run.stderr.contains(&device) && run.stderr.contains("bad CRC"),
        "the stop names the device and the cause: {}",
        run.stderr
    );
    assert!(!run.stderr.contains("may still turn"), "{}", run.stderr);
    let exit = peer.stop_server();
    assert_eq!(exit["run"], false, "the VFD is left stopped: {exit}");
}

#[test]
fn a_cut_line_ends_with_a_loud_warning_that_the_spindle_may_still_turn() {
    let mut peer = VfdPeer::start("cut", 2000.0);
    let klar = running(&peer);
    let before = peer.log().len();
    peer.relay_control("cut");
    let run = klar.wait();
    assert!(!run.status.success(), "{run:?}");
    let device = format!("spindle VFD (Modbus unit 1 on {})", peer.port);
    assert!(
        run.stderr.contains(&device) && run.stderr.contains("no valid response"),
        "the stop names the device and the cause: {}",
        run.stderr
    );
    let last = run.last_error_line();
    assert!(
        last.starts_with("WARNING: ")
            && last.contains(&device)
            && last.contains("did not confirm the stop")
            && last.contains("may still turn"),
        "the last line warns loudly: {}",
        run.stderr
    );
    // The warning is true: no stop reached the VFD after the cut and it still runs.
    let after: Vec<_> = command_writes(&peer.log())
        .into_iter()
        .filter(|&(i, _)| i >= before)
        .collect();
    assert!(after.iter().all(|&(_, w)| w != STOP), "{after:?}");
    let exit = peer.stop_server();
    assert_eq!(exit["run"], true, "{exit}");
}

#[test]
fn an_operator_signal_stops_the_spindle_and_confirms_it() {
    let mut peer = VfdPeer::start("signal", 2000.0);
    let klar = running(&peer);
    let before = peer.log().len();
    klar.signal("INT");
    let run = klar.wait();
    assert_eq!(run.status.code(), Some(130), "{run:?}");
    assert!(!run.stderr.contains("may still turn"), "{}", run.stderr);
    assert_stop_confirmed_after(&peer, before, &run.stderr);
    let exit = peer.stop_server();
    assert_eq!(exit["run"], false, "{exit}");
}

/// M3 at 3000 rpm, then M5 and M4 in the next blocks, then M3 right after M4: each reversal reaches the
/// VFD as a stop, the output frequency falls to zero, and only then the new direction.
#[test]
fn a_direction_change_stops_and_waits_for_zero_speed_first() {
    let mut peer = VfdPeer::start("reverse", 400.0);
    let machine = peer.machine("none");
    let program = peer.program(
        "reverse.h",
        "0 BEGIN PGM P MM\n1 TOOL CALL 1 Z S3000\n2 L X+1 F3000 M3\n\
         3 L X+0 M5\n4 L X+1 M4\n5 L X+0 M3\n6 L X+1 M5\n7 END PGM P MM\n",
    );
    let run = peer.klar(&program, &machine).wait();
    assert!(run.status.success(), "{run:?}");
    let log = peer.log();
    let writes = command_writes(&log);
    let words: Vec<u64> = writes.iter().map(|&(_, w)| w).collect();
    let fwd = words
        .iter()
        .position(|&w| w == RUN_FORWARD)
        .expect("forward");
    let rev = words
        .iter()
        .position(|&w| w == RUN_REVERSE)
        .expect("reverse");
    let fwd2 = fwd
        + 1
        + words[fwd + 1..]
            .iter()
            .position(|&w| w == RUN_FORWARD)
            .expect("forward again");
    assert!(fwd < rev && rev < fwd2, "{words:x?}");
    for (from, to) in [(fwd, rev), (rev, fwd2)] {
        // No run command in the other direction without a stop between them.
        assert!(
            words[from + 1..to].contains(&STOP),
            "no stop between {:x} and {:x}: {words:x?}",
            words[from],
            words[to]
        );
        // The VFD reported zero output frequency before the new direction was written.
        let (a, b) = (writes[from].0, writes[to].0);
        assert!(
            log[a..b].iter().any(|e| output_frequency_is(e, |f| f == 0)),
            "no zero speed between entries {a} and {b}"
        );
        assert!(
            log[a..b].iter().any(|e| output_frequency_is(e, |f| f > 0)),
            "the spindle turned between entries {a} and {b}"
        );
    }
    assert_eq!(words.last(), Some(&STOP), "{words:x?}");
    let exit = peer.stop_server();
    assert_eq!(exit["run"], false, "{exit}");
}

#[test]
fn even_parity_on_a_port_that_cannot_keep_it_is_refused() {
    let peer = VfdPeer::start("parity", 2000.0);
    let machine = peer.machine("even");
    let program = peer.program("short.h", LONG_CUT);
    let run = peer.klar(&program, &machine).wait();
    assert!(!run.status.success(), "{run:?}");
    assert!(
        run.stderr.contains(&peer.port) && run.stderr.contains("parity even"),
        "{}",
        run.stderr
    );
    // Nothing was sent to the VFD.
    std::thread::sleep(Duration::from_millis(100));
    assert!(command_writes(&peer.log()).is_empty());
}

/// A panic while the spindle turns: unwinding drops the machine's I/O, whose spindle guard
/// commands the stop and confirms it before the process goes on.
#[test]
fn unwinding_a_panic_stops_the_spindle_and_confirms_it() {
    let mut peer = VfdPeer::start("unwind", 2000.0);
    let config = klar::config::MachineConfig::load(&peer.machine("none")).expect("machine");
    let peer_ref = &peer;
    let unwound = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let mut io = klar::machine::MachineIo::open(&config).expect("the VFD opens");
        let spindle = io.spindle_mut().expect("a spindle");
        spindle.command(3000.0).expect("M3 S3000");
        peer_ref.wait_log("the VFD at 50 Hz", |e| {
            output_frequency_is(e, |f| f == 5_000)
        });
        panic!("a bug while the spindle turns");
    }));
    assert!(unwound.is_err());
    let log = peer.log();
    let at_speed = find(&log, 0, |e| output_frequency_is(e, |f| f == 5_000)).expect("at speed");
    assert_stop_confirmed_after(&peer, at_speed, "");
    let exit = peer.stop_server();
    assert_eq!(exit["run"], false, "{exit}");
}

/// The VFD trips (its error register shows the code, the output coasts): the run ends in a
/// controlled stop naming the device and the code, and the stop is written and confirmed.
#[test]
fn a_vfd_trip_ends_in_a_controlled_stop_with_the_stop_confirmed() {
    let mut peer = VfdPeer::start("trip", 2000.0);
    let klar = running(&peer);
    peer.vfd_control("fault 7");
    let run = klar.wait();
    let log = peer.log();
    let trip = find(&log, 0, |e| e["ev"] == "fault").expect("the VFD tripped");
    assert_stop_confirmed_after(&peer, trip, &run.stderr);
    assert!(!run.status.success(), "{run:?}");
    let device = format!("spindle VFD (Modbus unit 1 on {})", peer.port);
    assert!(
        run.stderr.contains(&device) && run.stderr.contains("fault code 7"),
        "the stop names the device and the fault: {}",
        run.stderr
    );
    assert!(!run.stderr.contains("may still turn"), "{}", run.stderr);
    let exit = peer.stop_server();
    assert_eq!(exit["run"], false, "{exit}");
}

/// A VFD that refuses every request from some moment on (exception 04 to all): the run ends
/// in a controlled stop, the stop cannot be confirmed, and the last line says so loudly.
#[test]
fn a_vfd_that_keeps_refusing_ends_with_the_loud_warning() {
    let mut peer = VfdPeer::start("refusing", 2000.0);
    let klar = running(&peer);
    peer.vfd_control("exception 4");
    let run = klar.wait();
    assert!(!run.status.success(), "{run:?}");
    let device = format!("spindle VFD (Modbus unit 1 on {})", peer.port);
    let last = run.last_error_line();
    assert!(
        last.starts_with("WARNING: ")
            && last.contains(&device)
            && last.contains("exception 0x04")
            && last.contains("may still turn"),
        "the last line warns loudly: {}",
        run.stderr
    );
    // The stop was tried (and refused) after the refusals began.
    let log = peer.log();
    let first = find(&log, 0, |e| e["exc"].as_u64() == Some(4)).expect("refusals");
    assert!(
        find(&log, first + 1, |e| e["addr"].as_u64() == Some(0x2001)
            && e["exc"].as_u64() == Some(4))
        .is_some(),
        "no stop attempt after the refusals began"
    );
    let exit = peer.stop_server();
    assert_eq!(exit["run"], true, "{exit}");
}
