//! Device description files (CiA 306 EDS and DCF, INI format): the reader that turns a vendor's
//! file into objects and sub-objects (name, data type, access, PDO-mappable flag, default value
//! with `$NODEID` expressions, limits, the DCF's `ParameterValue` and node id, the identity of
//! `[DeviceInfo]`), refusing a malformed file with its line; and the writer that produces the
//! device file of `ttdrive-sim` from the dictionary's table ([`super::od::ENTRIES`]). The INI
//! syntax is `rust-ini`'s; the CiA 306 meaning is here. Used when a configuration is loaded,
//! never in the cycle.

use super::od::{self, Access, DataType, ObjectCode};
use std::collections::BTreeMap;
use std::fmt::Write as _;

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

/// Parses a CiA 306 integer: decimal, `0x` hexadecimal, leading-zero octal, optionally
/// `$NODEID+…` / `…+$NODEID` / `$NODEID`.
pub fn parse_int(s: &str) -> Option<EdsValue> {
    let t: String = s.chars().filter(|c| !c.is_whitespace()).collect();
    let upper = t.to_ascii_uppercase();
    let (rest, node_relative) = if let Some(r) = upper.strip_prefix("$NODEID") {
        if !r.is_empty() && !r.starts_with('+') {
            return None;
        }
        (r.strip_prefix('+').unwrap_or(r).to_string(), true)
    } else if let Some(r) = upper.strip_suffix("$NODEID") {
        (r.strip_suffix('+')?.to_string(), true)
    } else {
        (upper.clone(), false)
    };
    if rest.is_empty() {
        return node_relative.then_some(EdsValue::Int {
            value: 0,
            node_relative,
        });
    }
    let (neg, digits) = match rest.strip_prefix('-') {
        Some(d) => (true, d),
        None => (false, rest.as_str()),
    };
    let v = if let Some(h) = digits.strip_prefix("0X") {
        i128::from_str_radix(h, 16).ok()?
    } else if digits.len() > 1 && digits.starts_with('0') {
        i128::from_str_radix(&digits[1..], 8).ok()?
    } else {
        digits.parse::<i128>().ok()?
    };
    let v = if neg { -v } else { v };
    // unsigned 64-bit values above i64::MAX keep their bits
    let v = if v > i64::MAX as i128 && v <= u64::MAX as i128 {
        v as u64 as i64
    } else {
        i64::try_from(v).ok()?
    };
    Some(EdsValue::Int {
        value: v,
        node_relative,
    })
}

/// Line numbers of section headers and keys, found in the text (the INI crate gives none).
struct Lines {
    sections: BTreeMap<String, usize>,
    keys: BTreeMap<(String, String), usize>,
}

impl Lines {
    fn scan(text: &str) -> Self {
        let mut sections = BTreeMap::new();
        let mut keys = BTreeMap::new();
        let mut current = String::new();
        for (k, line) in text.lines().enumerate() {
            let l = line.trim();
            if let Some(rest) = l.strip_prefix('[') {
                current = rest.split(']').next().unwrap_or("").trim().to_ascii_lowercase();
                sections.entry(current.clone()).or_insert(k + 1);
            } else if let Some((key, _)) = l.split_once('=') {
                keys.entry((current.clone(), key.trim().to_ascii_lowercase()))
                    .or_insert(k + 1);
            }
        }
        Lines { sections, keys }
    }

    fn section(&self, s: &str) -> Option<usize> {
        self.sections.get(&s.to_ascii_lowercase()).copied()
    }

    fn key(&self, s: &str, key: &str) -> Option<usize> {
        self.keys
            .get(&(s.to_ascii_lowercase(), key.to_ascii_lowercase()))
            .copied()
            .or_else(|| self.section(s))
    }
}

impl DeviceFile {
    /// Reads and parses the file at `path`.
    pub fn load(path: &std::path::Path) -> Result<Self, DeviceFileError> {
        let name = path.display().to_string();
        // within ttkin's file limit (16 MiB, UTF-8): a device such as /dev/zero ends the read
        let text = ttkin::budget::read_text_limited(path).map_err(|e| DeviceFileError {
            path: name.clone(),
            line: None,
            message: format!("cannot read the device file: {e}"),
        })?;
        Self::parse(&text, &name)
    }

    /// Parses the text of an EDS or DCF; `path` names it in messages.
    pub fn parse(text: &str, path: &str) -> Result<Self, DeviceFileError> {
        let err = |line: Option<usize>, message: String| DeviceFileError {
            path: path.to_string(),
            line,
            message,
        };
        let opt = ini::ParseOption {
            enabled_quote: false,
            enabled_escape: false,
            ..Default::default()
        };
        let ini = ini::Ini::load_from_str_opt(text, opt)
            .map_err(|e| err(Some(e.line), format!("not an INI file: {}", e.msg)))?;
        let lines = Lines::scan(text);
        // a line that is neither a section, a key = value, a comment nor empty
        for (k, line) in text.lines().enumerate() {
            let l = line.trim();
            if !(l.is_empty() || l.starts_with(';') || l.starts_with('#') || l.starts_with('[') || l.contains('=')) {
                return Err(err(
                    Some(k + 1),
                    format!("malformed line {l:?}: expected [section] or key=value"),
                ));
            }
        }
        let get = |s: &str, k: &str| ini.section(Some(s)).and_then(|p| p.get(k)).map(str::trim);
        let num = |s: &str, k: &str| -> Result<Option<u32>, DeviceFileError> {
            match get(s, k) {
                None | Some("") => Ok(None),
                Some(v) => match parse_int(v).and_then(|v| v.int(0)) {
                    Some(x) if (0..=u32::MAX as i64).contains(&x) => Ok(Some(x as u32)),
                    _ => Err(err(
                        lines.key(s, k),
                        format!("[{s}] {k}={v}: not an unsigned 32-bit number"),
                    )),
                },
            }
        };
        if ini.section(Some("DeviceInfo")).is_none() {
            return Err(err(None, "no [DeviceInfo] section: not a CiA 306 device file".into()));
        }
        let info = DeviceInfo {
            vendor_name: get("DeviceInfo", "VendorName").unwrap_or("").to_string(),
            vendor_number: num("DeviceInfo", "VendorNumber")?,
            product_name: get("DeviceInfo", "ProductName").unwrap_or("").to_string(),
            product_number: num("DeviceInfo", "ProductNumber")?,
            revision_number: num("DeviceInfo", "RevisionNumber")?,
        };
        let node_id = match num("DeviceComissioning", "NodeID")? {
            None => None,
            Some(n @ 1..=127) => Some(n as u8),
            Some(n) => {
                return Err(err(
                    lines.key("DeviceComissioning", "NodeID"),
                    format!("[DeviceComissioning] NodeID={n}: must be 1..=127"),
                ))
            }
        };
        // the object lists
        let mut indices = Vec::new();
        for list in ["MandatoryObjects", "OptionalObjects", "ManufacturerObjects"] {
            let Some(p) = ini.section(Some(list)) else { continue };
            let n = num(list, "SupportedObjects")?.unwrap_or(0);
            for k in 1..=n {
                let key = k.to_string();
                let Some(v) = p.get(&key) else {
                    return Err(err(
                        lines.section(list),
                        format!("[{list}] lists {n} objects but has no entry {k}"),
                    ));
                };
                match parse_int(v).and_then(|v| v.int(0)) {
                    Some(i @ 0..=0xFFFF) => indices.push((i as u16, lines.key(list, &key))),
                    _ => {
                        return Err(err(
                            lines.key(list, &key),
                            format!("[{list}] {k}={v}: not an object index"),
                        ))
                    }
                }
            }
        }
        if indices.is_empty() {
            return Err(err(
                None,
                "no objects: [MandatoryObjects]/[OptionalObjects] list none".into(),
            ));
        }
        let mut entries = BTreeMap::new();
        let mut objects = BTreeMap::new();
        for (index, list_line) in indices {
            let sec = format!("{index:04X}");
            let Some(p) = ini.section(Some(sec.as_str())) else {
                return Err(err(
                    list_line,
                    format!("object {index:#06x} is listed but has no [{sec}] section"),
                ));
            };
            let name = p.get("ParameterName").unwrap_or("").trim().to_string();
            if name.is_empty() {
                return Err(err(lines.section(&sec), format!("[{sec}]: no ParameterName")));
            }
            let code = match get(&sec, "ObjectType").map(parse_int) {
                None => ObjectCode::Var,
                Some(Some(EdsValue::Int { value: 7, .. })) => ObjectCode::Var,
                Some(Some(EdsValue::Int { value: 8, .. })) => ObjectCode::Array,
                Some(Some(EdsValue::Int { value: 9, .. })) => ObjectCode::Record,
                Some(_) => {
                    return Err(err(
                        lines.key(&sec, "ObjectType"),
                        format!(
                            "[{sec}] ObjectType={}: expected 0x7 (VAR), 0x8 (ARRAY) or 0x9 (RECORD)",
                            get(&sec, "ObjectType").unwrap_or("")
                        ),
                    ))
                }
            };
            objects.insert(index, (name.clone(), code));
            if code == ObjectCode::Var {
                let e = Self::entry(&ini, &lines, &sec, index, 0, path)?;
                entries.insert((index, 0), e);
                continue;
            }
            if get(&sec, "CompactSubObj").is_some_and(|v| v != "0") {
                return Err(err(
                    lines.key(&sec, "CompactSubObj"),
                    format!("[{sec}] CompactSubObj: compact arrays are not supported; write the sub-objects out"),
                ));
            }
            let mut found = 0;
            for sub in 0..=255u8 {
                let ss = format!("{index:04X}sub{sub:X}");
                if ini.section(Some(ss.as_str())).is_some() {
                    entries.insert((index, sub), Self::entry(&ini, &lines, &ss, index, sub, path)?);
                    found += 1;
                }
            }
            let declared = num(&sec, "SubNumber")?;
            if declared.is_some_and(|d| d != found) || found == 0 {
                return Err(err(
                    lines.key(&sec, "SubNumber"),
                    format!(
                        "[{sec}] SubNumber={}: {found} [{sec}subN] sections found",
                        declared.unwrap_or(0)
                    ),
                ));
            }
        }
        Ok(DeviceFile {
            path: path.to_string(),
            info,
            node_id,
            entries,
            objects,
        })
    }

    fn entry(
        ini: &ini::Ini,
        lines: &Lines,
        sec: &str,
        index: u16,
        sub: u8,
        path: &str,
    ) -> Result<EdsEntry, DeviceFileError> {
        let err = |key: &str, message: String| DeviceFileError {
            path: path.to_string(),
            line: lines.key(sec, key),
            message: format!("[{sec}] {message}"),
        };
        let p = ini.section(Some(sec)).ok_or_else(|| err("", "missing".into()))?;
        let get = |k: &str| p.get(k).map(str::trim);
        let name = get("ParameterName").unwrap_or("").to_string();
        if name.is_empty() {
            return Err(err("ParameterName", "no ParameterName".into()));
        }
        let dt = get("DataType").ok_or_else(|| err("DataType", "no DataType".into()))?;
        let data_type = parse_int(dt)
            .and_then(|v| v.int(0))
            .and_then(|c| u16::try_from(c).ok())
            .and_then(DataType::from_code)
            .ok_or_else(|| {
                err(
                    "DataType",
                    format!("DataType={dt}: not a CiA 301 basic data type this stack handles"),
                )
            })?;
        let at = get("AccessType").ok_or_else(|| err("AccessType", "no AccessType".into()))?;
        let access = EdsAccess::parse(at).ok_or_else(|| {
            err(
                "AccessType",
                format!("AccessType={at}: expected ro, wo, rw, rwr, rww or const"),
            )
        })?;
        let pdo_mapping = match get("PDOMapping") {
            None | Some("0") | Some("") => false,
            Some("1") => true,
            Some(v) => return Err(err("PDOMapping", format!("PDOMapping={v}: expected 0 or 1"))),
        };
        let value = |k: &str| -> Result<Option<EdsValue>, DeviceFileError> {
            match get(k) {
                None => Ok(None),
                Some(v) if data_type.size().is_none() => Ok(Some(EdsValue::Text(v.to_string()))),
                Some("") => Ok(None),
                Some(v) => {
                    let x = parse_int(v).ok_or_else(|| err(k, format!("{k}={v}: not a number")))?;
                    if let EdsValue::Int {
                        value,
                        node_relative: false,
                    } = x
                    {
                        let (lo, hi) = data_type.range();
                        // a signed value may be written with all its bits in hex (0xFFFF = -1)
                        let bits = 8 * data_type.size().unwrap_or(8) as u32;
                        let v64 = if data_type.signed() && value > hi && bits < 64 && value < (1i64 << bits) {
                            data_type.extend(value as u64)
                        } else {
                            value
                        };
                        if v64 < lo || v64 > hi {
                            return Err(err(k, format!("{k}={v}: outside the range of data type {dt}")));
                        }
                        return Ok(Some(EdsValue::Int {
                            value: v64,
                            node_relative: false,
                        }));
                    }
                    Ok(Some(x))
                }
            }
        };
        let limit = |k: &str| -> Result<Option<i64>, DeviceFileError> { Ok(value(k)?.and_then(|v| v.int(0))) };
        Ok(EdsEntry {
            index,
            sub,
            name,
            data_type,
            access,
            pdo_mapping,
            default: value("DefaultValue")?,
            parameter_value: value("ParameterValue")?,
            low: limit("LowLimit")?,
            high: limit("HighLimit")?,
            line: lines.section(sec).unwrap_or(0),
        })
    }

    /// The sub-object `index:sub`.
    pub fn get(&self, index: u16, sub: u8) -> Option<&EdsEntry> {
        self.entries.get(&(index, sub))
    }

    /// True when the file has object `index`.
    pub fn has_object(&self, index: u16) -> bool {
        self.objects.contains_key(&index)
    }

    /// Every sub-object, in (index, sub-index) order.
    pub fn entries(&self) -> impl Iterator<Item = &EdsEntry> {
        self.entries.values()
    }

    /// Name and object code of object `index`.
    pub fn object(&self, index: u16) -> Option<(&str, ObjectCode)> {
        self.objects.get(&index).map(|(n, c)| (n.as_str(), *c))
    }
}

fn access_name(a: Access) -> &'static str {
    match a {
        Access::Ro => "ro",
        Access::Rw => "rw",
        Access::Const => "const",
    }
}

fn write_entry(out: &mut String, section: &str, en: &od::Entry) {
    let _ = writeln!(out, "[{section}]");
    let _ = writeln!(out, "ParameterName={}", en.name);
    let _ = writeln!(out, "ObjectType=0x7");
    let _ = writeln!(out, "DataType=0x{:04X}", en.data_type.code());
    let _ = writeln!(out, "AccessType={}", access_name(en.access));
    if en.data_type.size().is_none() {
        let _ = writeln!(out, "DefaultValue={}", en.text);
    } else if en.node_relative {
        let _ = writeln!(out, "DefaultValue=$NODEID+0x{:X}", en.default);
    } else if en.data_type.signed() {
        let _ = writeln!(out, "DefaultValue={}", en.default);
    } else {
        let _ = writeln!(out, "DefaultValue=0x{:X}", en.default);
    }
    let (lo, hi) = en.data_type.range();
    if en.data_type.size().is_some() && (en.min, en.max) != (lo, hi) && en.access == Access::Rw {
        let _ = writeln!(out, "LowLimit={}", en.min);
        let _ = writeln!(out, "HighLimit={}", en.max);
    }
    let _ = writeln!(out, "PDOMapping={}", u8::from(en.mappable));
    let _ = writeln!(out);
}

/// The device file (EDS) of `ttdrive-sim`, written from [`od::OBJECTS`] and [`od::ENTRIES`].
pub fn write_eds() -> String {
    let mut s = String::new();
    let id = od::IDENTITY_VALUES;
    let _ = write!(
        s,
        "; ttdrive-sim: the virtual CiA 402 drive of ttmanip. Written by ttcan::canopen::eds::write_eds\n\
         ; from the tables of crates/ttcan/src/canopen/od.rs; a test checks this file against them.\n\n\
         [FileInfo]\nFileName=ttdrive-sim.eds\nFileVersion=1\nFileRevision=0\nEDSVersion=4.0\n\
         Description=Virtual CiA 402 drive (CSP, CSV, CST) of ttmanip\nCreatedBy=ttmanip\n\n\
         [DeviceInfo]\nVendorName=ttmanip\nVendorNumber=0x{:08X}\nProductName=ttdrive-sim\n\
         ProductNumber=0x{:08X}\nRevisionNumber=0x{:08X}\nOrderCode=ttdrive-sim\n\
         BaudRate_10=1\nBaudRate_20=1\nBaudRate_50=1\nBaudRate_125=1\nBaudRate_250=1\nBaudRate_500=1\n\
         BaudRate_800=1\nBaudRate_1000=1\nSimpleBootUpMaster=0\nSimpleBootUpSlave=1\nGranularity=8\n\
         DynamicChannelsSupported=0\nGroupMessaging=0\nNrOfRXPDO=1\nNrOfTXPDO=1\nLSS_Supported=0\n\n\
         [DummyUsage]\nDummy0001=0\nDummy0002=0\nDummy0003=0\nDummy0004=0\nDummy0005=0\nDummy0006=0\nDummy0007=0\n\n\
         [Comments]\nLines=0\n\n",
        id[0], id[1], id[2]
    );
    let mandatory = [0x1000u16, 0x1001, 0x1018];
    let lists: [(&str, Vec<u16>); 3] = [
        ("MandatoryObjects", mandatory.to_vec()),
        (
            "OptionalObjects",
            od::OBJECTS
                .iter()
                .map(|o| o.index)
                .filter(|i| !mandatory.contains(i) && !(0x2000..0x6000).contains(i))
                .collect(),
        ),
        (
            "ManufacturerObjects",
            od::OBJECTS
                .iter()
                .map(|o| o.index)
                .filter(|i| (0x2000..0x6000).contains(i))
                .collect(),
        ),
    ];
    for (name, list) in &lists {
        let _ = writeln!(s, "[{name}]\nSupportedObjects={}", list.len());
        for (k, i) in list.iter().enumerate() {
            let _ = writeln!(s, "{}=0x{i:04X}", k + 1);
        }
        let _ = writeln!(s);
        for i in list {
            let Some(o) = od::object(*i) else { continue };
            let subs: Vec<&od::Entry> = od::ENTRIES.iter().filter(|e| e.index == o.index).collect();
            if o.code == ObjectCode::Var {
                if let Some(en) = subs.first() {
                    write_entry(&mut s, &format!("{:04X}", o.index), en);
                }
                continue;
            }
            let _ = writeln!(
                s,
                "[{:04X}]\nParameterName={}\nObjectType=0x{:X}\nSubNumber={}\n",
                o.index,
                o.name,
                o.code.code(),
                subs.len()
            );
            for en in subs {
                write_entry(&mut s, &format!("{:04X}sub{:X}", en.index, en.sub), en);
            }
        }
    }
    s
}

/// The device file of `ttdrive-sim` as the project ships it.
pub const TTDRIVE_SIM_EDS: &str = include_str!("../../devices/ttdrive-sim.eds");

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shipped_eds_is_the_one_written_from_the_tables_and_reads_back_as_them() {
        let written = write_eds();
        if std::env::var_os("TTCAN_WRITE_EDS").is_some() {
            std::fs::write(
                concat!(env!("CARGO_MANIFEST_DIR"), "/devices/ttdrive-sim.eds"),
                &written,
            )
            .unwrap();
        }
        assert!(
            written == TTDRIVE_SIM_EDS,
            "devices/ttdrive-sim.eds differs from the tables: run TTCAN_WRITE_EDS=1 cargo test -p ttcan --lib eds"
        );
        let f = DeviceFile::parse(TTDRIVE_SIM_EDS, "ttdrive-sim.eds").unwrap();
        assert_eq!(f.info.product_number, Some(od::IDENTITY_VALUES[1]));
        let dict = od::ObjectDictionary::drive(5);
        assert_eq!(f.entries().count(), od::ENTRIES.len());
        for en in &od::ENTRIES {
            let e = f
                .get(en.index, en.sub)
                .unwrap_or_else(|| panic!("{:#06x}:{}", en.index, en.sub));
            assert_eq!(
                (e.data_type, e.pdo_mapping, e.name.as_str()),
                (en.data_type, en.mappable, en.name)
            );
            assert_eq!(e.access.writable(), en.access == Access::Rw, "{e:?}");
            match en.data_type.size() {
                Some(_) => assert_eq!(e.value().and_then(|v| v.int(5)), dict.get(en.index, en.sub), "{e:?}"),
                None => assert_eq!(e.value(), Some(&EdsValue::Text(en.text.to_string()))),
            }
        }
    }

    #[test]
    fn integers_of_cia_306() {
        let int = |s| parse_int(s).and_then(|v| v.int(3));
        assert_eq!(int("0x1A"), Some(26));
        assert_eq!(int("012"), Some(10), "octal");
        assert_eq!(int("-5"), Some(-5));
        assert_eq!(int("$NODEID+0x180"), Some(0x183));
        assert_eq!(int("0x200 + $NODEID"), Some(0x203));
        assert_eq!(int("$NODEID"), Some(3));
        assert_eq!(int("0xFFFFFFFFFFFFFFFF"), Some(-1));
        assert_eq!(int("12a"), None);
        assert_eq!(int("$NODEID-1"), None);
    }

    const SMALL: &str = "[DeviceInfo]\nVendorNumber=0x9A\nProductNumber=0x1234\n\n[MandatoryObjects]\nSupportedObjects=2\n1=0x1000\n2=0x1018\n\n\
        [1000]\nParameterName=Device type\nObjectType=0x7\nDataType=0x0007\nAccessType=ro\nDefaultValue=0x00020192\nPDOMapping=0\n\n\
        [1018]\nParameterName=Identity\nObjectType=0x9\nSubNumber=2\n\n\
        [1018sub0]\nParameterName=n\nDataType=0x0005\nAccessType=const\nDefaultValue=1\n\n\
        [1018sub1]\nParameterName=Vendor\nDataType=0x0007\nAccessType=ro\nDefaultValue=0x9A\nParameterValue=0x9B\n";

    #[test]
    fn a_small_file_parses_and_every_malformation_names_its_line() {
        let f = DeviceFile::parse(SMALL, "v.eds").unwrap();
        assert_eq!(f.info.vendor_number, Some(0x9A));
        assert_eq!(f.get(0x1018, 1).unwrap().value().and_then(|v| v.int(1)), Some(0x9B));
        assert_eq!(f.object(0x1018), Some(("Identity", ObjectCode::Record)));
        let bad = |from: &str, to: &str| {
            let text = SMALL.replacen(from, to, 1);
            DeviceFile::parse(&text, "v.eds").unwrap_err().to_string()
        };
        assert_eq!(
            bad(
                "DataType=0x0007\nAccessType=ro\nDefaultValue=0x00020192",
                "DataType=0x0042\nAccessType=ro\nDefaultValue=0x00020192"
            ),
            "v.eds:13: [1000] DataType=0x0042: not a CiA 301 basic data type this stack handles"
        );
        assert_eq!(
            bad(
                "AccessType=ro\nDefaultValue=0x0002",
                "AccessType=rx\nDefaultValue=0x0002"
            ),
            "v.eds:14: [1000] AccessType=rx: expected ro, wo, rw, rwr, rww or const"
        );
        assert_eq!(
            bad("PDOMapping=0", "PDOMapping"),
            "v.eds:16: malformed line \"PDOMapping\": expected [section] or key=value"
        );
        assert_eq!(
            bad("2=0x1018", "2=0x1019"),
            "v.eds:8: object 0x1019 is listed but has no [1019] section"
        );
        assert_eq!(
            bad("SubNumber=2", "SubNumber=3"),
            "v.eds:21: [1018] SubNumber=3: 2 [1018subN] sections found"
        );
        assert_eq!(
            bad("DefaultValue=1\n", "DefaultValue=300\n"),
            "v.eds:27: [1018sub0] DefaultValue=300: outside the range of data type 0x0005"
        );
        assert!(
            bad("[1018sub1]", "[1018sub1").contains("v.eds:"),
            "{}",
            bad("[1018sub1]", "[1018sub1")
        );
        let missing = DeviceFile::load(std::path::Path::new("/nonexistent/drive.eds"))
            .unwrap_err()
            .to_string();
        assert!(
            missing.starts_with("/nonexistent/drive.eds: cannot read the device file"),
            "{missing}"
        );
    }
}
