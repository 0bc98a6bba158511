//! CiA 402 state machine, scaling, interpolation period, bus load and configuration,
//! checked against the profile's tables and closed-form numbers.

use klar_drivers::canopen::busload::{self, CyclicTraffic};
use klar_drivers::cia402::cyclic_traffic;
use klar_drivers::cia402::objects::interpolation_period;
use klar_drivers::cia402::scaling::Scaling;
use klar_drivers::cia402::state::*;
use klar_drivers::cia402::{BusConfig, CanOpenConfig, PowerState};

#[test]
fn statusword_decodes_per_the_profile_table() {
    use PowerState::*;
    // Other bits (voltage enabled, remote, target reached, warning) must not matter.
    let table = [
        (0x0000, NotReadyToSwitchOn),
        (0x0250, SwitchOnDisabled),
        (0x0040, SwitchOnDisabled),
        (0x0231, ReadyToSwitchOn),
        (0x0233, SwitchedOn),
        (0x1637, OperationEnabled),
        (0x0617, QuickStopActive),
        (0x021F, FaultReactionActive),
        (0x0218, Fault),
        (0x0208, Fault),
    ];
    for (sw, state) in table {
        assert_eq!(
            PowerState::from_statusword(sw),
            state,
            "statusword 0x{sw:04X}"
        );
    }
    for state in [
        NotReadyToSwitchOn,
        SwitchOnDisabled,
        ReadyToSwitchOn,
        SwitchedOn,
        OperationEnabled,
        QuickStopActive,
        FaultReactionActive,
        Fault,
    ] {
        assert_eq!(
            PowerState::from_statusword(state.statusword_bits() | 0x0610),
            state
        );
    }
}

#[test]
fn enabling_takes_shutdown_switch_on_enable() {
    let mut state = PowerState::SwitchOnDisabled;
    let mut commands = Vec::new();
    while let Some(cw) = step_towards_enabled(state) {
        commands.push(cw);
        state = transition(state, cw, false);
        assert!(commands.len() < 5);
    }
    assert_eq!(commands, vec![0x0006, 0x0007, 0x000F]);
    assert_eq!(state, PowerState::OperationEnabled);
    // From quick stop the way back goes through switch-on disabled.
    assert_eq!(
        step_towards_enabled(PowerState::QuickStopActive),
        Some(0x0000)
    );
    assert_eq!(step_towards_enabled(PowerState::Fault), None);
}

#[test]
fn device_transitions_follow_the_table() {
    use PowerState::*;
    assert_eq!(transition(OperationEnabled, 0x0002, false), QuickStopActive);
    assert_eq!(transition(OperationEnabled, 0x0007, false), SwitchedOn);
    assert_eq!(transition(OperationEnabled, 0x0006, false), ReadyToSwitchOn);
    assert_eq!(
        transition(OperationEnabled, 0x0000, false),
        SwitchOnDisabled
    );
    assert_eq!(
        transition(OperationEnabled, 0x001F, false),
        OperationEnabled,
        "bit 4 is mode specific"
    );
    assert_eq!(
        transition(SwitchOnDisabled, 0x000F, false),
        SwitchOnDisabled,
        "no skipping"
    );
    assert_eq!(
        transition(ReadyToSwitchOn, 0x000F, false),
        OperationEnabled,
        "3 + 4 at once is allowed"
    );
    assert_eq!(transition(QuickStopActive, 0x0000, false), SwitchOnDisabled);
    assert_eq!(transition(Fault, 0x0080, true), SwitchOnDisabled);
    assert_eq!(
        transition(Fault, 0x0080, false),
        Fault,
        "only the rising edge resets"
    );
    assert_eq!(transition(FaultReactionActive, 0x000F, false), Fault);
}

#[test]
fn scaling_converts_and_refuses_nonsense() {
    let s = Scaling::new(10_000.0, false).expect("valid");
    assert_eq!(s.to_counts(1.23456), Ok(12_346));
    assert_eq!(s.to_counts(-0.00004), Ok(0));
    assert_eq!(s.to_units(-25_000), -2.5);
    let inv = Scaling::new(8192.0 / 5.0, true).expect("valid");
    assert_eq!(inv.to_counts(5.0), Ok(-8192));
    assert_eq!(inv.to_units(-8192), 5.0);
    assert!(s.to_counts(1e6).is_err(), "10^10 counts do not fit 32 bits");
    assert!(s.to_counts(f64::NAN).is_err());
    assert!(Scaling::new(0.0, false).is_err());
    assert!(Scaling::new(f64::INFINITY, false).is_err());
    assert_eq!(s.magnitude_counts(-12.5), 125_000);
}

#[test]
fn interpolation_period_picks_the_coarsest_exact_unit() {
    assert_eq!(interpolation_period(0.001), Some((1, -3)));
    assert_eq!(interpolation_period(0.004), Some((4, -3)));
    assert_eq!(interpolation_period(0.0005), Some((5, -4)));
    assert_eq!(interpolation_period(0.000_25), Some((25, -5)));
    assert_eq!(interpolation_period(0.3), Some((3, -1)));
    assert_eq!(interpolation_period(0.25), Some((25, -2)));
    assert_eq!(interpolation_period(0.000_000_5), None);
    assert_eq!(interpolation_period(100.0), None);
}

#[test]
fn bus_load_matches_the_worst_case_bit_count() {
    // Worst case with stuffing: 0-byte frame 47 + ⌊33/4⌋ = 55 bits; 6-byte frame
    // 47 + 48 + ⌊81/4⌋ = 115 bits; 8-byte frame 47 + 64 + ⌊97/4⌋ = 135 bits.
    assert_eq!(
        CyclicTraffic {
            frame_lengths: vec![0]
        }
        .bits_per_period(),
        55
    );
    assert_eq!(
        CyclicTraffic {
            frame_lengths: vec![6]
        }
        .bits_per_period(),
        115
    );
    assert_eq!(
        CyclicTraffic {
            frame_lengths: vec![8]
        }
        .bits_per_period(),
        135
    );
    let three = cyclic_traffic(3);
    assert_eq!(three.bits_per_period(), 55 + 6 * 115);
    let load = busload::check(&three, 1_000_000, 0.001).expect("fits");
    assert!((load - 0.745).abs() < 1e-12);
    let err = busload::check(&three, 500_000, 0.001).expect_err("too much");
    assert!((err.load_percent - 149.0).abs() < 1e-9);
    // 745 bits at 80 % of 500 kbit/s need 1.8625 ms: 2 ms is the next 0.25 ms step.
    assert_eq!(err.fitting_ms, 2.0);
    assert!(busload::check(&three, 500_000, 0.002).is_ok());
}

#[test]
fn configuration_parses_with_defaults_and_rejects_unknown_keys() {
    let cfg: CanOpenConfig = toml::from_str(
        r#"
        bus = { adapter = "socketcan", interface = "can0", bitrate = 500000 }
        [[drives]]
        node = 1
        counts_per_unit = 10000.0
        [[drives]]
        node = 2
        counts_per_unit = 131072.0
        invert = true
        following_error_window = 0.5
        homing = { method = 19, speed_search = 20.0, offset = -1.5 }
        "#,
    )
    .expect("parses");
    assert_eq!(
        cfg.bus,
        BusConfig::Socketcan {
            interface: "can0".into(),
            bitrate: 500_000
        }
    );
    assert_eq!(cfg.sdo_timeout_ms, 200);
    assert_eq!(cfg.heartbeat_ms, 100);
    assert_eq!(cfg.drives[0].rpdo, 1);
    let h = cfg.drives[1].homing.as_ref().expect("homing");
    assert_eq!(
        (h.method, h.speed_search, h.speed_zero, h.offset),
        (19, 20.0, 1.0, -1.5)
    );
    let slcan: CanOpenConfig = toml::from_str(
        "bus = { adapter = \"slcan\", port = \"/dev/ttyACM0\", bitrate = 1000000 }\ndrives = []",
    )
    .expect("parses");
    assert_eq!(
        slcan.bus,
        BusConfig::Slcan {
            port: "/dev/ttyACM0".into(),
            bitrate: 1_000_000,
            serial_baud: 115_200
        }
    );
    let pp: CanOpenConfig = toml::from_str(
        "bus = { adapter = \"sim\" }\n[[drives]]\nnode = 4\ncounts_per_unit = 100.0\nmode = \"pp\"\nprofile_velocity = 5.0",
    )
    .expect("parses");
    assert_eq!(
        pp.drives[0].mode,
        klar_drivers::cia402::config::AxisMode::Pp
    );
    assert_eq!(pp.drives[0].profile_velocity, Some(5.0));
    assert_eq!(
        cfg.drives[0].mode,
        klar_drivers::cia402::config::AxisMode::Csp
    );
    for bad in [
        "bus = { adapter = \"sim\" }\n[[drives]]\nnode = 1\ncounts_per_unit = 1.0\nmode = \"torque\"",
        "bus = { adapter = \"sim\" }\ndrives = []\nspeed = 3",
        "bus = { adapter = \"sim\", baud = 3 }\ndrives = []",
        "bus = { adapter = \"carrier-pigeon\" }\ndrives = []",
        "bus = { adapter = \"sim\" }\n[[drives]]\nnode = 1\ncounts_per_unit = 1.0\ngear = 2",
    ] {
        assert!(
            toml::from_str::<CanOpenConfig>(bad).is_err(),
            "accepted: {bad}"
        );
    }
}
