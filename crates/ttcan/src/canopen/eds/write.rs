//! The CiA 306 writer: the device file of `ttdrive-sim` from the dictionary's table.

use crate::canopen::od::{self, Access, ObjectCode};
use std::fmt::Write as _;

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
pub const TTDRIVE_SIM_EDS: &str = include_str!("../../../devices/ttdrive-sim.eds");
