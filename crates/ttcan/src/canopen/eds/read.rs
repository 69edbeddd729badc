//! The CiA 306 reader: a device file's text (INI) into its objects and entries, integers with
//! `$NODEID` expressions, every refusal naming its line.

use super::{DeviceFile, DeviceFileError, DeviceInfo, EdsAccess, EdsEntry, EdsValue};
use crate::canopen::od::{DataType, ObjectCode};
use std::collections::BTreeMap;

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
