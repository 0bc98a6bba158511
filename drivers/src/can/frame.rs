//! CAN 2.0 frames: 11-bit or 29-bit identifiers, up to 8 data bytes, data or remote.

use std::fmt;

/// The largest standard (11-bit) identifier.
pub const MAX_STANDARD_ID: u16 = 0x7FF;
/// The largest extended (29-bit) identifier.
pub const MAX_EXTENDED_ID: u32 = 0x1FFF_FFFF;

/// A CAN identifier.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum CanId {
    /// An 11-bit identifier (0..=0x7FF).
    Standard(u16),
    /// A 29-bit identifier (0..=0x1FFF_FFFF).
    Extended(u32),
}

impl CanId {
    /// The raw identifier value.
    pub fn raw(self) -> u32 {
        match self {
            CanId::Standard(id) => u32::from(id),
            CanId::Extended(id) => id,
        }
    }

    /// The standard identifier, if this is one.
    pub fn standard(self) -> Option<u16> {
        match self {
            CanId::Standard(id) => Some(id),
            CanId::Extended(_) => None,
        }
    }
}

/// Why a frame could not be built.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FrameError {
    /// Identifier out of range for its format.
    #[error("CAN identifier 0x{0:X} out of range")]
    IdOutOfRange(u32),
    /// More than 8 data bytes.
    #[error("CAN frame with {0} data bytes (at most 8)")]
    TooLong(usize),
}

/// A classic CAN frame.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct CanFrame {
    id: CanId,
    len: u8,
    data: [u8; 8],
    remote: bool,
}

impl CanFrame {
    /// A data frame; fails if the identifier is out of range or there are more than 8 bytes.
    pub fn new(id: CanId, data: &[u8]) -> Result<Self, FrameError> {
        check_id(id)?;
        if data.len() > 8 {
            return Err(FrameError::TooLong(data.len()));
        }
        let mut buf = [0u8; 8];
        buf[..data.len()].copy_from_slice(data);
        Ok(Self {
            id,
            len: data.len() as u8,
            data: buf,
            remote: false,
        })
    }

    /// A data frame with an 11-bit identifier.
    pub fn standard(id: u16, data: &[u8]) -> Result<Self, FrameError> {
        Self::new(CanId::Standard(id), data)
    }

    /// A data frame with an 11-bit identifier built from protocol constants (for example
    /// a CANopen function code plus a node ID): the identifier is masked to 11 bits and data
    /// beyond 8 bytes is dropped, so this cannot fail.
    pub fn fixed(id: u16, data: &[u8]) -> Self {
        let len = data.len().min(8);
        let mut buf = [0u8; 8];
        buf[..len].copy_from_slice(&data[..len]);
        Self {
            id: CanId::Standard(id & MAX_STANDARD_ID),
            len: len as u8,
            data: buf,
            remote: false,
        }
    }

    /// A remote (RTR) frame requesting `dlc` bytes.
    pub fn remote(id: CanId, dlc: u8) -> Result<Self, FrameError> {
        check_id(id)?;
        if dlc > 8 {
            return Err(FrameError::TooLong(usize::from(dlc)));
        }
        Ok(Self {
            id,
            len: dlc,
            data: [0; 8],
            remote: true,
        })
    }

    /// The identifier.
    pub fn id(&self) -> CanId {
        self.id
    }

    /// The data bytes (empty for a remote frame).
    pub fn data(&self) -> &[u8] {
        if self.remote {
            &[]
        } else {
            &self.data[..usize::from(self.len)]
        }
    }

    /// The data length code (for remote frames: the requested length).
    pub fn dlc(&self) -> u8 {
        self.len
    }

    /// True for a remote (RTR) frame.
    pub fn is_remote(&self) -> bool {
        self.remote
    }

    /// Bits this frame occupies on the wire in the worst case, with bit stuffing.
    ///
    /// A standard data frame has 47 bits of overhead (44 before stuffing counts plus the
    /// 3-bit interframe space) and an extended one 67; stuffing can add one bit per four
    /// after the first of the 34 (standard) or 54 (extended) stuffable header bits plus
    /// the data.
    pub fn wire_bits(&self) -> u32 {
        worst_case_bits(matches!(self.id, CanId::Extended(_)), usize::from(self.len))
    }
}

/// Worst-case bits on the wire of a data frame with `len` data bytes, including stuff bits
/// and the interframe space.
pub fn worst_case_bits(extended: bool, len: usize) -> u32 {
    let data_bits = 8 * len.min(8) as u32;
    let (fixed, stuffable) = if extended {
        (67, 54 + data_bits)
    } else {
        (47, 34 + data_bits)
    };
    fixed + data_bits + (stuffable - 1) / 4
}

fn check_id(id: CanId) -> Result<(), FrameError> {
    match id {
        CanId::Standard(v) if v > MAX_STANDARD_ID => Err(FrameError::IdOutOfRange(u32::from(v))),
        CanId::Extended(v) if v > MAX_EXTENDED_ID => Err(FrameError::IdOutOfRange(v)),
        _ => Ok(()),
    }
}

impl fmt::Debug for CanFrame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.id {
            CanId::Standard(id) => write!(f, "{id:03X}")?,
            CanId::Extended(id) => write!(f, "{id:08X}")?,
        }
        if self.remote {
            return write!(f, " R{}", self.len);
        }
        write!(f, " [{}]", self.len)?;
        for b in self.data() {
            write!(f, " {b:02X}")?;
        }
        Ok(())
    }
}
