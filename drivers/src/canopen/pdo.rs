//! PDO configuration over SDO: communication parameters (COB-ID, transmission type) and
//! mapping (which objects, in which order, fill the frame), following CiA 301's procedure
//! (disable the PDO, clear the mapping, write the entries, set their count, enable).

use super::{CanOpenError, Master};

/// Bit 31 of a PDO COB-ID entry: the PDO is not valid (disabled).
pub const COB_INVALID: u32 = 1 << 31;
/// Transmission type: synchronous, on every SYNC.
pub const TRANSMIT_EVERY_SYNC: u8 = 1;

/// One object mapped into a PDO.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PdoEntry {
    /// Object index.
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// Length in bits (8, 16 or 32).
    pub bits: u8,
}

impl PdoEntry {
    /// An entry for `index`/`sub` of `bits` bits.
    pub const fn new(index: u16, sub: u8, bits: u8) -> Self {
        Self { index, sub, bits }
    }

    /// The 32-bit mapping value: index, sub-index, length.
    pub fn mapping_value(self) -> u32 {
        (u32::from(self.index) << 16) | (u32::from(self.sub) << 8) | u32::from(self.bits)
    }

    /// The entry a mapping value describes.
    pub fn from_mapping_value(v: u32) -> Self {
        Self {
            index: (v >> 16) as u16,
            sub: (v >> 8) as u8,
            bits: v as u8,
        }
    }

    /// Length in bytes.
    pub fn bytes(self) -> usize {
        usize::from(self.bits).div_ceil(8)
    }
}

/// Which direction a PDO goes, seen from the drive.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PdoKind {
    /// Receive PDO: master → drive (parameters 0x1400+, mapping 0x1600+).
    Receive,
    /// Transmit PDO: drive → master (parameters 0x1800+, mapping 0x1A00+).
    Transmit,
}

/// A PDO to configure on a node.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PdoConfig {
    /// Direction.
    pub kind: PdoKind,
    /// PDO number, 1..=512.
    pub number: u16,
    /// The COB-ID it uses.
    pub cob_id: u16,
    /// Transmission type (1: every SYNC; 255: event-driven).
    pub transmission: u8,
    /// The mapped objects in frame order.
    pub entries: Vec<PdoEntry>,
}

impl PdoConfig {
    /// Bytes the PDO carries.
    pub fn len_bytes(&self) -> usize {
        self.entries.iter().map(|e| e.bytes()).sum()
    }

    /// The communication parameter object index.
    pub fn comm_index(&self) -> u16 {
        let base = match self.kind {
            PdoKind::Receive => 0x1400,
            PdoKind::Transmit => 0x1800,
        };
        base + self.number.saturating_sub(1)
    }

    /// The mapping object index.
    pub fn mapping_index(&self) -> u16 {
        let base = match self.kind {
            PdoKind::Receive => 0x1600,
            PdoKind::Transmit => 0x1A00,
        };
        base + self.number.saturating_sub(1)
    }
}

/// The default COB-ID of PDO `number` (1..=4) of `kind` on `node` (CiA 301's
/// pre-defined connection set).
pub fn default_cob_id(kind: PdoKind, number: u16, node: u8) -> Option<u16> {
    let base = match (kind, number) {
        (PdoKind::Transmit, 1..=4) => 0x180 + 0x100 * (number - 1),
        (PdoKind::Receive, 1..=4) => 0x200 + 0x100 * (number - 1),
        _ => return None,
    };
    Some(base + u16::from(node))
}

/// Errors of a PDO layout itself, found before anything is sent.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PdoLayoutError {
    /// More than 8 bytes mapped.
    #[error("PDO {number} maps {bytes} bytes, more than the 8 a CAN frame holds")]
    TooLong {
        /// The PDO number.
        number: u16,
        /// Bytes mapped.
        bytes: usize,
    },
    /// An entry whose length is not a whole number of bytes up to 32 bits.
    #[error("PDO {number}: entry 0x{index:04X}:{sub} has {bits} bits (use 8, 16 or 32)")]
    BadLength {
        /// The PDO number.
        number: u16,
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Its length.
        bits: u8,
    },
}

/// Checks that a PDO fits a classic CAN frame.
pub fn check_layout(pdo: &PdoConfig) -> Result<(), PdoLayoutError> {
    for e in &pdo.entries {
        if !matches!(e.bits, 8 | 16 | 32) {
            return Err(PdoLayoutError::BadLength {
                number: pdo.number,
                index: e.index,
                sub: e.sub,
                bits: e.bits,
            });
        }
    }
    let bytes = pdo.len_bytes();
    if bytes > 8 {
        return Err(PdoLayoutError::TooLong {
            number: pdo.number,
            bytes,
        });
    }
    Ok(())
}

impl Master {
    /// Configures one PDO of `node` over SDO (the node must be pre-operational).
    pub fn configure_pdo(&mut self, node: u8, pdo: &PdoConfig) -> Result<(), CanOpenError> {
        let comm = pdo.comm_index();
        let map = pdo.mapping_index();
        let cob = u32::from(pdo.cob_id);
        self.sdo_write(node, comm, 1, &(cob | COB_INVALID).to_le_bytes())?;
        self.sdo_write(node, comm, 2, &[pdo.transmission])?;
        self.sdo_write(node, map, 0, &[0])?;
        for (i, e) in pdo.entries.iter().enumerate() {
            let sub = u8::try_from(i + 1).unwrap_or(u8::MAX);
            self.sdo_write(node, map, sub, &e.mapping_value().to_le_bytes())?;
        }
        let count = u8::try_from(pdo.entries.len()).unwrap_or(u8::MAX);
        self.sdo_write(node, map, 0, &[count])?;
        self.sdo_write(node, comm, 1, &cob.to_le_bytes())?;
        tracing::debug!(node, ?pdo, "PDO configured");
        Ok(())
    }

    /// Disables PDO `number` of `kind` on `node` (sets the invalid bit of its COB-ID).
    pub fn disable_pdo(
        &mut self,
        node: u8,
        kind: PdoKind,
        number: u16,
    ) -> Result<(), CanOpenError> {
        let probe = PdoConfig {
            kind,
            number,
            cob_id: 0,
            transmission: 0,
            entries: Vec::new(),
        };
        let index = probe.comm_index();
        let current = self.sdo_read_u32(node, index, 1)?;
        self.sdo_write(node, index, 1, &(current | COB_INVALID).to_le_bytes())
    }
}

/// Packs values into a PDO payload following `entries` (little-endian, in order); each
/// value is truncated to its entry's length.
pub fn pack(entries: &[PdoEntry], values: &[u32]) -> Vec<u8> {
    let mut out = Vec::with_capacity(8);
    for (e, v) in entries.iter().zip(values) {
        out.extend_from_slice(&v.to_le_bytes()[..e.bytes().min(4)]);
    }
    out
}

/// Unpacks a PDO payload into one value per entry; `None` if the payload length differs
/// from the mapping's.
pub fn unpack(entries: &[PdoEntry], data: &[u8]) -> Option<Vec<u32>> {
    let total: usize = entries.iter().map(|e| e.bytes()).sum();
    if data.len() != total {
        return None;
    }
    let mut out = Vec::with_capacity(entries.len());
    let mut at = 0;
    for e in entries {
        let n = e.bytes().min(4);
        let mut b = [0u8; 4];
        b[..n].copy_from_slice(data.get(at..at + n)?);
        out.push(u32::from_le_bytes(b));
        at += n;
    }
    Some(out)
}
