//! Issue 27: the bus description in the controller's TOML with vendor device files. Everything a
//! file can get wrong is refused when the configuration is loaded, before the bus is used, and
//! the message names the node, the object (or the file and line) and the reason.

use ttcan::runtime::config::ControllerConfig;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data");

/// A one-channel configuration (in the test data directory) whose axis has `extra` keys.
fn load(extra: &str) -> Result<ControllerConfig, String> {
    let text = format!("cycle_hz = 1000\n[[channel]]\ninterface = \"can0\"\n[[channel.axis]]\nnode = 5\n{extra}\n");
    ControllerConfig::from_toml(&text, &format!("{DATA}/ctl.toml")).map_err(|e| e.to_string())
}

#[test]
fn vendor_file_with_its_own_default_mapping_is_remapped_to_ours() {
    let c = load("device_file = \"vendor-402.eds\"").unwrap();
    let plans = c.channel_plans(0, "ctl.toml").unwrap();
    let p = &plans[0];
    let jobs: Vec<_> = p.steps().map(|s| s.job).collect();
    use ttcan::canopen::sdo::SdoJob;
    // identity read against [DeviceInfo], the vendor's RPDO2/TPDO2 invalidated
    assert_eq!(jobs[0], SdoJob::Read { index: 0x1018, sub: 1 });
    assert!(jobs.contains(&SdoJob::write_int(0x1401, 1, 4, 0x8000_0305)), "{jobs:?}");
    assert!(jobs.contains(&SdoJob::write_int(0x1801, 1, 4, 0x8000_0285)));
    assert!(jobs.contains(&SdoJob::write_int(0x1600, 1, 4, 0x607A_0020)));
    assert_eq!(p.rpdo.len(), 8);
    // budget from the real mapping: 6-byte PDOs load the bus less than the default 8
    let short =
        load("device_file = \"vendor-402.eds\"\nrpdo = [[0x6040, 0], [0x607A, 0]]\ntpdo = [[0x6041, 0], [0x6064, 0]]")
            .unwrap();
    let (a, b) = (c.check("x").unwrap()[0], short.check("x").unwrap()[0]);
    // two frames of 6 instead of 8 bytes per cycle: 2 × (135 − 115) worst-case bits at 1 kHz
    assert!((a.worst - b.worst - 0.04).abs() < 1e-9, "{a:?} {b:?}");
}

#[test]
fn every_bad_bus_description_is_refused_with_node_object_and_reason() {
    let e = load("device_file = \"vendor-402.eds\"\nrpdo = [[0x6040, 0], [0x607A, 0], [0x60FF, 0], [0x6060, 0]]")
        .unwrap_err();
    assert!(
        e.contains("channel can0: node 5: RPDO1: 0x6040:0 (16 bits) + 0x607a:0 (32 bits) + 0x60ff:0 (32 bits) + 0x6060:0 (8 bits) = 88 bits, over the 64 bits (8 bytes) of a PDO"),
        "{e}"
    );
    let e = load("device_file = \"vendor-402.eds\"\ntpdo = [[0x6041, 0], [0x6064, 0], [0x6077, 0]]").unwrap_err();
    assert!(
        e.ends_with("node 5: 0x6077:0: not in ")
            || e.contains("node 5: 0x6077:0: not in") && e.contains("vendor-402.eds (mapped to TPDO1)"),
        "{e}"
    );
    let e = load("device_file = \"vendor-402.eds\"\ntpdo = [[0x6041, 0], [0x6064, 0], [0x6065, 0]]").unwrap_err();
    assert!(
        e.contains("node 5: 0x6065:0: Following error window is not PDO-mappable"),
        "{e}"
    );
    let e = load("device_file = \"vendor-402.eds\"\nsdo = [{ index = 0x6072, value = 70000 }]").unwrap_err();
    assert!(
        e.contains("node 5: 0x6072:0: value 70000 outside 0..=65535 of Max torque"),
        "{e}"
    );
    let e = load("device_file = \"vendor-402.eds\"\nmode = \"cst\"\nrpdo = [[0x6040, 0], [0x607A, 0]]").unwrap_err();
    assert!(e.contains("node 5: 0x6071:0: RPDO1 must carry it in Cst"), "{e}");
    let e = load("device_file = \"no-such-drive.eds\"").unwrap_err();
    assert!(
        e.contains("channel can0 node 5:") && e.contains("no-such-drive.eds: cannot read the device file"),
        "{e}"
    );
    // a malformed line of a copy of the vendor file
    let dir = std::env::temp_dir().join(format!("ttcan-bus-description-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(format!("{DATA}/vendor-402.eds")).unwrap();
    let broken = text.replacen(
        "[6041]\nParameterName=Statusword\n",
        "[6041]\nParameterName=Statusword\nthis is not a key\n",
        1,
    );
    let line = broken.lines().position(|l| l == "this is not a key").unwrap() + 1;
    std::fs::write(dir.join("broken.eds"), broken).unwrap();
    let text = "[[channel]]\ninterface = \"can0\"\n[[channel.axis]]\nnode = 5\ndevice_file = \"broken.eds\"\n";
    let e = ControllerConfig::from_toml(text, &dir.join("ctl.toml").display().to_string())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(&format!("broken.eds:{line}: malformed line \"this is not a key\"")),
        "{e}"
    );
    // a wrong data type: the file and the line of the key
    let bad = text_with(
        &std::fs::read_to_string(format!("{DATA}/vendor-402.eds")).unwrap(),
        "[6064]\nParameterName=Position actual value\nObjectType=0x7\nDataType=0x0004",
        "[6064]\nParameterName=Position actual value\nObjectType=0x7\nDataType=0x0099",
    );
    std::fs::write(dir.join("badtype.eds"), &bad.0).unwrap();
    let text = "[[channel]]\ninterface = \"can0\"\n[[channel.axis]]\nnode = 5\ndevice_file = \"badtype.eds\"\n";
    let e = ControllerConfig::from_toml(text, &dir.join("ctl.toml").display().to_string())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(&format!("badtype.eds:{}: [6064] DataType=0x0099", bad.1)),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).ok();
    // a key of the bus description misspelt: toml names it
    let e = load("device_fle = \"vendor-402.eds\"").unwrap_err();
    assert!(e.contains("device_fle"), "{e}");
}

/// `text` with `from` replaced by `to`, and the line of `to`'s last line.
fn text_with(text: &str, from: &str, to: &str) -> (String, usize) {
    let t = text.replacen(from, to, 1);
    let start = t.find(to).unwrap();
    let line = t[..start + to.len()].lines().count();
    (t, line)
}
