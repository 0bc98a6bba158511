//! The SDO client: expedited and segmented upload (read) and download (write) of object
//! dictionary entries, and the abort codes of CiA 301 with their names.
//!
//! Request frames go to COB-ID 0x600 + node, answers come from 0x580 + node. The first
//! byte of every SDO frame is the command specifier; the layouts are CiA 301's.

use std::time::Instant;

use super::{CanOpenError, Master};
use crate::can::{CanEvent, CanFrame};

/// COB-ID base of client→server SDO requests.
pub const SDO_RX_BASE: u16 = 0x600;
/// COB-ID base of server→client SDO answers.
pub const SDO_TX_BASE: u16 = 0x580;

/// Abort code: toggle bit not alternated.
pub const ABORT_TOGGLE: u32 = 0x0503_0000;
/// Abort code: SDO protocol timed out.
pub const ABORT_TIMEOUT: u32 = 0x0504_0000;
/// Abort code: command specifier not valid or unknown.
pub const ABORT_COMMAND: u32 = 0x0504_0001;
/// Abort code: object does not exist in the object dictionary.
pub const ABORT_NO_OBJECT: u32 = 0x0602_0000;
/// Abort code: sub-index does not exist.
pub const ABORT_NO_SUBINDEX: u32 = 0x0609_0011;
/// Abort code: attempt to write a read-only object.
pub const ABORT_READ_ONLY: u32 = 0x0601_0002;
/// Abort code: length of service parameter does not match.
pub const ABORT_LENGTH: u32 = 0x0607_0010;
/// Abort code: object cannot be mapped to the PDO.
pub const ABORT_NOT_MAPPABLE: u32 = 0x0604_0041;
/// Abort code: the mapped objects would exceed the PDO length.
pub const ABORT_PDO_LENGTH: u32 = 0x0604_0042;
/// Abort code: invalid value for parameter.
pub const ABORT_VALUE: u32 = 0x0609_0030;
/// Abort code: general error.
pub const ABORT_GENERAL: u32 = 0x0800_0000;
/// Abort code: data cannot be transferred because of the present device state.
pub const ABORT_DEVICE_STATE: u32 = 0x0800_0022;

/// The CiA 301 name of an SDO abort code.
pub fn abort_name(code: u32) -> &'static str {
    match code {
        0x0503_0000 => "toggle bit not alternated",
        0x0504_0000 => "SDO protocol timed out",
        0x0504_0001 => "client/server command specifier not valid or unknown",
        0x0504_0002 => "invalid block size",
        0x0504_0003 => "invalid sequence number",
        0x0504_0004 => "CRC error",
        0x0504_0005 => "out of memory",
        0x0601_0000 => "unsupported access to an object",
        0x0601_0001 => "attempt to read a write-only object",
        0x0601_0002 => "attempt to write a read-only object",
        0x0602_0000 => "object does not exist in the object dictionary",
        0x0604_0041 => "object cannot be mapped to the PDO",
        0x0604_0042 => "number and length of mapped objects would exceed PDO length",
        0x0604_0043 => "general parameter incompatibility",
        0x0604_0047 => "general internal incompatibility in the device",
        0x0606_0000 => "access failed due to a hardware error",
        0x0607_0010 => "data type does not match, length of service parameter does not match",
        0x0607_0012 => "data type does not match, length of service parameter too high",
        0x0607_0013 => "data type does not match, length of service parameter too low",
        0x0609_0011 => "sub-index does not exist",
        0x0609_0030 => "invalid value for parameter",
        0x0609_0031 => "value of parameter written too high",
        0x0609_0032 => "value of parameter written too low",
        0x0609_0036 => "maximum value is less than minimum value",
        0x060A_0023 => "resource not available: SDO connection",
        0x0800_0000 => "general error",
        0x0800_0020 => "data cannot be transferred or stored to the application",
        0x0800_0021 => "data cannot be transferred because of local control",
        0x0800_0022 => "data cannot be transferred because of the present device state",
        0x0800_0023 => "object dictionary dynamic generation failed or no object dictionary",
        0x0800_0024 => "no data available",
        _ => "unknown abort code",
    }
}

/// Builds an SDO frame (8 bytes: command, index, sub-index, 4 data bytes).
pub fn sdo_frame(cob: u16, command: u8, index: u16, sub: u8, data: [u8; 4]) -> CanFrame {
    let [i0, i1] = index.to_le_bytes();
    let [d0, d1, d2, d3] = data;
    CanFrame::fixed(cob, &[command, i0, i1, sub, d0, d1, d2, d3])
}

/// Builds an abort frame for `index`/`sub` with `code`.
pub fn abort_frame(cob: u16, index: u16, sub: u8, code: u32) -> CanFrame {
    sdo_frame(cob, 0x80, index, sub, code.to_le_bytes())
}

/// One SDO transfer's target, for error messages.
#[derive(Clone, Copy)]
struct Target {
    node: u8,
    index: u16,
    sub: u8,
}

impl Master {
    /// Writes `data` to object `index`/`sub` of `node` (expedited up to 4 bytes,
    /// segmented beyond).
    pub fn sdo_write(
        &mut self,
        node: u8,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<(), CanOpenError> {
        let t = Target { node, index, sub };
        let request = SDO_RX_BASE + u16::from(node);
        if data.len() <= 4 {
            let n = 4 - data.len() as u8;
            let mut payload = [0u8; 4];
            payload[..data.len()].copy_from_slice(data);
            let cmd = 0x23 | (n << 2);
            self.bus_send(&sdo_frame(request, cmd, index, sub, payload))?;
            let answer = self.sdo_answer(t)?;
            return expect_command(t, &answer, 0x60, true);
        }
        let size = u32::try_from(data.len()).map_err(|_| protocol(t, "data longer than 4 GiB"))?;
        self.bus_send(&sdo_frame(request, 0x21, index, sub, size.to_le_bytes()))?;
        let answer = self.sdo_answer(t)?;
        expect_command(t, &answer, 0x60, true)?;
        let mut toggle = 0u8;
        let chunks: Vec<&[u8]> = data.chunks(7).collect();
        let last = chunks.len().saturating_sub(1);
        for (i, chunk) in chunks.into_iter().enumerate() {
            let n = 7 - chunk.len() as u8;
            let c = u8::from(i == last);
            let mut bytes = [0u8; 8];
            bytes[0] = (toggle << 4) | (n << 1) | c;
            bytes[1..=chunk.len()].copy_from_slice(chunk);
            self.bus_send(&CanFrame::fixed(request, &bytes))?;
            let answer = self.sdo_answer(t)?;
            let first = answer.first().copied().unwrap_or(0xFF);
            if first & 0xE0 != 0x20 {
                return Err(self.abort_unexpected(t, &answer));
            }
            if (first >> 4) & 1 != toggle {
                self.send_abort(t, ABORT_TOGGLE)?;
                return Err(protocol(t, "toggle bit not alternated in segment answer"));
            }
            toggle ^= 1;
        }
        Ok(())
    }

    /// Reads object `index`/`sub` of `node` (expedited or segmented, as the server chooses).
    pub fn sdo_read(&mut self, node: u8, index: u16, sub: u8) -> Result<Vec<u8>, CanOpenError> {
        let t = Target { node, index, sub };
        let request = SDO_RX_BASE + u16::from(node);
        self.bus_send(&sdo_frame(request, 0x40, index, sub, [0; 4]))?;
        let answer = self.sdo_answer(t)?;
        let first = answer.first().copied().unwrap_or(0xFF);
        if first & 0xE0 != 0x40 {
            return Err(self.abort_unexpected(t, &answer));
        }
        check_multiplexer(t, &answer)?;
        let expedited = first & 0x02 != 0;
        let size_given = first & 0x01 != 0;
        let body = answer.get(4..8).unwrap_or_default();
        if expedited {
            let len = if size_given {
                4 - usize::from((first >> 2) & 3)
            } else {
                4
            };
            return Ok(body.get(..len).unwrap_or_default().to_vec());
        }
        let announced = if size_given {
            let b: [u8; 4] = body
                .try_into()
                .map_err(|_| protocol(t, "short initiate answer"))?;
            Some(u32::from_le_bytes(b) as usize)
        } else {
            None
        };
        let mut out = Vec::with_capacity(announced.unwrap_or(16).min(4096));
        let mut toggle = 0u8;
        loop {
            self.bus_send(&sdo_frame(request, 0x60 | (toggle << 4), 0, 0, [0; 4]))?;
            let seg = self.sdo_answer(t)?;
            let head = seg.first().copied().unwrap_or(0xFF);
            if head & 0xE0 != 0x00 {
                return Err(self.abort_unexpected(t, &seg));
            }
            if (head >> 4) & 1 != toggle {
                self.send_abort(t, ABORT_TOGGLE)?;
                return Err(protocol(t, "toggle bit not alternated in upload segment"));
            }
            let len = 7 - usize::from((head >> 1) & 7);
            out.extend_from_slice(seg.get(1..1 + len).unwrap_or_default());
            if head & 1 != 0 {
                break;
            }
            if out.len() > (1 << 20) {
                self.send_abort(t, ABORT_GENERAL)?;
                return Err(protocol(t, "upload longer than 1 MiB"));
            }
            toggle ^= 1;
        }
        if let Some(size) = announced
            && size != out.len()
        {
            return Err(protocol(
                t,
                &format!("announced {size} bytes but sent {}", out.len()),
            ));
        }
        Ok(out)
    }

    /// Reads an unsigned value of up to 4 bytes.
    pub fn sdo_read_u32(&mut self, node: u8, index: u16, sub: u8) -> Result<u32, CanOpenError> {
        let bytes = self.sdo_read(node, index, sub)?;
        if bytes.is_empty() || bytes.len() > 4 {
            return Err(protocol(
                Target { node, index, sub },
                &format!("expected 1 to 4 bytes, got {}", bytes.len()),
            ));
        }
        let mut b = [0u8; 4];
        b[..bytes.len()].copy_from_slice(&bytes);
        Ok(u32::from_le_bytes(b))
    }

    /// Waits for the node's next SDO answer, handling other traffic meanwhile.
    fn sdo_answer(&mut self, t: Target) -> Result<[u8; 8], CanOpenError> {
        let cob = SDO_TX_BASE + u16::from(t.node);
        let deadline = Instant::now() + self.sdo_timeout;
        loop {
            let now = Instant::now();
            if now >= deadline {
                self.send_abort(t, ABORT_TIMEOUT)?;
                return Err(CanOpenError::SdoTimeout {
                    node: t.node,
                    index: t.index,
                    sub: t.sub,
                    timeout_ms: self.sdo_timeout.as_millis() as u64,
                });
            }
            let event = self.bus_recv(deadline - now)?;
            match event {
                Some(CanEvent::Frame { frame, .. }) if frame.id().standard() == Some(cob) => {
                    let data: [u8; 8] = frame.data().try_into().map_err(|_| {
                        protocol(
                            t,
                            &format!("answer with {} bytes instead of 8", frame.data().len()),
                        )
                    })?;
                    if data[0] == 0x80 {
                        let code = u32::from_le_bytes([data[4], data[5], data[6], data[7]]);
                        return Err(CanOpenError::SdoAbort {
                            node: t.node,
                            index: t.index,
                            sub: t.sub,
                            code,
                            name: abort_name(code),
                        });
                    }
                    return Ok(data);
                }
                Some(ev) => self.dispatch(ev),
                None => {}
            }
        }
    }

    fn send_abort(&mut self, t: Target, code: u32) -> Result<(), CanOpenError> {
        self.bus_send(&abort_frame(
            SDO_RX_BASE + u16::from(t.node),
            t.index,
            t.sub,
            code,
        ))
    }

    fn abort_unexpected(&mut self, t: Target, answer: &[u8; 8]) -> CanOpenError {
        if let Err(e) = self.send_abort(t, ABORT_COMMAND) {
            return e;
        }
        protocol(t, &format!("unexpected answer command 0x{:02X}", answer[0]))
    }
}

fn check_multiplexer(t: Target, answer: &[u8; 8]) -> Result<(), CanOpenError> {
    let index = u16::from_le_bytes([answer[1], answer[2]]);
    if index != t.index || answer[3] != t.sub {
        return Err(protocol(
            t,
            &format!("answer is for 0x{index:04X}:{} instead", answer[3]),
        ));
    }
    Ok(())
}

fn expect_command(
    t: Target,
    answer: &[u8; 8],
    command: u8,
    multiplexed: bool,
) -> Result<(), CanOpenError> {
    if answer[0] & 0xE0 != command {
        return Err(protocol(
            t,
            &format!("unexpected answer command 0x{:02X}", answer[0]),
        ));
    }
    if multiplexed {
        check_multiplexer(t, answer)?;
    }
    Ok(())
}

fn protocol(t: Target, what: &str) -> CanOpenError {
    CanOpenError::SdoProtocol {
        node: t.node,
        index: t.index,
        sub: t.sub,
        what: what.to_string(),
    }
}
