//! The CiA 402 power state machine: statusword decoding, controlword commands, and the
//! next command on the way to a wanted state.

/// Statusword bit: ready to switch on.
pub const SW_READY: u16 = 1 << 0;
/// Statusword bit: switched on.
pub const SW_SWITCHED_ON: u16 = 1 << 1;
/// Statusword bit: operation enabled.
pub const SW_OPERATION_ENABLED: u16 = 1 << 2;
/// Statusword bit: fault.
pub const SW_FAULT: u16 = 1 << 3;
/// Statusword bit: voltage enabled.
pub const SW_VOLTAGE_ENABLED: u16 = 1 << 4;
/// Statusword bit: quick stop (active low: 0 means a quick stop is in progress).
pub const SW_QUICK_STOP: u16 = 1 << 5;
/// Statusword bit: switch on disabled.
pub const SW_SWITCH_ON_DISABLED: u16 = 1 << 6;
/// Statusword bit: warning.
pub const SW_WARNING: u16 = 1 << 7;
/// Statusword bit: remote (controlword is obeyed).
pub const SW_REMOTE: u16 = 1 << 9;
/// Statusword bit: target reached.
pub const SW_TARGET_REACHED: u16 = 1 << 10;
/// Statusword bit: internal limit active.
pub const SW_INTERNAL_LIMIT: u16 = 1 << 11;
/// Statusword bit 12, mode specific: CSP "drive follows the target", homing "attained",
/// profile position "set-point acknowledge".
pub const SW_OMS1: u16 = 1 << 12;
/// Statusword bit 13, mode specific: CSP/PP "following error", homing "homing error".
pub const SW_OMS2: u16 = 1 << 13;

/// Controlword: shutdown (→ ready to switch on).
pub const CW_SHUTDOWN: u16 = 0x0006;
/// Controlword: switch on (→ switched on).
pub const CW_SWITCH_ON: u16 = 0x0007;
/// Controlword: enable operation (→ operation enabled).
pub const CW_ENABLE_OPERATION: u16 = 0x000F;
/// Controlword: disable voltage (→ switch on disabled).
pub const CW_DISABLE_VOLTAGE: u16 = 0x0000;
/// Controlword: quick stop (→ quick stop active).
pub const CW_QUICK_STOP: u16 = 0x0002;
/// Controlword bit 7: fault reset (on its rising edge).
pub const CW_FAULT_RESET: u16 = 0x0080;
/// Controlword bit 4, mode specific: homing "start" (on its rising edge).
pub const CW_HOMING_START: u16 = 0x0010;
/// Controlword bit 4 in profile position mode: "new set-point" (on its rising edge).
pub const CW_NEW_SETPOINT: u16 = 0x0010;
/// Controlword bit 5 in profile position mode: "change set immediately".
pub const CW_CHANGE_IMMEDIATELY: u16 = 0x0020;

/// True when the controlword's command bits (0–3, 7) say "enable operation", whatever the
/// mode-specific bits.
pub fn is_enable_operation(controlword: u16) -> bool {
    controlword & 0x008F == CW_ENABLE_OPERATION
}

/// The states of the CiA 402 power state machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PowerState {
    /// Initialising; the controlword is not yet obeyed.
    NotReadyToSwitchOn,
    /// No power; waits for shutdown.
    SwitchOnDisabled,
    /// Ready; waits for switch on.
    ReadyToSwitchOn,
    /// Power stage on, not following commands.
    SwitchedOn,
    /// Following commands.
    OperationEnabled,
    /// Braking with the quick stop ramp, or holding after it.
    QuickStopActive,
    /// Reacting to a fault (braking).
    FaultReactionActive,
    /// Faulted; waits for fault reset.
    Fault,
}

impl PowerState {
    /// Decodes the state from a statusword (bits 0–3, 5, 6).
    pub fn from_statusword(sw: u16) -> Self {
        if sw & 0x004F == 0x0000 {
            PowerState::NotReadyToSwitchOn
        } else if sw & 0x004F == 0x0040 {
            PowerState::SwitchOnDisabled
        } else if sw & 0x004F == 0x000F {
            PowerState::FaultReactionActive
        } else if sw & 0x004F == 0x0008 {
            PowerState::Fault
        } else {
            match sw & 0x006F {
                0x0021 => PowerState::ReadyToSwitchOn,
                0x0023 => PowerState::SwitchedOn,
                0x0027 => PowerState::OperationEnabled,
                0x0007 => PowerState::QuickStopActive,
                // Bit combinations the profile does not define: treat as not ready.
                _ => PowerState::NotReadyToSwitchOn,
            }
        }
    }

    /// The statusword bits (0–3, 5, 6) that show this state; the other bits are zero.
    pub fn statusword_bits(self) -> u16 {
        match self {
            PowerState::NotReadyToSwitchOn => 0x0000,
            PowerState::SwitchOnDisabled => 0x0040,
            PowerState::ReadyToSwitchOn => 0x0021,
            PowerState::SwitchedOn => 0x0023,
            PowerState::OperationEnabled => 0x0027,
            PowerState::QuickStopActive => 0x0007,
            PowerState::FaultReactionActive => 0x000F,
            PowerState::Fault => 0x0008,
        }
    }

    /// True in the two fault states.
    pub fn is_fault(self) -> bool {
        matches!(self, PowerState::Fault | PowerState::FaultReactionActive)
    }
}

/// The controlword that moves a drive in `current` one step towards operation enabled;
/// `None` when it is there, or cannot get there without a fault reset.
pub fn step_towards_enabled(current: PowerState) -> Option<u16> {
    match current {
        PowerState::SwitchOnDisabled => Some(CW_SHUTDOWN),
        PowerState::ReadyToSwitchOn => Some(CW_SWITCH_ON),
        PowerState::SwitchedOn => Some(CW_ENABLE_OPERATION),
        PowerState::QuickStopActive => Some(CW_DISABLE_VOLTAGE),
        PowerState::NotReadyToSwitchOn => Some(CW_DISABLE_VOLTAGE),
        PowerState::OperationEnabled | PowerState::Fault | PowerState::FaultReactionActive => None,
    }
}

/// The state a drive in `current` enters on `controlword` (a device-side reading of the
/// CiA 402 transition table; fault transitions come from the device itself).
pub fn transition(current: PowerState, controlword: u16, fault_reset_edge: bool) -> PowerState {
    use PowerState::*;
    let cw = controlword & 0x008F;
    // Command patterns (bits 7, 3, 2, 1, 0): x = don't care.
    let disable_voltage = cw & 0x0002 == 0; // xxx0x
    let quick_stop = cw & 0x0006 == 0x0002; // xx01x
    let shutdown = cw & 0x0087 == 0x0006; // 0x110
    let switch_on = cw & 0x008F == 0x0007; // 00111
    let enable = cw & 0x008F == 0x000F; // 01111
    let disable_op = cw & 0x008F == 0x0007;
    match current {
        NotReadyToSwitchOn => SwitchOnDisabled,
        SwitchOnDisabled if shutdown => ReadyToSwitchOn,
        ReadyToSwitchOn if switch_on => SwitchedOn,
        ReadyToSwitchOn if enable => OperationEnabled,
        ReadyToSwitchOn if disable_voltage || quick_stop => SwitchOnDisabled,
        SwitchedOn if enable => OperationEnabled,
        SwitchedOn if shutdown => ReadyToSwitchOn,
        SwitchedOn if disable_voltage || quick_stop => SwitchOnDisabled,
        OperationEnabled if disable_op => SwitchedOn,
        OperationEnabled if shutdown => ReadyToSwitchOn,
        OperationEnabled if disable_voltage => SwitchOnDisabled,
        OperationEnabled if quick_stop => QuickStopActive,
        QuickStopActive if disable_voltage => SwitchOnDisabled,
        FaultReactionActive => Fault,
        Fault if fault_reset_edge => SwitchOnDisabled,
        s => s,
    }
}
