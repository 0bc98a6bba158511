//! Consistency checks of a parsed machine file beyond its syntax: positive and finite values,
//! axes and backends that fit together, machine functions that do not clash with klar's own.
//! The physical ranges of single values are in [`super::ranges`].

use super::*;

impl MachineConfig {
    pub(super) fn validate(&self) -> Result<(), String> {
        let positive = |what: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(format!("{what} must be a positive number, got {v}"))
            }
        };
        positive("servo_period", self.servo_period)?;
        if self.servo_period > 0.1 {
            return Err(format!(
                "servo_period {} s is longer than 0.1 s",
                self.servo_period
            ));
        }
        positive("tolerance", self.tolerance)?;
        self.validate_probe()?;
        if self.axes.is_empty() {
            return Err("a machine needs at least one [[axis]]".into());
        }
        if self.kinematics == KinematicsConfig::TableTable {
            let has = |l: AxisLetter| self.axes.iter().any(|a| a.letter == l);
            let tilts = usize::from(has(AxisLetter::A)) + usize::from(has(AxisLetter::B));
            if !has(AxisLetter::C) || tilts != 1 {
                return Err("kinematics table_table needs a C axis and one of A or B".into());
            }
            let pivots = self.table_table.tilt_pivot.iter();
            if pivots
                .chain(&self.table_table.table_pivot)
                .any(|v| !v.is_finite())
            {
                return Err("table_table pivots must be finite numbers".into());
            }
        }
        for (i, a) in self.axes.iter().enumerate() {
            let l = a.letter;
            if self.axes[..i].iter().any(|b| b.letter == l) {
                return Err(format!("axis {l} is defined twice"));
            }
            if a.letter.is_rotary() != (a.kind == AxisKind::Rotary) {
                return Err(format!(
                    "axis {l}: kind {:?} does not fit the letter (A, B, C are rotary)",
                    a.kind
                ));
            }
            positive(&format!("axis {l}: max_velocity"), a.max_velocity)?;
            positive(&format!("axis {l}: max_acceleration"), a.max_acceleration)?;
            positive(&format!("axis {l}: max_jerk"), a.max_jerk)?;
            let [lo, hi] = a.travel;
            if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                return Err(format!("axis {l}: travel [{lo}, {hi}] must have min < max"));
            }
            match &a.backend {
                BackendConfig::Canopen(c) if !self.canopen.contains_key(&c.bus) => {
                    return Err(format!("axis {l}: no [canopen.{}] bus", c.bus));
                }
                BackendConfig::Canopen(c) => {
                    positive(&format!("axis {l}: in_position"), c.in_position)?;
                    positive(&format!("axis {l}: settle_timeout"), c.settle_timeout)?;
                }
                BackendConfig::Modbus(m) => {
                    positive(&format!("axis {l}: in_position"), m.in_position)?;
                    positive(&format!("axis {l}: settle_timeout"), m.settle_timeout)?;
                }
                BackendConfig::Stepdir(_) if a.start != 0.0 => {
                    return Err(format!(
                        "axis {l}: a step/dir axis counts from 0 at power-up; start must be 0"
                    ));
                }
                _ => {}
            }
            if let Some(fe) = a.following_error_limit {
                positive(&format!("axis {l}: following_error_limit"), fe)?;
            }
            if !(a.start >= lo && a.start <= hi) {
                return Err(format!(
                    "axis {l}: start {} is outside travel [{lo}, {hi}]",
                    a.start
                ));
            }
        }
        ranges::check(self)?;
        for f in &self.faults {
            if !(f.at.is_finite() && f.at >= 0.0) {
                return Err(format!("fault {:?}: at must be seconds >= 0", f.kind));
            }
            match f.axis {
                Some(l) if !self.axes.iter().any(|a| a.letter == l) => {
                    return Err(format!("fault {:?}: no axis {l} on this machine", f.kind));
                }
                None if !matches!(
                    f.kind,
                    crate::faults::FaultKind::Estop
                        | crate::faults::FaultKind::Stall
                        | crate::faults::FaultKind::Spindle
                ) =>
                {
                    return Err(format!("fault {:?} at {} s needs an axis", f.kind, f.at));
                }
                _ => {}
            }
            if f.kind == crate::faults::FaultKind::Spindle
                && !matches!(
                    self.spindle.as_ref().map(|s| &s.backend),
                    Some(SpindleBackendConfig::Sim(_))
                )
            {
                return Err(format!(
                    "fault {:?} at {} s needs a simulated spindle",
                    f.kind, f.at
                ));
            }
            if let Some(d) = f.duration
                && !(d.is_finite() && d > 0.0)
            {
                return Err(format!("fault {:?}: duration must be seconds > 0", f.kind));
            }
        }
        self.validate_m_functions()?;
        if let Some(l) = self.max_setpoint_lateness
            && !(l.is_finite() && l >= self.servo_period)
        {
            return Err(format!(
                "max_setpoint_lateness {l} must be at least one servo period ({} s)",
                self.servo_period
            ));
        }
        if let Some(s) = &self.spindle {
            positive("spindle.max_rpm", s.max_rpm)?;
            positive("spindle.at_speed_timeout", s.at_speed_timeout)?;
            let sim = match &s.backend {
                SpindleBackendConfig::Sim(sim) => Some(sim),
                SpindleBackendConfig::Canopen(c) => {
                    if !self.canopen.contains_key(&c.bus) {
                        return Err(format!("spindle: no [canopen.{}] bus", c.bus));
                    }
                    if !(c.load_droop.is_finite() && c.load_droop >= 0.0) {
                        return Err(format!(
                            "spindle load_droop {} must be a number ≥ 0",
                            c.load_droop
                        ));
                    }
                    positive("spindle load_time_constant", c.load_time_constant)?;
                    None
                }
                SpindleBackendConfig::Modbus(m) => {
                    if m.vfd.max_rpm < s.max_rpm {
                        return Err(format!(
                            "spindle.max_rpm {} is above the VFD's max_rpm {}",
                            s.max_rpm, m.vfd.max_rpm
                        ));
                    }
                    m.simulate.as_ref()
                }
            };
            if let Some(sim) = sim {
                positive("spindle simulation acceleration", sim.acceleration)?;
                positive(
                    "spindle simulation at_speed_fraction",
                    sim.at_speed_fraction,
                )?;
                if sim.encoder_counts == 0 {
                    return Err("spindle simulation encoder_counts must be at least 1".into());
                }
                if !(sim.load_droop.is_finite() && sim.load_droop >= 0.0) {
                    return Err(format!(
                        "spindle simulation load_droop {} must be a number ≥ 0",
                        sim.load_droop
                    ));
                }
                positive(
                    "spindle simulation load_time_constant",
                    sim.load_time_constant,
                )?;
            }
        }
        Ok(())
    }

    fn validate_m_functions(&self) -> Result<(), String> {
        for (i, m) in self.m_functions.iter().enumerate() {
            let n = m.number;
            if !(0..=i64::from(MAX_MACHINE_FUNCTION)).contains(&n) {
                return Err(format!(
                    "m_function M{n}: the number must lie in 0..={MAX_MACHINE_FUNCTION}"
                ));
            }
            if BUILT_IN_M_NUMBERS.iter().any(|&b| i64::from(b) == n) {
                return Err(format!(
                    "m_function M{n}: klar defines M{n} itself; a machine function needs \
                     another number"
                ));
            }
            if self.m_functions[..i].iter().any(|o| o.number == n) {
                return Err(format!("m_function M{n} is defined twice"));
            }
            if !(m.wait.is_finite() && m.wait >= 0.0) {
                return Err(format!(
                    "m_function M{n}: wait must be seconds >= 0, got {}",
                    m.wait
                ));
            }
        }
        Ok(())
    }

    /// Things in a valid machine file that a user should hear about before a run: today a
    /// device given a real port while `simulate` is still set (klar then talks to the
    /// simulation on a pseudo-terminal, not to the port).
    pub fn notices(&self) -> Vec<String> {
        let real = |port: &str| port != "simulated";
        let mut out = Vec::new();
        for a in &self.axes {
            if let BackendConfig::Modbus(m) = &a.backend
                && m.simulate.is_some()
                && real(&m.servo.serial.port)
            {
                out.push(format!(
                    "axis {}: `simulate` is set, so the drive is simulated: klar does not use \
                     port {} (remove `simulate` to drive the device)",
                    a.letter, m.servo.serial.port
                ));
            }
        }
        if let Some(SpindleBackendConfig::Modbus(m)) = self.spindle.as_ref().map(|s| &s.backend)
            && m.simulate.is_some()
            && real(&m.vfd.serial.port)
        {
            out.push(format!(
                "spindle: `simulate` is set, so the VFD is simulated: klar does not use port {} \
                 (remove `simulate` to drive the device)",
                m.vfd.serial.port
            ));
        }
        out
    }
}
