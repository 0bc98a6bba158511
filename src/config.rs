//! The machine description: axes, limits, servo period, tolerance, backends and spindle,
//! read from TOML. Unknown keys are errors. [`MachineConfig::builtin_mill`] is the machine
//! `klar run` uses when no `--machine` file is given.
//!
//! Units: positions in mm (linear) or degrees (rotary), velocities per second, accelerations
//! per second², jerks per second³, periods in seconds.

use klar_drivers::cia402::{CanOpenConfig, DriveConfig};
use klar_drivers::modbus::{ModbusServoConfig, ModbusVfdConfig};
use klar_drivers::stepdir::StepDirConfig;
use klar_interp::op::{
    BUILT_IN_M_NUMBERS, MAX_MACHINE_FUNCTION, MachineFunctionDef, MachineFunctionTime,
};
use klar_interp::{AxisLetter, Diagnostic, Interpreter, Pose};
use klar_motion::kinematics::{Cartesian, Kinematics, Lathe, TableTable, TiltAxis};
use klar_motion::planner::TableGeometry;
use klar_motion::{AxisLimits, MotionError, Planner, PlannerConfig};
use klar_sim::plant::SimAxisParams;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;

mod locate;
mod probe;
mod probe_features;
mod ranges;
mod tables;
mod validate;
pub use probe::{BoreConfig, BossConfig, PocketConfig, ProbeConfig, WorkpieceConfig};
pub use probe_features::{HoleCircleConfig, RidgeConfig, SlotConfig};
pub use ranges::{MAX_PIVOT, MAX_SPINDLE_RPM, MAX_TRAVEL};
pub use tables::ActivePreset;

/// Linear or rotary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AxisKind {
    /// Moves in mm.
    Linear,
    /// Turns in degrees.
    Rotary,
}

/// Which backend drives an axis.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum BackendConfig {
    /// A simulated servo axis (klar-sim).
    Sim(SimAxisParams),
    /// A CiA 402 drive on a CANopen bus named in `[canopen.NAME]`.
    Canopen(CanopenAxisConfig),
    /// A Modbus RTU positioning drive (auxiliary axes only: too slow for contouring).
    Modbus(ModbusAxisConfig),
    /// A stepper drive on step/direction outputs.
    Stepdir(StepDirAxisConfig),
}

/// An axis on a CiA 402 drive.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CanopenAxisConfig {
    /// Name of the bus in `[canopen.NAME]`.
    pub bus: String,
    /// The drive: node, scaling, homing, mode (see docs/canopen.md).
    pub drive: DriveConfig,
    /// On a simulated bus: the servo plant behind the drive (defaults when absent).
    #[serde(default)]
    pub plant: Option<SimAxisParams>,
    /// At the program's end the drive is switched off only once its measured position is
    /// within this distance of the end point, mm or degrees.
    #[serde(default = "default_in_position")]
    pub in_position: f64,
    /// How long the axis may take to come within `in_position` at the program's end, s;
    /// beyond it the run ends with an error naming the axis and its distance.
    #[serde(default = "default_end_timeout")]
    pub settle_timeout: f64,
}

fn default_end_timeout() -> f64 {
    2.0
}

/// An axis on a Modbus RTU positioning drive.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModbusAxisConfig {
    /// The drive: serial line, unit, register map (see docs/modbus.md).
    pub servo: ModbusServoConfig,
    /// Window within which the axis counts as in position after a move, mm or degrees.
    #[serde(default = "default_in_position")]
    pub in_position: f64,
    /// How long a positioning move may take to settle after its setpoints end, s.
    #[serde(default = "default_settle_timeout")]
    pub settle_timeout: f64,
    /// When present, klar starts a simulated drive with this plant on a pseudo-terminal and
    /// talks to it instead of `servo.serial.port`.
    #[serde(default)]
    pub simulate: Option<SimAxisParams>,
}

fn default_in_position() -> f64 {
    0.01
}
fn default_settle_timeout() -> f64 {
    5.0
}

/// An axis on a stepper drive.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StepDirAxisConfig {
    /// Step timing, scaling, switches (see docs/stepdir.md).
    pub stepdir: StepDirConfig,
    /// Drive a simulated stepper motor instead of GPIO lines.
    #[serde(default)]
    pub simulate: bool,
}

impl Default for BackendConfig {
    fn default() -> Self {
        BackendConfig::Sim(SimAxisParams::default())
    }
}

/// One machine axis.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxisConfig {
    /// Axis letter as programs name it.
    pub letter: AxisLetter,
    /// Linear or rotary.
    pub kind: AxisKind,
    /// Soft limits `[min, max]`.
    pub travel: [f64; 2],
    /// Maximum velocity (mm/s or °/s).
    pub max_velocity: f64,
    /// Maximum acceleration (mm/s² or °/s²).
    pub max_acceleration: f64,
    /// Maximum jerk (mm/s³ or °/s³).
    pub max_jerk: f64,
    /// Position at start of a simulated run (defaults to 0).
    #[serde(default)]
    pub start: f64,
    /// The control's following-error monitor: largest tolerated |commanded − measured|
    /// (mm or degrees) before the run stops; none: only the drive's own window applies.
    #[serde(default)]
    pub following_error_limit: Option<f64>,
    /// The backend.
    #[serde(default)]
    pub backend: BackendConfig,
}

/// How program coordinates map to machine axes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum KinematicsConfig {
    /// Each machine axis is the program axis of the same letter.
    #[default]
    Cartesian,
    /// A turning centre: X (radius), Z, C main spindle, Y, B tool tilt; without a Y axis a
    /// point off the X axis is reached by turning C.
    Lathe,
    /// A 5-axis mill whose workpiece sits on a rotary table C carried by a tilting cradle A
    /// or B (whichever of the two the machine lists); pivots in `[table_table]`.
    #[serde(rename = "table_table")]
    TableTable,
}

/// Where the rotary axes of a table-table machine lie (machine coordinates, mm, at zero
/// angles): the tilt axis passes through `tilt_pivot`, the table axis through `table_pivot`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TableTableConfig {
    /// A point on the tilt axis (A parallel to X, or B parallel to Y).
    #[serde(default)]
    pub tilt_pivot: [f64; 3],
    /// A point on the table axis C (parallel to Z at zero tilt).
    #[serde(default)]
    pub table_pivot: [f64; 3],
}

/// A spindle motor simulated inside klar: its speed ramps at `acceleration`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimSpindleConfig {
    /// Ramp rate, rpm per second.
    #[serde(default = "default_spindle_acceleration")]
    pub acceleration: f64,
    /// At-speed window as a fraction of the command.
    #[serde(default = "default_at_speed_fraction")]
    pub at_speed_fraction: f64,
    /// Encoder counts per revolution of the simulated spindle's angle measurement.
    #[serde(default = "default_encoder_counts")]
    pub encoder_counts: u32,
    /// Fraction of the speed lost per mm² of chip cross-section under cut (0: no dip).
    #[serde(default)]
    pub load_droop: f64,
    /// Time constant of the speed dip under cut, s.
    #[serde(default = "default_load_time_constant")]
    pub load_time_constant: f64,
}

fn default_spindle_acceleration() -> f64 {
    8000.0
}
fn default_at_speed_fraction() -> f64 {
    0.02
}
fn default_encoder_counts() -> u32 {
    4096
}
fn default_load_time_constant() -> f64 {
    0.05
}
fn default_at_speed_timeout() -> f64 {
    10.0
}

impl Default for SimSpindleConfig {
    fn default() -> Self {
        Self {
            acceleration: default_spindle_acceleration(),
            at_speed_fraction: default_at_speed_fraction(),
            encoder_counts: default_encoder_counts(),
            load_droop: 0.0,
            load_time_constant: default_load_time_constant(),
        }
    }
}

/// A spindle VFD on Modbus RTU, optionally simulated on a pseudo-terminal.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModbusSpindleConfig {
    /// The VFD: serial line, unit, register map (see docs/modbus.md).
    pub vfd: ModbusVfdConfig,
    /// When present, klar starts a simulated VFD with the same register map on a
    /// pseudo-terminal and talks to it instead of `vfd.serial.port` (no hardware needed).
    #[serde(default)]
    pub simulate: Option<SimSpindleConfig>,
}

/// A spindle on a CiA 402 drive in cyclic synchronous velocity mode.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CanopenSpindleConfig {
    /// Name of the bus in `[canopen.NAME]`.
    pub bus: String,
    /// The drive (see docs/canopen.md).
    pub drive: klar_drivers::cia402::SpindleConfig,
    /// On a simulated bus: fraction of the drive's speed lost per mm² of chip
    /// cross-section under cut (0: no dip), as the simulated spindle's `load_droop`.
    #[serde(default)]
    pub load_droop: f64,
    /// On a simulated bus: time constant of the speed dip under cut, s.
    #[serde(default = "default_load_time_constant")]
    pub load_time_constant: f64,
}

/// Which backend drives the spindle.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum SpindleBackendConfig {
    /// Simulated spindle motor.
    Sim(SimSpindleConfig),
    /// Modbus RTU VFD.
    Modbus(ModbusSpindleConfig),
    /// CiA 402 drive on a CANopen bus.
    Canopen(CanopenSpindleConfig),
}

impl Default for SpindleBackendConfig {
    fn default() -> Self {
        SpindleBackendConfig::Sim(SimSpindleConfig::default())
    }
}

/// The spindle.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpindleConfig {
    /// Highest speed in rpm.
    pub max_rpm: f64,
    /// How long a spindle command may take to reach speed before the run stops, s.
    #[serde(default = "default_at_speed_timeout")]
    pub at_speed_timeout: f64,
    /// The backend.
    #[serde(default)]
    pub backend: SpindleBackendConfig,
}

/// A whole machine.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MachineConfig {
    /// A name for reports.
    pub name: String,
    /// Servo period in seconds.
    pub servo_period: f64,
    /// Default path tolerance in mm.
    pub tolerance: f64,
    /// Kinematics.
    #[serde(default)]
    pub kinematics: KinematicsConfig,
    /// Pivots of a table-table machine (`kinematics = "table_table"`; zero when absent).
    #[serde(default)]
    pub table_table: TableTableConfig,
    /// The axes, in machine order (trace columns follow this order).
    #[serde(rename = "axis")]
    pub axes: Vec<AxisConfig>,
    /// The spindle, if any.
    #[serde(default)]
    pub spindle: Option<SpindleConfig>,
    /// Simulation only: axes start referenced, no homing needed.
    #[serde(default)]
    pub start_homed: bool,
    /// CANopen buses by name; their drives come from the axes (and spindle) naming them.
    #[serde(default)]
    pub canopen: BTreeMap<String, CanOpenConfig>,
    /// Run the test run (`klar check --machine`) before every run and refuse to start a
    /// program it refuses (default true). Tests of run-time reactions switch it off.
    #[serde(default = "default_true")]
    pub check_before_run: bool,
    /// The tool table: when present, a TOOL CALL of a tool not listed is an error.
    #[serde(default, rename = "tool")]
    pub tools: Option<Vec<ToolConfig>>,
    /// A HEIDENHAIN tool table file (TOOL.T columns T, NAME, L, R, R2, DL, DR, DR2), relative
    /// to the machine file; its tools join the `[[tool]]` entries.
    #[serde(default)]
    pub tool_table: Option<std::path::PathBuf>,
    /// A HEIDENHAIN preset table (PRESET.PR: columns NR, X, Y, Z, A, B, C …), relative to the
    /// machine file: cycle 247 activates its rows.
    #[serde(default)]
    pub preset_table: Option<std::path::PathBuf>,
    /// The preset (row of `preset_table`) active when a program starts, as the operator
    /// activated it on the machine; none: program coordinates are machine coordinates.
    #[serde(default)]
    pub active_preset: Option<i64>,
    /// A HEIDENHAIN datum table (.D: columns NR, X, Y, Z …), relative to the machine file:
    /// `CYCL DEF 7.1 #n` and ISO `G53` take their shifts from it.
    #[serde(default)]
    pub datum_table: Option<std::path::PathBuf>,
    /// The folder of the machine file (relative paths in it are resolved from here).
    #[serde(skip)]
    pub base_dir: Option<std::path::PathBuf>,
    /// Faults injected into the simulated axes (see docs/safety.md).
    #[serde(default, rename = "fault")]
    pub faults: Vec<crate::faults::FaultConfig>,
    /// How late a setpoint may reach the axes before the run counts a setpoint underrun and
    /// stops on the path, s (default [`DEFAULT_LATENESS_PERIODS`] servo periods).
    #[serde(default)]
    pub max_setpoint_lateness: Option<f64>,
    /// The machine's own M functions (`[[m_function]]`): M numbers programs may use
    /// besides the ones klar defines.
    #[serde(default, rename = "m_function")]
    pub m_functions: Vec<MFunctionConfig>,
    /// The touch probe's data (`[probe]`).
    #[serde(default)]
    pub probe: Option<ProbeConfig>,
    /// A simulated part on the table for the touch probe to find (`[workpiece]`).
    #[serde(default)]
    pub workpiece: Option<WorkpieceConfig>,
}

/// A machine-dependent M function (door, clamping, chip conveyor, …), `[[m_function]]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MFunctionConfig {
    /// The M number, 0 to 9999, not one klar defines itself.
    pub number: i64,
    /// Text shown in the log when it acts.
    #[serde(default)]
    pub name: String,
    /// When in its block it acts: `"start"` (before the motion) or `"end"` (after it, the
    /// default).
    #[serde(default)]
    pub at: MachineFunctionTime,
    /// The path comes to rest exactly before the function acts (default true). Without a
    /// stop it is switched on the fly and `wait` is not applied.
    #[serde(default = "default_true")]
    pub stop: bool,
    /// Seconds the machine waits after the function before it goes on (default 0).
    #[serde(default)]
    pub wait: f64,
}

/// Default setpoint lateness that ends a run, in servo periods. Drives in cyclic synchronous
/// modes ride through a few missed SYNC periods by extrapolating; beyond that they fault.
pub const DEFAULT_LATENESS_PERIODS: f64 = 10.0;

/// Opens `program` for a front end (`klar run`, `check`, `ops`, `plot`, the dashboard): on
/// `machine` exactly as a run does ([`MachineConfig::open_program`]); with no machine (`None`:
/// a check or plot of the program on its own, no machine file named) with nothing of a
/// machine: PLANE and cycle 19 assume an A/C table, TOOL CALL takes length and radius from
/// TOOL DEF and the call, and only klar's own M functions are known.
pub fn open_on(
    machine: Option<&MachineConfig>,
    program: &Path,
    start: Pose,
) -> Result<Interpreter, Diagnostic> {
    match machine {
        Some(m) => m.open_program(program, start),
        None => Interpreter::open(program, start),
    }
}

impl MachineConfig {
    /// The setpoint lateness that counts as an underrun and stops the run, s.
    pub fn setpoint_lateness_limit(&self) -> f64 {
        self.max_setpoint_lateness
            .unwrap_or(DEFAULT_LATENESS_PERIODS * self.servo_period)
    }
}

fn default_true() -> bool {
    true
}

/// One entry of the machine's tool table.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToolConfig {
    /// Tool number as TOOL CALL names it.
    pub number: u32,
    /// Tool name (TOOL CALL "name" finds it).
    #[serde(default)]
    pub name: Option<String>,
    /// Tool length L, mm.
    #[serde(default)]
    pub length: f64,
    /// Tool radius R, mm (radius compensation uses it, plus DR from TOOL CALL).
    #[serde(default)]
    pub radius: f64,
}

/// What can be wrong with a machine file.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// File name.
        path: String,
        /// Cause.
        source: std::io::Error,
    },
    /// TOML syntax or schema error (with line and column from the TOML parser).
    #[error("{path}: {message}")]
    Parse {
        /// File name.
        path: String,
        /// What the parser said.
        message: String,
    },
    /// A value that parses but makes no sense.
    #[error("{path}: {message}")]
    Invalid {
        /// File name.
        path: String,
        /// What is wrong.
        message: String,
    },
}

/// Largest machine file read, bytes (klar's limit: a machine file is a few kB).
pub const MAX_MACHINE_FILE: u64 = 1024 * 1024;

/// The built-in simulated 3-axis mill as TOML (also the reference example of the format).
pub const BUILTIN_MILL: &str = include_str!("../machines/mill.toml");

/// The built-in simulated turning centre (X Z C Y B), used for lathe DIN programs.
pub const BUILTIN_LATHE: &str = include_str!("../machines/lathe.toml");

/// The built-in simulated 5-axis table-table mill (X Y Z A C), for PLANE and M128 programs.
pub const BUILTIN_MILL5: &str = include_str!("../machines/mill5.toml");

impl MachineConfig {
    /// Reads and validates a machine file.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let shown = path.display().to_string();
        let bytes = klar_interp::read_bounded(path, MAX_MACHINE_FILE).map_err(|source| {
            ConfigError::Io {
                path: shown.clone(),
                source,
            }
        })?;
        let text = String::from_utf8(bytes).map_err(|_| ConfigError::Parse {
            path: shown.clone(),
            message: "not UTF-8 text (a machine file is TOML)".into(),
        })?;
        let mut config = Self::parse(&shown, &text)?;
        config.base_dir = path.parent().map(Path::to_path_buf);
        // Read the tables now, so that a bad file is refused with the machine file.
        config
            .check_tables()
            .map_err(|message| ConfigError::Invalid {
                path: shown,
                message,
            })?;
        Ok(config)
    }

    /// Parses and validates machine TOML; `name` is used in messages.
    pub fn parse(name: &str, text: &str) -> Result<Self, ConfigError> {
        let place = |at: Option<(usize, usize)>| match at {
            Some((line, col)) => format!("{name}:{line}:{col}"),
            None => name.to_string(),
        };
        let config: MachineConfig = toml::from_str(text).map_err(|e| {
            let (at, message) = locate::unknown_key(text, e.to_string().trim_end());
            ConfigError::Parse {
                path: place(at),
                message,
            }
        })?;
        config.validate().map_err(|message| ConfigError::Invalid {
            path: place(locate::locate(text, &message)),
            message,
        })?;
        Ok(config)
    }

    /// The built-in simulated mill.
    pub fn builtin_mill() -> Self {
        match Self::parse("built-in mill", BUILTIN_MILL) {
            Ok(c) => c,
            // The built-in file is part of the binary and covered by a test.
            Err(e) => unreachable!("built-in machine is invalid: {e}"),
        }
    }

    /// The built-in simulated lathe.
    pub fn builtin_lathe() -> Self {
        match Self::parse("built-in lathe", BUILTIN_LATHE) {
            Ok(c) => c,
            // The built-in file is part of the binary and covered by a test.
            Err(e) => unreachable!("built-in machine is invalid: {e}"),
        }
    }

    /// The built-in simulated 5-axis table-table mill (X Y Z A C).
    pub fn builtin_mill5() -> Self {
        match Self::parse("built-in 5-axis mill", BUILTIN_MILL5) {
            Ok(c) => c,
            // The built-in file is part of the binary and covered by a test.
            Err(e) => unreachable!("built-in machine is invalid: {e}"),
        }
    }

    /// The built-in machine for a program: the lathe for lathe DIN programs, else the mill.
    pub fn builtin_for(program: &Path) -> Self {
        if klar_interp::not_a_file(program).is_some() {
            // refused when the program is opened; a FIFO must not be opened here
            return Self::builtin_mill();
        }
        let head = std::fs::File::open(program)
            .and_then(|f| {
                use std::io::Read;
                let mut buf = Vec::with_capacity(4096);
                f.take(4096).read_to_end(&mut buf).map(|_| buf)
            })
            .unwrap_or_default();
        match klar_interp::detect_dialect(program, &head) {
            Some(klar_interp::Dialect::LatheDin) => Self::builtin_lathe(),
            _ => Self::builtin_mill(),
        }
    }

    /// Opens a program for this machine: the interpreter told everything the machine file
    /// says that concerns the program (rotary axes for PLANE and cycle 19 / G80, the table
    /// geometry for PLANE … TURN, the machine builder's M functions, the tool table), whatever
    /// the program's dialect. Every front end
    /// opens programs through here or [`open_on`], so they cannot drift apart.
    pub fn open_program(&self, program: &Path, start: Pose) -> Result<Interpreter, Diagnostic> {
        // PLANE and cycle 19 compute angles for the machine's rotary axes.
        let mut interp = Interpreter::open(program, start)?
            .with_rotary_axes(&self.letters())
            .with_machine_functions(&self.machine_functions());
        // M140 MB MAX retracts to the travel limits.
        for a in self.axes.iter().filter(|a| a.kind == AxisKind::Linear) {
            interp = interp.with_travel(a.letter, a.travel);
        }
        // PLANE … TURN keeps the linear axes still: the tip's new place needs the pivots.
        if self.kinematics == KinematicsConfig::TableTable {
            // the tilt axis as in `kinematics`
            let tilt = if self.letters().contains(&AxisLetter::B) {
                AxisLetter::B
            } else {
                AxisLetter::A
            };
            let t = &self.table_table;
            interp = interp.with_table_geometry(tilt, t.tilt_pivot, t.table_pivot);
        }
        Ok(self.with_probe(self.with_tables(interp)))
    }

    /// The start pose of this machine in program coordinates: each axis at its `start`.
    pub fn start_pose(&self) -> Pose {
        let mut p = Pose::ZERO;
        for a in &self.axes {
            p[a.letter] = a.start;
        }
        p
    }

    /// A planner for this machine standing at `start`: its axis limits, servo period and
    /// tolerance, and on a table-table machine the table geometry that bounds turning moves
    /// with TCPM.
    pub fn planner(&self, start: Pose) -> Result<Planner, MotionError> {
        let mut planner = Planner::new(
            PlannerConfig {
                limits: self.axis_limits(),
                period: self.servo_period,
                tolerance: self.tolerance,
            },
            start,
        )?;
        if self.kinematics == KinematicsConfig::TableTable {
            let t = &self.table_table;
            planner.set_table_geometry(TableGeometry::new(t.tilt_pivot, t.table_pivot));
        }
        Ok(planner)
    }

    /// The kinematics this machine names, over its axes in machine order.
    pub fn kinematics(&self) -> Box<dyn Kinematics> {
        let letters = self.letters();
        match self.kinematics {
            KinematicsConfig::Cartesian => Box::new(Cartesian::new(&letters)),
            KinematicsConfig::Lathe => Box::new(Lathe::new(&letters)),
            KinematicsConfig::TableTable => {
                let tilt = if letters.contains(&AxisLetter::B) {
                    TiltAxis::B
                } else {
                    TiltAxis::A
                };
                let t = &self.table_table;
                Box::new(TableTable::new(&letters, tilt, t.tilt_pivot, t.table_pivot))
            }
        }
    }

    /// Planner limits per program axis (None for axes this machine lacks).
    pub fn axis_limits(&self) -> [Option<AxisLimits>; 9] {
        let mut out = [None; 9];
        for a in &self.axes {
            out[a.letter.index()] = Some(AxisLimits {
                max_velocity: a.max_velocity,
                max_acceleration: a.max_acceleration,
                max_jerk: a.max_jerk,
            });
        }
        out
    }

    /// True when a backend runs on the wall clock (a bus, a serial line, a device simulated
    /// in its own thread): such a machine can only run with `--realtime`.
    pub fn needs_wall_clock(&self) -> bool {
        use klar_drivers::cia402::BusConfig;
        let modbus_spindle = matches!(
            self.spindle.as_ref().map(|s| &s.backend),
            Some(SpindleBackendConfig::Modbus(_))
        );
        let modbus_axis = self
            .axes
            .iter()
            .any(|a| matches!(a.backend, BackendConfig::Modbus(_)));
        let real_stepdir = self
            .axes
            .iter()
            .any(|a| matches!(&a.backend, BackendConfig::Stepdir(s) if !s.simulate));
        let real_can = self
            .canopen
            .values()
            .any(|c| matches!(c.bus, BusConfig::Socketcan { .. } | BusConfig::Slcan { .. }));
        modbus_spindle || modbus_axis || real_stepdir || real_can
    }

    /// The machine's own M functions as the interpreter takes them.
    pub fn machine_functions(&self) -> Vec<MachineFunctionDef> {
        self.m_functions
            .iter()
            .filter_map(|m| {
                Some(MachineFunctionDef {
                    number: u32::try_from(m.number).ok()?,
                    at: m.at,
                    stop: m.stop,
                    wait: m.wait,
                })
            })
            .collect()
    }

    /// The name of machine function `number` for the log (empty when it has none).
    pub fn machine_function_name(&self, number: u32) -> &str {
        self.m_functions
            .iter()
            .find(|m| m.number == i64::from(number))
            .map_or("", |m| m.name.as_str())
    }

    /// This machine with every axis's `start` at `positions` (machine order): where the
    /// drives were found standing, so that a test run checks from there.
    pub fn starting_at(&self, positions: impl IntoIterator<Item = f64>) -> Self {
        let mut c = self.clone();
        for (a, x) in c.axes.iter_mut().zip(positions) {
            a.start = x;
        }
        c
    }

    /// The axis letters in machine order.
    pub fn letters(&self) -> Vec<AxisLetter> {
        self.axes.iter().map(|a| a.letter).collect()
    }
}
