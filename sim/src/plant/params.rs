//! Parameters of one simulated servo axis and their validation.

use serde::Deserialize;

/// Parameters of one simulated servo axis: mechanics, controller, encoder and switches.
///
/// Positions are in mm for linear axes and degrees for rotary axes (the machine's units);
/// the mechanical quantities are SI, so a linear axis has a mass in kg, forces in N and
/// viscous friction in N/(m/s), and a rotary axis (`rotary = true`) has an inertia in kg·m²,
/// torques in N·m and viscous friction in N·m/(rad/s). The defaults describe a mid-size
/// mill axis: a 400 kg table on a ball screw, 8 kN peak force, a 150 Hz velocity loop,
/// a 0.1 µm linear scale and a 1 mm following-error window.
///
/// In a machine TOML every field is optional (missing fields take the default) and unknown
/// fields are errors.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimAxisParams {
    /// True for a rotary axis (positions in degrees, inertia/torque units), false for a
    /// linear axis (positions in mm, mass/force units).
    pub rotary: bool,
    /// Moving mass in kg (linear) or moment of inertia in kg·m² (rotary). Must be > 0.
    pub mass: f64,
    /// Viscous friction coefficient in N/(m/s) (linear) or N·m/(rad/s) (rotary). ≥ 0.
    pub viscous_friction: f64,
    /// Coulomb (dry) friction force in N or torque in N·m; also the breakaway force. ≥ 0.
    pub coulomb_friction: f64,
    /// Largest force (N) or torque (N·m) the drive can produce. Must be > 0.
    pub force_limit: f64,
    /// Position-loop gain in 1/s: commanded velocity correction per unit of following error.
    pub position_gain: f64,
    /// Velocity-loop proportional gain in N/(m/s) (linear) or N·m/(rad/s) (rotary).
    /// The default is the mass times 2π·150 Hz. Must be > 0.
    pub velocity_gain: f64,
    /// Integral time of the velocity loop in seconds; 0 switches integral action off.
    pub velocity_integral_time: f64,
    /// Velocity feed-forward gain (1 = the full commanded velocity is fed forward).
    pub velocity_feedforward: f64,
    /// Acceleration feed-forward gain (1 = mass × commanded acceleration is fed forward).
    pub acceleration_feedforward: f64,
    /// Friction feed-forward gain (1 = the nominal viscous and Coulomb friction at the
    /// commanded velocity is fed forward; 0 leaves friction to the loop).
    pub friction_feedforward: f64,
    /// Encoder resolution in counts per mm (linear) or per degree (rotary). Measured
    /// positions are whole numbers of counts. Must be > 0.
    pub counts_per_unit: f64,
    /// Integration and control substeps per servo cycle (the drive's internal loop rate is
    /// `substeps / servo period`). Must be 1..=10000.
    pub substeps: u32,
    /// Position of the negative hardware limit switch (active at and below it); `None`:
    /// no switch.
    pub limit_switch_negative: Option<f64>,
    /// Position of the positive hardware limit switch (active at and above it); `None`:
    /// no switch.
    pub limit_switch_positive: Option<f64>,
    /// Largest tolerated |following error| (mm or degrees) before the axis faults. > 0.
    pub following_error_limit: f64,
    /// Position of the home switch edge. The switch is a cam active at and above this
    /// position; homing sets the reference so that the measured position at the edge equals
    /// this value.
    pub home_switch: f64,
    /// Speed of the homing moves (mm/s or °/s). Must be > 0.
    pub homing_velocity: f64,
    /// Acceleration of the homing moves (mm/s² or °/s²). Must be > 0.
    pub homing_acceleration: f64,
    /// What the encoder reads in excess of the true position before homing (an incremental
    /// encoder counts from wherever it was powered on). Homing removes it.
    pub unreferenced_offset: f64,
    /// Simulation convenience: the axis starts referenced (homed, no offset) at power-on.
    pub start_homed: bool,
}

impl Default for SimAxisParams {
    fn default() -> Self {
        let mass = 400.0;
        Self {
            rotary: false,
            mass,
            viscous_friction: 1500.0,
            coulomb_friction: 150.0,
            force_limit: 8000.0,
            position_gain: 80.0,
            velocity_gain: mass * 2.0 * std::f64::consts::PI * 150.0,
            velocity_integral_time: 0.004,
            velocity_feedforward: 1.0,
            acceleration_feedforward: 1.0,
            friction_feedforward: 0.0,
            counts_per_unit: 10_000.0,
            substeps: 10,
            limit_switch_negative: None,
            limit_switch_positive: None,
            following_error_limit: 1.0,
            home_switch: 0.0,
            homing_velocity: 10.0,
            homing_acceleration: 500.0,
            unreferenced_offset: 0.0,
            start_homed: false,
        }
    }
}

/// Why a set of [`SimAxisParams`] cannot describe an axis.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimParamsError {
    /// A numeric parameter is outside its allowed range (or not finite).
    #[error("sim axis parameter `{name}` must be {requirement}, got {value}")]
    OutOfRange {
        /// The parameter's field name.
        name: &'static str,
        /// What the value must satisfy.
        requirement: &'static str,
        /// The value given.
        value: f64,
    },
    /// The negative limit switch is not below the positive one.
    #[error("limit switches crossed: negative {negative} is not below positive {positive}")]
    LimitsCrossed {
        /// Negative switch position.
        negative: f64,
        /// Positive switch position.
        positive: f64,
    },
    /// The home switch lies outside the travel bounded by the limit switches.
    #[error("home switch {home} lies outside the limit switches")]
    HomeOutsideTravel {
        /// Home switch position.
        home: f64,
    },
}

/// Checks `value` against a predicate, naming the parameter on failure.
fn check(
    name: &'static str,
    value: f64,
    requirement: &'static str,
    ok: impl Fn(f64) -> bool,
) -> Result<(), SimParamsError> {
    if value.is_finite() && ok(value) {
        Ok(())
    } else {
        Err(SimParamsError::OutOfRange {
            name,
            requirement,
            value,
        })
    }
}

impl SimAxisParams {
    /// SI units per machine unit: metres per mm for linear axes, radians per degree for
    /// rotary axes. Multiplying a machine-unit length, velocity or acceleration by this gives
    /// the SI quantity the mechanical parameters are expressed in.
    pub fn si_per_unit(&self) -> f64 {
        if self.rotary {
            std::f64::consts::PI / 180.0
        } else {
            1e-3
        }
    }

    /// Checks every parameter for a physically meaningful, finite value.
    pub fn validate(&self) -> Result<(), SimParamsError> {
        let positive = |v: f64| v > 0.0;
        let non_negative = |v: f64| v >= 0.0;
        let any = |_: f64| true;
        check("mass", self.mass, "finite and > 0", positive)?;
        check(
            "viscous_friction",
            self.viscous_friction,
            "finite and >= 0",
            non_negative,
        )?;
        check(
            "coulomb_friction",
            self.coulomb_friction,
            "finite and >= 0",
            non_negative,
        )?;
        check("force_limit", self.force_limit, "finite and > 0", positive)?;
        check(
            "position_gain",
            self.position_gain,
            "finite and >= 0",
            non_negative,
        )?;
        check(
            "velocity_gain",
            self.velocity_gain,
            "finite and > 0",
            positive,
        )?;
        check(
            "velocity_integral_time",
            self.velocity_integral_time,
            "finite and >= 0",
            non_negative,
        )?;
        check(
            "velocity_feedforward",
            self.velocity_feedforward,
            "finite",
            any,
        )?;
        check(
            "acceleration_feedforward",
            self.acceleration_feedforward,
            "finite",
            any,
        )?;
        check(
            "friction_feedforward",
            self.friction_feedforward,
            "finite",
            any,
        )?;
        check(
            "counts_per_unit",
            self.counts_per_unit,
            "finite, > 0 and <= 1e9",
            |v| v > 0.0 && v <= 1e9,
        )?;
        check(
            "substeps",
            f64::from(self.substeps),
            "between 1 and 10000",
            |v| (1.0..=10_000.0).contains(&v),
        )?;
        if let Some(n) = self.limit_switch_negative {
            check("limit_switch_negative", n, "finite", any)?;
        }
        if let Some(p) = self.limit_switch_positive {
            check("limit_switch_positive", p, "finite", any)?;
        }
        if let (Some(negative), Some(positive)) =
            (self.limit_switch_negative, self.limit_switch_positive)
            && negative >= positive
        {
            return Err(SimParamsError::LimitsCrossed { negative, positive });
        }
        check(
            "following_error_limit",
            self.following_error_limit,
            "finite and > 0",
            positive,
        )?;
        check("home_switch", self.home_switch, "finite", any)?;
        let home = self.home_switch;
        if self.limit_switch_negative.is_some_and(|n| home <= n)
            || self.limit_switch_positive.is_some_and(|p| home >= p)
        {
            return Err(SimParamsError::HomeOutsideTravel { home });
        }
        check(
            "homing_velocity",
            self.homing_velocity,
            "finite and > 0",
            positive,
        )?;
        check(
            "homing_acceleration",
            self.homing_acceleration,
            "finite and > 0",
            positive,
        )?;
        check(
            "unreferenced_offset",
            self.unreferenced_offset,
            "finite",
            any,
        )?;
        Ok(())
    }
}
