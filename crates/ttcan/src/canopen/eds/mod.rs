//! Device description files (CiA 306 EDS and DCF, INI format): the reader that turns a vendor's
//! file into objects and sub-objects (name, data type, access, PDO-mappable flag, default value
//! with `$NODEID` expressions, limits, the DCF's `ParameterValue` and node id, the identity of
//! `[DeviceInfo]`), refusing a malformed file with its line; and the writer that produces the
//! device file of `ttdrive-sim` from the dictionary's table ([`super::od::ENTRIES`]). The INI
//! syntax is `rust-ini`'s; the CiA 306 meaning is here. Used when a configuration is loaded,
//! never in the cycle.

mod read;
#[cfg(test)]
mod tests;
mod write;

pub use read::parse_int;
pub use write::{write_eds, TTDRIVE_SIM_EDS};

use super::od::{DataType, ObjectCode};
use std::collections::BTreeMap;

/// A refused device file: which file, which line (when known), what is wrong.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{path}{}: {message}", line.map(|l| format!(":{l}")).unwrap_or_default())]
pub struct DeviceFileError {
    /// File name as given.
    pub path: String,
    /// 1-based line number.
    pub line: Option<usize>,
    /// What is wrong.
    pub message: String,
}

/// CiA 306 access types.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EdsAccess {
    /// `ro`.
    Ro,
    /// `wo`.
    Wo,
    /// `rw`.
    Rw,
    /// `rwr`: read/write, process input (TPDO).
    Rwr,
    /// `rww`: read/write, process output (RPDO).
    Rww,
    /// `const`.
    Const,
}

impl EdsAccess {
    fn parse(s: &str) -> Option<Self> {
        Some(match s.trim().to_ascii_lowercase().as_str() {
            "ro" => EdsAccess::Ro,
            "wo" => EdsAccess::Wo,
            "rw" => EdsAccess::Rw,
            "rwr" => EdsAccess::Rwr,
            "rww" => EdsAccess::Rww,
            "const" => EdsAccess::Const,
            _ => return None,
        })
    }

    /// The CiA 306 name (`ro`, `rw`, …).
    pub fn name(self) -> &'static str {
        match self {
            EdsAccess::Ro => "ro",
            EdsAccess::Wo => "wo",
            EdsAccess::Rw => "rw",
            EdsAccess::Rwr => "rwr",
            EdsAccess::Rww => "rww",
            EdsAccess::Const => "const",
        }
    }

    /// May be read over SDO / sent in a TPDO.
    pub fn readable(self) -> bool {
        self != EdsAccess::Wo
    }

    /// May be written over SDO / received in an RPDO.
    pub fn writable(self) -> bool {
        matches!(self, EdsAccess::Wo | EdsAccess::Rw | EdsAccess::Rwr | EdsAccess::Rww)
    }
}

/// A value as the file writes it: a number (possibly `$NODEID`-relative) or a text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum EdsValue {
    /// An integer, plus the node id when `node_relative`.
    Int {
        /// The constant part.
        value: i64,
        /// `$NODEID+…`.
        node_relative: bool,
    },
    /// A string (VISIBLE_STRING, OCTET_STRING, DOMAIN).
    Text(String),
}

impl EdsValue {
    /// The integer for node `node` (`None` for a text).
    pub fn int(&self, node: u8) -> Option<i64> {
        match self {
            EdsValue::Int { value, node_relative } => Some(value + if *node_relative { node as i64 } else { 0 }),
            EdsValue::Text(_) => None,
        }
    }
}

/// One sub-object of a device file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EdsEntry {
    /// Index.
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// `ParameterName`.
    pub name: String,
    /// `DataType`.
    pub data_type: DataType,
    /// `AccessType`.
    pub access: EdsAccess,
    /// `PDOMapping=1`.
    pub pdo_mapping: bool,
    /// `DefaultValue`.
    pub default: Option<EdsValue>,
    /// `ParameterValue` (DCF).
    pub parameter_value: Option<EdsValue>,
    /// `LowLimit`.
    pub low: Option<i64>,
    /// `HighLimit`.
    pub high: Option<i64>,
    /// Line of the section in the file.
    pub line: usize,
}

impl EdsEntry {
    /// The value the device has after configuration: the DCF's `ParameterValue`, else the
    /// default.
    pub fn value(&self) -> Option<&EdsValue> {
        self.parameter_value.as_ref().or(self.default.as_ref())
    }

    /// Size in bytes of a numeric entry.
    pub fn size(&self) -> Option<u8> {
        self.data_type.size()
    }
}

/// The identity a device file declares (`[DeviceInfo]`).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct DeviceInfo {
    /// `VendorName`.
    pub vendor_name: String,
    /// `VendorNumber` (0x1018:1).
    pub vendor_number: Option<u32>,
    /// `ProductName`.
    pub product_name: String,
    /// `ProductNumber` (0x1018:2).
    pub product_number: Option<u32>,
    /// `RevisionNumber` (0x1018:3).
    pub revision_number: Option<u32>,
}

/// A parsed device file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeviceFile {
    /// File name as given.
    pub path: String,
    /// `[DeviceInfo]`.
    pub info: DeviceInfo,
    /// Node id of a DCF's `[DeviceComissioning]` (`None` in an EDS).
    pub node_id: Option<u8>,
    entries: BTreeMap<(u16, u8), EdsEntry>,
    objects: BTreeMap<u16, (String, ObjectCode)>,
}
