//! Runs a simulated [`BusDevice`] on any [`CanBus`] in a thread of its own (for example a
//! simulated drive behind an slcan pseudo-terminal), until stopped or dropped.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

use super::memory::BusDevice;
use super::{CanBus, CanEvent};

/// A device running on a bus in a background thread.
pub struct DeviceRunner {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl DeviceRunner {
    /// Starts `device` on `bus`: sends its start frames, then answers every frame.
    pub fn spawn(
        mut device: Box<dyn BusDevice>,
        mut bus: Box<dyn CanBus>,
    ) -> std::io::Result<Self> {
        let stop = Arc::new(AtomicBool::new(false));
        let flag = Arc::clone(&stop);
        let thread = std::thread::Builder::new()
            .name("can-device".into())
            .spawn(move || {
                let mut out = Vec::new();
                device.start(&mut out);
                while !flag.load(Ordering::Relaxed) {
                    for f in out.drain(..) {
                        if let Err(e) = bus.send(&f) {
                            tracing::warn!(error = %e, "simulated device: send failed");
                        }
                    }
                    match bus.recv_timeout(Duration::from_millis(20)) {
                        Ok(Some(CanEvent::Frame { frame, .. })) => {
                            device.on_frame(&frame, &mut out)
                        }
                        Ok(Some(CanEvent::Error(e))) => {
                            tracing::debug!(%e, "simulated device: bus error")
                        }
                        Ok(None) => {}
                        Err(e) => {
                            tracing::warn!(error = %e, "simulated device: bus closed");
                            return;
                        }
                    }
                }
            })?;
        Ok(Self {
            stop,
            thread: Some(thread),
        })
    }

    /// Stops the device and waits for its thread.
    pub fn stop(mut self) {
        self.halt();
    }

    fn halt(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for DeviceRunner {
    fn drop(&mut self) {
        self.halt();
    }
}
