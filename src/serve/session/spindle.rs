//! The spindle by hand, as in a TNC's manual mode: on clockwise (M3) or counter-clockwise
//! (M4) at a speed, or off, while no program runs.
//!
//! A run opens the machine's backends and stops the spindle when it ends; to keep the
//! spindle turning between jogs and MDI blocks the machine thread holds it between runs
//! (cycling it on the wall clock while it turns), hands it to the next run and takes it back
//! when a manual run ends normally. A program run takes it over for good: the program's
//! M3/M4/M5 act on it and the run's end stops it, as every program run's end does. A run
//! that ends with a fault or an error stops it too, and so does Reset. Only a simulated
//! spindle is held this way for now; a spindle drive or VFD is refused (its device cannot be
//! opened twice, once here and once by the run).

use super::{MachineLoop, MachineState, Reply};
use crate::config::{MachineConfig, SpindleBackendConfig};
use crate::machine::Spindle;
use crate::runtime::Run;
use crate::serve::manual::Refusal;
use serde::{Deserialize, Serialize};
use std::time::{Duration, Instant};

/// Wall time between two cycles of the held spindle while it turns or ramps.
pub const SPINDLE_POLL: Duration = Duration::from_millis(20);

/// Below this measured speed (rpm) a stopped spindle counts as standing still.
const STANDSTILL_RPM: f64 = 0.5;

/// The direction the operator asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SpindleDirection {
    /// Clockwise, M3.
    Cw,
    /// Counter-clockwise, M4.
    Ccw,
    /// Off, M5.
    Stop,
}

/// What the operator asks of the spindle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpindleRequest {
    /// Direction or off.
    pub direction: SpindleDirection,
    /// Speed, rpm (ignored for [`SpindleDirection::Stop`]).
    pub speed: f64,
}

/// The spindle as the page shows it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SpindleStatus {
    /// The commanded direction (`stop` while commanded to stand).
    pub direction: SpindleDirection,
    /// The commanded speed, rpm (unsigned; 0 when stopped).
    pub commanded: f64,
    /// The measured speed, rpm, signed (positive clockwise).
    pub measured: f64,
}

impl SpindleStatus {
    /// The status of a spindle commanded `commanded` (signed rpm) and turning `measured`.
    pub fn of(commanded: f64, measured: f64) -> Self {
        let direction = if commanded > 0.0 {
            SpindleDirection::Cw
        } else if commanded < 0.0 {
            SpindleDirection::Ccw
        } else {
            SpindleDirection::Stop
        };
        Self {
            direction,
            commanded: commanded.abs(),
            measured,
        }
    }

    /// A spindle at rest.
    pub fn stopped() -> Self {
        Self::of(0.0, 0.0)
    }
}

/// The signed speed (rpm) `request` commands on `config`, or why it is refused: the machine
/// has no spindle, one the dashboard cannot hold, or the speed lies outside its range.
pub fn signed_speed(config: &MachineConfig, request: SpindleRequest) -> Result<f64, Refusal> {
    let Some(s) = &config.spindle else {
        return Err(Refusal::NoSpindle);
    };
    if !matches!(s.backend, SpindleBackendConfig::Sim(_)) {
        return Err(Refusal::Unsupported(
            "the spindle by hand is supported for a simulated spindle only, not yet for a \
             spindle drive or VFD"
                .into(),
        ));
    }
    let sign = match request.direction {
        SpindleDirection::Stop => return Ok(0.0),
        SpindleDirection::Cw => 1.0,
        SpindleDirection::Ccw => -1.0,
    };
    let speed = request.speed;
    if !speed.is_finite() || speed <= 0.0 || speed > s.max_rpm {
        return Err(Refusal::SpindleSpeed {
            speed,
            max: s.max_rpm,
        });
    }
    Ok(sign * speed)
}

/// The spindle the machine thread holds between runs, with its own clock.
pub struct HeldSpindle {
    spindle: Spindle,
    /// The spindle's machine time, s: advanced by the wall clock between runs.
    t: f64,
    /// When the spindle was last cycled.
    last: Instant,
}

impl HeldSpindle {
    fn new(spindle: Spindle, t: f64) -> Self {
        Self {
            spindle,
            t,
            last: Instant::now(),
        }
    }

    fn status(&self) -> SpindleStatus {
        SpindleStatus::of(self.spindle.commanded(), self.spindle.feedback().rpm)
    }

    /// True while it is commanded to turn or still turns.
    fn moving(&self) -> bool {
        self.spindle.commanded() != 0.0 || self.spindle.feedback().rpm.abs() > STANDSTILL_RPM
    }
}

impl MachineLoop {
    /// `POST /api/spindle`: refused while a program runs or a fault waits for Reset, and for
    /// a request the machine cannot do; else the spindle is commanded and held.
    pub(super) fn spindle(&mut self, request: SpindleRequest, reply: Reply) {
        if let Some(r) = self.refusal() {
            let _ = reply.send(Err(r));
            return;
        }
        let rpm = match signed_speed(&self.config, request) {
            Ok(rpm) => rpm,
            Err(r) => {
                let _ = reply.send(Err(r));
                return;
            }
        };
        if self.held.is_none() {
            match Spindle::open_simulated(&self.config) {
                Some(s) => self.held = Some(HeldSpindle::new(s, 0.0)),
                None => {
                    let _ = reply.send(Err(Refusal::NoSpindle));
                    return;
                }
            }
        }
        let Some(held) = self.held.as_mut() else {
            let _ = reply.send(Err(Refusal::NoSpindle));
            return;
        };
        if let Err(e) = held.spindle.command(rpm) {
            let _ = reply.send(Err(Refusal::Unsupported(e.to_string())));
            return;
        }
        let _ = reply.send(Ok(()));
        let words = match request.direction {
            SpindleDirection::Stop => "spindle stop".to_string(),
            d => format!(
                "spindle {} {:.0} rpm",
                if d == SpindleDirection::Cw {
                    "M3"
                } else {
                    "M4"
                },
                rpm.abs()
            ),
        };
        tracing::info!(operation = %words, "manual operation");
        self.snap.manual = Some(words);
        self.show_held_spindle();
    }

    /// Cycles the held spindle on the wall clock while it turns or ramps; true while it
    /// does (the idle loop then looks again after [`SPINDLE_POLL`]). A spindle fault stops
    /// it and becomes the machine's fault.
    pub(super) fn spindle_tick(&mut self) -> bool {
        let Some(held) = self.held.as_mut() else {
            return false;
        };
        if !held.moving() {
            return false;
        }
        let now = Instant::now();
        held.t += now.duration_since(held.last).as_secs_f64();
        held.last = now;
        let cycled = held.spindle.cycle(held.t);
        let fault = match cycled {
            Err(e) => Some(format!("{}: {e}", held.spindle.name())),
            Ok(()) => held
                .spindle
                .feedback()
                .fault
                .clone()
                .map(|f| held.spindle.describe_fault(&f)),
        };
        if let Some(message) = fault {
            self.stop_spindle();
            self.snap.state = MachineState::Fault;
            self.snap.message = Some(message);
        }
        self.show_held_spindle();
        self.held.as_ref().is_some_and(HeldSpindle::moving)
    }

    /// Hands the held spindle to a run that has just started (its own, never turned, is
    /// dropped).
    pub(super) fn spindle_into_run(&mut self, run: &mut Run<'_, '_>) {
        if let Some(held) = self.held.take() {
            drop(run.swap_spindle(Some(held.spindle)));
        }
    }

    /// Takes the run's spindle back before the run finishes when `keep` (a manual run that
    /// ended normally); otherwise the run's end stops it.
    pub(super) fn spindle_out_of_run(&mut self, run: &mut Run<'_, '_>, keep: bool) {
        if keep && let Some(s) = run.swap_spindle(None) {
            self.held = Some(HeldSpindle::new(s, run.time()));
        }
    }

    /// Stops the held spindle (Reset, a fault); it ramps down under the idle loop's cycles.
    pub(super) fn stop_spindle(&mut self) {
        if let Some(held) = self.held.as_mut()
            && let Err(e) = held.spindle.stop()
        {
            tracing::error!("stopping the spindle: {e}");
        }
    }

    /// The held spindle's status in the snapshot (stopped when none is held).
    pub(super) fn show_held_spindle(&mut self) {
        let status = match &self.held {
            Some(h) => Some(h.status()),
            None => self
                .config
                .spindle
                .as_ref()
                .map(|_| SpindleStatus::stopped()),
        };
        self.snap.spindle = status;
        self.snap.spindle_rpm = status.map(|s| s.measured);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speeds_outside_the_spindle_range_are_refused() {
        // The built-in mill's simulated spindle turns up to its max_rpm.
        let mill = MachineConfig::builtin_mill();
        let max = mill.spindle.as_ref().map(|s| s.max_rpm).unwrap();
        let ask = |direction, speed| signed_speed(&mill, SpindleRequest { direction, speed });
        assert_eq!(ask(SpindleDirection::Cw, 1200.0), Ok(1200.0));
        assert_eq!(ask(SpindleDirection::Ccw, 1200.0), Ok(-1200.0));
        assert_eq!(ask(SpindleDirection::Cw, max), Ok(max));
        assert_eq!(ask(SpindleDirection::Stop, f64::NAN), Ok(0.0));
        for bad in [0.0, -5.0, max + 1.0, f64::INFINITY, f64::NAN] {
            assert!(
                matches!(
                    ask(SpindleDirection::Cw, bad),
                    Err(Refusal::SpindleSpeed { .. })
                ),
                "{bad}"
            );
        }
        let mut bare = MachineConfig::builtin_mill();
        bare.spindle = None;
        assert_eq!(
            signed_speed(
                &bare,
                SpindleRequest {
                    direction: SpindleDirection::Cw,
                    speed: 100.0
                }
            ),
            Err(Refusal::NoSpindle)
        );
    }

    #[test]
    fn the_status_reads_the_direction_from_the_commanded_sign() {
        let s = SpindleStatus::of(-800.0, -790.0);
        assert_eq!(s.direction, SpindleDirection::Ccw);
        assert_eq!(s.commanded, 800.0);
        assert_eq!(s.measured, -790.0);
        assert_eq!(SpindleStatus::stopped().direction, SpindleDirection::Stop);
    }
}
