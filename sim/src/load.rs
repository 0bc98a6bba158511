//! How a simulated spindle feels the cut: while the tool cuts a chip of cross-section `A`
//! mm², the spindle's speed sinks below the speed it is driven at by the fraction
//! `droop · A` (at most half), reached with a first-order time constant and recovered the
//! same way once the tool leaves the cut. The VFD-driven spindle model and the simulated
//! CiA 402 spindle drive both slow by this one model.

/// The speed dip of a spindle under cut.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LoadDip {
    /// Fraction of the speed lost per mm² of chip cross-section (0: no dip).
    droop: f64,
    /// Time constant of the dip, s (0: the dip follows the load at once).
    time_constant: f64,
    /// Chip cross-section under cut, mm².
    load: f64,
    /// Present dip as a fraction of the driven speed.
    dip: f64,
}

impl LoadDip {
    /// A spindle losing `droop` of its speed per mm² of chip with time constant
    /// `time_constant` s; negative or non-number parameters count as 0.
    pub fn new(droop: f64, time_constant: f64) -> Self {
        let clean = |v: f64| if v.is_finite() { v.max(0.0) } else { 0.0 };
        Self {
            droop: clean(droop),
            time_constant: clean(time_constant),
            load: 0.0,
            dip: 0.0,
        }
    }

    /// Sets the chip cross-section under cut, mm² (0 out of the cut; non-numbers and
    /// negative values count as 0).
    pub fn set_load(&mut self, section_mm2: f64) {
        self.load = if section_mm2.is_finite() {
            section_mm2.max(0.0)
        } else {
            0.0
        };
    }

    /// Moves the dip toward `droop · load` (at most 0.5) over `dt` seconds.
    pub fn advance(&mut self, dt: f64) {
        if !(dt.is_finite() && dt > 0.0) {
            return;
        }
        let goal = (self.droop * self.load).clamp(0.0, 0.5);
        let share = if self.time_constant > 0.0 {
            1.0 - (-dt / self.time_constant).exp()
        } else {
            1.0
        };
        self.dip += (goal - self.dip) * share;
    }

    /// The speed as a fraction of the driven speed: 1 − dip.
    pub fn factor(&self) -> f64 {
        1.0 - self.dip
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_dip_approaches_droop_times_section_with_its_time_constant() {
        // 0.1 per mm² × 2 mm² → 20 %; after one time constant 1 − e⁻¹ of it, after the
        // load is gone it decays by e⁻¹ per time constant.
        let mut d = LoadDip::new(0.1, 0.05);
        d.set_load(2.0);
        for _ in 0..50 {
            d.advance(0.001);
        }
        let expected = 0.2 * (1.0 - (-1.0f64).exp());
        assert!(
            (1.0 - d.factor() - expected).abs() < 1e-12,
            "{}",
            d.factor()
        );
        d.set_load(0.0);
        for _ in 0..50 {
            d.advance(0.001);
        }
        assert!((1.0 - d.factor() - expected * (-1.0f64).exp()).abs() < 1e-12);
    }

    #[test]
    fn the_dip_is_at_most_half_and_bad_input_means_no_load() {
        let mut d = LoadDip::new(0.1, 0.0);
        d.set_load(100.0);
        d.advance(0.001);
        assert_eq!(d.factor(), 0.5);
        d.set_load(f64::NAN);
        d.advance(0.001);
        assert_eq!(d.factor(), 1.0);
        let mut none = LoadDip::default();
        none.set_load(5.0);
        none.advance(1.0);
        assert_eq!(none.factor(), 1.0);
    }
}
