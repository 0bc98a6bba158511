//! The simulated drive's object dictionary and its SDO server (expedited and segmented
//! transfers, CiA 301 abort codes for unknown objects, read-only entries, wrong lengths,
//! values outside an entry's allowed set and PDO mappings changed while the PDO is valid).

use std::collections::BTreeMap;

use klar_drivers::canopen::pdo::{COB_INVALID, PdoEntry};
use klar_drivers::canopen::sdo::{
    ABORT_COMMAND, ABORT_DEVICE_STATE, ABORT_LENGTH, ABORT_NO_OBJECT, ABORT_NO_SUBINDEX,
    ABORT_NOT_MAPPABLE, ABORT_PDO_LENGTH, ABORT_READ_ONLY, ABORT_TOGGLE, ABORT_VALUE,
};

/// Whether an entry may be written over SDO.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    /// Read only.
    ReadOnly,
    /// Read and write.
    ReadWrite,
}

/// One object dictionary entry.
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    /// Current value, little-endian.
    pub value: Vec<u8>,
    /// Access over SDO.
    pub access: Access,
    /// True when the length is fixed (numbers); false for strings and domains.
    pub fixed_len: bool,
    /// True when the entry may be mapped into a PDO.
    pub mappable: bool,
}

/// An object dictionary: entries by (index, sub-index).
#[derive(Debug, Clone, Default)]
pub struct ObjectDictionary {
    entries: BTreeMap<(u16, u8), Entry>,
    /// Entries that accept only some values over SDO (compared as unsigned numbers).
    allowed: BTreeMap<(u16, u8), Vec<u32>>,
}

impl ObjectDictionary {
    /// An empty dictionary.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a fixed-length numeric entry.
    pub fn add(&mut self, index: u16, sub: u8, value: &[u8], access: Access, mappable: bool) {
        self.entries.insert(
            (index, sub),
            Entry {
                value: value.to_vec(),
                access,
                fixed_len: true,
                mappable,
            },
        );
    }

    /// Adds a variable-length entry (string or domain).
    pub fn add_bytes(&mut self, index: u16, sub: u8, value: &[u8], access: Access) {
        self.entries.insert(
            (index, sub),
            Entry {
                value: value.to_vec(),
                access,
                fixed_len: false,
                mappable: false,
            },
        );
    }

    /// Limits what an SDO write may put into `index`/`sub` to `values` (as unsigned
    /// numbers of the entry's width); other values are refused with abort 0x0609_0030.
    pub fn restrict(&mut self, index: u16, sub: u8, values: Vec<u32>) {
        self.allowed.insert((index, sub), values);
    }

    /// The entry at `index`/`sub`.
    pub fn get(&self, index: u16, sub: u8) -> Option<&Entry> {
        self.entries.get(&(index, sub))
    }

    /// Reads a value of up to 4 bytes as u32 (0 when missing).
    pub fn u32(&self, index: u16, sub: u8) -> u32 {
        let mut b = [0u8; 4];
        if let Some(e) = self.get(index, sub) {
            for (dst, src) in b.iter_mut().zip(&e.value) {
                *dst = *src;
            }
        }
        u32::from_le_bytes(b)
    }

    /// Sets the value of an existing entry from the device side (no access check); the
    /// value is cut or zero-padded to the entry's length.
    pub fn set(&mut self, index: u16, sub: u8, value: u32) {
        if let Some(e) = self.entries.get_mut(&(index, sub)) {
            let len = e.value.len();
            let bytes = value.to_le_bytes();
            for (i, slot) in e.value.iter_mut().enumerate().take(len) {
                *slot = bytes.get(i).copied().unwrap_or(0);
            }
        }
    }

    fn has_index(&self, index: u16) -> bool {
        self.entries
            .range((index, 0)..=(index, u8::MAX))
            .next()
            .is_some()
    }

    /// Checks and performs an SDO write; returns the abort code on refusal.
    pub fn write(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), u32> {
        let entry = match self.entries.get(&(index, sub)) {
            Some(e) => e,
            None if self.has_index(index) => return Err(ABORT_NO_SUBINDEX),
            None => return Err(ABORT_NO_OBJECT),
        };
        if entry.access == Access::ReadOnly {
            return Err(ABORT_READ_ONLY);
        }
        if entry.fixed_len && entry.value.len() != data.len() {
            return Err(ABORT_LENGTH);
        }
        if let Some(values) = self.allowed.get(&(index, sub)) {
            let mut b = [0u8; 4];
            for (dst, src) in b.iter_mut().zip(data) {
                *dst = *src;
            }
            if !values.contains(&u32::from_le_bytes(b)) {
                return Err(ABORT_VALUE);
            }
        }
        self.check_pdo_rules(index, sub, data)?;
        if let Some(e) = self.entries.get_mut(&(index, sub)) {
            e.value = data.to_vec();
        }
        Ok(())
    }

    /// CiA 301's rules for PDO mapping objects (0x1600.., 0x1A00..).
    fn check_pdo_rules(&self, index: u16, sub: u8, data: &[u8]) -> Result<(), u32> {
        let comm = match index {
            0x1600..=0x17FF => index - 0x200,
            0x1A00..=0x1BFF => index - 0x200,
            _ => return Ok(()),
        };
        if self.u32(comm, 1) & COB_INVALID == 0 {
            // The mapping of a valid PDO cannot change.
            return Err(ABORT_DEVICE_STATE);
        }
        if sub == 0 {
            let count = data.first().copied().unwrap_or(0);
            let mut bits = 0u32;
            for s in 1..=count {
                let e = PdoEntry::from_mapping_value(self.u32(index, s));
                bits += u32::from(e.bits);
            }
            if bits > 64 {
                return Err(ABORT_PDO_LENGTH);
            }
            return Ok(());
        }
        if self.u32(index, 0) != 0 {
            return Err(ABORT_DEVICE_STATE);
        }
        let mut b = [0u8; 4];
        for (dst, src) in b.iter_mut().zip(data) {
            *dst = *src;
        }
        let e = PdoEntry::from_mapping_value(u32::from_le_bytes(b));
        match self.get(e.index, e.sub) {
            Some(target) if target.mappable && target.value.len() * 8 == usize::from(e.bits) => {
                Ok(())
            }
            Some(_) => Err(ABORT_NOT_MAPPABLE),
            None => Err(ABORT_NOT_MAPPABLE),
        }
    }

    /// Checks and performs an SDO read.
    pub fn read(&self, index: u16, sub: u8) -> Result<Vec<u8>, u32> {
        match self.entries.get(&(index, sub)) {
            Some(e) => Ok(e.value.clone()),
            None if self.has_index(index) => Err(ABORT_NO_SUBINDEX),
            None => Err(ABORT_NO_OBJECT),
        }
    }
}

/// A segmented transfer in progress.
#[derive(Debug, Clone)]
enum Transfer {
    Idle,
    Download {
        index: u16,
        sub: u8,
        size: Option<usize>,
        buf: Vec<u8>,
        toggle: u8,
    },
    Upload {
        data: Vec<u8>,
        at: usize,
        toggle: u8,
    },
}

/// The SDO server state of one node.
#[derive(Debug, Clone)]
pub struct SdoServer {
    transfer: Transfer,
}

impl Default for SdoServer {
    fn default() -> Self {
        Self {
            transfer: Transfer::Idle,
        }
    }
}

fn answer(command: u8, index: u16, sub: u8, data: [u8; 4]) -> [u8; 8] {
    let [i0, i1] = index.to_le_bytes();
    let [d0, d1, d2, d3] = data;
    [command, i0, i1, sub, d0, d1, d2, d3]
}

fn abort(index: u16, sub: u8, code: u32) -> [u8; 8] {
    answer(0x80, index, sub, code.to_le_bytes())
}

impl SdoServer {
    /// Handles one request (the 8 data bytes of a frame to 0x600 + node) and returns the
    /// answer, or `None` for a client's abort (which is not answered).
    pub fn handle(&mut self, od: &mut ObjectDictionary, req: &[u8]) -> Option<[u8; 8]> {
        let Ok(req) = <[u8; 8]>::try_from(req) else {
            self.transfer = Transfer::Idle;
            return Some(abort(0, 0, ABORT_LENGTH));
        };
        let index = u16::from_le_bytes([req[1], req[2]]);
        let sub = req[3];
        let ccs = req[0] >> 5;
        match ccs {
            // Initiate download.
            1 => {
                self.transfer = Transfer::Idle;
                let expedited = req[0] & 0x02 != 0;
                let sized = req[0] & 0x01 != 0;
                if expedited {
                    let len = if sized {
                        4 - usize::from((req[0] >> 2) & 3)
                    } else {
                        4
                    };
                    let data = req.get(4..4 + len).unwrap_or_default();
                    Some(match od.write(index, sub, data) {
                        Ok(()) => answer(0x60, index, sub, [0; 4]),
                        Err(code) => abort(index, sub, code),
                    })
                } else {
                    let size = sized
                        .then(|| u32::from_le_bytes([req[4], req[5], req[6], req[7]]) as usize);
                    if let Err(code) = od.read(index, sub) {
                        return Some(abort(index, sub, code));
                    }
                    self.transfer = Transfer::Download {
                        index,
                        sub,
                        size,
                        buf: Vec::new(),
                        toggle: 0,
                    };
                    Some(answer(0x60, index, sub, [0; 4]))
                }
            }
            // Download segment.
            0 => {
                let Transfer::Download {
                    index,
                    sub,
                    size,
                    mut buf,
                    toggle,
                } = std::mem::replace(&mut self.transfer, Transfer::Idle)
                else {
                    return Some(abort(0, 0, ABORT_COMMAND));
                };
                if (req[0] >> 4) & 1 != toggle {
                    return Some(abort(index, sub, ABORT_TOGGLE));
                }
                let n = 7 - usize::from((req[0] >> 1) & 7);
                buf.extend_from_slice(req.get(1..1 + n).unwrap_or_default());
                let reply = answer(0x20 | (toggle << 4), 0, 0, [0; 4]);
                if req[0] & 1 != 0 {
                    if size.is_some_and(|s| s != buf.len()) {
                        return Some(abort(index, sub, ABORT_LENGTH));
                    }
                    if let Err(code) = od.write(index, sub, &buf) {
                        return Some(abort(index, sub, code));
                    }
                } else {
                    if buf.len() > 4096 {
                        return Some(abort(index, sub, ABORT_VALUE));
                    }
                    self.transfer = Transfer::Download {
                        index,
                        sub,
                        size,
                        buf,
                        toggle: toggle ^ 1,
                    };
                }
                Some(reply)
            }
            // Initiate upload.
            2 => {
                self.transfer = Transfer::Idle;
                let data = match od.read(index, sub) {
                    Ok(d) => d,
                    Err(code) => return Some(abort(index, sub, code)),
                };
                if data.len() <= 4 {
                    let mut d = [0u8; 4];
                    d[..data.len()].copy_from_slice(&data);
                    let n = (4 - data.len()) as u8;
                    Some(answer(0x43 | (n << 2), index, sub, d))
                } else {
                    let size = (data.len() as u32).to_le_bytes();
                    self.transfer = Transfer::Upload {
                        data,
                        at: 0,
                        toggle: 0,
                    };
                    Some(answer(0x41, index, sub, size))
                }
            }
            // Upload segment.
            3 => {
                let Transfer::Upload { data, at, toggle } =
                    std::mem::replace(&mut self.transfer, Transfer::Idle)
                else {
                    return Some(abort(0, 0, ABORT_COMMAND));
                };
                if (req[0] >> 4) & 1 != toggle {
                    return Some(abort(0, 0, ABORT_TOGGLE));
                }
                let chunk = data.get(at..(at + 7).min(data.len())).unwrap_or_default();
                let last = at + chunk.len() >= data.len();
                let mut out = [0u8; 8];
                out[0] = (toggle << 4) | (((7 - chunk.len()) as u8) << 1) | u8::from(last);
                out[1..=chunk.len()].copy_from_slice(chunk);
                if !last {
                    self.transfer = Transfer::Upload {
                        at: at + chunk.len(),
                        data,
                        toggle: toggle ^ 1,
                    };
                }
                Some(out)
            }
            // Abort from the client.
            4 => {
                self.transfer = Transfer::Idle;
                None
            }
            _ => {
                self.transfer = Transfer::Idle;
                Some(abort(index, sub, ABORT_COMMAND))
            }
        }
    }
}
