//! The fuzz target bodies, shared by the cargo-fuzz binaries (fuzz_targets/) and the bounded
//! stable harness (tests/fuzz_bounded.rs). Each takes arbitrary bytes and must neither panic
//! nor hang; where an input decodes, a round trip or an invariant is checked too.

#![allow(dead_code)]

use klar::config::MachineConfig;
use klar::runtime::stream::OpStream;
use klar::testrun::{check_travel, start_pose, test_run};
use klar_drivers::can::memory::MemoryBus;
use klar_drivers::can::slcan::{SlcanDecoder, SlcanMessage, decode_line, encode_frame};
use klar_drivers::can::{CanBus, CanFrame, CanId};
use klar_drivers::canopen::Master;
use klar_drivers::canopen::emcy::Emergency;
use klar_interp::{Interpreter, OpKind, Pose};
use klar_motion::Step;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::Duration;

/// Most ops taken from one fuzzed program (loops in a program may be endless by design).
const MAX_OPS: usize = 20_000;

fn program(name: &str, data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let interp = Interpreter::from_source(name, &text, Pose::ZERO);
    // Every op the interpreter lets out carries a real source line.
    for op in interp.take(MAX_OPS).flatten() {
        assert!(op.loc.line >= 1, "op without a line: {op:?}");
    }
}

/// Klartext parser and interpreter.
pub fn program_klartext(data: &[u8]) {
    program("fuzz.h", data);
}

/// TNC ISO parser and interpreter.
pub fn program_tnc_iso(data: &[u8]) {
    program("fuzz.i", data);
}

/// Lathe DIN parser and interpreter.
pub fn program_lathe_din(data: &[u8]) {
    program("fuzz.nc", data);
}

/// The machine TOML loader and its validation; an accepted machine is usable.
pub fn machine_toml(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    if let Ok(m) = MachineConfig::parse("fuzz.toml", &text) {
        assert!(!m.axes.is_empty());
        assert!(m.servo_period > 0.0 && m.servo_period.is_finite());
        let _ = m.axis_limits();
        let _ = m.needs_wall_clock();
    }
}

/// The slcan stream decoder: any byte stream, split anywhere, decodes without panic, and
/// every frame it yields survives an encode/decode round trip.
pub fn slcan_stream(data: &[u8]) {
    let split = data.first().map_or(0, |&b| usize::from(b)).min(data.len());
    let mut decoder = SlcanDecoder::new();
    let mut out = Vec::new();
    decoder.feed(&data[..split], &mut out);
    decoder.feed(&data[split..], &mut out);
    for line in data.split(|&b| b == b'\r') {
        let _ = decode_line(line);
    }
    for m in out {
        if let SlcanMessage::Frame { frame, .. } = m {
            let mut bytes = Vec::new();
            encode_frame(&frame, &mut bytes);
            let line = bytes.strip_suffix(b"\r").unwrap_or(&bytes);
            match decode_line(line) {
                SlcanMessage::Frame { frame: back, .. } => assert_eq!(back, frame),
                other => panic!("{frame:?} encoded as {bytes:?} decodes to {other:?}"),
            }
        }
    }
}

/// CANopen decoding in the master: arbitrary frames (id, length, data from the bytes) reach
/// a master, which classifies them (NMT, heartbeat, EMCY, PDO, SDO) without panic.
pub fn canopen_frames(data: &[u8]) {
    let bus = MemoryBus::new();
    let mut master = Master::new(Box::new(bus.endpoint()), Duration::from_millis(1));
    let mut sender = bus.endpoint();
    master.watch_heartbeat(1, 0.1);
    let mut rest = data;
    let mut t = 0.0;
    while let [hi, lo, len, tail @ ..] = rest {
        let n = usize::from(*len % 9).min(tail.len());
        let (payload, next) = tail.split_at(n);
        rest = next;
        let raw = u16::from_be_bytes([*hi, *lo]);
        let id = if hi & 0x80 != 0 {
            CanId::Extended(u32::from(raw) << 8 | u32::from(*len))
        } else {
            CanId::Standard(raw & 0x7FF)
        };
        if let Ok(frame) = CanFrame::new(id, payload) {
            let _ = Emergency::decode((raw & 0x7F) as u8, frame.data());
            if sender.send(&frame).is_err() {
                return;
            }
        }
        t += 0.01;
        master.set_time(t);
        let _ = master.poll();
        while master.next_event().is_some() {}
    }
}

/// Whole pipeline: most ops one input may feed the planner.
const PIPELINE_MAX_OPS: usize = 5_000;
/// Whole pipeline: most planned machine time per input, s.
const PIPELINE_MAX_TIME: f64 = 5.0;
/// Whole pipeline: most samples per input (5 s at the built-in machines' 1 ms period, with
/// room for a shorter period).
const PIPELINE_MAX_SAMPLES: usize = 10_000;
/// Slack on the per-period step check: the velocity limit · period · (1 + this) + 1e-9.
const STEP_MARGIN: f64 = 0.10;

static MILL5: OnceLock<MachineConfig> = OnceLock::new();
static LATHE: OnceLock<MachineConfig> = OnceLock::new();

/// The whole pipeline as a run executes it, without the drives: the program (the first byte
/// 0, 1 or 2 picks Klartext, TNC ISO or lathe DIN and is dropped; any other input is
/// Klartext) on the built-in 5-axis mill (lathe DIN: the built-in lathe) through the
/// interpreter, radius compensation with the tilted working plane and the feed resolution
/// ([`OpStream`]), the travel check, the planner, and each sample through the machine's
/// kinematics to machine-axis setpoints. Bounded per input by ops, planned time and samples.
///
/// Every sample and setpoint must be finite. On programs the test run accepts, no machine
/// axis may be commanded further in one servo period than its velocity limit allows (10 %
/// margin); a violation panics naming the axis and the step.
pub fn pipeline(data: &[u8]) {
    let (path, config) = scratch_program(data);
    let run = run_pipeline(&path, config);
    // A step beyond the limit counts only where a run would start: the test run accepts.
    let step = run.step_error.filter(|_| test_run(&path, config).passed());
    let _ = std::fs::remove_file(&path);
    if let Some(message) = step {
        panic!("{message}");
    }
}

/// What one input did in the whole pipeline.
#[derive(Debug, Clone, Default)]
pub struct PipelineRun {
    /// Ops the planner was offered.
    pub ops: usize,
    /// Samples planned (servo cycles).
    pub samples: usize,
    /// The first setpoint step beyond an axis's velocity limit, in words (before the test
    /// run's verdict on the program).
    pub step_error: Option<String>,
}

/// Runs one input through the whole pipeline as [`pipeline`] does and reports it, without
/// the test run's verdict; panics on a non-finite sample or setpoint.
pub fn pipeline_run(data: &[u8]) -> PipelineRun {
    let (path, config) = scratch_program(data);
    let run = run_pipeline(&path, config);
    let _ = std::fs::remove_file(&path);
    run
}

/// Writes the program of a pipeline input to this thread's scratch file; returns the file
/// and the machine it runs on.
fn scratch_program(data: &[u8]) -> (PathBuf, &'static MachineConfig) {
    let (dialect, text) = match data.split_first() {
        Some((&b @ 0..=2, rest)) => (b, rest),
        _ => (0, data),
    };
    let (ext, config) = match dialect {
        1 => ("i", MILL5.get_or_init(MachineConfig::builtin_mill5)),
        2 => ("nc", LATHE.get_or_init(MachineConfig::builtin_lathe)),
        _ => ("h", MILL5.get_or_init(MachineConfig::builtin_mill5)),
    };
    // The runtime opens programs by path (dialect by content and extension, called programs
    // beside it): the input goes to a scratch file of this thread.
    let path = scratch_file(ext);
    if let Err(e) = std::fs::write(&path, text) {
        panic!("fuzz harness: cannot write {}: {e}", path.display());
    }
    (path, config)
}

/// A file name in the temp folder for this process and thread, with extension `ext`.
fn scratch_file(ext: &str) -> PathBuf {
    let thread: String = format!("{:?}", std::thread::current().id())
        .chars()
        .filter(char::is_ascii_digit)
        .collect();
    std::env::temp_dir().join(format!(
        "klar-fuzz-pipeline-{}-{thread}.{ext}",
        std::process::id()
    ))
}

/// Streams the program at `path` through the pipeline on `config`, as `Run` feeds and steps
/// it. Panics on a non-finite sample or setpoint.
fn run_pipeline(path: &Path, config: &MachineConfig) -> PipelineRun {
    let mut run = PipelineRun::default();
    let start = start_pose(config);
    let Ok(mut interp) = config.open_program(path, start) else {
        return run;
    };
    // No file is written (FN 16, FN 27) while fuzzing.
    interp.set_dry_run(true);
    let max_rpm = config.spindle.as_ref().map_or(0.0, |s| s.max_rpm);
    let mut ops = OpStream::new(interp, start, max_rpm, path);
    let Ok(mut planner) = config.planner(start) else {
        return run;
    };
    let mut kin = config.kinematics();
    let letters = config.letters();
    let travel: Vec<[f64; 2]> = config.axes.iter().map(|a| a.travel).collect();
    let period = config.servo_period;
    let max_step: Vec<f64> = config
        .axes
        .iter()
        .map(|a| a.max_velocity * period * (1.0 + STEP_MARGIN) + 1e-9)
        .collect();
    let mut commanded: Vec<f64> = config.axes.iter().map(|a| a.start).collect();
    let mut next = commanded.clone();
    let mut input_done = false;
    loop {
        // Feeding as `Run::feed_planner`: the first error (program, travel, planner) lets
        // the motion before it finish.
        while !input_done && planner.needs_input() {
            let op = match ops.next() {
                Some(Ok(op)) => op,
                Some(Err(_)) | None => {
                    planner.finish();
                    input_done = true;
                    break;
                }
            };
            run.ops += 1;
            if run.ops > PIPELINE_MAX_OPS {
                return run;
            }
            let refused =
                check_travel(&op, &letters, &travel, path).is_err() || planner.push(op).is_err();
            if refused {
                planner.finish();
                input_done = true;
            }
        }
        let sample = match planner.next_step() {
            Some(Step::Sample(s)) => s,
            Some(Step::Event(op)) => {
                match &op.kind {
                    OpKind::Tcpm { on, .. } => kin.set_tcpm(*on),
                    // A thread pass is geared to the measured spindle angle by the servo loop
                    // (its profile is checked by the test run and tests/lathe_threads.rs): the
                    // planner stops at its start and goes on from its end.
                    OpKind::SpindleSync { .. } | OpKind::RigidTap { .. } => {
                        if let Some((_, to)) = op.kind.geared_ends() {
                            kin.to_machine(&to, &mut commanded);
                        }
                    }
                    _ => {}
                }
                continue;
            }
            // The planner freed room and wants more before it goes on.
            None if !input_done && planner.needs_input() => continue,
            None => return run,
        };
        let finite = sample.t.is_finite()
            && sample.pose.0.iter().all(|v| v.is_finite())
            && sample.velocity.iter().all(|v| v.is_finite())
            && sample.acceleration.iter().all(|v| v.is_finite());
        assert!(finite, "non-finite sample: {sample:?}");
        kin.to_machine(&sample.pose, &mut next);
        for (k, (&to, &from)) in next.iter().zip(&commanded).enumerate() {
            let axis = letters[k];
            assert!(
                to.is_finite(),
                "axis {axis}: non-finite setpoint {to} at t = {} s (line {})",
                sample.t,
                sample.loc.line
            );
            let step = (to - from).abs();
            if step > max_step[k] && run.step_error.is_none() {
                run.step_error = Some(format!(
                    "axis {axis}: setpoint step {step:.6} from {from:.6} to {to:.6} in one \
                     period at t = {:.3} s (line {}), above the limit {:.6} (velocity {} · \
                     period {period} · (1 + {STEP_MARGIN}) + 1e-9)",
                    sample.t, sample.loc.line, max_step[k], config.axes[k].max_velocity
                ));
            }
        }
        std::mem::swap(&mut commanded, &mut next);
        run.samples += 1;
        if run.samples >= PIPELINE_MAX_SAMPLES || sample.t >= PIPELINE_MAX_TIME {
            return run;
        }
    }
}
