//! A CANopen (CiA 301) master: network management (NMT), boot-up detection, the SDO
//! client, PDO configuration over SDO, the SYNC producer, and the EMCY and heartbeat
//! consumers.
//!
//! [`Master`] owns one [`CanBus`]. Everything it receives that is not the answer it is
//! waiting for is dispatched: emergencies, boot-ups and heartbeat state changes are queued
//! as [`NodeEvent`]s, and PDOs are kept per COB-ID as the latest [`PdoSample`].
//! Heartbeat supervision takes the time as an argument (the servo loop's clock), so that
//! simulated runs faster than real time supervise in simulated time.

pub mod busload;
pub mod emcy;
pub mod pdo;
pub mod sdo;

use std::collections::{BTreeMap, HashMap, VecDeque};
use std::time::{Duration, Instant};

use crate::can::{BusErrorKind, CanBus, CanError, CanEvent, CanFrame};
pub use emcy::Emergency;

/// COB-ID of NMT commands.
pub const NMT_COB: u16 = 0x000;
/// COB-ID of the SYNC message.
pub const SYNC_COB: u16 = 0x080;
/// COB-ID base of emergency messages (plus node ID).
pub const EMCY_BASE: u16 = 0x080;
/// COB-ID base of heartbeat and boot-up messages (plus node ID).
pub const HEARTBEAT_BASE: u16 = 0x700;

/// An NMT command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NmtCommand {
    /// Enter operational.
    Start,
    /// Enter stopped.
    Stop,
    /// Enter pre-operational.
    PreOperational,
    /// Reset the application (then boot-up).
    ResetNode,
    /// Reset communication parameters (then boot-up).
    ResetCommunication,
}

impl NmtCommand {
    /// The command specifier byte.
    pub fn specifier(self) -> u8 {
        match self {
            NmtCommand::Start => 0x01,
            NmtCommand::Stop => 0x02,
            NmtCommand::PreOperational => 0x80,
            NmtCommand::ResetNode => 0x81,
            NmtCommand::ResetCommunication => 0x82,
        }
    }

    /// The command for a specifier byte.
    pub fn from_specifier(cs: u8) -> Option<Self> {
        match cs {
            0x01 => Some(NmtCommand::Start),
            0x02 => Some(NmtCommand::Stop),
            0x80 => Some(NmtCommand::PreOperational),
            0x81 => Some(NmtCommand::ResetNode),
            0x82 => Some(NmtCommand::ResetCommunication),
            _ => None,
        }
    }
}

/// The NMT state a node reports in its heartbeat.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NmtState {
    /// Boot-up (sent once after reset).
    BootUp,
    /// Stopped.
    Stopped,
    /// Operational.
    Operational,
    /// Pre-operational.
    PreOperational,
}

impl NmtState {
    /// The heartbeat state byte.
    pub fn code(self) -> u8 {
        match self {
            NmtState::BootUp => 0x00,
            NmtState::Stopped => 0x04,
            NmtState::Operational => 0x05,
            NmtState::PreOperational => 0x7F,
        }
    }

    /// The state for a heartbeat byte (the toggle bit 7 of node guarding is ignored
    /// except in 0x7F).
    pub fn from_code(code: u8) -> Option<Self> {
        match code {
            0x00 => Some(NmtState::BootUp),
            0x04 | 0x84 => Some(NmtState::Stopped),
            0x05 | 0x85 => Some(NmtState::Operational),
            0x7F | 0xFF => Some(NmtState::PreOperational),
            _ => None,
        }
    }
}

/// Something a node reported.
#[derive(Debug, Clone, PartialEq)]
pub enum NodeEvent {
    /// The node booted (after power-on or an NMT reset).
    BootUp(u8),
    /// The node's heartbeat reports a new state.
    StateChanged(u8, NmtState),
    /// An emergency message.
    Emergency(Emergency),
    /// The node's heartbeat is overdue.
    HeartbeatLost {
        /// The node.
        node: u8,
        /// Seconds since its last heartbeat.
        silent_for: f64,
    },
    /// A frame from the node that breaks the protocol (wrong length, unknown state).
    Malformed {
        /// The node, when the COB-ID names one.
        node: Option<u8>,
        /// What is wrong.
        what: String,
    },
    /// The bus reported an error condition.
    Bus(BusErrorKind),
}

/// The latest data received on one PDO COB-ID.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PdoSample {
    /// The frame.
    pub frame: CanFrame,
    /// The number of SYNCs sent before it arrived.
    pub sync_count: u64,
}

/// Errors of the CANopen master; each names the node concerned.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CanOpenError {
    /// The bus failed.
    #[error("CAN bus: {0}")]
    Bus(#[from] CanError),
    /// The node aborted an SDO transfer.
    #[error("node {node}: SDO 0x{index:04X}:{sub} aborted with 0x{code:08X} ({name})")]
    SdoAbort {
        /// The node.
        node: u8,
        /// The object index.
        index: u16,
        /// The sub-index.
        sub: u8,
        /// The abort code.
        code: u32,
        /// Its CiA 301 name.
        name: &'static str,
    },
    /// The node did not answer an SDO request in time.
    #[error("node {node}: no SDO answer for 0x{index:04X}:{sub} within {timeout_ms} ms")]
    SdoTimeout {
        /// The node.
        node: u8,
        /// The object index.
        index: u16,
        /// The sub-index.
        sub: u8,
        /// The wait in milliseconds.
        timeout_ms: u64,
    },
    /// The node answered an SDO request against the protocol.
    #[error("node {node}: SDO 0x{index:04X}:{sub}: {what}")]
    SdoProtocol {
        /// The node.
        node: u8,
        /// The object index.
        index: u16,
        /// The sub-index.
        sub: u8,
        /// What was wrong.
        what: String,
    },
    /// Nodes that did not send their boot-up message in time.
    #[error("no boot-up from node(s) {nodes:?} within {timeout_ms} ms{}", unexpected_text(.unexpected))]
    BootTimeout {
        /// The silent nodes.
        nodes: Vec<u8>,
        /// The wait in milliseconds.
        timeout_ms: u64,
        /// Nodes that did boot but are not configured (a drive set to another node ID?).
        unexpected: Vec<u8>,
    },
    /// A node ID outside 1..=127.
    #[error("node ID {0} outside 1..=127")]
    BadNodeId(u8),
}

/// ` (boot-up from node(s) [..], not configured: ...)` when other nodes answered.
fn unexpected_text(unexpected: &[u8]) -> String {
    if unexpected.is_empty() {
        String::new()
    } else {
        format!(
            "; boot-up from node(s) {unexpected:?}, which are not configured: is a drive set \
             to another node ID?"
        )
    }
}

#[derive(Debug, Clone, Default)]
struct NodeStatus {
    state: Option<NmtState>,
    last_heartbeat: Option<f64>,
    heartbeat_timeout: Option<f64>,
    lost_reported: bool,
}

/// A CANopen master on one bus.
pub struct Master {
    bus: Box<dyn CanBus>,
    sdo_timeout: Duration,
    nodes: BTreeMap<u8, NodeStatus>,
    events: VecDeque<NodeEvent>,
    pdos: HashMap<u16, PdoSample>,
    sync_count: u64,
    now: f64,
    bus_off: bool,
}

impl Master {
    /// A master on `bus` with the given SDO answer timeout.
    pub fn new(bus: Box<dyn CanBus>, sdo_timeout: Duration) -> Self {
        Self {
            bus,
            sdo_timeout,
            nodes: BTreeMap::new(),
            events: VecDeque::new(),
            pdos: HashMap::new(),
            sync_count: 0,
            now: 0.0,
            bus_off: false,
        }
    }

    /// The SDO answer timeout.
    pub fn sdo_timeout(&self) -> Duration {
        self.sdo_timeout
    }

    /// True once the bus reported bus-off (cleared by a successful send).
    pub fn is_bus_off(&self) -> bool {
        self.bus_off
    }

    /// Sends one frame.
    pub fn bus_send(&mut self, frame: &CanFrame) -> Result<(), CanOpenError> {
        match self.bus.send(frame) {
            Ok(()) => Ok(()),
            Err(CanError::BusOff) => {
                self.bus_off = true;
                Err(CanOpenError::Bus(CanError::BusOff))
            }
            Err(e) => Err(e.into()),
        }
    }

    fn bus_recv(&mut self, timeout: Duration) -> Result<Option<CanEvent>, CanOpenError> {
        Ok(self.bus.recv_timeout(timeout)?)
    }

    /// Sends an NMT command to `node` (0: all nodes).
    pub fn nmt(&mut self, command: NmtCommand, node: u8) -> Result<(), CanOpenError> {
        if node > 127 {
            return Err(CanOpenError::BadNodeId(node));
        }
        tracing::debug!(?command, node, "NMT");
        self.bus_send(&CanFrame::fixed(NMT_COB, &[command.specifier(), node]))
    }

    /// Sends SYNC and counts it. Everything received before is handled first, so that
    /// PDOs from earlier cycles are not taken for answers to this SYNC.
    pub fn sync(&mut self) -> Result<(), CanOpenError> {
        self.poll()?;
        self.bus_send(&CanFrame::fixed(SYNC_COB, &[]))?;
        self.sync_count += 1;
        Ok(())
    }

    /// SYNCs sent so far.
    pub fn sync_count(&self) -> u64 {
        self.sync_count
    }

    /// Supervises `node`'s heartbeat: silence longer than `timeout` seconds (in the time
    /// given to [`Master::set_time`]) raises [`NodeEvent::HeartbeatLost`].
    pub fn watch_heartbeat(&mut self, node: u8, timeout: f64) {
        let now = self.now;
        let status = self.nodes.entry(node).or_default();
        status.heartbeat_timeout = Some(timeout);
        status.last_heartbeat = Some(now);
        status.lost_reported = false;
    }

    /// Sets the supervision clock (seconds) and checks heartbeats against it.
    pub fn set_time(&mut self, now: f64) {
        self.now = now;
        for (&node, status) in self.nodes.iter_mut() {
            if let (Some(timeout), Some(last)) = (status.heartbeat_timeout, status.last_heartbeat)
                && now - last > timeout
                && !status.lost_reported
            {
                status.lost_reported = true;
                self.events.push_back(NodeEvent::HeartbeatLost {
                    node,
                    silent_for: now - last,
                });
            }
        }
    }

    /// The last NMT state `node` reported.
    pub fn node_state(&self, node: u8) -> Option<NmtState> {
        self.nodes.get(&node).and_then(|s| s.state)
    }

    /// Handles everything already received, without waiting.
    pub fn poll(&mut self) -> Result<(), CanOpenError> {
        while let Some(ev) = self.bus_recv(Duration::ZERO)? {
            self.dispatch(ev);
        }
        Ok(())
    }

    /// Receives for up to `wait` until every COB-ID in `cobs` has a sample that arrived
    /// after the latest SYNC; returns the COB-IDs still missing.
    pub fn await_pdos(&mut self, cobs: &[u16], wait: Duration) -> Result<Vec<u16>, CanOpenError> {
        let deadline = Instant::now() + wait;
        loop {
            self.poll()?;
            let missing: Vec<u16> = cobs
                .iter()
                .copied()
                .filter(|c| {
                    self.pdos
                        .get(c)
                        .is_none_or(|s| s.sync_count < self.sync_count)
                })
                .collect();
            let now = Instant::now();
            if missing.is_empty() || now >= deadline {
                return Ok(missing);
            }
            if let Some(ev) = self.bus_recv(deadline - now)? {
                self.dispatch(ev);
            }
        }
    }

    /// The latest sample received on `cob`.
    pub fn pdo(&self, cob: u16) -> Option<&PdoSample> {
        self.pdos.get(&cob)
    }

    /// Puts events back at the front of the queue, in order.
    pub fn requeue(&mut self, events: Vec<NodeEvent>) {
        for ev in events.into_iter().rev() {
            self.events.push_front(ev);
        }
    }

    /// Takes the next queued node event.
    pub fn next_event(&mut self) -> Option<NodeEvent> {
        self.events.pop_front()
    }

    /// Resets communication of `nodes` and waits up to `timeout` for each boot-up.
    pub fn reset_and_wait_boot(
        &mut self,
        nodes: &[u8],
        timeout: Duration,
    ) -> Result<(), CanOpenError> {
        for &n in nodes {
            if n == 0 || n > 127 {
                return Err(CanOpenError::BadNodeId(n));
            }
            self.nodes.entry(n).or_default().state = None;
        }
        self.nmt(NmtCommand::ResetCommunication, 0)?;
        let deadline = Instant::now() + timeout;
        loop {
            let missing: Vec<u8> = nodes
                .iter()
                .copied()
                .filter(|n| self.nodes.get(n).and_then(|s| s.state).is_none())
                .collect();
            if missing.is_empty() {
                return Ok(());
            }
            let now = Instant::now();
            if now >= deadline {
                let unexpected = self
                    .nodes
                    .iter()
                    .filter(|(n, s)| s.state.is_some() && !nodes.contains(n))
                    .map(|(&n, _)| n)
                    .collect();
                return Err(CanOpenError::BootTimeout {
                    nodes: missing,
                    timeout_ms: timeout.as_millis() as u64,
                    unexpected,
                });
            }
            if let Some(ev) = self.bus_recv(deadline - now)? {
                self.dispatch(ev);
            }
        }
    }

    /// Sorts one received event into node state, PDO samples and the event queue.
    pub(crate) fn dispatch(&mut self, event: CanEvent) {
        let frame = match event {
            CanEvent::Frame { frame, .. } => frame,
            CanEvent::Error(kind) => {
                if kind == BusErrorKind::BusOff {
                    self.bus_off = true;
                }
                self.events.push_back(NodeEvent::Bus(kind));
                return;
            }
        };
        let Some(cob) = frame.id().standard() else {
            return;
        };
        let node = (cob & 0x7F) as u8;
        match cob & 0x780 {
            0x080 if node != 0 => match Emergency::decode(node, frame.data()) {
                Some(e) => {
                    tracing::warn!("{e}");
                    self.events.push_back(NodeEvent::Emergency(e));
                }
                None => self.events.push_back(NodeEvent::Malformed {
                    node: Some(node),
                    what: format!("EMCY with {} bytes instead of 8", frame.data().len()),
                }),
            },
            0x700 if node != 0 => {
                let state = match frame.data() {
                    [b] => NmtState::from_code(*b),
                    _ => None,
                };
                let Some(state) = state else {
                    self.events.push_back(NodeEvent::Malformed {
                        node: Some(node),
                        what: format!("heartbeat {:?} is not a state byte", frame.data()),
                    });
                    return;
                };
                let now = self.now;
                let status = self.nodes.entry(node).or_default();
                status.last_heartbeat = Some(now);
                if status.lost_reported {
                    tracing::info!(node, "heartbeat back");
                    status.lost_reported = false;
                }
                if state == NmtState::BootUp {
                    status.state = Some(NmtState::PreOperational);
                    self.events.push_back(NodeEvent::BootUp(node));
                } else if status.state != Some(state) {
                    status.state = Some(state);
                    self.events.push_back(NodeEvent::StateChanged(node, state));
                }
            }
            0x180..=0x500 => {
                self.pdos.insert(
                    cob,
                    PdoSample {
                        frame,
                        sync_count: self.sync_count,
                    },
                );
            }
            _ => {}
        }
    }
}
