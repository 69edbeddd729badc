//! The object dictionary of a virtual drive as data: a fixed table of entries (index, sub-index,
//! size, access, allowed range, value) that the SDO server reads and writes, with the abort code
//! for every refusal. The application reads values by index; nothing here allocates.

use super::sdo::{SdoRequest, SdoResponse, ABORT_LENGTH, ABORT_NO_OBJECT, ABORT_NO_SUBINDEX};
use super::sdo::{ABORT_RANGE, ABORT_READ_ONLY};

/// Device type: CiA 402 drive profile.
pub const DEVICE_TYPE: u16 = 0x1000;
/// Error register.
pub const ERROR_REGISTER: u16 = 0x1001;
/// Producer heartbeat time, ms.
pub const HEARTBEAT_TIME: u16 = 0x1017;
/// Controlword.
pub const CONTROLWORD: u16 = 0x6040;
/// Statusword.
pub const STATUSWORD: u16 = 0x6041;
/// Modes of operation.
pub const MODES_OF_OPERATION: u16 = 0x6060;
/// Modes of operation display.
pub const MODES_DISPLAY: u16 = 0x6061;
/// Position actual value, increments.
pub const POSITION_ACTUAL: u16 = 0x6064;
/// Following error window, increments.
pub const FOLLOWING_ERROR_WINDOW: u16 = 0x6065;
/// Max torque, ‰ of rated torque.
pub const MAX_TORQUE: u16 = 0x6072;
/// Rated current, mA.
pub const RATED_CURRENT: u16 = 0x6075;
/// Rated torque, mN·m.
pub const RATED_TORQUE: u16 = 0x6076;
/// Software position limit (sub 1 min, sub 2 max), increments.
pub const SOFTWARE_POSITION_LIMIT: u16 = 0x607D;
/// Quick stop deceleration, increments/s².
pub const QUICK_STOP_DECELERATION: u16 = 0x6085;
/// Communication cycle period, µs.
pub const CYCLE_PERIOD: u16 = 0x1006;

/// Who may write an entry over SDO.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    /// Read only.
    Ro,
    /// Read and write.
    Rw,
}

/// One object dictionary entry; values are kept as sign-extended `i64` within `[min, max]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Entry {
    /// Object index.
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// Size in bytes (1, 2 or 4).
    pub size: u8,
    /// Whether the value is signed (for range checks and sign extension).
    pub signed: bool,
    /// Access over SDO.
    pub access: Access,
    /// Smallest allowed value.
    pub min: i64,
    /// Largest allowed value.
    pub max: i64,
    /// Present value.
    pub value: i64,
}

#[allow(clippy::too_many_arguments)] // one table row: the columns of the dictionary
const fn e(index: u16, sub: u8, size: u8, signed: bool, access: Access, min: i64, max: i64, value: i64) -> Entry {
    Entry {
        index,
        sub,
        size,
        signed,
        access,
        min,
        max,
        value,
    }
}

/// Number of entries of the drive dictionary.
pub const DRIVE_ENTRIES: usize = 16;

/// The dictionary of the virtual CiA 402 drive.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ObjectDictionary {
    entries: [Entry; DRIVE_ENTRIES],
}

impl Default for ObjectDictionary {
    fn default() -> Self {
        Self::drive()
    }
}

impl ObjectDictionary {
    /// The drive dictionary with its defaults (CSP, 100 ms heartbeat, 1 ms cycle).
    pub fn drive() -> Self {
        use Access::*;
        const I32_MIN: i64 = i32::MIN as i64;
        const I32_MAX: i64 = i32::MAX as i64;
        ObjectDictionary {
            entries: [
                e(DEVICE_TYPE, 0, 4, false, Ro, 0, u32::MAX as i64, 0x0002_0192),
                e(ERROR_REGISTER, 0, 1, false, Ro, 0, 255, 0),
                e(CYCLE_PERIOD, 0, 4, false, Rw, 0, 1_000_000, 1000),
                e(HEARTBEAT_TIME, 0, 2, false, Rw, 0, 65535, 100),
                e(CONTROLWORD, 0, 2, false, Rw, 0, 65535, 0),
                e(STATUSWORD, 0, 2, false, Ro, 0, 65535, 0),
                e(MODES_OF_OPERATION, 0, 1, true, Rw, 8, 10, 8),
                e(MODES_DISPLAY, 0, 1, true, Ro, -128, 127, 8),
                e(POSITION_ACTUAL, 0, 4, true, Ro, I32_MIN, I32_MAX, 0),
                e(FOLLOWING_ERROR_WINDOW, 0, 4, false, Rw, 0, I32_MAX, 10_000),
                e(MAX_TORQUE, 0, 2, false, Rw, 0, 32767, 3000),
                e(RATED_CURRENT, 0, 4, false, Ro, 0, u32::MAX as i64, 1200),
                e(RATED_TORQUE, 0, 4, false, Ro, 0, u32::MAX as i64, 1000),
                e(SOFTWARE_POSITION_LIMIT, 1, 4, true, Rw, I32_MIN, I32_MAX, I32_MIN + 1),
                e(SOFTWARE_POSITION_LIMIT, 2, 4, true, Rw, I32_MIN, I32_MAX, I32_MAX),
                e(QUICK_STOP_DECELERATION, 0, 4, false, Rw, 1, I32_MAX, 20_000_000),
            ],
        }
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

    /// The value of `index:sub` (`None` when absent).
    pub fn get(&self, index: u16, sub: u8) -> Option<i64> {
        self.find(index, sub).ok().map(|k| self.entries[k].value)
    }

    /// Sets `index:sub` from the application side (read-only entries included); false when absent
    /// or out of range.
    pub fn set(&mut self, index: u16, sub: u8, value: i64) -> bool {
        match self.find(index, sub) {
            Ok(k) if (self.entries[k].min..=self.entries[k].max).contains(&value) => {
                self.entries[k].value = value;
                true
            }
            _ => false,
        }
    }

    /// Serves one SDO request: checks existence, access, size and range; returns the response.
    pub fn serve(&mut self, req: &SdoRequest) -> SdoResponse {
        let (index, sub) = req.address();
        let abort = |code| SdoResponse::Abort { index, sub, code };
        let k = match self.find(index, sub) {
            Ok(k) => k,
            Err(code) => return abort(code),
        };
        let en = &mut self.entries[k];
        match *req {
            SdoRequest::Upload { .. } => {
                let mask = if en.size == 4 {
                    u32::MAX as i64
                } else {
                    (1i64 << (8 * en.size)) - 1
                };
                SdoResponse::Uploaded {
                    index,
                    sub,
                    size: en.size,
                    value: (en.value & mask) as u32,
                }
            }
            SdoRequest::Download { size, value, .. } => {
                if en.access == Access::Ro {
                    return abort(ABORT_READ_ONLY);
                }
                if size != en.size {
                    return abort(ABORT_LENGTH);
                }
                let bits = 8 * size as u32;
                let v = if en.signed {
                    ((value as i64) << (64 - bits)) >> (64 - bits)
                } else {
                    value as i64
                };
                if !(en.min..=en.max).contains(&v) {
                    return abort(ABORT_RANGE);
                }
                en.value = v;
                SdoResponse::Downloaded { index, sub }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn server_checks_existence_access_size_and_range() {
        let mut od = ObjectDictionary::drive();
        let w = |index, sub, size, value| SdoRequest::Download {
            index,
            sub,
            size,
            value,
        };
        assert_eq!(
            od.serve(&w(MODES_OF_OPERATION, 0, 1, 9)),
            SdoResponse::Downloaded { index: 0x6060, sub: 0 }
        );
        assert_eq!(od.get(MODES_OF_OPERATION, 0), Some(9));
        let code = |r| match r {
            SdoResponse::Abort { code, .. } => code,
            _ => 0,
        };
        assert_eq!(code(od.serve(&w(MODES_OF_OPERATION, 0, 1, 1))), ABORT_RANGE);
        assert_eq!(code(od.serve(&w(MODES_OF_OPERATION, 0, 2, 8))), ABORT_LENGTH);
        assert_eq!(code(od.serve(&w(STATUSWORD, 0, 2, 8))), ABORT_READ_ONLY);
        assert_eq!(code(od.serve(&w(0x2000, 0, 2, 8))), ABORT_NO_OBJECT);
        assert_eq!(code(od.serve(&w(SOFTWARE_POSITION_LIMIT, 3, 4, 8))), ABORT_NO_SUBINDEX);
        // signed 4-byte value is sign-extended
        assert!(matches!(
            od.serve(&w(SOFTWARE_POSITION_LIMIT, 1, 4, (-5i32) as u32)),
            SdoResponse::Downloaded { .. }
        ));
        assert_eq!(od.get(SOFTWARE_POSITION_LIMIT, 1), Some(-5));
        let r = od.serve(&SdoRequest::Upload {
            index: DEVICE_TYPE,
            sub: 0,
        });
        assert_eq!(
            r,
            SdoResponse::Uploaded {
                index: 0x1000,
                sub: 0,
                size: 4,
                value: 0x0002_0192
            }
        );
    }
}
