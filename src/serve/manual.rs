//! Manual operation from the dashboard: jog, continuous jog and MDI become a small program
//! of the machine's own language, which then runs through the same [`crate::runtime::Run`]
//! (and the same test run) as any program; homing uses the backends' own sequence
//! ([`crate::state::home_axes`]).
//!
//! The rules, after the TNC's manual and MDI operating modes: nothing manual happens while a
//! program runs or while a fault is not yet acknowledged; a jog never leaves an axis's
//! travel (the soft limits), so a continuous jog ends at the limit at the latest; an MDI
//! block is checked by the test run from where the axes stand before anything moves.

use crate::config::{KinematicsConfig, MachineConfig};
use klar_interp::AxisLetter;
use std::path::{Path, PathBuf};

/// One manual operation the operator asks for.
#[derive(Debug, Clone, PartialEq)]
pub enum ManualOp {
    /// Move one axis by `distance` (mm or degrees) at `speed` (mm/s or °/s).
    Jog {
        /// The axis letter as written (`X`, `Z`, `C`, …).
        axis: String,
        /// Signed distance.
        distance: f64,
        /// Speed, per second.
        speed: f64,
    },
    /// Move one axis in `direction` (+1 or −1) at `speed` until stopped, at most to the end
    /// of its travel.
    JogContinuous {
        /// The axis letter as written.
        axis: String,
        /// +1 or −1.
        direction: f64,
        /// Speed, per second.
        speed: f64,
    },
    /// Home one axis, or all (the tool axis Z first, then the others in machine order).
    Home {
        /// The axis letter, or `None` for all.
        axis: Option<String>,
    },
    /// One block of the machine's language, run from where the axes stand.
    Mdi {
        /// The block text (one line).
        block: String,
    },
}

/// Why the machine refused a request; the API answers it with a status and this sentence.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Refusal {
    /// A program (or a manual move) is running.
    #[error("the machine is running: stop it first")]
    Busy,
    /// The last run ended with a fault that was not acknowledged.
    #[error("the machine has a fault that is not acknowledged: press Reset first ({0})")]
    Faulted(String),
    /// Start without a loaded program.
    #[error("no program loaded")]
    NoProgram,
    /// The machine has no such axis.
    #[error("the machine has no axis {0:?}")]
    NoAxis(String),
    /// A jog whose end lies outside the axis's travel.
    #[error(
        "axis {axis}: the jog would end at {target:.3}, outside its travel {min:.3} … {max:.3}"
    )]
    SoftLimit {
        /// The axis.
        axis: String,
        /// Where the jog would end.
        target: f64,
        /// Travel minimum.
        min: f64,
        /// Travel maximum.
        max: f64,
    },
    /// A continuous jog from an axis already at the end of its travel in that direction.
    #[error("axis {0} stands at the end of its travel in that direction")]
    AtLimit(String),
    /// A speed that is not a positive number.
    #[error("the speed must be a positive number (mm/s or °/s), not {0}")]
    BadSpeed(f64),
    /// A distance that is zero or not a number.
    #[error("the distance must be a non-zero number, not {0}")]
    BadDistance(f64),
    /// A direction other than +1 or −1.
    #[error("the direction must be 1 or -1, not {0}")]
    BadDirection(f64),
    /// An MDI request that is not one block.
    #[error("an MDI request is one non-empty line")]
    BadBlock,
    /// A spindle request on a machine without a spindle.
    #[error("this machine has no spindle")]
    NoSpindle,
    /// A spindle speed outside the machine's spindle range.
    #[error("the spindle speed must lie above 0 and at most {max} rpm, not {speed}")]
    SpindleSpeed {
        /// The speed asked for, rpm.
        speed: f64,
        /// The machine's highest spindle speed, rpm.
        max: f64,
    },
    /// What the operation needs the machine cannot do from the dashboard.
    #[error("{0}")]
    Unsupported(String),
    /// The test run (or the start) refused the generated program.
    #[error("{0}")]
    Check(String),
    /// The generated program could not be written.
    #[error("cannot write the manual program: {0}")]
    Io(String),
}

impl Refusal {
    /// True when the refusal comes from the machine's state (answered with 409), not from
    /// the request itself (answered with 422).
    pub fn is_conflict(&self) -> bool {
        matches!(
            self,
            Refusal::Busy | Refusal::Faulted(_) | Refusal::NoProgram
        )
    }
}

/// The machine axis index of `letter` (case-insensitive), or why not.
pub fn axis_index(config: &MachineConfig, letter: &str) -> Result<usize, Refusal> {
    config
        .axes
        .iter()
        .position(|a| a.letter.to_string().eq_ignore_ascii_case(letter.trim()))
        .ok_or_else(|| Refusal::NoAxis(letter.to_string()))
}

/// True for a machine whose programs are written in lathe DIN.
pub fn is_lathe(config: &MachineConfig) -> bool {
    config.kinematics == KinematicsConfig::Lathe
}

/// The program (file name, text) that carries out a jog or an MDI block on `config` with the
/// axes at `standing` (machine order); `None` for homing, which is no program.
pub fn program_for(
    op: &ManualOp,
    config: &MachineConfig,
    standing: &[f64],
) -> Result<Option<(&'static str, String)>, Refusal> {
    let (axis, distance, speed) = match op {
        ManualOp::Home { axis } => {
            if let Some(a) = axis {
                axis_index(config, a)?;
            }
            return Ok(None);
        }
        ManualOp::Mdi { block } => return mdi_program(config, block).map(Some),
        ManualOp::Jog {
            axis,
            distance,
            speed,
        } => {
            if !distance.is_finite() || *distance == 0.0 {
                return Err(Refusal::BadDistance(*distance));
            }
            (axis, *distance, *speed)
        }
        ManualOp::JogContinuous {
            axis,
            direction,
            speed,
        } => {
            if *direction != 1.0 && *direction != -1.0 {
                return Err(Refusal::BadDirection(*direction));
            }
            let i = axis_index(config, axis)?;
            let (Some(a), Some(&at)) = (config.axes.get(i), standing.get(i)) else {
                return Err(Refusal::NoAxis(axis.clone()));
            };
            // To the end of the travel: the soft limit ends a continuous jog.
            let end = if *direction > 0.0 {
                a.travel[1]
            } else {
                a.travel[0]
            };
            let mut distance = end - at;
            if distance * direction <= 1e-6 {
                return Err(Refusal::AtLimit(a.letter.to_string()));
            }
            if is_lathe(config) && a.letter == AxisLetter::X {
                // The request's X distance is a diameter (see below).
                distance *= 2.0;
            }
            (axis, distance, *speed)
        }
    };
    if !speed.is_finite() || speed <= 0.0 {
        return Err(Refusal::BadSpeed(speed));
    }
    let i = axis_index(config, axis)?;
    let (Some(a), Some(&at)) = (config.axes.get(i), standing.get(i)) else {
        return Err(Refusal::NoAxis(axis.clone()));
    };
    // On a lathe, X is jogged as a diameter, as lathe DIN programs write it and as a turning
    // control shows it: the X axis (a radius) moves by half the distance.
    let lathe_x = is_lathe(config) && a.letter == AxisLetter::X;
    let target = at + if lathe_x { distance / 2.0 } else { distance };
    let [min, max] = a.travel;
    // A hair of rounding at the limit itself is allowed: the continuous jog ends there.
    if target < min - 1e-9 || target > max + 1e-9 {
        return Err(Refusal::SoftLimit {
            axis: a.letter.to_string(),
            target,
            min,
            max,
        });
    }
    let feed = speed * 60.0;
    if is_lathe(config) {
        // Lathe DIN: G94 (feed in mm/min, not per revolution: no spindle needed) and an
        // incremental straight line of the one axis (`Xi` a diameter, `Zi`, `Ci`, …). The
        // tool moves `speed` along the axis: for X that is half the diameter's rate, so the
        // feed of a diameter move is the axis speed itself.
        let text = format!(
            "%jog.nc\nMACHINING\nN1 G94\nN2 G1 {}i{distance:.4} F{feed:.1}\nEND\n",
            a.letter
        );
        return Ok(Some(("jog.nc", text)));
    }
    // Klartext: an incremental straight line of the one axis, feed in units per minute.
    let letter = incremental_address(a.letter);
    let text =
        format!("0 BEGIN PGM JOG MM\n1 L {letter}{distance:+.4} R0 F{feed:.1}\n2 END PGM JOG MM\n");
    Ok(Some(("jog.h", text)))
}

/// The Klartext incremental address of an axis (`IX`, `IC`, …).
fn incremental_address(letter: AxisLetter) -> String {
    format!("I{letter}")
}

/// The one-block program of the machine's language for an MDI block.
fn mdi_program(config: &MachineConfig, block: &str) -> Result<(&'static str, String), Refusal> {
    let block = block.trim();
    if block.is_empty() || block.contains(['\n', '\r']) {
        return Err(Refusal::BadBlock);
    }
    if is_lathe(config) {
        // Lathe DIN: the block in the MACHINING section.
        Ok(("mdi.nc", format!("%mdi.nc\nMACHINING\nN1 {block}\nEND\n")))
    } else {
        Ok((
            "mdi.h",
            format!("0 BEGIN PGM MDI MM\n1 {block}\n2 END PGM MDI MM\n"),
        ))
    }
}

/// Writes a generated program into `dir` (created when missing); returns its path.
pub fn write_program(dir: &Path, name: &str, text: &str) -> Result<PathBuf, Refusal> {
    std::fs::create_dir_all(dir).map_err(|e| Refusal::Io(e.to_string()))?;
    let path = dir.join(name);
    std::fs::write(&path, text).map_err(|e| Refusal::Io(e.to_string()))?;
    Ok(path)
}

/// The homing order: one axis, or the tool axis Z first and then the others in machine order.
pub fn homing_order(config: &MachineConfig, axis: Option<&str>) -> Result<Vec<usize>, Refusal> {
    if let Some(a) = axis {
        return Ok(vec![axis_index(config, a)?]);
    }
    let z = config.axes.iter().position(|a| a.letter == AxisLetter::Z);
    let mut order: Vec<usize> = z.into_iter().collect();
    order.extend((0..config.axes.len()).filter(|i| Some(*i) != z));
    Ok(order)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mill() -> MachineConfig {
        MachineConfig::builtin_mill()
    }

    #[test]
    fn a_jog_is_an_incremental_line_of_its_axis_at_its_speed() {
        let op = ManualOp::Jog {
            axis: "x".into(),
            distance: 2.5,
            speed: 20.0,
        };
        let (name, text) = program_for(&op, &mill(), &[0.0, 0.0, 100.0])
            .unwrap()
            .unwrap();
        assert_eq!(name, "jog.h");
        assert!(text.contains("\n1 L IX+2.5000 R0 F1200.0\n"), "{text}");
    }

    #[test]
    fn a_jog_past_the_travel_is_refused_and_a_continuous_one_ends_at_it() {
        // The built-in mill's Z travels -200 … 200 and stands at 100.
        let standing = [0.0, 0.0, 100.0];
        let op = ManualOp::Jog {
            axis: "Z".into(),
            distance: 100.5,
            speed: 10.0,
        };
        assert!(matches!(
            program_for(&op, &mill(), &standing),
            Err(Refusal::SoftLimit { target, .. }) if (target - 200.5).abs() < 1e-12
        ));
        let op = ManualOp::JogContinuous {
            axis: "Z".into(),
            direction: 1.0,
            speed: 10.0,
        };
        let (_, text) = program_for(&op, &mill(), &standing).unwrap().unwrap();
        assert!(text.contains("L IZ+100.0000 "), "{text}");
        let at_end = [0.0, 0.0, 200.0];
        assert_eq!(
            program_for(&op, &mill(), &at_end),
            Err(Refusal::AtLimit("Z".into()))
        );
    }

    #[test]
    fn bad_requests_are_refused_with_their_reason() {
        let standing = [0.0, 0.0, 100.0];
        let jog = |axis: &str, distance: f64, speed: f64| ManualOp::Jog {
            axis: axis.into(),
            distance,
            speed,
        };
        let m = mill();
        assert_eq!(
            program_for(&jog("Q", 1.0, 1.0), &m, &standing),
            Err(Refusal::NoAxis("Q".into()))
        );
        assert_eq!(
            program_for(&jog("X", 1.0, 0.0), &m, &standing),
            Err(Refusal::BadSpeed(0.0))
        );
        assert!(matches!(
            program_for(&jog("X", f64::NAN, 1.0), &m, &standing),
            Err(Refusal::BadDistance(_))
        ));
        let mdi = ManualOp::Mdi {
            block: "L X+1\nL X+2".into(),
        };
        assert_eq!(program_for(&mdi, &m, &standing), Err(Refusal::BadBlock));
    }

    #[test]
    fn a_lathe_jogs_x_as_a_diameter_up_to_the_radius_travel() {
        // The built-in lathe's X (a radius) travels -20 … 160 and stands at 100.
        let lathe = MachineConfig::builtin_lathe();
        let standing = [100.0, 200.0, 0.0, 0.0, 0.0];
        let op = ManualOp::Jog {
            axis: "X".into(),
            distance: -10.0,
            speed: 5.0,
        };
        let (name, text) = program_for(&op, &lathe, &standing).unwrap().unwrap();
        assert_eq!(name, "jog.nc");
        assert!(
            text.contains("\nN1 G94\nN2 G1 Xi-10.0000 F300.0\n"),
            "{text}"
        );
        // Continuous: 60 mm of radius to the end of the travel is a diameter of 120.
        let op = ManualOp::JogContinuous {
            axis: "X".into(),
            direction: 1.0,
            speed: 5.0,
        };
        let (_, text) = program_for(&op, &lathe, &standing).unwrap().unwrap();
        assert!(text.contains("G1 Xi120.0000 "), "{text}");
        // Z is not a diameter: its distance is its own.
        let op = ManualOp::JogContinuous {
            axis: "Z".into(),
            direction: -1.0,
            speed: 5.0,
        };
        let (_, text) = program_for(&op, &lathe, &standing).unwrap().unwrap();
        assert!(text.contains("G1 Zi-600.0000 "), "{text}");
    }

    #[test]
    fn homing_all_starts_with_the_tool_axis() {
        assert_eq!(homing_order(&mill(), None).unwrap(), vec![2, 0, 1]);
        assert_eq!(homing_order(&mill(), Some("y")).unwrap(), vec![1]);
    }
}
