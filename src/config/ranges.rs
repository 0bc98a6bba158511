//! Physical ranges of machine values: a machine file whose numbers lie outside them is
//! refused with the key, the value and the range, so that the planner never receives limits
//! it cannot plan with (a move at 1e-300 mm/s² would take longer than any run, a servo period
//! of 1 ns asks for more samples than a control computes). docs/machine-toml.md lists them.

use super::{KinematicsConfig, MachineConfig};
use klar_motion::config::{
    ACCELERATION_RANGE, JERK_RANGE, MAX_TOLERANCE, PERIOD_RANGE, VELOCITY_RANGE, within,
};

/// Largest distance of a table-table pivot point from the machine origin, mm.
pub const MAX_PIVOT: f64 = 10_000.0;

/// Largest travel end (either sign), mm or degrees.
pub const MAX_TRAVEL: f64 = 1_000_000.0;

/// Highest spindle speed, rpm.
pub const MAX_SPINDLE_RPM: f64 = 200_000.0;

/// A number as people write it: plain within 0.001 … 10 000 000, else with an exponent.
fn num(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-3..=1e7).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Checks every range; the first value outside its range is the error, naming its key.
pub(super) fn check(config: &MachineConfig) -> Result<(), String> {
    let range = |key: &str, v: f64, r: [f64; 2], unit: &str| {
        if within(v, r) {
            Ok(())
        } else {
            Err(format!(
                "{key} = {} is outside the range {} … {} {unit} klar plans with",
                num(v),
                num(r[0]),
                num(r[1])
            ))
        }
    };
    range("servo_period", config.servo_period, PERIOD_RANGE, "s")?;
    range("tolerance", config.tolerance, [0.0, MAX_TOLERANCE], "mm")?;
    for a in &config.axes {
        let l = a.letter;
        let unit = if l.is_rotary() { "°" } else { "mm" };
        let key = |k: &str| format!("axis {l}: {k}");
        range(
            &key("max_velocity"),
            a.max_velocity,
            VELOCITY_RANGE,
            &format!("{unit}/s"),
        )?;
        range(
            &key("max_acceleration"),
            a.max_acceleration,
            ACCELERATION_RANGE,
            &format!("{unit}/s²"),
        )?;
        range(
            &key("max_jerk"),
            a.max_jerk,
            JERK_RANGE,
            &format!("{unit}/s³"),
        )?;
        for (k, v) in [("travel", a.travel[0]), ("travel", a.travel[1])] {
            range(&key(k), v, [-MAX_TRAVEL, MAX_TRAVEL], unit)?;
        }
    }
    if config.kinematics == KinematicsConfig::TableTable {
        let tt = &config.table_table;
        for (key, p) in [
            ("table_table.tilt_pivot", tt.tilt_pivot),
            ("table_table.table_pivot", tt.table_pivot),
        ] {
            for v in p {
                range(key, v, [-MAX_PIVOT, MAX_PIVOT], "mm")?;
            }
        }
    }
    if let Some(s) = &config.spindle {
        range("spindle.max_rpm", s.max_rpm, [0.0, MAX_SPINDLE_RPM], "rpm")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with(edit: &str, from: &str) -> Result<MachineConfig, String> {
        let text = super::super::BUILTIN_MILL.replacen(from, edit, 1);
        assert_ne!(text, super::super::BUILTIN_MILL, "{from} not found");
        MachineConfig::parse("m.toml", &text).map_err(|e| e.to_string())
    }

    #[test]
    fn values_outside_their_range_name_the_key_and_the_range() {
        let e = with("max_acceleration = 1e-300", "max_acceleration = 2000.0").unwrap_err();
        assert_eq!(
            e,
            "m.toml:14:1: axis X: max_acceleration = 1e-300 is outside the range 0.1 … 10000000 \
             mm/s² klar plans with"
        );
        let e = with("max_velocity = 1e-300", "max_velocity = 166.0").unwrap_err();
        assert!(
            e.contains("axis X: max_velocity = 1e-300 is outside the range 0.01 … 100000 mm/s"),
            "{e}"
        );
        let e = with("servo_period = 1e-9", "servo_period = 0.001").unwrap_err();
        assert!(
            e.contains("servo_period = 1e-9 is outside the range 5e-5 … 0.1 s"),
            "{e}"
        );
        let e = with("max_jerk = 1e300", "max_jerk = 50000.0").unwrap_err();
        assert!(e.contains("axis X: max_jerk = 1e300"), "{e}");
        let e = with("travel = [-3e6, 300.0]", "travel = [-300.0, 300.0]").unwrap_err();
        assert!(e.contains("axis X: travel = -3000000 is outside"), "{e}");
        // the ends of a range are accepted
        assert!(with("max_velocity = 0.01", "max_velocity = 166.0").is_ok());
        assert!(with("servo_period = 0.00005", "servo_period = 0.001").is_ok());
    }

    #[test]
    fn a_table_table_pivot_beyond_ten_metres_is_refused() {
        let text = super::super::BUILTIN_MILL5.to_string();
        let at = text
            .find("tilt_pivot")
            .expect("the 5-axis mill has a tilt pivot");
        let line_end = at + text[at..].find('\n').unwrap_or(text.len() - at);
        let edited = format!(
            "{}tilt_pivot = [0.0, 0.0, -1e12]{}",
            &text[..at],
            &text[line_end..]
        );
        let e = MachineConfig::parse("m5.toml", &edited)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("table_table.tilt_pivot = -1e12 is outside the range -10000 … 10000 mm"),
            "{e}"
        );
    }
}
