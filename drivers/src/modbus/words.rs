//! 32-bit values in pairs of 16-bit registers, and the counts ↔ machine-unit scaling.

use super::WordOrder;

/// Splits a signed 32-bit value into two registers in the given word order
/// (element 0 goes to the lower address).
pub fn i32_to_words(value: i32, order: WordOrder) -> [u16; 2] {
    let bits = value as u32;
    let high = (bits >> 16) as u16;
    let low = (bits & 0xFFFF) as u16;
    match order {
        WordOrder::HighFirst => [high, low],
        WordOrder::LowFirst => [low, high],
    }
}

/// Joins two registers (element 0 from the lower address) into a signed 32-bit value.
pub fn words_to_i32(words: [u16; 2], order: WordOrder) -> i32 {
    let (high, low) = match order {
        WordOrder::HighFirst => (words[0], words[1]),
        WordOrder::LowFirst => (words[1], words[0]),
    };
    ((u32::from(high) << 16) | u32::from(low)) as i32
}

/// Converts a position in machine units to drive counts, rounding to the nearest count
/// and saturating at the 32-bit range.
pub fn units_to_counts(position: f64, counts_per_unit: f64) -> i32 {
    let counts = (position * counts_per_unit).round();
    if counts.is_nan() {
        0
    } else {
        // `as` saturates for out-of-range floats.
        counts as i32
    }
}

/// Converts drive counts to machine units.
pub fn counts_to_units(counts: i32, counts_per_unit: f64) -> f64 {
    f64::from(counts) / counts_per_unit
}

/// True when bit `bit` (0..=15) of `word` is set; bits beyond 15 read as clear.
pub fn bit(word: u16, bit: u8) -> bool {
    word.checked_shr(u32::from(bit)).is_some_and(|w| w & 1 == 1)
}

/// `word` with bit `bit` set or cleared; bits beyond 15 leave it unchanged.
pub fn with_bit(word: u16, bit: u8, on: bool) -> u16 {
    match 1u16.checked_shl(u32::from(bit)) {
        Some(mask) if on => word | mask,
        Some(mask) => word & !mask,
        None => word,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_match_hand_computed_layout() {
        // -2 = 0xFFFF_FFFE; 0x0001_86A0 = 100000.
        assert_eq!(i32_to_words(-2, WordOrder::HighFirst), [0xFFFF, 0xFFFE]);
        assert_eq!(i32_to_words(-2, WordOrder::LowFirst), [0xFFFE, 0xFFFF]);
        assert_eq!(
            i32_to_words(100_000, WordOrder::HighFirst),
            [0x0001, 0x86A0]
        );
        assert_eq!(
            words_to_i32([0x0001, 0x86A0], WordOrder::HighFirst),
            100_000
        );
        assert_eq!(words_to_i32([0x86A0, 0x0001], WordOrder::LowFirst), 100_000);
        assert_eq!(
            words_to_i32([0x8000, 0x0000], WordOrder::HighFirst),
            i32::MIN
        );
    }

    #[test]
    fn scaling_rounds_and_saturates() {
        assert_eq!(units_to_counts(1.23456, 1000.0), 1235);
        assert_eq!(units_to_counts(-0.0004, 1000.0), 0);
        assert_eq!(units_to_counts(1e12, 1000.0), i32::MAX);
        assert_eq!(units_to_counts(f64::NAN, 1000.0), 0);
        assert!((counts_to_units(1235, 1000.0) - 1.235).abs() < 1e-12);
    }

    #[test]
    fn bits_read_and_write() {
        assert!(bit(0b1000, 3));
        assert!(!bit(0b1000, 2));
        assert!(!bit(0xFFFF, 16));
        assert_eq!(with_bit(0, 15, true), 0x8000);
        assert_eq!(with_bit(0xFFFF, 0, false), 0xFFFE);
        assert_eq!(with_bit(7, 40, true), 7);
    }
}
