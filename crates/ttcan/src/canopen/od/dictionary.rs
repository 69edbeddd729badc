//! The drive's object dictionary at run time: values of the table's entries (sign-extended
//! within their range), strings in fixed slots, whole-value SDO reads and checked writes.

use super::table::{DRIVE_ENTRIES, ENTRIES, TEXT_CAPACITY};
use super::{Access, Entry};
use crate::canopen::sdo::{ABORT_LENGTH, ABORT_LENGTH_HIGH, ABORT_NO_OBJECT, ABORT_NO_SUBINDEX};
use crate::canopen::sdo::{ABORT_RANGE, ABORT_READ_ONLY, SDO_BUFFER};

/// Number of string slots of the dictionary.
const TEXT_SLOTS: usize = 4;

/// The dictionary of the virtual CiA 402 drive (values of [`ENTRIES`], strings in fixed slots).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ObjectDictionary {
    entries: [Entry; DRIVE_ENTRIES],
    values: [i64; DRIVE_ENTRIES],
    texts: [([u8; TEXT_CAPACITY], u8); TEXT_SLOTS],
}

impl Default for ObjectDictionary {
    fn default() -> Self {
        Self::drive(1)
    }
}

impl ObjectDictionary {
    /// The drive dictionary of node `node` with its defaults (CSP, 100 ms heartbeat, 1 ms cycle,
    /// the default PDO mappings, COB-IDs from the node id).
    pub fn drive(node: u8) -> Self {
        let mut od = ObjectDictionary {
            entries: ENTRIES,
            values: [0; DRIVE_ENTRIES],
            texts: [([0; TEXT_CAPACITY], 0); TEXT_SLOTS],
        };
        let mut slot = 0;
        for (k, en) in ENTRIES.iter().enumerate() {
            od.values[k] = en.default + if en.node_relative { node as i64 } else { 0 };
            if en.data_type.size().is_none() && slot < TEXT_SLOTS {
                let t = en.text.as_bytes();
                let n = t.len().min(TEXT_CAPACITY);
                od.texts[slot].0[..n].copy_from_slice(&t[..n]);
                od.texts[slot].1 = n as u8;
                od.values[k] = slot as i64;
                slot += 1;
            }
        }
        od
    }

    /// The entries (definitions).
    pub fn entries(&self) -> &[Entry] {
        &self.entries
    }

    fn find(&self, index: u16, sub: u8) -> Result<usize, u32> {
        let mut index_seen = false;
        for (k, en) in self.entries.iter().enumerate() {
            if en.index == index {
                index_seen = true;
                if en.sub == sub {
                    return Ok(k);
                }
            }
        }
        Err(if index_seen { ABORT_NO_SUBINDEX } else { ABORT_NO_OBJECT })
    }

    /// The definition of `index:sub`, or the abort code for an absent object / sub-index.
    pub fn entry(&self, index: u16, sub: u8) -> Result<&Entry, u32> {
        self.find(index, sub).map(|k| &self.entries[k])
    }

    /// The value of `index:sub` (`None` when absent or a string).
    pub fn get(&self, index: u16, sub: u8) -> Option<i64> {
        let k = self.find(index, sub).ok()?;
        self.entries[k].data_type.size().map(|_| self.values[k])
    }

    /// The text of the string entry `index:sub`.
    pub fn text(&self, index: u16, sub: u8) -> Option<&[u8]> {
        let k = self.find(index, sub).ok()?;
        if self.entries[k].data_type.size().is_some() {
            return None;
        }
        let (t, n) = &self.texts[self.values[k] as usize];
        Some(&t[..*n as usize])
    }

    /// Sets `index:sub` from the application side (read-only entries included); false when absent,
    /// a string or out of range.
    pub fn set(&mut self, index: u16, sub: u8, value: i64) -> bool {
        match self.find(index, sub) {
            Ok(k)
                if self.entries[k].data_type.size().is_some()
                    && (self.entries[k].min..=self.entries[k].max).contains(&value) =>
            {
                self.values[k] = value;
                true
            }
            _ => false,
        }
    }

    /// Reads `index:sub` as its little-endian bytes into `out` (SDO upload); returns the length.
    pub fn read(&self, index: u16, sub: u8, out: &mut [u8; SDO_BUFFER]) -> Result<usize, u32> {
        let k = self.find(index, sub)?;
        match self.entries[k].data_type.size() {
            Some(n) => {
                out[..n as usize].copy_from_slice(&self.values[k].to_le_bytes()[..n as usize]);
                Ok(n as usize)
            }
            None => {
                let (t, n) = &self.texts[self.values[k] as usize];
                out[..*n as usize].copy_from_slice(&t[..*n as usize]);
                Ok(*n as usize)
            }
        }
    }

    /// Decodes and checks an SDO write of `data` to `index:sub` (existence, access, length,
    /// range) without storing it; returns the value (strings: 0).
    pub fn check_write(&self, index: u16, sub: u8, data: &[u8]) -> Result<i64, u32> {
        let k = self.find(index, sub)?;
        let en = &self.entries[k];
        if en.access != Access::Rw {
            return Err(ABORT_READ_ONLY);
        }
        match en.data_type.size() {
            Some(n) => {
                if data.len() != n as usize {
                    return Err(ABORT_LENGTH);
                }
                let mut b = [0u8; 8];
                b[..data.len()].copy_from_slice(data);
                let v = en.data_type.extend(u64::from_le_bytes(b));
                if !(en.min..=en.max).contains(&v) {
                    return Err(ABORT_RANGE);
                }
                Ok(v)
            }
            None if data.len() > TEXT_CAPACITY => Err(ABORT_LENGTH_HIGH),
            None => Ok(0),
        }
    }

    /// Writes `data` to `index:sub` as an SDO download does (checked by [`Self::check_write`]).
    pub fn write(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), u32> {
        let v = self.check_write(index, sub, data)?;
        let k = self.find(index, sub)?;
        if self.entries[k].data_type.size().is_some() {
            self.values[k] = v;
        } else {
            let slot = &mut self.texts[self.values[k] as usize];
            slot.0 = [0; TEXT_CAPACITY];
            slot.0[..data.len()].copy_from_slice(data);
            slot.1 = data.len() as u8;
        }
        Ok(())
    }
}
