//! A sparse copy of device registers gathered by a few block reads.

use super::{ModbusError, RegisterTable, link::ModbusLink};

/// Registers read from a device, by address.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RegisterImage {
    entries: Vec<(u16, u16)>,
}

impl RegisterImage {
    /// An image from `(address, value)` pairs.
    pub fn from_pairs(pairs: impl IntoIterator<Item = (u16, u16)>) -> Self {
        Self {
            entries: pairs.into_iter().collect(),
        }
    }

    /// The value at `address`, if it was read.
    pub fn get(&self, address: u16) -> Option<u16> {
        self.entries
            .iter()
            .find(|(a, _)| *a == address)
            .map(|(_, v)| *v)
    }

    /// Adds the values of a block read starting at `address`.
    pub fn insert_block(&mut self, address: u16, values: &[u16]) {
        for (i, v) in values.iter().enumerate() {
            if let Some(a) = u16::try_from(i).ok().and_then(|i| address.checked_add(i)) {
                self.entries.push((a, *v));
            }
        }
    }
}

/// Block reads covering a set of addresses: addresses closer together than `max_gap`
/// registers share one read, so a typical status block costs one transaction.
pub fn plan_reads(addresses: &[u16], max_gap: u16) -> Vec<(u16, u16)> {
    let mut sorted: Vec<u16> = addresses.to_vec();
    sorted.sort_unstable();
    sorted.dedup();
    let mut blocks: Vec<(u16, u16)> = Vec::new();
    for a in sorted {
        match blocks.last_mut() {
            Some((start, count))
                if u32::from(a) < u32::from(*start) + u32::from(*count) + u32::from(max_gap)
                    && u32::from(a) - u32::from(*start) < 125 =>
            {
                *count = (a - *start) + 1;
            }
            _ => blocks.push((a, 1)),
        }
    }
    blocks
}

/// Performs the planned block reads and gathers the image.
pub async fn read_image(
    link: &mut ModbusLink,
    table: RegisterTable,
    blocks: &[(u16, u16)],
) -> Result<RegisterImage, ModbusError> {
    let mut image = RegisterImage::default();
    for (address, count) in blocks {
        let words = link.read(table, *address, *count).await?;
        image.insert_block(*address, &words);
    }
    Ok(image)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_addresses_share_a_read() {
        assert_eq!(plan_reads(&[0x2103, 0x2100, 0x2101], 8), vec![(0x2100, 4)]);
        assert_eq!(plan_reads(&[10, 11, 100, 101], 8), vec![(10, 2), (100, 2)]);
        assert_eq!(plan_reads(&[], 8), Vec::<(u16, u16)>::new());
        assert_eq!(plan_reads(&[u16::MAX, 0], 8), vec![(0, 1), (u16::MAX, 1)]);
    }

    #[test]
    fn image_lookup() {
        let mut img = RegisterImage::default();
        img.insert_block(0xFFFE, &[1, 2, 3]);
        assert_eq!(img.get(0xFFFE), Some(1));
        assert_eq!(img.get(0xFFFF), Some(2));
        assert_eq!(img.get(0), None);
    }
}
