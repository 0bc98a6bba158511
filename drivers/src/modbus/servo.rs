//! A positioning servo drive on Modbus RTU as one machine axis (auxiliary axes: rotary
//! tables, tool changers). The drive runs its own position loop; klar writes the target
//! position each poll and reads the actual position and status back.

use std::thread::JoinHandle;
use std::time::Duration;

use klar_motion::{AxisBackend, AxisFault, AxisFeedback, AxisState, BackendError, Setpoint};
use tokio::sync::{mpsc, watch};
use tokio::time::MissedTickBehavior;
use tracing::{error, info, warn};

use super::image::{RegisterImage, plan_reads, read_image};
use super::link::{LinkStats, ModbusLink};
use super::words::{bit, counts_to_units, i32_to_words, units_to_counts, with_bit, words_to_i32};
use super::worker::{Call, Shared, call, command_wait, spawn};
use super::{ModbusError, ModbusServoConfig, ServoRegisterMap};

/// What the worker last learned about the drive.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ServoSnapshot {
    /// Actual position, machine units.
    pub position: f64,
    /// Operating state.
    pub state: AxisState,
    /// Drive referenced.
    pub homed: bool,
    /// Active fault.
    pub fault: Option<AxisFault>,
    /// The last communication failure, in words.
    pub last_error: Option<String>,
    /// Completed polls (status reads).
    pub polls: u64,
    /// Link counters.
    pub stats: LinkStats,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Command {
    Enable,
    Disable,
    Home,
    ResetFault,
}

/// A Modbus RTU positioning drive behind [`AxisBackend`] (one axis).
pub struct ModbusServo {
    commands: Option<mpsc::UnboundedSender<Call<Command>>>,
    setpoint: watch::Sender<Option<f64>>,
    snapshot: Shared<ServoSnapshot>,
    has_homing: bool,
    wait: Duration,
    thread: Option<JoinHandle<()>>,
}

impl std::fmt::Debug for ModbusServo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ModbusServo")
            .field("snapshot", &*self.snapshot.lock())
            .finish()
    }
}

impl ModbusServo {
    /// Validates `config`, opens the serial port and starts polling the drive.
    pub fn open(config: &ModbusServoConfig) -> Result<Self, ModbusError> {
        config.validate()?;
        let poll = super::config::positive_seconds("poll_period", config.poll_period)?;
        let snapshot = Shared::new(ServoSnapshot::default());
        let (commands, command_rx) = mpsc::unbounded_channel();
        let (setpoint, setpoint_rx) = watch::channel(None);
        let map = config.registers.clone();
        let shared = snapshot.clone();
        let name = format!("modbus-servo-{}", config.unit);
        let thread = spawn(&name, config.serial.clone(), config.unit, move |link| {
            let worker = ServoWorker {
                link,
                map,
                poll,
                snapshot: shared,
                setpoint: setpoint_rx,
                control: 0,
                enabled: false,
                homing: false,
                last_target: None,
                comm_fault: None,
                last_image: None,
            };
            worker.run(command_rx)
        })?;
        Ok(Self {
            commands: Some(commands),
            setpoint,
            snapshot,
            has_homing: config.registers.home_bit.is_some(),
            wait: command_wait(&config.serial, 4, poll),
            thread: Some(thread),
        })
    }

    /// What the worker last learned about the drive.
    pub fn snapshot(&self) -> ServoSnapshot {
        self.snapshot.lock().clone()
    }

    fn send(&self, command: Command) -> Result<(), BackendError> {
        let commands = self
            .commands
            .as_ref()
            .ok_or_else(|| BackendError::InvalidState("backend closed".into()))?;
        call(commands, command, self.wait).map_err(|e| BackendError::Communication(e.to_string()))
    }
}

impl Drop for ModbusServo {
    fn drop(&mut self) {
        // Closing the command channel ends the worker loop.
        self.commands = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl AxisBackend for ModbusServo {
    fn axis_count(&self) -> usize {
        1
    }

    fn enable(&mut self) -> Result<(), BackendError> {
        // Forget any old setpoint: the drive holds its actual position until the runtime
        // sends the first one.
        self.setpoint.send_replace(None);
        self.send(Command::Enable)
    }

    fn disable(&mut self) -> Result<(), BackendError> {
        self.send(Command::Disable)
    }

    fn start_homing(&mut self, axis: usize) -> Result<(), BackendError> {
        if axis != 0 {
            return Err(BackendError::NoSuchAxis(axis));
        }
        if !self.has_homing {
            return Err(BackendError::InvalidState(
                "the register map has no home_bit: this drive cannot be homed over Modbus".into(),
            ));
        }
        self.send(Command::Home)
    }

    fn reset_fault(&mut self, axis: usize) -> Result<(), BackendError> {
        if axis != 0 {
            return Err(BackendError::NoSuchAxis(axis));
        }
        self.send(Command::ResetFault)
    }

    fn cycle(
        &mut self,
        _t: f64,
        setpoints: &[Setpoint],
        feedback: &mut [AxisFeedback],
    ) -> Result<(), BackendError> {
        let lengths = (setpoints.len(), feedback.len());
        let (Some(sp), Some(fb), (1, 1)) = (setpoints.first(), feedback.first_mut(), lengths)
        else {
            return Err(BackendError::AxisCount {
                expected: 1,
                got: if lengths.0 == 1 { lengths.1 } else { lengths.0 },
            });
        };
        if self.thread.as_ref().is_none_or(|t| t.is_finished()) {
            return Err(BackendError::Communication(
                "the Modbus worker thread has stopped".into(),
            ));
        }
        if sp.position.is_finite() {
            self.setpoint.send_replace(Some(sp.position));
        }
        let snap = self.snapshot.lock();
        *fb = AxisFeedback {
            position: snap.position,
            following_error: sp.position - snap.position,
            state: snap.state,
            homed: snap.homed,
            fault: snap.fault.clone(),
        };
        Ok(())
    }
}

struct ServoWorker {
    link: ModbusLink,
    map: ServoRegisterMap,
    poll: Duration,
    snapshot: Shared<ServoSnapshot>,
    setpoint: watch::Receiver<Option<f64>>,
    control: u16,
    enabled: bool,
    homing: bool,
    last_target: Option<i32>,
    comm_fault: Option<String>,
    last_image: Option<RegisterImage>,
}

impl ServoWorker {
    async fn run(mut self, mut commands: mpsc::UnboundedReceiver<Call<Command>>) {
        // Start from the drive's control word so bits klar does not own are kept.
        if let Ok(words) = self
            .link
            .read(super::RegisterTable::Holding, self.map.control, 1)
            .await
            && let Some(w) = words.first()
        {
            self.control = *w;
        }
        let mut ticker = tokio::time::interval(self.poll);
        ticker.set_missed_tick_behavior(MissedTickBehavior::Delay);
        loop {
            tokio::select! {
                call = commands.recv() => {
                    let Some(call) = call else { break };
                    let result = self.command(call.command).await;
                    let _ = call.reply.send(result);
                }
                _ = ticker.tick() => self.poll_once().await,
            }
        }
        // The backend is gone: leave the drive disabled (best effort).
        if self.enabled {
            let word = with_bit(self.control, self.map.enable_bit, false);
            if self.write_control(word).await.is_err() {
                warn!(
                    unit = self.link.unit(),
                    "could not disable the drive on close"
                );
            }
        }
    }

    fn status_addresses(&self) -> Vec<u16> {
        let m = &self.map;
        let mut a = vec![
            m.status,
            m.actual_position,
            m.actual_position.saturating_add(1),
        ];
        if let Some(f) = m.fault_code {
            a.push(f);
        }
        a
    }

    async fn read_status(&mut self) -> Result<RegisterImage, ModbusError> {
        let blocks = plan_reads(&self.status_addresses(), 8);
        read_image(&mut self.link, self.map.status_table, &blocks).await
    }

    async fn write_control(&mut self, word: u16) -> Result<(), ModbusError> {
        self.link.write_single(self.map.control, word).await?;
        self.control = word;
        Ok(())
    }

    async fn write_target(&mut self, counts: i32) -> Result<(), ModbusError> {
        let words = i32_to_words(counts, self.map.word_order);
        self.link
            .write_multiple(self.map.target_position, &words)
            .await?;
        self.last_target = Some(counts);
        Ok(())
    }

    fn actual_counts(&self, image: &RegisterImage) -> Option<i32> {
        let a = self.map.actual_position;
        let w0 = image.get(a)?;
        let w1 = image.get(a.checked_add(1)?)?;
        Some(words_to_i32([w0, w1], self.map.word_order))
    }

    async fn command(&mut self, command: Command) -> Result<(), ModbusError> {
        let result = self.execute(command).await;
        if let Err(e) = &result
            && e.is_transient_or_exhausted()
        {
            self.communication_lost(e).await;
        }
        self.poll_once().await;
        result
    }

    async fn execute(&mut self, command: Command) -> Result<(), ModbusError> {
        let m = self.map.clone();
        match command {
            Command::Enable => {
                if self.comm_fault.is_some() {
                    return Err(ModbusError::Worker(
                        "communication fault latched: reset the fault first".into(),
                    ));
                }
                // Target = actual first, so enabling never makes the axis jump.
                let image = self.read_status().await?;
                let actual = self.actual_counts(&image).unwrap_or(0);
                self.write_target(actual).await?;
                // Enable on a rising edge: drives that latch their enable input (and
                // the simulated one) need to see the bit go from 0 to 1.
                if crate::modbus::words::bit(self.control, m.enable_bit) {
                    self.write_control(with_bit(self.control, m.enable_bit, false))
                        .await?;
                }
                self.write_control(with_bit(self.control, m.enable_bit, true))
                    .await?;
                self.enabled = true;
                info!(unit = self.link.unit(), "drive enabled at {actual} counts");
                Ok(())
            }
            Command::Disable => {
                self.enabled = false;
                self.homing = false;
                let word = with_bit(
                    with_bit(self.control, m.enable_bit, false),
                    m.home_bit.unwrap_or(16),
                    false,
                );
                self.write_control(word).await
            }
            Command::Home => {
                let Some(home) = m.home_bit else {
                    return Err(ModbusError::Config("no home_bit configured".into()));
                };
                self.write_control(with_bit(self.control, home, true))
                    .await?;
                self.homing = true;
                Ok(())
            }
            Command::ResetFault => {
                let pulse = with_bit(self.control, m.fault_reset_bit, true);
                self.write_control(pulse).await?;
                self.write_control(with_bit(pulse, m.fault_reset_bit, false))
                    .await?;
                self.comm_fault = None;
                Ok(())
            }
        }
    }

    async fn poll_once(&mut self) {
        if self.comm_fault.is_none() {
            match self.exchange().await {
                Ok(image) => self.last_image = Some(image),
                Err(e) => self.communication_lost(&e).await,
            }
        } else if let Ok(image) = self.read_status().await {
            // Keep the position display alive while the fault is latched.
            self.last_image = Some(image);
        }
        self.publish();
    }

    /// One poll: new target (if enabled and changed), then the status block.
    async fn exchange(&mut self) -> Result<RegisterImage, ModbusError> {
        let setpoint = *self.setpoint.borrow_and_update();
        if self.enabled
            && let Some(position) = setpoint
        {
            let counts = units_to_counts(position, self.map.counts_per_unit);
            if self.last_target != Some(counts) {
                self.write_target(counts).await?;
            }
        }
        let image = self.read_status().await?;
        let status = image.get(self.map.status).unwrap_or(0);
        if bit(status, self.map.fault_bit) && self.enabled {
            warn!(unit = self.link.unit(), "drive reports a fault: holding");
            self.enabled = false;
        }
        if self.homing
            && let Some(hb) = self.map.homed_bit
            && bit(status, hb)
        {
            self.homing = false;
            if let Some(home) = self.map.home_bit {
                self.write_control(with_bit(self.control, home, false))
                    .await?;
            }
        }
        Ok(image)
    }

    /// Bounded retries are exhausted: latch the fault, stop following setpoints and try
    /// once to make the drive hold where it is (the controlled stop).
    async fn communication_lost(&mut self, err: &ModbusError) {
        if self.comm_fault.is_some() {
            return;
        }
        error!(
            unit = self.link.unit(),
            "communication lost, stopping axis: {err}"
        );
        self.comm_fault = Some(err.to_string());
        self.enabled = false;
        self.homing = false;
        if let Some(actual) = self.last_image.as_ref().and_then(|i| self.actual_counts(i))
            && self.write_target(actual).await.is_err()
        {
            warn!(unit = self.link.unit(), "could not command a hold position");
        }
    }

    fn publish(&self) {
        let mut snap = self.snapshot.lock();
        if let Some(image) = &self.last_image {
            if let Some(c) = self.actual_counts(image) {
                snap.position = counts_to_units(c, self.map.counts_per_unit);
            }
            let status = image.get(self.map.status).unwrap_or(0);
            let drive_fault = bit(status, self.map.fault_bit);
            snap.homed = self.map.homed_bit.is_none_or(|b| bit(status, b));
            snap.fault = if self.comm_fault.is_some() {
                Some(AxisFault::CommunicationLost)
            } else if drive_fault {
                let code = self.map.fault_code.and_then(|a| image.get(a)).unwrap_or(0);
                Some(AxisFault::Drive {
                    code: u32::from(code),
                    text: format!("Modbus drive unit {} in fault", self.link.unit()),
                })
            } else {
                None
            };
            snap.state = if snap.fault.is_some() {
                AxisState::Faulted
            } else if self.homing {
                AxisState::Homing
            } else if bit(status, self.map.enabled_bit) {
                AxisState::Enabled
            } else {
                AxisState::Disabled
            };
            snap.polls += 1;
        } else if self.comm_fault.is_some() {
            snap.fault = Some(AxisFault::CommunicationLost);
            snap.state = AxisState::Faulted;
        }
        snap.last_error.clone_from(&self.comm_fault);
        snap.stats = self.link.stats();
    }
}
