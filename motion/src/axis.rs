//! The axis boundary: what every backend (simulated axes, CANopen drives, Modbus drives,
//! step/dir outputs) implements, and what the runtime calls once per servo cycle.
//!
//! A backend serves one or more machine axes, indexed `0..axis_count()` in the order the
//! runtime assigned them. The runtime never plans inside [`AxisBackend::cycle`]: it hands
//! over one [`Setpoint`] per axis and reads one [`AxisFeedback`] per axis back.

use std::fmt;

/// The commanded state of one axis for one servo cycle (machine units: mm or degrees).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Setpoint {
    /// Commanded position.
    pub position: f64,
    /// Commanded velocity (units/s), for velocity feed-forward.
    pub velocity: f64,
    /// Commanded acceleration (units/s²), for acceleration feed-forward.
    pub acceleration: f64,
}

/// The power/operating state an axis reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AxisState {
    /// Not powered; does not follow setpoints.
    #[default]
    Disabled,
    /// Powered and following setpoints.
    Enabled,
    /// Running its homing sequence.
    Homing,
    /// Stopped by a fault; needs [`AxisBackend::reset_fault`].
    Faulted,
}

/// A fault reported by an axis.
#[derive(Debug, Clone, PartialEq)]
pub enum AxisFault {
    /// Following error beyond the configured window (mm or degrees).
    FollowingError(f64),
    /// A hardware limit switch was hit (true: positive end).
    LimitSwitch {
        /// True for the positive end of travel.
        positive: bool,
    },
    /// The drive reported a fault with a code (e.g. a CiA 402 / EMCY error code).
    Drive {
        /// Vendor or profile error code.
        code: u32,
        /// Human-readable description.
        text: String,
    },
    /// The emergency stop chain is open.
    EStop,
    /// Communication with the drive was lost.
    CommunicationLost,
    /// The device answered a request with an exception: it is there and talking, but
    /// refused what it was asked (a Modbus exception response, e.g. 02 illegal data
    /// address or 04 server device failure).
    DeviceException {
        /// The exception code the device sent.
        code: u8,
        /// What the code means, as the protocol defines it.
        meaning: &'static str,
    },
}

impl fmt::Display for AxisFault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AxisFault::FollowingError(e) => write!(f, "following error {e:.4} beyond limit"),
            AxisFault::LimitSwitch { positive: true } => write!(f, "positive limit switch"),
            AxisFault::LimitSwitch { positive: false } => write!(f, "negative limit switch"),
            AxisFault::Drive { code, text } => write!(f, "drive fault 0x{code:04X}: {text}"),
            AxisFault::EStop => write!(f, "emergency stop"),
            AxisFault::CommunicationLost => write!(f, "communication lost"),
            AxisFault::DeviceException { code, meaning } => {
                write!(f, "device exception 0x{code:02X} ({meaning})")
            }
        }
    }
}

/// What one axis reports back each cycle.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct AxisFeedback {
    /// Measured position (after encoder quantisation), mm or degrees.
    pub position: f64,
    /// Commanded minus measured position.
    pub following_error: f64,
    /// Operating state.
    pub state: AxisState,
    /// True once the axis has a valid reference.
    pub homed: bool,
    /// The active fault, if any.
    pub fault: Option<AxisFault>,
}

/// A failure of the backend itself (not of an axis): transport errors, bad arguments.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BackendError {
    /// The axis index is not served by this backend.
    #[error("axis index {0} is not served by this backend")]
    NoSuchAxis(usize),
    /// Setpoint/feedback slices do not match the number of axes.
    #[error("expected {expected} axes, got {got}")]
    AxisCount {
        /// Axes served.
        expected: usize,
        /// Slice length given.
        got: usize,
    },
    /// Transport failure (bus, serial line) with a description.
    #[error("communication: {0}")]
    Communication(String),
    /// The backend refused the request in its current state.
    #[error("not possible now: {0}")]
    InvalidState(String),
}

/// A backend driving one or more machine axes.
pub trait AxisBackend {
    /// Number of axes served.
    fn axis_count(&self) -> usize;

    /// Powers all axes so they follow setpoints.
    fn enable(&mut self) -> Result<(), BackendError>;

    /// Removes power from all axes (after a controlled stop).
    fn disable(&mut self) -> Result<(), BackendError>;

    /// Starts the homing sequence of one axis; progress shows in [`AxisFeedback::state`]
    /// and [`AxisFeedback::homed`].
    fn start_homing(&mut self, axis: usize) -> Result<(), BackendError>;

    /// Clears the fault of one axis if its cause is gone.
    fn reset_fault(&mut self, axis: usize) -> Result<(), BackendError>;

    /// One servo cycle at time `t` (seconds since start): hand over `setpoints`
    /// (one per axis) and fill `feedback` (one per axis).
    fn cycle(
        &mut self,
        t: f64,
        setpoints: &[Setpoint],
        feedback: &mut [AxisFeedback],
    ) -> Result<(), BackendError>;

    /// Where the fault `axis` reports comes from, when the backend knows more than the
    /// [`AxisFault`] says (the device and the cause). `None`: nothing more to say.
    fn fault_origin(&self, _axis: usize) -> Option<FaultOrigin> {
        None
    }

    /// How many servo cycles the feedback of [`AxisBackend::cycle`] lags behind the
    /// setpoints handed over with it (1 for a bus exchange that uses the answers to the SYNC
    /// before); following errors compare the feedback with the setpoints that many cycles
    /// back.
    fn feedback_lag(&self) -> u32 {
        0
    }

    /// Arms the touch-probe latch of `axis`: the next time the probe input switches on, the
    /// drive stores the position it measures at that instant. Returns false when the axis
    /// has no such latch (the default).
    fn arm_touch_probe(&mut self, _axis: usize) -> Result<bool, BackendError> {
        Ok(false)
    }

    /// The position `axis` latched since its touch probe was armed, once it has one.
    fn touch_probe_position(&mut self, _axis: usize) -> Result<Option<f64>, BackendError> {
        Ok(None)
    }

    /// Switches the touch-probe latch of `axis` off.
    fn disarm_touch_probe(&mut self, _axis: usize) -> Result<(), BackendError> {
        Ok(())
    }
}

/// The origin of an axis's fault as the backend knows it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FaultOrigin {
    /// True when the axis's own device faulted; false when the axis was only stopped
    /// because another device on the same link faulted.
    pub primary: bool,
    /// The device and the cause in words, e.g. `node 1: heartbeat lost (silent for 0.5 s)`.
    pub detail: String,
}

/// What a spindle reports back.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SpindleFeedback {
    /// Measured speed in rpm, signed: positive clockwise (M3), negative counter-clockwise (M4).
    pub rpm: f64,
    /// True when the measured speed is within the at-speed window of the command.
    pub at_speed: bool,
    /// The active fault, if any.
    pub fault: Option<AxisFault>,
    /// Measured spindle angle in degrees, unwrapped (it keeps counting past 360°, positive
    /// clockwise like `rpm`), with 0 at the encoder's index; `None` when the device does not
    /// measure the spindle's position (a VFD), so nothing can be synchronised to it.
    pub position: Option<f64>,
}

/// A spindle drive (simulated, Modbus VFD, or a CiA 402 drive in velocity mode).
pub trait SpindleBackend {
    /// Commands a signed speed in rpm: positive clockwise (M3), negative counter-clockwise
    /// (M4), zero stops (M5).
    fn command(&mut self, rpm: f64) -> Result<(), BackendError>;

    /// Advances by one servo cycle at time `t` and reports the spindle's state.
    fn cycle(&mut self, t: f64) -> Result<SpindleFeedback, BackendError>;

    /// Commands the spindle to stop and, where the device can say so, waits (bounded) until
    /// it confirms: the stop command acknowledged and the device no longer driving the
    /// spindle. An error means the stop is not confirmed and the spindle may still turn.
    /// The default commands 0 rpm: for backends whose speed follows from their own cycle
    /// (simulated spindles, drives disabled with their bus).
    fn stop_confirmed(&mut self) -> Result<(), BackendError> {
        self.command(0.0)
    }

    /// Details of the present fault beyond [`AxisFault`] (e.g. the failed request), if the
    /// backend knows them.
    fn fault_detail(&self) -> Option<String> {
        None
    }

    /// Tells the spindle the chip cross-section (mm²) the tool cuts from now on, 0 when it
    /// leaves the cut. Only a simulated spindle uses it (its speed dips under load); real
    /// drives feel the load themselves. The default ignores it.
    fn set_load(&mut self, _section_mm2: f64) {}
}
