//! Conversion between machine units (mm, degrees) and drive counts.

/// Counts per machine unit with direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scaling {
    counts_per_unit: f64,
}

/// A scaling that cannot work.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("counts per unit must be finite and non-zero, got {0}")]
pub struct BadScaling(pub f64);

/// A position outside the drive's 32-bit count range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("position {0} is outside the drive's 32-bit count range")]
pub struct OutOfRange(pub f64);

impl Scaling {
    /// `counts_per_unit` counts per mm or degree; `invert` flips the direction.
    pub fn new(counts_per_unit: f64, invert: bool) -> Result<Self, BadScaling> {
        if !counts_per_unit.is_finite() || counts_per_unit == 0.0 {
            return Err(BadScaling(counts_per_unit));
        }
        Ok(Self {
            counts_per_unit: if invert {
                -counts_per_unit
            } else {
                counts_per_unit
            },
        })
    }

    /// Position in counts (rounded to the nearest count).
    pub fn to_counts(&self, units: f64) -> Result<i32, OutOfRange> {
        let c = (units * self.counts_per_unit).round();
        if c.is_finite() && c >= f64::from(i32::MIN) && c <= f64::from(i32::MAX) {
            Ok(c as i32)
        } else {
            Err(OutOfRange(units))
        }
    }

    /// Position in machine units.
    pub fn to_units(&self, counts: i32) -> f64 {
        f64::from(counts) / self.counts_per_unit
    }

    /// A count total wider than the drive's 32 bits (an unwrapped position) in machine
    /// units.
    pub fn wide_to_units(&self, counts: i64) -> f64 {
        counts as f64 / self.counts_per_unit
    }

    /// A speed or acceleration (always positive) in counts per second (or per s²),
    /// saturated to the u32 range.
    pub fn magnitude_counts(&self, units: f64) -> u32 {
        let c = (units * self.counts_per_unit).abs().round();
        if c.is_finite() {
            c.min(f64::from(u32::MAX)) as u32
        } else {
            u32::MAX
        }
    }
}
