//! An in-memory CAN bus: any number of endpoints (each a [`CanBus`]) and attached
//! simulated devices, with fault injection (dropping or corrupting frames, bus-off).
//!
//! Devices attached with [`MemoryBus::attach`] answer synchronously: when an endpoint sends
//! a frame, every device sees it at once and its answers are delivered before `send`
//! returns. A master on the bus therefore runs in lock step with simulated drives and needs
//! no threads, which keeps simulated runs deterministic and as fast as the CPU allows.

use std::collections::VecDeque;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use super::{BusErrorKind, CanBus, CanError, CanEvent, CanFrame};

/// A simulated participant attached to an in-memory bus (or run on any bus by
/// [`super::device::DeviceRunner`]).
pub trait BusDevice: Send {
    /// Frames the device sends when it is attached (for CANopen: its boot-up message).
    fn start(&mut self, out: &mut Vec<CanFrame>);

    /// Handles one frame seen on the bus and pushes any answers to `out`.
    fn on_frame(&mut self, frame: &CanFrame, out: &mut Vec<CanFrame>);
}

/// What the fault injector does with a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameFate {
    /// Deliver unchanged.
    Deliver,
    /// Lose the frame.
    Drop,
    /// Deliver it with its last data byte removed (a malformed frame).
    Truncate,
}

type Injector = Box<dyn FnMut(&CanFrame) -> FrameFate + Send>;

struct Hub {
    queues: Vec<VecDeque<CanEvent>>,
    devices: Vec<Box<dyn BusDevice>>,
    injector: Option<Injector>,
    bus_off: bool,
    start: Instant,
    frames: u64,
}

struct Shared {
    hub: Mutex<Hub>,
    arrived: Condvar,
}

/// An in-memory CAN bus. Cloning gives another handle to the same bus.
#[derive(Clone)]
pub struct MemoryBus {
    shared: Arc<Shared>,
}

/// One participant's connection to a [`MemoryBus`].
pub struct MemoryEndpoint {
    shared: Arc<Shared>,
    index: usize,
}

impl Default for MemoryBus {
    fn default() -> Self {
        Self::new()
    }
}

impl MemoryBus {
    /// An empty bus.
    pub fn new() -> Self {
        Self {
            shared: Arc::new(Shared {
                hub: Mutex::new(Hub {
                    queues: Vec::new(),
                    devices: Vec::new(),
                    injector: None,
                    bus_off: false,
                    start: Instant::now(),
                    frames: 0,
                }),
                arrived: Condvar::new(),
            }),
        }
    }

    fn lock(&self) -> MutexGuard<'_, Hub> {
        lock(&self.shared)
    }

    /// A new endpoint; it receives every frame sent after its creation by others.
    pub fn endpoint(&self) -> MemoryEndpoint {
        let mut hub = self.lock();
        hub.queues.push(VecDeque::new());
        MemoryEndpoint {
            shared: Arc::clone(&self.shared),
            index: hub.queues.len() - 1,
        }
    }

    /// Attaches a device; the frames it sends on start are delivered at once.
    pub fn attach(&self, mut device: Box<dyn BusDevice>) {
        let mut out = Vec::new();
        device.start(&mut out);
        let mut hub = self.lock();
        hub.devices.push(device);
        let from = Sender::Device(hub.devices.len() - 1);
        for f in out {
            deliver(&mut hub, f, from);
        }
        drop(hub);
        self.shared.arrived.notify_all();
    }

    /// Installs a fault injector that decides the fate of every frame from now on.
    pub fn set_injector(&self, injector: impl FnMut(&CanFrame) -> FrameFate + Send + 'static) {
        self.lock().injector = Some(Box::new(injector));
    }

    /// Removes the fault injector.
    pub fn clear_injector(&self) {
        self.lock().injector = None;
    }

    /// Puts the bus into bus-off (`true`): sends fail and every endpoint gets a bus-off
    /// event; `false` recovers.
    pub fn set_bus_off(&self, off: bool) {
        let mut hub = self.lock();
        if off && !hub.bus_off {
            for q in hub.queues.iter_mut() {
                q.push_back(CanEvent::Error(BusErrorKind::BusOff));
            }
        }
        hub.bus_off = off;
        drop(hub);
        self.shared.arrived.notify_all();
    }

    /// Frames carried so far (after fault injection).
    pub fn frames_carried(&self) -> u64 {
        self.lock().frames
    }
}

fn lock(shared: &Shared) -> MutexGuard<'_, Hub> {
    // A panic while holding the lock cannot leave the queues half-updated in a way that
    // matters to a test bus, so a poisoned lock is simply taken over.
    shared.hub.lock().unwrap_or_else(|p| p.into_inner())
}

#[derive(Clone, Copy, PartialEq)]
enum Sender {
    Endpoint(usize),
    Device(usize),
}

/// Delivers `frame` from `from` to every other participant, then the devices' answers,
/// breadth first.
fn deliver(hub: &mut Hub, frame: CanFrame, from: Sender) {
    let mut pending = VecDeque::from([(frame, from)]);
    let mut out = Vec::new();
    while let Some((frame, from)) = pending.pop_front() {
        let frame = match hub
            .injector
            .as_mut()
            .map_or(FrameFate::Deliver, |f| f(&frame))
        {
            FrameFate::Deliver => frame,
            FrameFate::Drop => continue,
            FrameFate::Truncate => {
                let data = frame.data();
                let cut = &data[..data.len().saturating_sub(1)];
                CanFrame::new(frame.id(), cut).unwrap_or(frame)
            }
        };
        hub.frames += 1;
        let timestamp = hub.start.elapsed().as_secs_f64();
        for (i, q) in hub.queues.iter_mut().enumerate() {
            if from != Sender::Endpoint(i) {
                q.push_back(CanEvent::Frame { frame, timestamp });
            }
        }
        for i in 0..hub.devices.len() {
            if from == Sender::Device(i) {
                continue;
            }
            if let Some(dev) = hub.devices.get_mut(i) {
                dev.on_frame(&frame, &mut out);
            }
            for f in out.drain(..) {
                pending.push_back((f, Sender::Device(i)));
            }
        }
    }
}

impl CanBus for MemoryEndpoint {
    fn send(&mut self, frame: &CanFrame) -> Result<(), CanError> {
        let mut hub = lock(&self.shared);
        if hub.bus_off {
            return Err(CanError::BusOff);
        }
        deliver(&mut hub, *frame, Sender::Endpoint(self.index));
        drop(hub);
        self.shared.arrived.notify_all();
        Ok(())
    }

    fn recv_timeout(&mut self, timeout: Duration) -> Result<Option<CanEvent>, CanError> {
        let deadline = Instant::now() + timeout;
        let mut hub = lock(&self.shared);
        loop {
            if let Some(ev) = hub.queues.get_mut(self.index).and_then(|q| q.pop_front()) {
                return Ok(Some(ev));
            }
            let now = Instant::now();
            if now >= deadline {
                return Ok(None);
            }
            hub = self
                .shared
                .arrived
                .wait_timeout(hub, deadline - now)
                .map(|(g, _)| g)
                .unwrap_or_else(|p| p.into_inner().0);
        }
    }
}
