//! Machine-TOML shapes of the Modbus backends, validation, and the limits check with its
//! wire-time figures computed by hand from the RTU framing rules.

use klar_drivers::modbus::limits::{
    ModbusLimitError, check_servo, check_vfd, read_time, servo_timing,
};
use klar_drivers::modbus::{
    ModbusServoConfig, ModbusVfdConfig, Parity, SerialLineConfig, VfdPreset, WordOrder,
};

const SERVO: &str = r#"
unit = 3
poll_period = 0.02
[serial]
port = "/dev/ttyUSB0"
baud = 115200
parity = "none"
timeout = 0.05
retries = 2
turnaround = 0.002
[registers]
target_position = 0x0100
actual_position = 0x0110
status = 0x0112
control = 0x0120
fault_code = 0x0113
enable_bit = 0
fault_reset_bit = 7
home_bit = 4
enabled_bit = 1
fault_bit = 3
homed_bit = 12
counts_per_unit = 1000.0
word_order = "low_first"
"#;

const VFD: &str = r#"
unit = 1
max_rpm = 24000
[serial]
port = "/dev/ttyUSB1"
baud = 19200
[profile]
preset = "delta"
rpm_per_hz = 60
"#;

#[test]
fn servo_toml_parses_and_validates() {
    let c: ModbusServoConfig = toml::from_str(SERVO).expect("parse");
    assert_eq!(c.unit, 3);
    assert_eq!(c.registers.word_order, WordOrder::LowFirst);
    assert_eq!(c.serial.parity, Parity::None);
    assert_eq!(c.registers.fault_code, Some(0x0113));
    c.validate().expect("valid");
}

#[test]
fn vfd_toml_presets() {
    let c: ModbusVfdConfig = toml::from_str(VFD).expect("parse");
    assert_eq!(c.profile, VfdPreset::Delta { rpm_per_hz: 60.0 });
    assert_eq!(c.serial.parity, Parity::Even, "Modbus default parity");
    c.validate().expect("valid");
    let generic = VFD.replace(
        "preset = \"delta\"\nrpm_per_hz = 60",
        "preset = \"generic\"\n[profile.registers]\nspeed_setpoint = 9",
    );
    let c: ModbusVfdConfig = toml::from_str(&generic).expect("parse generic");
    match c.profile {
        VfdPreset::Generic { registers } => {
            assert_eq!(registers.speed_setpoint, 9);
            assert_eq!(registers.control, 0, "defaults fill the rest");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn unknown_keys_and_bad_values_are_errors() {
    let typo = SERVO.replace("enable_bit", "enabel_bit");
    assert!(toml::from_str::<ModbusServoConfig>(&typo).is_err());
    let extra = VFD.replace("rpm_per_hz = 60", "rpm_per_hz = 60\nspeed = 3");
    assert!(toml::from_str::<ModbusVfdConfig>(&extra).is_err());
    let unknown = VFD.replace("\"delta\"", "\"huanyang\"");
    assert!(toml::from_str::<ModbusVfdConfig>(&unknown).is_err());

    let mut c: ModbusServoConfig = toml::from_str(SERVO).unwrap();
    c.registers.fault_bit = 16;
    assert!(
        c.validate()
            .unwrap_err()
            .to_string()
            .contains("fault_bit = 16")
    );
    let mut c: ModbusServoConfig = toml::from_str(SERVO).unwrap();
    c.unit = 0;
    assert!(c.validate().is_err());
    let mut c: ModbusServoConfig = toml::from_str(SERVO).unwrap();
    c.serial.timeout = f64::NAN;
    assert!(c.validate().is_err());
    let mut c: ModbusVfdConfig = toml::from_str(VFD).unwrap();
    c.max_rpm = 60_000.0; // 1000 Hz does not fit 0.01 Hz units in 16 bits
    assert!(c.validate().is_err());
}

#[test]
fn wire_times_match_the_framing_rules() {
    // 115200 baud, 8N1 = 10 bits per character; gap fixed at 1.75 ms above 19200 baud.
    let mut line = SerialLineConfig::new("/dev/null");
    line.baud = 115_200;
    line.parity = Parity::None;
    line.turnaround = 0.0;
    // Read of 4 registers: 8 + 13 bytes.
    let expected = 21.0 * 10.0 / 115_200.0 + 2.0 * 0.001_75;
    assert!((read_time(&line, 4) - expected).abs() < 1e-12);
    // 9600 baud 8E1: 11 bits, gap 3.5 characters.
    line.baud = 9_600;
    line.parity = Parity::Even;
    let expected = 21.0 * 11.0 / 9_600.0 + 2.0 * 3.5 * 11.0 / 9_600.0;
    assert!((read_time(&line, 4) - expected).abs() < 1e-12);
}

#[test]
fn servo_limits_refuse_contouring_and_slow_lines() {
    let c: ModbusServoConfig = toml::from_str(SERVO).unwrap();
    // Write 2 registers (13 + 8 bytes) and one read of 0x0110..0x0113 (8 + 13 bytes),
    // each with two 1.75 ms gaps and 2 ms turnaround.
    let per = |bytes: f64| bytes * 10.0 / 115_200.0 + 0.0035 + 0.002;
    let t = servo_timing(&c);
    assert!((t.poll_time - (per(21.0) + per(21.0))).abs() < 1e-12);
    assert!((t.loss_detection - 0.15).abs() < 1e-12);
    let t = check_servo(&c, 0.001, false).expect("an auxiliary axis is fine");
    assert!(t.to_string().starts_with(
        "Modbus RTU: one poll takes 14.65 ms on the wire, polled every 20.0 ms; a dead \
         device is detected after 150 ms"
    ));
    let e = check_servo(&c, 0.001, true).unwrap_err();
    assert!(matches!(e, ModbusLimitError::Contouring { .. }));
    assert!(e.to_string().contains("cannot contour"), "{e}");
    assert!(e.to_string().contains("one poll takes 14.65 ms"), "{e}");

    let mut slow = c.clone();
    slow.serial.baud = 1_200;
    slow.serial.parity = Parity::Even;
    let e = check_servo(&slow, 0.001, false).unwrap_err();
    assert!(
        matches!(e, ModbusLimitError::PollTooShort { baud: 1_200, .. }),
        "{e:?}"
    );
}

#[test]
fn vfd_limits() {
    let c: ModbusVfdConfig = toml::from_str(VFD).unwrap();
    let t = check_vfd(&c).expect("19200 baud, 50 ms poll fits");
    // 8E1 at 19200: 11 bits per character, gaps of 3.5 characters, 5 ms turnaround.
    let per = |bytes: f64| (bytes + 7.0) * 11.0 / 19_200.0 + 0.005;
    // One read of 2100H..2103H (8 + 13 bytes); a speed change adds two single writes.
    assert!((t.poll_time - per(21.0)).abs() < 1e-12);
    assert!((t.command_time - 2.0 * per(16.0)).abs() < 1e-12);
    let mut fast = c.clone();
    fast.poll_period = 0.002;
    assert!(matches!(
        check_vfd(&fast),
        Err(ModbusLimitError::PollTooShort { .. })
    ));
}

/// The machine file embeds a backend as a table tagged by `kind`; the Modbus tables must
/// work there with their unknown-key checks intact.
#[derive(Debug, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
enum Backend {
    Modbus(ModbusServoConfig),
}

#[test]
fn embeds_in_a_kind_tagged_backend_table() {
    let tagged = format!("kind = \"modbus\"\n{SERVO}");
    let Backend::Modbus(c) = toml::from_str::<Backend>(&tagged).expect("tagged table");
    assert_eq!(c.unit, 3);
    let typo = tagged.replace("poll_period", "pol_period");
    assert!(toml::from_str::<Backend>(&typo).is_err());
}

/// A pseudo-terminal has no parity bit: Linux clears PARENB on a pty (or refuses the
/// setting outright). Asking for even parity on one is an error naming the port and the
/// setting, never a line that silently runs without parity; parity none opens.
#[test]
fn a_port_that_cannot_keep_even_parity_is_refused() {
    use serialport::SerialPort as _;
    let (_master, slave) = serialport::TTYPort::pair().expect("pseudo-terminal pair");
    let path = slave.name().expect("the pty has a name");
    drop(slave);
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .expect("runtime");
    let _entered = runtime.enter();
    let mut line = SerialLineConfig::new(path.clone());
    line.parity = Parity::Even;
    let message = match klar_drivers::modbus::link::open_serial(&line) {
        Ok(_) => panic!("even parity on {path} was accepted"),
        Err(e) => e.to_string(),
    };
    assert!(
        message.contains(&path) && message.contains("parity") && message.contains("even"),
        "{message}"
    );
    line.parity = Parity::None;
    klar_drivers::modbus::link::open_serial(&line).expect("parity none opens on a pty");
}
