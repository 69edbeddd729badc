use super::*;
use crate::canopen::sdo::{ABORT_LENGTH, ABORT_LENGTH_HIGH, ABORT_NO_OBJECT, ABORT_NO_SUBINDEX};
use crate::canopen::sdo::{ABORT_RANGE, ABORT_READ_ONLY, SDO_BUFFER};

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
