//! A spindle VFD on Modbus RTU behind [`SpindleBackend`].
//!
//! Fault handling: when the link gives up (all retries used) the spindle reports
//! [`AxisFault::CommunicationLost`] and the worker keeps trying to write a stop; an exception
//! the VFD answers (it is there, but refuses the request) is reported as
//! [`AxisFault::DeviceException`] with its code and meaning instead. The fault clears once the runtime commands 0 rpm and the VFD answers again. A VFD fault is
//! reported as [`AxisFault::Drive`] with the VFD's code; it is cleared with
//! [`ModbusVfd::reset_fault`].
//!
//! Stopping: [`SpindleBackend::stop_confirmed`] writes the stop and reads the status back
//! until two reads in a row show that the VFD no longer drives the spindle (Delta: not in
//! the run state; generic: the running bit clear), retrying within a bounded time; an error
//! says the stop could not be confirmed. Two reads, because RTU answers carry no
//! transaction number: after a timed-out request whose answer came late, the next read can
//! be answered with that older status; the second read's answer is then the first one's. When the backend is dropped (every exit of the program, also a panic
//! unwinding) the worker does the same unless a stop was already tried since the last
//! speed command, and logs an error when it cannot confirm it.

use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use klar_motion::{AxisFault, BackendError, SpindleBackend, SpindleFeedback};
use tokio::sync::{mpsc, watch};
use tokio::time::MissedTickBehavior;
use tracing::{error, info, warn};

use super::image::{plan_reads, read_image};
use super::link::{LinkStats, ModbusLink};
use super::vfd_map::{VfdProfile, VfdStatus};
use super::worker::{Call, Shared, call, command_wait, spawn};
use super::{ModbusError, ModbusVfdConfig};

/// What the worker last learned about the VFD.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct VfdSnapshot {
    /// Last decoded status.
    pub status: Option<VfdStatus>,
    /// The speed the VFD has been told (rpm), once the write succeeded.
    pub written_rpm: Option<f64>,
    /// Active fault.
    pub fault: Option<AxisFault>,
    /// The last communication failure, in words.
    pub last_error: Option<String>,
    /// Completed status polls.
    pub polls: u64,
    /// Link counters.
    pub stats: LinkStats,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Command {
    ResetFault,
    /// Write the stop and read the status back until the VFD confirms it.
    Stop,
}

/// A Modbus RTU spindle VFD.
pub struct ModbusVfd {
    commands: Option<mpsc::UnboundedSender<Call<Command>>>,
    rpm: watch::Sender<f64>,
    snapshot: Shared<VfdSnapshot>,
    max_rpm: f64,
    at_speed_fraction: f64,
    at_speed_min_rpm: f64,
    wait: Duration,
    /// How long a confirmed stop may take, with a margin for the last transaction.
    stop_wait: Duration,
    /// "spindle VFD (Modbus unit 1 on /dev/ttyUSB1)", for messages.
    device: String,
    thread: Option<JoinHandle<()>>,
}

impl std::fmt::Debug for ModbusVfd {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ModbusVfd")
            .field("snapshot", &*self.snapshot.lock())
            .finish()
    }
}

impl ModbusVfd {
    /// Validates `config`, opens the port and starts polling the VFD. The VFD is
    /// commanded to stop first.
    pub fn open(config: &ModbusVfdConfig) -> Result<Self, ModbusError> {
        config.validate()?;
        let poll = super::config::positive_seconds("poll_period", config.poll_period)?;
        let profile = VfdProfile::from_preset(&config.profile);
        let snapshot = Shared::new(VfdSnapshot::default());
        let (commands, command_rx) = mpsc::unbounded_channel();
        let (rpm, rpm_rx) = watch::channel(0.0);
        let shared = snapshot.clone();
        let name = format!("modbus-vfd-{}", config.unit);
        let device = describe(config);
        let stop_budget = stop_budget(config, poll);
        let worker_device = device.clone();
        let thread = spawn(&name, config.serial.clone(), config.unit, move |link| {
            let worker = VfdWorker {
                link,
                profile,
                snapshot: shared,
                rpm: rpm_rx,
                written: None,
                status: None,
                comm_fault: None,
                exception: None,
                vfd_fault: None,
                device: worker_device,
                poll,
                stop_budget,
                stop_tried: false,
            };
            worker.run(command_rx)
        })?;
        Ok(Self {
            commands: Some(commands),
            rpm,
            snapshot,
            max_rpm: config.max_rpm,
            at_speed_fraction: config.at_speed_fraction,
            at_speed_min_rpm: config.at_speed_min_rpm,
            wait: command_wait(&config.serial, 4, poll),
            stop_wait: stop_budget.saturating_add(command_wait(&config.serial, 2, poll)),
            device,
            thread: Some(thread),
        })
    }

    /// The device in words: "spindle VFD (Modbus unit 1 on /dev/ttyUSB1)".
    pub fn device(&self) -> &str {
        &self.device
    }

    /// What the worker last learned about the VFD.
    pub fn snapshot(&self) -> VfdSnapshot {
        self.snapshot.lock().clone()
    }

    /// Acknowledges a VFD fault (and a latched communication fault).
    pub fn reset_fault(&mut self) -> Result<(), BackendError> {
        let commands = self
            .commands
            .as_ref()
            .ok_or_else(|| BackendError::InvalidState("backend closed".into()))?;
        call(commands, Command::ResetFault, self.wait)
            .map_err(|e| BackendError::Communication(e.to_string()))
    }

    /// True when `actual` is within the at-speed window of `commanded`.
    pub fn within_window(&self, commanded: f64, actual: f64) -> bool {
        let window = (commanded.abs() * self.at_speed_fraction).max(self.at_speed_min_rpm);
        (actual - commanded).abs() <= window
    }
}

impl Drop for ModbusVfd {
    fn drop(&mut self) {
        self.commands = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// "spindle VFD (Modbus unit 1 on PORT)".
fn describe(config: &ModbusVfdConfig) -> String {
    format!(
        "spindle VFD (Modbus unit {} on {})",
        config.unit, config.serial.port
    )
}

/// How long a confirmed stop is tried: two rounds of the stop writes and the status read,
/// each transaction with all its retries, plus a poll period.
fn stop_budget(config: &ModbusVfdConfig, poll: Duration) -> Duration {
    command_wait(&config.serial, 6, poll)
}

impl SpindleBackend for ModbusVfd {
    fn command(&mut self, rpm: f64) -> Result<(), BackendError> {
        if !rpm.is_finite() {
            return Err(BackendError::InvalidState(format!(
                "spindle speed {rpm} is not a number"
            )));
        }
        if rpm.abs() > self.max_rpm {
            return Err(BackendError::InvalidState(format!(
                "spindle speed {rpm} rpm beyond the VFD's max_rpm {}",
                self.max_rpm
            )));
        }
        self.rpm.send_replace(rpm);
        Ok(())
    }

    fn cycle(&mut self, _t: f64) -> Result<SpindleFeedback, BackendError> {
        if self.thread.as_ref().is_none_or(|t| t.is_finished()) {
            return Err(BackendError::Communication(
                "the Modbus worker thread has stopped".into(),
            ));
        }
        let commanded = *self.rpm.borrow();
        let snap = self.snapshot.lock();
        let rpm = snap.status.map_or(0.0, |s| s.rpm);
        let acknowledged = snap.written_rpm == Some(commanded);
        Ok(SpindleFeedback {
            // A VFD measures no spindle position.
            position: None,
            rpm,
            at_speed: acknowledged && snap.fault.is_none() && self.within_window(commanded, rpm),
            fault: snap.fault.clone(),
        })
    }

    fn stop_confirmed(&mut self) -> Result<(), BackendError> {
        self.rpm.send_replace(0.0);
        let commands = self.commands.as_ref().ok_or_else(|| {
            BackendError::Communication(format!(
                "{}: backend closed, stop not confirmed",
                self.device
            ))
        })?;
        call(commands, Command::Stop, self.stop_wait).map_err(|e| match e {
            e @ ModbusError::StopUnconfirmed { .. } => BackendError::Communication(e.to_string()),
            other => BackendError::Communication(format!(
                "{} did not confirm the stop: {other}",
                self.device
            )),
        })
    }

    fn fault_detail(&self) -> Option<String> {
        self.snapshot.lock().last_error.clone()
    }
}

struct VfdWorker {
    link: ModbusLink,
    profile: VfdProfile,
    snapshot: Shared<VfdSnapshot>,
    rpm: watch::Receiver<f64>,
    written: Option<f64>,
    status: Option<VfdStatus>,
    comm_fault: Option<String>,
    /// The exception code when the failure behind `comm_fault` was an exception answer.
    exception: Option<u8>,
    vfd_fault: Option<u16>,
    device: String,
    poll: Duration,
    stop_budget: Duration,
    /// A confirmed stop was tried since the last speed command.
    stop_tried: bool,
}

impl VfdWorker {
    async fn run(mut self, mut commands: mpsc::UnboundedReceiver<Call<Command>>) {
        let mut ticker = tokio::time::interval(self.poll);
        ticker.set_missed_tick_behavior(MissedTickBehavior::Delay);
        loop {
            tokio::select! {
                call = commands.recv() => {
                    let Some(call) = call else { break };
                    let result = match call.command {
                        Command::ResetFault => self.reset().await,
                        Command::Stop => self.stop_confirmed().await,
                    };
                    let _ = call.reply.send(result);
                    self.poll_once().await;
                }
                _ = ticker.tick() => self.poll_once().await,
            }
        }
        // Leaving (the backend was dropped, also while a panic unwinds): stop the spindle
        // unless that was tried since the last speed command, whatever the link's state.
        if !self.stop_tried
            && let Err(e) = self.stop_confirmed().await
        {
            error!(unit = self.link.unit(), "{e}: the spindle may still turn");
        }
    }

    /// Writes the stop (until acknowledged) and reads the status until two reads in a row
    /// show that the VFD no longer drives the spindle, every poll period, within the stop
    /// budget.
    async fn stop_confirmed(&mut self) -> Result<(), ModbusError> {
        self.stop_tried = true;
        let started = Instant::now();
        let deadline = started + self.stop_budget;
        let mut acknowledged = false;
        let mut stopped_reads = 0;
        let mut last = String::from("no answer");
        loop {
            if !acknowledged {
                match self.write(0.0).await {
                    Ok(()) => acknowledged = true,
                    Err(e) => last = e.to_string(),
                }
            }
            if acknowledged {
                match self.read_status().await {
                    Ok(Some(status)) => {
                        self.status = Some(status);
                        stopped_reads = if status.running { 0 } else { stopped_reads + 1 };
                        last = format!(
                            "the stop was acknowledged but the VFD still reports running at \
                             {:.0} rpm",
                            status.rpm
                        );
                        if stopped_reads == 1 {
                            last = "one status read showed the stop, no second one".into();
                        }
                        if stopped_reads >= 2 {
                            info!(
                                unit = self.link.unit(),
                                rpm = status.rpm,
                                "VFD confirms the stop"
                            );
                            self.publish();
                            return Ok(());
                        }
                    }
                    Ok(None) => {
                        stopped_reads = 0;
                        last = "the status registers could not be decoded".into();
                    }
                    Err(e) => {
                        stopped_reads = 0;
                        last = e.to_string();
                    }
                }
            }
            if Instant::now() + self.poll >= deadline {
                break;
            }
            tokio::time::sleep(self.poll).await;
        }
        self.publish();
        Err(ModbusError::StopUnconfirmed {
            device: self.device.clone(),
            waited: started.elapsed(),
            reason: last,
        })
    }

    async fn read_status(&mut self) -> Result<Option<VfdStatus>, ModbusError> {
        let (table, addresses) = self.profile.status_addresses();
        let blocks = plan_reads(&addresses, 8);
        let image = read_image(&mut self.link, table, &blocks).await?;
        Ok(self.profile.decode(&image))
    }

    async fn write(&mut self, rpm: f64) -> Result<(), ModbusError> {
        if rpm != 0.0 {
            // From the first byte of a run command on, the VFD may turn.
            self.stop_tried = false;
        }
        for (address, value) in self.profile.command_writes(rpm) {
            self.link.write_single(address, value).await?;
        }
        self.written = Some(rpm);
        Ok(())
    }

    async fn reset(&mut self) -> Result<(), ModbusError> {
        for (address, value) in self.profile.fault_reset_writes() {
            self.link.write_single(address, value).await?;
        }
        self.comm_fault = None;
        self.exception = None;
        self.vfd_fault = None;
        info!(unit = self.link.unit(), "VFD fault reset");
        Ok(())
    }

    async fn poll_once(&mut self) {
        let result = self.exchange().await;
        match result {
            Ok(()) => {
                let commanded = *self.rpm.borrow();
                if self.comm_fault.is_some() && commanded == 0.0 && self.written == Some(0.0) {
                    info!(
                        unit = self.link.unit(),
                        "VFD answers again; spindle stopped"
                    );
                    self.comm_fault = None;
                    self.exception = None;
                }
            }
            Err(e) => {
                self.exception = match &e {
                    ModbusError::Exception { code, .. } => Some(*code),
                    _ => None,
                };
                if self.comm_fault.is_none() {
                    let what = if self.exception.is_some() {
                        "VFD refused a request"
                    } else {
                        "VFD communication lost"
                    };
                    error!(unit = self.link.unit(), "{what}, stopping spindle: {e}");
                }
                self.comm_fault = Some(e.to_string());
                // Force a new stop write once the link is back.
                self.written = None;
            }
        }
        self.publish();
    }

    async fn exchange(&mut self) -> Result<(), ModbusError> {
        let commanded = *self.rpm.borrow_and_update();
        // While faulted, the only thing written is a stop.
        let target = if self.comm_fault.is_some() || self.vfd_fault.is_some() {
            0.0
        } else {
            commanded
        };
        if self.written != Some(target) {
            self.write(target).await?;
        }
        let status = self.read_status().await?;
        if let Some(code) = status.and_then(|s| s.fault_code)
            && self.vfd_fault.is_none()
        {
            warn!(
                unit = self.link.unit(),
                code, "VFD reports a fault: spindle stopped"
            );
            self.vfd_fault = Some(code);
        }
        self.status = status;
        Ok(())
    }

    fn publish(&self) {
        let mut snap = self.snapshot.lock();
        snap.status = self.status;
        // Report the command only while it is the one in force.
        snap.written_rpm = if self.comm_fault.is_some() || self.vfd_fault.is_some() {
            None
        } else {
            self.written
        };
        snap.fault = if self.comm_fault.is_some() {
            Some(match self.exception {
                Some(code) => AxisFault::DeviceException {
                    code,
                    meaning: super::exception_name(code),
                },
                None => AxisFault::CommunicationLost,
            })
        } else {
            self.vfd_fault.map(|code| AxisFault::Drive {
                code: u32::from(code),
                text: format!("{} reports fault code {code}", self.device),
            })
        };
        snap.last_error.clone_from(&self.comm_fault);
        snap.polls += 1;
        snap.stats = self.link.stats();
    }
}
