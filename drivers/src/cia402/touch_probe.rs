//! The touch-probe function of CiA 402 drives (CiA 402-2, IEC 61800-7-201): a drive with a
//! probe input latches its own position at the input's edge, so the position a touch probe
//! triggered at is exact to a count whatever the servo period.
//!
//! klar arms touch probe 1 of an axis's drive through SDO: 0x60B8 with "enabled", "first
//! event only", source "touch-probe input 1" and "latch at the positive edge" (the stylus
//! deflecting raises the input). It then polls 0x60B9 until bit 1 says a positive-edge
//! position is stored, reads it from 0x60BA and turns the counts into mm or degrees with the
//! axis's scaling. Re-arming writes 0x60B8 = 0 first, so that the drive sees the enable bit
//! rise and clears what it stored before; disarming writes 0.

use super::backend::{Cia402Backend, lock};
use super::network::Cia402Error;
use super::objects::*;

/// 0x60B8 as klar arms touch probe 1: enabled, first event, input 1, positive edge.
pub const ARM_FIRST_POSITIVE: u16 = TP_ENABLE | TP_POSITIVE_EDGE;

/// What 0x60B9 says about touch probe 1.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TouchProbeStatus {
    /// The latch is enabled.
    pub enabled: bool,
    /// A position latched at a positive edge is stored in 0x60BA.
    pub positive: bool,
    /// A position latched at a negative edge is stored in 0x60BB.
    pub negative: bool,
}

impl TouchProbeStatus {
    /// Decodes 0x60B9.
    pub fn from_word(word: u16) -> Self {
        Self {
            enabled: word & TPS_ENABLED != 0,
            positive: word & TPS_POSITIVE_STORED != 0,
            negative: word & TPS_NEGATIVE_STORED != 0,
        }
    }
}

impl Cia402Backend {
    /// The node of axis `axis` (0 = the first axis drive).
    fn axis_node(&self, axis: usize) -> Result<(u8, super::scaling::Scaling), Cia402Error> {
        let net = lock(&self.net);
        if axis >= net.axes {
            return Err(Cia402Error::Config(format!(
                "touch probe: no axis drive {axis} on this bus ({} axes)",
                net.axes
            )));
        }
        let d = &net.drives[axis];
        Ok((d.node, d.scaling))
    }

    /// Arms touch probe 1 of axis `axis`'s drive: the next positive edge of its probe input
    /// latches the position (only that one).
    pub fn arm_touch_probe(&self, axis: usize) -> Result<(), Cia402Error> {
        let (node, _) = self.axis_node(axis)?;
        let mut net = lock(&self.net);
        net.master
            .sdo_write(node, TOUCH_PROBE_FUNCTION, 0, &0u16.to_le_bytes())?;
        net.master.sdo_write(
            node,
            TOUCH_PROBE_FUNCTION,
            0,
            &ARM_FIRST_POSITIVE.to_le_bytes(),
        )?;
        Ok(())
    }

    /// Switches touch probe 1 of axis `axis`'s drive off.
    pub fn disarm_touch_probe(&self, axis: usize) -> Result<(), Cia402Error> {
        let (node, _) = self.axis_node(axis)?;
        lock(&self.net)
            .master
            .sdo_write(node, TOUCH_PROBE_FUNCTION, 0, &0u16.to_le_bytes())?;
        Ok(())
    }

    /// Touch probe 1's status of axis `axis`'s drive (0x60B9).
    pub fn touch_probe_status(&self, axis: usize) -> Result<TouchProbeStatus, Cia402Error> {
        let (node, _) = self.axis_node(axis)?;
        let word = lock(&self.net)
            .master
            .sdo_read_u32(node, TOUCH_PROBE_STATUS, 0)?;
        Ok(TouchProbeStatus::from_word(word as u16))
    }

    /// The position (mm or degrees) axis `axis`'s drive latched at the positive edge of its
    /// probe input, once it has stored one; `None` while it has not.
    pub fn touch_probe_position(&self, axis: usize) -> Result<Option<f64>, Cia402Error> {
        let (node, scaling) = self.axis_node(axis)?;
        if !self.touch_probe_status(axis)?.positive {
            return Ok(None);
        }
        let counts = lock(&self.net)
            .master
            .sdo_read_u32(node, TOUCH_PROBE_1_POSITIVE, 0)? as i32;
        Ok(Some(scaling.to_units(counts)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_bits_decode_as_cia_402_2_lays_them_out() {
        assert_eq!(
            TouchProbeStatus::from_word(0b011),
            TouchProbeStatus {
                enabled: true,
                positive: true,
                negative: false
            }
        );
        assert_eq!(
            TouchProbeStatus::from_word(0b101),
            TouchProbeStatus {
                enabled: true,
                positive: false,
                negative: true
            }
        );
        // bits of touch probe 2 (8 … 10) are not probe 1's
        assert!(!TouchProbeStatus::from_word(0x0700).enabled);
        assert_eq!(ARM_FIRST_POSITIVE, 0x0011);
    }
}
