//! A simulated RS-485 line: a pseudo-terminal pair with a tokio-modbus RTU server on the
//! master side answering for the simulated devices; clients open the slave side's path
//! exactly like a USB-RS485 adapter.

use std::collections::BTreeMap;
use std::future::{Ready, ready};
use std::os::unix::fs::OpenOptionsExt;
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use klar_drivers::modbus::RegisterTable;
use tokio_modbus::prelude::{ExceptionCode, Request, Response, SlaveRequest};
use tokio_modbus::server::Service;
use tokio_serial::SerialPort;
use tracing::{debug, warn};

/// A device on the simulated line. `now` is seconds since the line started (wall clock),
/// so devices with dynamics advance between requests.
pub trait ModbusDevice: Send {
    /// Reads `count` registers from `table` at `address`.
    fn read(
        &mut self,
        table: RegisterTable,
        address: u16,
        count: u16,
        now: f64,
    ) -> Result<Vec<u16>, ExceptionCode>;

    /// Writes consecutive holding registers starting at `address`.
    fn write(&mut self, address: u16, values: &[u16], now: f64) -> Result<(), ExceptionCode>;

    /// False makes the device ignore requests (a dead or disconnected device).
    fn responds(&self) -> bool {
        true
    }
}

/// A device shared between the line and a test or the runtime.
pub type SharedDevice = Arc<Mutex<dyn ModbusDevice>>;

/// Addresses `address`, `address + 1`, … for `count` registers; an address beyond 0xFFFF is an
/// illegal data address (the request names registers that cannot exist).
pub fn addresses(address: u16, count: usize) -> impl Iterator<Item = Result<u16, ExceptionCode>> {
    (0..count).map(move |i| {
        u16::try_from(i)
            .ok()
            .and_then(|i| address.checked_add(i))
            .ok_or(ExceptionCode::IllegalDataAddress)
    })
}

/// Locks a shared device; a poisoned lock still gives the data.
pub fn lock_device(device: &SharedDevice) -> MutexGuard<'_, dyn ModbusDevice + 'static> {
    device.lock().unwrap_or_else(|p| p.into_inner())
}

/// Why the simulated line could not start.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimBusError {
    /// The pseudo-terminal could not be created.
    #[error("cannot create a pseudo-terminal: {0}")]
    Pty(String),
    /// The server thread could not start.
    #[error("cannot start the simulated Modbus line: {0}")]
    Thread(String),
    /// Two devices were given the same unit address, or an address outside 1..247.
    #[error("unit address {0} is used twice or outside 1..247")]
    Unit(u8),
}

/// Requests answered, per unit, for tests and reports.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct BusCounters {
    /// Requests answered (normal or exception response), by unit.
    pub answered: BTreeMap<u8, u64>,
    /// Requests for units not on the line or not responding (no answer given).
    pub ignored: u64,
}

#[derive(Clone)]
struct BusService {
    devices: Arc<BTreeMap<u8, SharedDevice>>,
    counters: Arc<Mutex<BusCounters>>,
    start: Instant,
}

impl BusService {
    fn handle(&self, req: SlaveRequest<'static>) -> Result<Option<Response>, ExceptionCode> {
        let unit = req.slave;
        let now = self.start.elapsed().as_secs_f64();
        let mut counters = self.counters.lock().unwrap_or_else(|p| p.into_inner());
        let Some(device) = self.devices.get(&unit) else {
            counters.ignored += 1;
            return Ok(None);
        };
        let mut device = lock_device(device);
        if !device.responds() {
            counters.ignored += 1;
            return Ok(None);
        }
        *counters.answered.entry(unit).or_default() += 1;
        drop(counters);
        debug!(unit, "simulated Modbus request {:?}", req.request);
        let response = match req.request {
            Request::ReadHoldingRegisters(a, n) => {
                Response::ReadHoldingRegisters(device.read(RegisterTable::Holding, a, n, now)?)
            }
            Request::ReadInputRegisters(a, n) => {
                Response::ReadInputRegisters(device.read(RegisterTable::Input, a, n, now)?)
            }
            Request::WriteSingleRegister(a, v) => {
                device.write(a, &[v], now)?;
                Response::WriteSingleRegister(a, v)
            }
            Request::WriteMultipleRegisters(a, values) => {
                device.write(a, &values, now)?;
                let n = u16::try_from(values.len()).map_err(|_| ExceptionCode::IllegalDataValue)?;
                Response::WriteMultipleRegisters(a, n)
            }
            _ => return Err(ExceptionCode::IllegalFunction),
        };
        Ok(Some(response))
    }
}

impl Service for BusService {
    type Request = SlaveRequest<'static>;
    type Response = Option<Response>;
    type Exception = ExceptionCode;
    type Future = Ready<Result<Self::Response, Self::Exception>>;

    fn call(&self, req: Self::Request) -> Self::Future {
        ready(self.handle(req))
    }
}

/// A running simulated line. Dropping it stops the server.
pub struct SimModbusBus {
    path: String,
    counters: Arc<Mutex<BusCounters>>,
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<JoinHandle<()>>,
}

impl std::fmt::Debug for SimModbusBus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SimModbusBus")
            .field("path", &self.path)
            .finish()
    }
}

impl SimModbusBus {
    /// Creates a pty pair and serves `devices` (unit address, device) on it.
    pub fn start(devices: Vec<(u8, SharedDevice)>) -> Result<Self, SimBusError> {
        let mut map = BTreeMap::new();
        for (unit, device) in devices {
            if !(1..=247).contains(&unit) || map.insert(unit, device).is_some() {
                return Err(SimBusError::Unit(unit));
            }
        }
        let counters = Arc::new(Mutex::new(BusCounters::default()));
        let service = BusService {
            devices: Arc::new(map),
            counters: Arc::clone(&counters),
            start: Instant::now(),
        };
        let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
        let (path_tx, path_rx) = std::sync::mpsc::sync_channel(1);
        let thread = std::thread::Builder::new()
            .name("sim-modbus-line".into())
            .spawn(move || {
                let runtime = match tokio::runtime::Builder::new_current_thread()
                    .enable_all()
                    .build()
                {
                    Ok(rt) => rt,
                    Err(e) => {
                        let _ = path_tx.send(Err(SimBusError::Thread(e.to_string())));
                        return;
                    }
                };
                runtime.block_on(async move {
                    let (master, slave) = match tokio_serial::SerialStream::pair() {
                        Ok(pair) => pair,
                        Err(e) => {
                            let _ = path_tx.send(Err(SimBusError::Pty(e.to_string())));
                            return;
                        }
                    };
                    let Some(path) = slave.name() else {
                        let _ = path_tx.send(Err(SimBusError::Pty("the pty has no name".into())));
                        return;
                    };
                    // A second, unlocked descriptor of the slave stays open (never read) so
                    // the master never sees a hang-up between client connections; the
                    // locked one from `pair` is closed so clients can take the port.
                    let keep_open = std::fs::OpenOptions::new()
                        .read(true)
                        .write(true)
                        .custom_flags(libc::O_NOCTTY | libc::O_NONBLOCK)
                        .open(&path);
                    let keep_open = match keep_open {
                        Ok(f) => f,
                        Err(e) => {
                            let _ = path_tx.send(Err(SimBusError::Pty(e.to_string())));
                            return;
                        }
                    };
                    drop(slave);
                    let _ = path_tx.send(Ok(path));
                    let server = tokio_modbus::server::rtu::Server::new(master);
                    let abort = async move {
                        let _ = stop_rx.await;
                    };
                    if let Err(e) = server.serve_until(service, abort).await {
                        warn!("simulated Modbus line stopped: {e}");
                    }
                    drop(keep_open);
                });
            })
            .map_err(|e| SimBusError::Thread(e.to_string()))?;
        let path = path_rx
            .recv_timeout(Duration::from_secs(10))
            .map_err(|_| SimBusError::Thread("the line did not start within 10 s".into()))??;
        Ok(Self {
            path,
            counters,
            stop: Some(stop_tx),
            thread: Some(thread),
        })
    }

    /// Path of the serial device clients open.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// Requests answered so far.
    pub fn counters(&self) -> BusCounters {
        self.counters
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .clone()
    }
}

impl Drop for SimModbusBus {
    fn drop(&mut self) {
        if let Some(stop) = self.stop.take() {
            let _ = stop.send(());
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
