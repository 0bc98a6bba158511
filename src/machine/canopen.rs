//! Opening the CANopen buses of a machine: the axes and the spindle of one bus gathered,
//! the bus opened (a real adapter, or simulated drives on an in-memory bus or behind an
//! slcan pseudo-terminal), and start-up errors named by axis.

use std::any::Any;

use klar_drivers::can::memory::MemoryBus;
use klar_drivers::can::slcan::{SlcanBus, SlcanOptions};
use klar_drivers::cia402::{BusConfig, CanOpenConfig, Cia402Backend, DriveConfig};
use klar_sim::cia402::{SimCia402Drive, SimDriveConfig, SimDriveControl, serve_on_slcan};
use klar_sim::plant::SimAxisParams;

use super::{MachineError, SimInputs, open_err};

/// Axes of one CANopen bus gathered from the machine's axes and spindle.
#[derive(Default)]
pub(super) struct CanGroup {
    pub(super) axes: Vec<usize>,
    pub(super) letters: Vec<klar_interp::AxisLetter>,
    pub(super) drives: Vec<DriveConfig>,
    pub(super) plants: Vec<(SimAxisParams, f64)>,
    pub(super) spindle: Option<klar_drivers::cia402::SpindleConfig>,
    /// The speed dip of a simulated spindle drive: droop per mm², time constant s.
    pub(super) spindle_load: (f64, f64),
}

/// `message` with the axis of every configured node it names added at its end (`node 3 is
/// axis Z`), so that a start-up error says which axis is concerned.
fn name_axes(message: &str, letters: &[(u8, String)]) -> String {
    let named: Vec<String> = letters
        .iter()
        .filter(|(node, _)| {
            let n = node.to_string();
            let bytes = message.as_bytes();
            message.match_indices(&n).any(|(at, _)| {
                let before = message[..at].trim_end_matches(['[', ' ', ',']);
                let after = bytes.get(at + n.len()).copied();
                (before.ends_with("node") || before.ends_with("node(s)"))
                    && !after.is_some_and(|b| b.is_ascii_digit())
            })
        })
        .map(|(node, what)| format!("node {node} is {what}"))
        .collect();
    if named.is_empty() {
        message.to_string()
    } else {
        format!("{message} ({})", named.join(", "))
    }
}

/// An opened CANopen bus.
pub(super) struct OpenedBus {
    /// The bus's axes and spindle.
    pub(super) backend: Cia402Backend,
    /// What must stay alive beside the backend (the in-memory bus, the slcan runner).
    pub(super) companions: Vec<Box<dyn Any>>,
    /// The handle of the simulated spindle drive, on a simulated bus.
    pub(super) spindle: Option<SimDriveControl>,
    /// The probe inputs of the simulated axis drives, by machine axis.
    pub(super) probe_inputs: SimInputs,
}

/// Opens a CANopen bus with its drives; returns the backend and what must stay alive.
pub(super) fn open_canopen(
    name: &str,
    network: &CanOpenConfig,
    group: CanGroup,
    period: f64,
) -> Result<OpenedBus, MachineError> {
    let what = format!("CANopen bus {name}");
    let mut letters: Vec<(u8, String)> = group
        .drives
        .iter()
        .zip(&group.letters)
        .map(|(d, l)| (d.node, format!("axis {l}")))
        .collect();
    if let Some(s) = &group.spindle {
        letters.push((s.node, "the spindle".into()));
    }
    let mut config = network.clone();
    config.drives = group.drives;
    config.spindle = group.spindle;
    let mut sim_drives = Vec::new();
    let mut spindle_control = None;
    let mut probe_inputs = Vec::new();
    if matches!(
        config.bus,
        BusConfig::Sim { .. } | BusConfig::SimSlcan { .. }
    ) {
        for ((d, (plant, start)), &axis) in config.drives.iter().zip(group.plants).zip(&group.axes)
        {
            let mut plant = plant;
            plant.counts_per_unit = d.counts_per_unit.abs();
            let (drive, control) = SimCia402Drive::new(SimDriveConfig {
                node: d.node,
                plant,
                start_position: start,
            });
            sim_drives.push(drive);
            probe_inputs.push((axis, control));
        }
        if let Some(s) = &config.spindle {
            let (drive, control) = SimCia402Drive::new(SimDriveConfig {
                node: s.node,
                plant: klar_sim::cia402::spindle_plant(s.counts_per_rev),
                start_position: 0.0,
            });
            control.set_load_model(group.spindle_load.0, group.spindle_load.1);
            spindle_control = Some(control);
            sim_drives.push(drive);
        }
    }
    let mut companions: Vec<Box<dyn Any>> = Vec::new();
    let backend = match config.bus {
        BusConfig::Sim { .. } => {
            let bus = MemoryBus::new();
            for d in sim_drives {
                bus.attach(Box::new(d));
            }
            let endpoint = bus.endpoint();
            companions.push(Box::new(bus));
            Cia402Backend::with_bus(&config, period, Box::new(endpoint))
        }
        BusConfig::SimSlcan { bitrate } => {
            let (host, adapter) =
                serialport::TTYPort::pair().map_err(|e| open_err(what.clone(), &e))?;
            let runner = serve_on_slcan(adapter, bitrate, sim_drives)
                .map_err(|e| open_err(what.clone(), &e))?;
            companions.push(Box::new(runner));
            let line = SlcanBus::from_tty(host, SlcanOptions::host(bitrate))
                .map_err(|e| open_err(what.clone(), &e))?;
            Cia402Backend::with_bus(&config, period, Box::new(line))
        }
        _ => Cia402Backend::open(&config, period),
    }
    .map_err(|e| open_err(what, &name_axes(&e.to_string(), &letters)))?;
    Ok(OpenedBus {
        backend,
        companions,
        spindle: spindle_control,
        probe_inputs,
    })
}
