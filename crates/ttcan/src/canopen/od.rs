//! The object dictionary of the virtual CiA 402 drive as data: one table of entries (index,
//! sub-index, name, CiA 301 data type, access, PDO-mappable flag, allowed range, default) from
//! which the drive's dictionary is built and the device file the project ships
//! (`crates/ttcan/devices/ttdrive-sim.eds`) is written ([`super::eds::write_eds`], checked against
//! the file by a test). Values are kept as sign-extended `i64` within `[min, max]`; strings in
//! fixed slots. The PDO communication and mapping objects (0x1400, 0x1600, 0x1800, 0x1A00) are
//! ordinary entries here; their CiA 301 write rules are the node's ([`super::node`]). Nothing
//! here allocates.

use super::sdo::{ABORT_LENGTH, ABORT_LENGTH_HIGH, ABORT_NO_OBJECT, ABORT_NO_SUBINDEX};
use super::sdo::{ABORT_RANGE, ABORT_READ_ONLY, SDO_BUFFER};

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

const fn obj(index: u16, name: &'static str, code: ObjectCode) -> Object {
    Object { index, name, code }
}

use Access::{Const, Ro, Rw};
use DataType::*;

#[allow(clippy::too_many_arguments)] // one table row: the columns of the dictionary
const fn e(
    index: u16,
    sub: u8,
    name: &'static str,
    data_type: DataType,
    access: Access,
    mappable: bool,
    min: i64,
    max: i64,
    default: i64,
) -> Entry {
    Entry {
        index,
        sub,
        name,
        data_type,
        access,
        mappable,
        min,
        max,
        default,
        node_relative: false,
        text: "",
    }
}

/// A string entry.
const fn s(index: u16, name: &'static str, access: Access, text: &'static str) -> Entry {
    Entry {
        index,
        sub: 0,
        name,
        data_type: VisibleString,
        access,
        mappable: false,
        min: 0,
        max: 0,
        default: 0,
        node_relative: false,
        text,
    }
}

/// A COB-ID entry whose default is `$NODEID + base`.
const fn cob(index: u16, base: i64) -> Entry {
    Entry {
        index,
        sub: 1,
        name: "COB-ID used by PDO",
        data_type: Unsigned32,
        access: Rw,
        mappable: false,
        min: 0,
        max: u32::MAX as i64,
        default: base,
        node_relative: true,
        text: "",
    }
}

const I32_MIN: i64 = i32::MIN as i64;
const I32_MAX: i64 = i32::MAX as i64;
const I16_MIN: i64 = i16::MIN as i64;
const I16_MAX: i64 = i16::MAX as i64;
const U32_MAX: i64 = u32::MAX as i64;

/// The objects of the virtual drive, in index order.
pub const OBJECTS: [Object; 32] = [
    obj(0x1000, "Device type", ObjectCode::Var),
    obj(0x1001, "Error register", ObjectCode::Var),
    obj(0x1006, "Communication cycle period", ObjectCode::Var),
    obj(0x1008, "Manufacturer device name", ObjectCode::Var),
    obj(0x1009, "Manufacturer hardware version", ObjectCode::Var),
    obj(0x100A, "Manufacturer software version", ObjectCode::Var),
    obj(0x1017, "Producer heartbeat time", ObjectCode::Var),
    obj(0x1018, "Identity object", ObjectCode::Record),
    obj(0x1400, "RPDO1 communication parameter", ObjectCode::Record),
    obj(0x1600, "RPDO1 mapping parameter", ObjectCode::Record),
    obj(0x1800, "TPDO1 communication parameter", ObjectCode::Record),
    obj(0x1A00, "TPDO1 mapping parameter", ObjectCode::Record),
    obj(0x2000, "Drive label", ObjectCode::Var),
    obj(0x6040, "Controlword", ObjectCode::Var),
    obj(0x6041, "Statusword", ObjectCode::Var),
    obj(0x6060, "Modes of operation", ObjectCode::Var),
    obj(0x6061, "Modes of operation display", ObjectCode::Var),
    obj(0x6064, "Position actual value", ObjectCode::Var),
    obj(0x6065, "Following error window", ObjectCode::Var),
    obj(0x606C, "Velocity actual value", ObjectCode::Var),
    obj(0x6071, "Target torque", ObjectCode::Var),
    obj(0x6072, "Max torque", ObjectCode::Var),
    obj(0x6075, "Motor rated current", ObjectCode::Var),
    obj(0x6076, "Motor rated torque", ObjectCode::Var),
    obj(0x6078, "Current actual value", ObjectCode::Var),
    obj(0x607A, "Target position", ObjectCode::Var),
    obj(0x607D, "Software position limit", ObjectCode::Array),
    obj(0x6085, "Quick stop deceleration", ObjectCode::Var),
    obj(0x60B2, "Torque offset", ObjectCode::Var),
    obj(0x60C2, "Interpolation time period", ObjectCode::Record),
    obj(0x60FF, "Target velocity", ObjectCode::Var),
    obj(0x6502, "Supported drive modes", ObjectCode::Var),
];

/// Number of entries of the drive dictionary.
pub const DRIVE_ENTRIES: usize = 62;

/// Number of string slots of the dictionary.
const TEXT_SLOTS: usize = 4;
/// Longest string an entry holds, bytes.
pub const TEXT_CAPACITY: usize = 48;

/// Every entry of the virtual drive, in (index, sub-index) order: the one table the dictionary
/// and the device file come from.
pub const ENTRIES: [Entry; DRIVE_ENTRIES] = [
    e(0x1000, 0, "Device type", Unsigned32, Ro, false, 0, U32_MAX, 0x0002_0192),
    e(0x1001, 0, "Error register", Unsigned8, Ro, true, 0, 255, 0),
    e(
        0x1006,
        0,
        "Communication cycle period",
        Unsigned32,
        Rw,
        false,
        0,
        1_000_000,
        1000,
    ),
    s(
        0x1008,
        "Manufacturer device name",
        Const,
        "ttdrive-sim virtual CiA 402 drive",
    ),
    s(
        0x1009,
        "Manufacturer hardware version",
        Const,
        "maxon RE 25 + GP 26 A model",
    ),
    s(0x100A, "Manufacturer software version", Const, "ttmanip 0.1"),
    e(
        0x1017,
        0,
        "Producer heartbeat time",
        Unsigned16,
        Rw,
        false,
        0,
        65535,
        100,
    ),
    e(
        0x1018,
        0,
        "Highest sub-index supported",
        Unsigned8,
        Const,
        false,
        4,
        4,
        4,
    ),
    e(
        0x1018,
        1,
        "Vendor-ID",
        Unsigned32,
        Ro,
        false,
        0,
        U32_MAX,
        IDENTITY_VALUES[0] as i64,
    ),
    e(
        0x1018,
        2,
        "Product code",
        Unsigned32,
        Ro,
        false,
        0,
        U32_MAX,
        IDENTITY_VALUES[1] as i64,
    ),
    e(
        0x1018,
        3,
        "Revision number",
        Unsigned32,
        Ro,
        false,
        0,
        U32_MAX,
        IDENTITY_VALUES[2] as i64,
    ),
    e(
        0x1018,
        4,
        "Serial number",
        Unsigned32,
        Ro,
        false,
        0,
        U32_MAX,
        IDENTITY_VALUES[3] as i64,
    ),
    e(
        0x1400,
        0,
        "Highest sub-index supported",
        Unsigned8,
        Const,
        false,
        2,
        2,
        2,
    ),
    cob(0x1400, 0x200),
    e(0x1400, 2, "Transmission type", Unsigned8, Rw, false, 0, 255, 1),
    e(0x1600, 0, "Number of mapped objects", Unsigned8, Rw, false, 0, 8, 3),
    e(
        0x1600,
        1,
        "Mapping entry 1",
        Unsigned32,
        Rw,
        false,
        0,
        U32_MAX,
        0x607A_0020,
    ),
    e(
        0x1600,
        2,
        "Mapping entry 2",
        Unsigned32,
        Rw,
        false,
        0,
        U32_MAX,
        0x60B2_0010,
    ),
    e(
        0x1600,
        3,
        "Mapping entry 3",
        Unsigned32,
        Rw,
        false,
        0,
        U32_MAX,
        0x6040_0010,
    ),
    e(0x1600, 4, "Mapping entry 4", Unsigned32, Rw, false, 0, U32_MAX, 0),
    e(0x1600, 5, "Mapping entry 5", Unsigned32, Rw, false, 0, U32_MAX, 0),
    e(0x1600, 6, "Mapping entry 6", Unsigned32, Rw, false, 0, U32_MAX, 0),
    e(0x1600, 7, "Mapping entry 7", Unsigned32, Rw, false, 0, U32_MAX, 0),
    e(0x1600, 8, "Mapping entry 8", Unsigned32, Rw, false, 0, U32_MAX, 0),
    e(
        0x1800,
        0,
        "Highest sub-index supported",
        Unsigned8,
        Const,
        false,
        5,
        5,
        5,
    ),
    cob(0x1800, 0x180),
    e(0x1800, 2, "Transmission type", Unsigned8, Rw, false, 0, 255, 1),
    e(0x1800, 3, "Inhibit time", Unsigned16, Rw, false, 0, 65535, 0),
    e(0x1800, 5, "Event timer", Unsigned16, Rw, false, 0, 65535, 0),
    e(0x1A00, 0, "Number of mapped objects", Unsigned8, Rw, false, 0, 8, 3),
    e(
        0x1A00,
        1,
        "Mapping entry 1",
        Unsigned32,
        Rw,
        false,
        0,
        U32_MAX,
        0x6064_0020,
    ),
    e(
        0x1A00,
        2,
        "Mapping entry 2",
        Unsigned32,
        Rw,
        false,
        0,
        U32_MAX,
        0x6078_0010,
    ),
    e(
        0x1A00,
        3,
        "Mapping entry 3",
        Unsigned32,
        Rw,
        false,
        0,
        U32_MAX,
        0x6041_0010,
    ),
    e(0x1A00, 4, "Mapping entry 4", Unsigned32, Rw, false, 0, U32_MAX, 0),
    e(0x1A00, 5, "Mapping entry 5", Unsigned32, Rw, false, 0, U32_MAX, 0),
    e(0x1A00, 6, "Mapping entry 6", Unsigned32, Rw, false, 0, U32_MAX, 0),
    e(0x1A00, 7, "Mapping entry 7", Unsigned32, Rw, false, 0, U32_MAX, 0),
    e(0x1A00, 8, "Mapping entry 8", Unsigned32, Rw, false, 0, U32_MAX, 0),
    s(0x2000, "Drive label", Rw, ""),
    e(0x6040, 0, "Controlword", Unsigned16, Rw, true, 0, 65535, 0),
    e(0x6041, 0, "Statusword", Unsigned16, Ro, true, 0, 65535, 0),
    e(0x6060, 0, "Modes of operation", Integer8, Rw, true, 8, 10, 8),
    e(
        0x6061,
        0,
        "Modes of operation display",
        Integer8,
        Ro,
        true,
        -128,
        127,
        8,
    ),
    e(
        0x6064,
        0,
        "Position actual value",
        Integer32,
        Ro,
        true,
        I32_MIN,
        I32_MAX,
        0,
    ),
    e(
        0x6065,
        0,
        "Following error window",
        Unsigned32,
        Rw,
        false,
        0,
        I32_MAX,
        10_000,
    ),
    e(
        0x606C,
        0,
        "Velocity actual value",
        Integer32,
        Ro,
        true,
        I32_MIN,
        I32_MAX,
        0,
    ),
    e(0x6071, 0, "Target torque", Integer16, Rw, true, I16_MIN, I16_MAX, 0),
    e(0x6072, 0, "Max torque", Unsigned16, Rw, false, 0, 32767, 3000),
    e(
        0x6075,
        0,
        "Motor rated current",
        Unsigned32,
        Ro,
        false,
        0,
        U32_MAX,
        1200,
    ),
    e(0x6076, 0, "Motor rated torque", Unsigned32, Ro, false, 0, U32_MAX, 1000),
    e(
        0x6078,
        0,
        "Current actual value",
        Integer16,
        Ro,
        true,
        I16_MIN,
        I16_MAX,
        0,
    ),
    e(0x607A, 0, "Target position", Integer32, Rw, true, I32_MIN, I32_MAX, 0),
    e(
        0x607D,
        0,
        "Highest sub-index supported",
        Unsigned8,
        Const,
        false,
        2,
        2,
        2,
    ),
    e(
        0x607D,
        1,
        "Min position limit",
        Integer32,
        Rw,
        false,
        I32_MIN,
        I32_MAX,
        I32_MIN + 1,
    ),
    e(
        0x607D,
        2,
        "Max position limit",
        Integer32,
        Rw,
        false,
        I32_MIN,
        I32_MAX,
        I32_MAX,
    ),
    e(
        0x6085,
        0,
        "Quick stop deceleration",
        Unsigned32,
        Rw,
        false,
        1,
        I32_MAX,
        20_000_000,
    ),
    e(0x60B2, 0, "Torque offset", Integer16, Rw, true, I16_MIN, I16_MAX, 0),
    e(
        0x60C2,
        0,
        "Highest sub-index supported",
        Unsigned8,
        Const,
        false,
        2,
        2,
        2,
    ),
    e(
        0x60C2,
        1,
        "Interpolation time period value",
        Unsigned8,
        Rw,
        false,
        0,
        255,
        1,
    ),
    e(0x60C2, 2, "Interpolation time index", Integer8, Rw, false, -6, 0, -3),
    e(0x60FF, 0, "Target velocity", Integer32, Rw, true, I32_MIN, I32_MAX, 0),
    // bits 7, 8, 9: cyclic synchronous position, velocity, torque
    e(
        0x6502,
        0,
        "Supported drive modes",
        Unsigned32,
        Ro,
        false,
        0,
        U32_MAX,
        0x0380,
    ),
];

/// The object of `index` in [`OBJECTS`].
pub fn object(index: u16) -> Option<&'static Object> {
    OBJECTS.iter().find(|o| o.index == index)
}

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canopen::sdo::ABORT_NO_SUBINDEX;

    #[test]
    fn table_is_sorted_every_object_has_entries_and_defaults_are_in_range() {
        for w in ENTRIES.windows(2) {
            assert!((w[0].index, w[0].sub) < (w[1].index, w[1].sub), "{:?}", w[1]);
        }
        for o in &OBJECTS {
            assert!(ENTRIES.iter().any(|e| e.index == o.index), "{:#06x}", o.index);
        }
        for en in &ENTRIES {
            assert!(object(en.index).is_some(), "{:#06x} has no object", en.index);
            let (lo, hi) = en.data_type.range();
            assert!(lo <= en.min && en.max <= hi, "{en:?}");
            if en.data_type.size().is_some() && !en.node_relative {
                assert!((en.min..=en.max).contains(&en.default), "{en:?}");
            }
        }
    }

    #[test]
    fn writes_check_existence_access_size_and_range() {
        let mut od = ObjectDictionary::drive(3);
        assert_eq!(od.write(MODES_OF_OPERATION, 0, &[9]), Ok(()));
        assert_eq!(od.get(MODES_OF_OPERATION, 0), Some(9));
        assert_eq!(od.write(MODES_OF_OPERATION, 0, &[1]), Err(ABORT_RANGE));
        assert_eq!(od.write(MODES_OF_OPERATION, 0, &[8, 0]), Err(ABORT_LENGTH));
        assert_eq!(od.write(STATUSWORD, 0, &[8, 0]), Err(ABORT_READ_ONLY));
        assert_eq!(od.write(0x2100, 0, &[8, 0]), Err(ABORT_NO_OBJECT));
        assert_eq!(od.write(SOFTWARE_POSITION_LIMIT, 3, &[0; 4]), Err(ABORT_NO_SUBINDEX));
        assert_eq!(od.write(SOFTWARE_POSITION_LIMIT, 1, &(-5i32).to_le_bytes()), Ok(()));
        assert_eq!(od.get(SOFTWARE_POSITION_LIMIT, 1), Some(-5));
        let mut buf = [0u8; SDO_BUFFER];
        assert_eq!(od.read(DEVICE_TYPE, 0, &mut buf), Ok(4));
        assert_eq!(buf[..4], 0x0002_0192u32.to_le_bytes());
        assert_eq!(od.get(RPDO1_COMM, 1), Some(0x203));
        let n = od.read(DEVICE_NAME, 0, &mut buf).unwrap();
        assert_eq!(&buf[..n], b"ttdrive-sim virtual CiA 402 drive");
        assert_eq!(od.write(DEVICE_NAME, 0, b"x"), Err(ABORT_READ_ONLY));
        assert_eq!(od.write(DRIVE_LABEL, 0, b"left shoulder, axis 2"), Ok(()));
        assert_eq!(od.text(DRIVE_LABEL, 0), Some(&b"left shoulder, axis 2"[..]));
        assert_eq!(od.write(DRIVE_LABEL, 0, &[b'x'; 49]), Err(ABORT_LENGTH_HIGH));
    }
}
