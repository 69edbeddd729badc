//! The object dictionary of the virtual CiA 402 drive as data: one table of entries (index,
//! sub-index, name, CiA 301 data type, access, PDO-mappable flag, allowed range, default) from
//! which the drive's dictionary is built and the device file the project ships
//! (`crates/ttcan/devices/ttdrive-sim.eds`) is written ([`super::eds::write_eds`], checked against
//! the file by a test). Values are kept as sign-extended `i64` within `[min, max]`; strings in
//! fixed slots. The PDO communication and mapping objects (0x1400, 0x1600, 0x1800, 0x1A00) are
//! ordinary entries here; their CiA 301 write rules are the node's ([`super::node`]). Nothing
//! here allocates.

mod dictionary;
mod table;
#[cfg(test)]
mod tests;

pub use dictionary::ObjectDictionary;
pub use table::{object, DRIVE_ENTRIES, ENTRIES, OBJECTS, TEXT_CAPACITY};

/// Device type: CiA 402 drive profile.
pub const DEVICE_TYPE: u16 = 0x1000;
/// Error register.
pub const ERROR_REGISTER: u16 = 0x1001;
/// Communication cycle period, µs.
pub const CYCLE_PERIOD: u16 = 0x1006;
/// Manufacturer device name (string).
pub const DEVICE_NAME: u16 = 0x1008;
/// Manufacturer hardware version (string).
pub const HARDWARE_VERSION: u16 = 0x1009;
/// Manufacturer software version (string).
pub const SOFTWARE_VERSION: u16 = 0x100A;
/// Producer heartbeat time, ms.
pub const HEARTBEAT_TIME: u16 = 0x1017;
/// Identity (sub 1 vendor-ID, 2 product code, 3 revision, 4 serial number).
pub const IDENTITY: u16 = 0x1018;
/// RPDO1 communication parameter (sub 1 COB-ID, 2 transmission type).
pub const RPDO1_COMM: u16 = 0x1400;
/// RPDO1 mapping parameter (sub 0 number of entries, 1–8 entries).
pub const RPDO1_MAP: u16 = 0x1600;
/// TPDO1 communication parameter (sub 1 COB-ID, 2 transmission type, 3 inhibit, 5 event timer).
pub const TPDO1_COMM: u16 = 0x1800;
/// TPDO1 mapping parameter.
pub const TPDO1_MAP: u16 = 0x1A00;
/// Drive label: a writable manufacturer-specific string (up to 48 bytes).
pub const DRIVE_LABEL: u16 = 0x2000;
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
/// Velocity actual value, increments/s.
pub const VELOCITY_ACTUAL: u16 = 0x606C;
/// Target torque, ‰ of rated torque.
pub const TARGET_TORQUE: u16 = 0x6071;
/// Max torque, ‰ of rated torque.
pub const MAX_TORQUE: u16 = 0x6072;
/// Rated current, mA.
pub const RATED_CURRENT: u16 = 0x6075;
/// Rated torque, mN·m.
pub const RATED_TORQUE: u16 = 0x6076;
/// Current actual value, ‰ of rated current.
pub const CURRENT_ACTUAL: u16 = 0x6078;
/// Target position, increments.
pub const TARGET_POSITION: u16 = 0x607A;
/// Software position limit (sub 1 min, sub 2 max), increments.
pub const SOFTWARE_POSITION_LIMIT: u16 = 0x607D;
/// Quick stop deceleration, increments/s².
pub const QUICK_STOP_DECELERATION: u16 = 0x6085;
/// Torque offset, ‰ of rated torque.
pub const TORQUE_OFFSET: u16 = 0x60B2;
/// Interpolation time period (sub 1 value, sub 2 index: period = value · 10^index s).
pub const INTERPOLATION_PERIOD: u16 = 0x60C2;
/// Target velocity, increments/s.
pub const TARGET_VELOCITY: u16 = 0x60FF;
/// Supported drive modes (bit 7 CSP, 8 CSV, 9 CST).
pub const SUPPORTED_MODES: u16 = 0x6502;

/// The identity of `ttdrive-sim` (0x1018): vendor-ID 0 (none assigned), product code, revision.
pub const IDENTITY_VALUES: [u32; 4] = [0x0000_0000, 0x7474_0402, 0x0001_0000, 0];

/// CiA 301 data types (the index of their definition in the dictionary).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DataType {
    /// BOOLEAN (0x0001).
    Boolean,
    /// INTEGER8 (0x0002).
    Integer8,
    /// INTEGER16 (0x0003).
    Integer16,
    /// INTEGER32 (0x0004).
    Integer32,
    /// UNSIGNED8 (0x0005).
    Unsigned8,
    /// UNSIGNED16 (0x0006).
    Unsigned16,
    /// UNSIGNED32 (0x0007).
    Unsigned32,
    /// VISIBLE_STRING (0x0009).
    VisibleString,
    /// OCTET_STRING (0x000A).
    OctetString,
    /// DOMAIN (0x000F).
    Domain,
    /// INTEGER64 (0x0015).
    Integer64,
    /// UNSIGNED64 (0x001B).
    Unsigned64,
}

impl DataType {
    /// The CiA 301 code.
    pub fn code(self) -> u16 {
        match self {
            DataType::Boolean => 0x01,
            DataType::Integer8 => 0x02,
            DataType::Integer16 => 0x03,
            DataType::Integer32 => 0x04,
            DataType::Unsigned8 => 0x05,
            DataType::Unsigned16 => 0x06,
            DataType::Unsigned32 => 0x07,
            DataType::VisibleString => 0x09,
            DataType::OctetString => 0x0A,
            DataType::Domain => 0x0F,
            DataType::Integer64 => 0x15,
            DataType::Unsigned64 => 0x1B,
        }
    }

    /// The type of a CiA 301 code (`None`: a type this stack does not handle).
    pub fn from_code(c: u16) -> Option<Self> {
        Some(match c {
            0x01 => DataType::Boolean,
            0x02 => DataType::Integer8,
            0x03 => DataType::Integer16,
            0x04 => DataType::Integer32,
            0x05 => DataType::Unsigned8,
            0x06 => DataType::Unsigned16,
            0x07 => DataType::Unsigned32,
            0x09 => DataType::VisibleString,
            0x0A => DataType::OctetString,
            0x0F => DataType::Domain,
            0x15 => DataType::Integer64,
            0x1B => DataType::Unsigned64,
            _ => return None,
        })
    }

    /// Size in bytes of a numeric type (`None` for strings and domains).
    pub fn size(self) -> Option<u8> {
        match self {
            DataType::Boolean | DataType::Integer8 | DataType::Unsigned8 => Some(1),
            DataType::Integer16 | DataType::Unsigned16 => Some(2),
            DataType::Integer32 | DataType::Unsigned32 => Some(4),
            DataType::Integer64 | DataType::Unsigned64 => Some(8),
            DataType::VisibleString | DataType::OctetString | DataType::Domain => None,
        }
    }

    /// True for the signed integers.
    pub fn signed(self) -> bool {
        matches!(
            self,
            DataType::Integer8 | DataType::Integer16 | DataType::Integer32 | DataType::Integer64
        )
    }

    /// The full range of a numeric type (strings: 0..=0).
    pub fn range(self) -> (i64, i64) {
        match self {
            DataType::Boolean => (0, 1),
            DataType::Integer8 => (i8::MIN as i64, i8::MAX as i64),
            DataType::Integer16 => (i16::MIN as i64, i16::MAX as i64),
            DataType::Integer32 => (i32::MIN as i64, i32::MAX as i64),
            DataType::Unsigned8 => (0, u8::MAX as i64),
            DataType::Unsigned16 => (0, u16::MAX as i64),
            DataType::Unsigned32 => (0, u32::MAX as i64),
            DataType::Integer64 | DataType::Unsigned64 => (i64::MIN, i64::MAX),
            _ => (0, 0),
        }
    }

    /// Sign- or zero-extends the `size()` low bytes of `raw`.
    pub fn extend(self, raw: u64) -> i64 {
        let bits = 8 * self.size().unwrap_or(8) as u32;
        if bits >= 64 {
            return raw as i64;
        }
        if self.signed() {
            ((raw << (64 - bits)) as i64) >> (64 - bits)
        } else {
            (raw & ((1u64 << bits) - 1)) as i64
        }
    }
}

/// Who may access an entry over SDO.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    /// Read only (may change: measured values, statusword).
    Ro,
    /// Read and write.
    Rw,
    /// Constant.
    Const,
}

/// CiA 301 object code of an index.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ObjectCode {
    /// A single value (VAR, 0x7).
    Var,
    /// Sub-indices of one type (ARRAY, 0x8).
    Array,
    /// Sub-indices of different types (RECORD, 0x9).
    Record,
}

impl ObjectCode {
    /// The CiA 306 `ObjectType` value.
    pub fn code(self) -> u8 {
        match self {
            ObjectCode::Var => 7,
            ObjectCode::Array => 8,
            ObjectCode::Record => 9,
        }
    }
}

/// One object dictionary entry (one sub-index).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Entry {
    /// Object index.
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// Parameter name (CiA 306 `ParameterName`).
    pub name: &'static str,
    /// Data type.
    pub data_type: DataType,
    /// Access over SDO.
    pub access: Access,
    /// May be mapped to a PDO (readable: TPDO; writable: RPDO).
    pub mappable: bool,
    /// Smallest allowed value.
    pub min: i64,
    /// Largest allowed value.
    pub max: i64,
    /// Default value; with `node_relative`, plus the node id (`$NODEID+…` in the device file).
    pub default: i64,
    /// The default is relative to the node id.
    pub node_relative: bool,
    /// Default text of a string entry.
    pub text: &'static str,
}

/// One object (index) of the table: name and object code; its sub-indices are in [`ENTRIES`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Object {
    /// Index.
    pub index: u16,
    /// Name.
    pub name: &'static str,
    /// VAR, ARRAY or RECORD.
    pub code: ObjectCode,
}
