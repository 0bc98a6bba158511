//! The touch-probe input of a simulated CiA 402 drive and its latch (0x60B8 … 0x60BB,
//! CiA 402-2): the input is high while the axis's true position lies past a trigger
//! position (a stylus deflected against a surface there); at an edge of the input the drive
//! latches the position its encoder reads at that instant, to the count.
//!
//! The latch follows 0x60B8 at every SYNC: bit 0 enables touch probe 1 (clearing it clears
//! the status); bits 4 and 5 choose the positive and negative edge; bit 1 clear latches only
//! the first event of each chosen edge, until the edge's bit (or bit 0) rises again; set, it
//! latches every event. Only source 0 (the probe input, bits 2–3) is wired: another source
//! never triggers. 0x60B9 bit 0 mirrors "enabled", bits 1 and 2 "positive / negative edge
//! position stored" (in 0x60BA / 0x60BB).

use klar_drivers::cia402::objects::*;

use super::od::ObjectDictionary;

/// Where the simulated probe input switches: it is high while the true position is at or
/// past `at` (above it when `above`, below it otherwise), in the plant's units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProbeInput {
    /// The trigger position, mm or degrees (the plant's true position, before any home
    /// offset of the drive).
    pub at: f64,
    /// True: high at or above `at`; false: at or below.
    pub above: bool,
}

impl ProbeInput {
    fn high(&self, position: f64) -> bool {
        if self.above {
            position >= self.at
        } else {
            position <= self.at
        }
    }
}

/// The latch of touch probe 1.
#[derive(Debug, Clone, Default)]
pub(crate) struct TouchProbe {
    /// 0x60B8 as seen at the last SYNC.
    function: u16,
    /// The positive / negative edge may still latch.
    armed: (bool, bool),
    /// 0x60B9.
    pub status: u16,
    /// 0x60BA and 0x60BB, counts.
    pub latched: (i32, i32),
}

impl TouchProbe {
    /// Writes 0x60B9 … 0x60BB into the drive's dictionary.
    pub(crate) fn publish(&self, od: &mut ObjectDictionary) {
        od.set(TOUCH_PROBE_STATUS, 0, u32::from(self.status));
        od.set(TOUCH_PROBE_1_POSITIVE, 0, self.latched.0 as u32);
        od.set(TOUCH_PROBE_1_NEGATIVE, 0, self.latched.1 as u32);
    }

    /// Takes 0x60B8 `function` (after an SDO write and at every SYNC, for a mapped one):
    /// the enable and edge bits that rose arm their latch and clear what it stored.
    pub(crate) fn apply(&mut self, function: u16) {
        let rose = |bit: u16| function & bit != 0 && self.function & bit == 0;
        if function & TP_ENABLE == 0 {
            self.status = 0;
            self.armed = (false, false);
        } else {
            self.status |= TPS_ENABLED;
            let enabled_now = rose(TP_ENABLE);
            if enabled_now || rose(TP_POSITIVE_EDGE) {
                self.armed.0 = function & TP_POSITIVE_EDGE != 0;
                self.status &= !TPS_POSITIVE_STORED;
            }
            if enabled_now || rose(TP_NEGATIVE_EDGE) {
                self.armed.1 = function & TP_NEGATIVE_EDGE != 0;
                self.status &= !TPS_NEGATIVE_STORED;
            }
            // an edge bit cleared stops that edge from latching
            self.armed.0 &= function & TP_POSITIVE_EDGE != 0;
            self.armed.1 &= function & TP_NEGATIVE_EDGE != 0;
        }
        self.function = function;
    }

    /// One SYNC: takes 0x60B8 `function` ([`TouchProbe::apply`]), and latches when the
    /// input switched while the true position went from `before` to `after`. `offset` is
    /// added to a true position to give the reported one; `counts_per_unit` scales it.
    pub(crate) fn step(
        &mut self,
        function: u16,
        input: Option<ProbeInput>,
        (before, after): (f64, f64),
        offset: f64,
        counts_per_unit: f64,
    ) {
        self.apply(function);
        let wired = function & TP_SOURCE_MASK == 0;
        let Some(input) = input.filter(|_| wired && function & TP_ENABLE != 0) else {
            return;
        };
        let (was, is) = (input.high(before), input.high(after));
        if was == is {
            return;
        }
        // the encoder reads the trigger position at the edge
        let counts = ((input.at + offset) * counts_per_unit)
            .round()
            .clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32;
        let continuous = function & TP_CONTINUOUS != 0;
        if is && self.armed.0 {
            self.latched.0 = counts;
            self.status |= TPS_POSITIVE_STORED;
            self.armed.0 = continuous;
        }
        if !is && self.armed.1 {
            self.latched.1 = counts;
            self.status |= TPS_NEGATIVE_STORED;
            self.armed.1 = continuous;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CPU: f64 = 1000.0;

    #[test]
    fn first_event_latches_once_and_rearms_on_the_edge_bit() {
        let input = Some(ProbeInput {
            at: 2.0,
            above: true,
        });
        let mut tp = TouchProbe::default();
        let arm = TP_ENABLE | TP_POSITIVE_EDGE;
        tp.step(arm, input, (0.0, 1.0), 0.5, CPU);
        assert_eq!(tp.status, TPS_ENABLED);
        tp.step(arm, input, (1.0, 2.5), 0.5, CPU);
        assert_eq!(tp.status, TPS_ENABLED | TPS_POSITIVE_STORED);
        assert_eq!(tp.latched.0, 2500);
        // back below and up again: the first event only
        tp.step(arm, input, (2.5, 1.0), 0.5, CPU);
        tp.step(arm, input, (1.0, 3.0), 0.0, CPU);
        assert_eq!(tp.latched.0, 2500);
        // the edge bit rises again: armed, the stored flag cleared
        tp.step(TP_ENABLE, input, (3.0, 1.0), 0.0, CPU);
        tp.step(arm, input, (1.0, 1.5), 0.0, CPU);
        assert_eq!(tp.status, TPS_ENABLED);
        tp.step(arm, input, (1.5, 2.2), 0.0, CPU);
        assert_eq!(tp.latched.0, 2000);
        // disabled: status cleared, nothing latches
        tp.step(0, input, (2.2, 0.0), 0.0, CPU);
        assert_eq!(tp.status, 0);
    }

    #[test]
    fn negative_edges_continuous_mode_and_other_sources() {
        let input = Some(ProbeInput {
            at: -1.0,
            above: false,
        });
        let mut tp = TouchProbe::default();
        let f = TP_ENABLE | TP_CONTINUOUS | TP_NEGATIVE_EDGE;
        tp.step(f, input, (0.0, -2.0), 0.0, CPU);
        assert_eq!(tp.status, TPS_ENABLED);
        tp.step(f, input, (-2.0, 0.0), 0.0, CPU);
        assert_eq!(tp.status, TPS_ENABLED | TPS_NEGATIVE_STORED);
        assert_eq!(tp.latched.1, -1000);
        tp.step(f, input, (0.0, -2.0), 0.25, CPU);
        tp.step(f, input, (-2.0, 0.0), 0.25, CPU);
        assert_eq!(tp.latched.1, -750, "continuous: every event");
        // the zero-impulse source (bits 2–3 = 01) is not wired
        let mut tp = TouchProbe::default();
        let g = TP_ENABLE | TP_POSITIVE_EDGE | (1 << 2);
        tp.step(g, input, (0.0, -2.0), 0.0, CPU);
        assert_eq!(tp.status, TPS_ENABLED);
    }
}
