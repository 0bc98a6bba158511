//! Emergency (EMCY) messages: the error code, error register and manufacturer bytes a node
//! sends when an error occurs or is cleared, and their names from CiA 301 and CiA 402.

use std::fmt;

/// One emergency message from a node.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Emergency {
    /// The sending node.
    pub node: u8,
    /// The emergency error code (0x0000: error reset / no error).
    pub code: u16,
    /// The node's error register (object 0x1001).
    pub register: u8,
    /// Five manufacturer-specific bytes.
    pub manufacturer: [u8; 5],
}

impl Emergency {
    /// Decodes the 8 data bytes of an EMCY frame from `node`; `None` if the frame is not
    /// 8 bytes long (a malformed emergency).
    pub fn decode(node: u8, data: &[u8]) -> Option<Self> {
        let bytes: &[u8; 8] = data.try_into().ok()?;
        let [c0, c1, register, m0, m1, m2, m3, m4] = *bytes;
        Some(Self {
            node,
            code: u16::from_le_bytes([c0, c1]),
            register,
            manufacturer: [m0, m1, m2, m3, m4],
        })
    }

    /// The 8 data bytes of this emergency.
    pub fn encode(&self) -> [u8; 8] {
        let [c0, c1] = self.code.to_le_bytes();
        let [m0, m1, m2, m3, m4] = self.manufacturer;
        [c0, c1, self.register, m0, m1, m2, m3, m4]
    }

    /// True when the message reports that the node's errors are cleared.
    pub fn is_reset(&self) -> bool {
        self.code == 0
    }

    /// The name of the error code.
    pub fn name(&self) -> &'static str {
        error_code_name(self.code)
    }

    /// The message in words: node, code, its name, its class (when the name is more exact
    /// than the class) and the error register, e.g. `node 2: EMCY 0x2310 continuous
    /// over-current (current, device output side; error register 0x03: generic, current)`.
    pub fn describe(&self) -> String {
        self.to_string()
    }
}

impl fmt::Display for Emergency {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "node {}: EMCY 0x{:04X} {}",
            self.node,
            self.code,
            self.name()
        )?;
        let class = class_name(self.code);
        if class != self.name() {
            write!(f, " ({class}; ")?;
        } else {
            write!(f, " (")?;
        }
        write!(f, "error register 0x{:02X}", self.register)?;
        let bits = register_bit_names(self.register);
        if !bits.is_empty() {
            write!(f, ": {}", bits.join(", "))?;
        }
        write!(f, ")")
    }
}

/// Names the bits set in an error register (object 0x1001).
pub fn register_bit_names(register: u8) -> Vec<&'static str> {
    const NAMES: [&str; 8] = [
        "generic",
        "current",
        "voltage",
        "temperature",
        "communication",
        "device profile specific",
        "reserved",
        "manufacturer specific",
    ];
    NAMES
        .iter()
        .enumerate()
        .filter(|(bit, _)| register & (1 << bit) != 0)
        .map(|(_, n)| *n)
        .collect()
}

/// The name of an emergency error code: the exact CiA 301 / CiA 402 entry when known,
/// otherwise the name of its class.
pub fn error_code_name(code: u16) -> &'static str {
    match code {
        0x0000 => "error reset or no error",
        0x2310 => "continuous over-current",
        0x2320 => "short circuit or earth leakage",
        0x3110 => "mains over-voltage",
        0x3120 => "mains under-voltage",
        0x3210 => "DC link over-voltage",
        0x3220 => "DC link under-voltage",
        0x4310 => "drive over-temperature",
        0x5530 => "data storage error",
        0x7121 => "motor blocked",
        0x7305 => "incremental sensor 1 fault",
        0x8100 => "communication error",
        0x8110 => "CAN overrun (objects lost)",
        0x8120 => "CAN in error passive mode",
        0x8130 => "life guard error or heartbeat error",
        0x8140 => "recovered from bus-off",
        0x8150 => "CAN-ID collision",
        0x8210 => "PDO not processed due to length error",
        0x8220 => "PDO length exceeded",
        0x8240 => "unexpected SYNC data length",
        0x8250 => "RPDO timeout",
        0x8611 => "following error",
        0x8612 => "reference limit",
        _ => class_name(code),
    }
}

fn class_name(code: u16) -> &'static str {
    match code >> 8 {
        0x10..=0x1F => "generic error",
        0x21 => "current, device input side",
        0x22 => "current inside the device",
        0x23 => "current, device output side",
        0x20..=0x2F => "current",
        0x31 => "mains voltage",
        0x32 => "voltage inside the device",
        0x33 => "output voltage",
        0x30..=0x3F => "voltage",
        0x41 => "ambient temperature",
        0x42 => "device temperature",
        0x40..=0x4F => "temperature",
        0x50..=0x5F => "device hardware",
        0x61 => "internal software",
        0x62 => "user software",
        0x63 => "data set",
        0x60..=0x6F => "device software",
        0x70..=0x7F => "additional modules",
        0x81 => "communication",
        0x82 => "protocol error",
        0x86 => "positioning controller",
        0x80..=0x8F => "monitoring",
        0x90..=0x9F => "external error",
        0xF0..=0xFE => "additional functions",
        0xFF => "device specific",
        _ => "unknown error code",
    }
}
