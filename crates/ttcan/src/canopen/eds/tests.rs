use super::*;
use crate::canopen::od::{self, Access};

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
