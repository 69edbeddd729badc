use super::*;
use crate::canopen::cia402::{CW_ENABLE_OPERATION, CW_SHUTDOWN, CW_SWITCH_ON};
use crate::canopen::nmt::{encode_nmt, encode_sync};
use crate::canopen::pdo::Rpdo;
use crate::canopen::sdo::ABORT_READ_ONLY;

/// One SDO request to `n`; returns its response.
fn sdo(n: &mut DriveNode, req: SdoRequest) -> SdoResponse {
    let mut out = Frames::new();
    n.on_frame(&req.encode(n.node()).unwrap(), &mut out);
    SdoResponse::decode(&out.as_slice()[0]).unwrap().1
}

fn write(n: &mut DriveNode, index: u16, sub: u8, size: u8, value: u32) -> Result<(), u32> {
    match sdo(
        n,
        SdoRequest::Download {
            index,
            sub,
            size,
            value,
        },
    ) {
        SdoResponse::Downloaded { .. } => Ok(()),
        SdoResponse::Abort { code, .. } => Err(code),
        r => panic!("{r:?}"),
    }
}

fn read(n: &mut DriveNode, index: u16, sub: u8) -> u32 {
    match sdo(n, SdoRequest::Upload { index, sub }) {
        SdoResponse::Uploaded { value, .. } => value,
        r => panic!("{r:?}"),
    }
}

#[test]
fn node_boots_starts_enables_and_refuses_out_of_range_targets() {
    let mut out = Frames::new();
    let mut n = DriveNode::new(3, &mut out).unwrap();
    assert_eq!(out.as_slice()[0].id(), 0x703);
    out.clear();
    // RPDO before Start is ignored, no TPDO in Pre-operational
    n.on_frame(
        &Rpdo {
            target: 0,
            torque_offset: 0,
            controlword: CW_SHUTDOWN,
        }
        .encode(3)
        .unwrap(),
        &mut out,
    );
    assert_eq!(n.on_frame(&encode_sync(), &mut out), NodeEvent::Sync);
    n.on_sync(0, 0, 0, 100, &mut out);
    assert!(out.is_empty());
    n.on_frame(&encode_nmt(NmtCommand::Start, 0).unwrap(), &mut out);
    for cw in [CW_SHUTDOWN, CW_SWITCH_ON, CW_ENABLE_OPERATION] {
        n.on_frame(
            &Rpdo {
                target: 10,
                torque_offset: 0,
                controlword: cw,
            }
            .encode(3)
            .unwrap(),
            &mut out,
        );
        let c = n.on_sync(0, 0, 0, 100, &mut out);
        assert!(c.fresh);
    }
    assert_eq!(n.cia402.state(), DriveState::OperationEnabled);
    out.clear();
    n.on_frame(
        &Rpdo {
            target: 1000,
            torque_offset: 0,
            controlword: CW_ENABLE_OPERATION,
        }
        .encode(3)
        .unwrap(),
        &mut out,
    );
    let c = n.on_sync(0, 0, 0, 100, &mut out);
    assert!(!c.fresh && c.target == 10, "jump refused, previous target held");
    assert_eq!(n.counters().out_of_range, 1);
    assert!(out.as_slice().iter().any(|f| f.id() == 0x83), "EMCY sent");
    // missing RPDO is counted
    n.on_sync(0, 0, 0, 100, &mut out);
    assert_eq!(n.missed_in_row(), 1);
    // malformed RPDO
    n.on_frame(&Frame::new(0x203, &[1, 2]).unwrap(), &mut out);
    assert_eq!(n.counters().malformed, 1);
    // two RPDOs before one SYNC: the first is replaced, and counted
    let r = Rpdo {
        target: 10,
        torque_offset: 0,
        controlword: CW_ENABLE_OPERATION,
    }
    .encode(3)
    .unwrap();
    n.on_frame(&r, &mut out);
    n.on_frame(&r, &mut out);
    assert_eq!(n.counters().replaced_rpdo, 1);
}

#[test]
fn state_machine_over_sdo_from_switch_on_disabled_right_after_boot_up() {
    let mut out = Frames::new();
    let mut n = DriveNode::new(5, &mut out).unwrap();
    // Switch On Disabled (0x40) with remote (bit 9), before any SYNC or NMT Start
    assert_eq!(read(&mut n, od::STATUSWORD, 0), 0x0240);
    for (cw, state) in [
        (CW_SHUTDOWN, DriveState::ReadyToSwitchOn),
        (CW_SWITCH_ON, DriveState::SwitchedOn),
        (CW_ENABLE_OPERATION, DriveState::OperationEnabled),
    ] {
        write(&mut n, od::CONTROLWORD, 0, 2, cw as u32).unwrap();
        let sw = read(&mut n, od::STATUSWORD, 0) as u16;
        assert_eq!(DriveState::from_statusword(sw).unwrap(), state, "{sw:#06x}");
    }
    assert_eq!(read(&mut n, od::CONTROLWORD, 0), CW_ENABLE_OPERATION as u32);
    assert_eq!(write(&mut n, od::STATUSWORD, 0, 2, 0), Err(ABORT_READ_ONLY));
    assert_eq!(read(&mut n, od::SUPPORTED_MODES, 0), 0x380);
    assert_eq!(read(&mut n, od::IDENTITY, 2), od::IDENTITY_VALUES[1]);
    // without RPDO the targets written over SDO are the command at every SYNC
    write(&mut n, od::RPDO1_COMM, 1, 4, COB_INVALID | 0x205).unwrap();
    write(&mut n, od::TARGET_POSITION, 0, 4, 40).unwrap();
    n.on_frame(&encode_nmt(NmtCommand::Start, 0).unwrap(), &mut out);
    let c = n.on_sync(0, 0, 0, 100, &mut out);
    assert!(c.fresh && c.target == 40, "{c:?}");
    assert_eq!(n.missed_in_row(), 0);
}

#[test]
fn pdo_remapping_follows_the_cia_301_rules() {
    let mut out = Frames::new();
    let mut n = DriveNode::new(2, &mut out).unwrap();
    // valid PDO: mapping cannot change
    assert_eq!(write(&mut n, od::RPDO1_MAP, 0, 1, 0), Err(ABORT_UNSUPPORTED));
    write(&mut n, od::RPDO1_COMM, 1, 4, COB_INVALID | 0x202).unwrap();
    // entries only while the number is 0
    assert_eq!(write(&mut n, od::RPDO1_MAP, 1, 4, 0x6040_0010), Err(ABORT_UNSUPPORTED));
    write(&mut n, od::RPDO1_MAP, 0, 1, 0).unwrap();
    // not mappable, wrong length, read-only in an RPDO, absent
    assert_eq!(write(&mut n, od::RPDO1_MAP, 1, 4, 0x6065_0020), Err(ABORT_NOT_MAPPABLE));
    assert_eq!(write(&mut n, od::RPDO1_MAP, 1, 4, 0x6040_0020), Err(ABORT_NOT_MAPPABLE));
    assert_eq!(write(&mut n, od::RPDO1_MAP, 1, 4, 0x6041_0010), Err(ABORT_NOT_MAPPABLE));
    assert_eq!(write(&mut n, od::RPDO1_MAP, 1, 4, 0x2345_0010), Err(ABORT_NO_OBJECT));
    // controlword first, then the target: 6 bytes
    write(&mut n, od::RPDO1_MAP, 1, 4, 0x6040_0010).unwrap();
    write(&mut n, od::RPDO1_MAP, 2, 4, 0x607A_0020).unwrap();
    write(&mut n, od::RPDO1_MAP, 3, 4, 0x60FF_0020).unwrap();
    assert_eq!(write(&mut n, od::RPDO1_MAP, 0, 1, 3), Err(ABORT_PDO_LENGTH), "10 bytes");
    write(&mut n, od::RPDO1_MAP, 0, 1, 2).unwrap();
    // a reserved identifier and a 29-bit one are refused
    assert_eq!(write(&mut n, od::RPDO1_COMM, 1, 4, 0x602), Err(ABORT_RANGE));
    assert_eq!(write(&mut n, od::RPDO1_COMM, 1, 4, (1 << 29) | 0x202), Err(ABORT_RANGE));
    write(&mut n, od::RPDO1_COMM, 1, 4, 0x302).unwrap();
    // the CAN-ID of a valid PDO cannot change
    assert_eq!(write(&mut n, od::RPDO1_COMM, 1, 4, 0x303), Err(ABORT_RANGE));
    // TPDO: statusword and position only, every 2nd SYNC; event-driven types refused
    write(&mut n, od::TPDO1_COMM, 1, 4, COB_INVALID | 0x182).unwrap();
    write(&mut n, od::TPDO1_MAP, 0, 1, 0).unwrap();
    write(&mut n, od::TPDO1_MAP, 1, 4, 0x6041_0010).unwrap();
    write(&mut n, od::TPDO1_MAP, 2, 4, 0x6064_0020).unwrap();
    write(&mut n, od::TPDO1_MAP, 0, 1, 2).unwrap();
    assert_eq!(write(&mut n, od::TPDO1_COMM, 2, 1, 255), Err(ABORT_RANGE));
    write(&mut n, od::TPDO1_COMM, 2, 1, 2).unwrap();
    write(&mut n, od::TPDO1_COMM, 1, 4, 0x182).unwrap();
    n.on_frame(&encode_nmt(NmtCommand::Start, 0).unwrap(), &mut out);
    out.clear();
    let mut sent = Vec::new();
    for (k, cw) in [CW_SHUTDOWN, CW_SWITCH_ON, CW_ENABLE_OPERATION, CW_ENABLE_OPERATION]
        .into_iter()
        .enumerate()
    {
        let mut d = [0u8; 6];
        d[..2].copy_from_slice(&cw.to_le_bytes());
        d[2..].copy_from_slice(&(7 * k as i32).to_le_bytes());
        n.on_frame(&Frame::new(0x302, &d).unwrap(), &mut out);
        let c = n.on_sync(7 * k as i32, 0, 0, 100, &mut out);
        assert!(c.fresh && c.target == 7 * k as i32, "{c:?}");
        sent.extend(out.as_slice().iter().copied());
        out.clear();
    }
    assert_eq!(n.cia402.state(), DriveState::OperationEnabled);
    // the old identifier is no RPDO any more
    n.on_frame(&Rpdo::default().encode(2).unwrap(), &mut out);
    assert!(!n.on_sync(0, 0, 0, 100, &mut out).fresh);
    assert_eq!(sent.len(), 2, "every 2nd SYNC: {sent:?}");
    assert_eq!(sent[1].id(), 0x182);
    assert_eq!(
        sent[1].data()[..2],
        0x0237u16.to_le_bytes(),
        "Operation Enabled, voltage, remote"
    );
    assert_eq!(sent[1].data()[2..], 21i32.to_le_bytes(), "sampled at the 4th SYNC");
    // reset communication restores the default mappings
    n.on_frame(&encode_nmt(NmtCommand::ResetCommunication, 2).unwrap(), &mut out);
    assert_eq!(n.rpdo_mapping(), PdoMapping::default_rpdo(OpMode::Csp));
    assert_eq!(n.tpdo_mapping(), PdoMapping::default_tpdo());
    assert_eq!(read(&mut n, od::RPDO1_COMM, 1), 0x202);
}
