//! The boot-up of one drive as CiA 301/302 masters do it, planned before the bus is touched:
//! from the drive's device file ([`crate::canopen::eds::DeviceFile`]; `ttdrive-sim`'s shipped EDS
//! when none is given) and the axis' bus description ([`NodeSetup`]) a fixed list of SDO steps
//! ([`BootPlan`]): read the identity 0x1018 and compare it with the file, read the device name
//! 0x1008, check the profile
//! (0x1000) and the supported modes (0x6502), write the DCF's parameter values and the SDO
//! initialisation list, remap RPDO1 and TPDO1 (invalidate with COB-ID bit 31, sub-index 0 = 0,
//! the entries, sub-index 0 = n, transmission type 1 = synchronous, revalidate; every other PDO
//! of the file invalidated), the interpolation period 0x60C2 = the cycle, the mode 0x6060, the
//! following-error window 0x6065 and the heartbeat 0x1017. The master ([`super::master`]) sends
//! NMT Reset Communication, waits for the boot-up message, runs the steps, then NMT Start.
//! Every check that can be made on the files is made here: each mapped object exists, is
//! mappable in its direction and the PDO fits 8 bytes; each written object exists, is writable
//! and its value fits; each refusal names the node, the object and the reason.

use crate::canopen::cia402::OpMode;
use crate::canopen::eds::{DeviceFile, EdsEntry};
use crate::canopen::node::COB_INVALID;
use crate::canopen::od;
use crate::canopen::pdo::{MapEntry, PdoMapping, MAX_MAP_ENTRIES};
use crate::canopen::sdo::{SdoData, SdoJob};

/// Most SDO steps of one drive's boot-up.
pub const MAX_BOOT_STEPS: usize = 96;

/// A value of the SDO initialisation list: an integer or a text.
#[derive(Debug, Clone, PartialEq, Eq, serde::Deserialize)]
#[serde(untagged)]
pub enum SdoValue {
    /// Integer (written with the object's size from the device file).
    Int(i64),
    /// Text (VISIBLE_STRING, OCTET_STRING, DOMAIN: segmented when longer than 4 bytes).
    Text(String),
}

/// One entry of the SDO initialisation list.
#[derive(Debug, Clone, PartialEq, Eq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SdoInit {
    /// Object index.
    pub index: u16,
    /// Sub-index.
    #[serde(default)]
    pub sub: u8,
    /// Value.
    pub value: SdoValue,
}

/// The bus description of one drive (from the controller's TOML; every field optional there).
#[derive(Debug, Clone, PartialEq)]
pub struct NodeSetup {
    /// Node id.
    pub node: u8,
    /// Mode of operation.
    pub mode: OpMode,
    /// RPDO1 objects (index, sub-index); `None`: the project's default for the mode.
    pub rpdo: Option<Vec<(u16, u8)>>,
    /// TPDO1 objects; `None`: the project's default.
    pub tpdo: Option<Vec<(u16, u8)>>,
    /// SDO initialisation list, written in order after the DCF's values.
    pub sdo: Vec<SdoInit>,
    /// Producer heartbeat time written to 0x1017, ms.
    pub heartbeat_ms: u16,
    /// Following-error window written to 0x6065 (if the drive has it), increments.
    pub following_window: u32,
    /// Cycle period, s (0x60C2).
    pub cycle_s: f64,
}

/// What a read during boot-up must return (`value & mask == expect`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Expect {
    /// Bits compared.
    pub mask: u32,
    /// Expected bits.
    pub value: u32,
}

/// One boot-up step: an SDO transfer, and for a read the value it must have.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BootStep {
    /// The transfer.
    pub job: SdoJob,
    /// For a read: the check.
    pub expect: Option<Expect>,
}

/// A refused bus description: node, object and reason.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("node {node}: {object}: {reason}")]
pub struct BootError {
    /// Node id.
    pub node: u8,
    /// The object (`0x607a:0`), or the device file.
    pub object: String,
    /// Why.
    pub reason: String,
}

/// The planned boot-up of one drive: its steps and the PDO mappings the master then uses.
#[derive(Debug, Clone, Copy)]
pub struct BootPlan {
    steps: [Option<BootStep>; MAX_BOOT_STEPS],
    n: usize,
    /// Mode of operation.
    pub mode: OpMode,
    /// RPDO1 mapping (master → drive).
    pub rpdo: PdoMapping,
    /// TPDO1 mapping (drive → master).
    pub tpdo: PdoMapping,
}

/// The objects the controller can put in an RPDO (it writes their values every cycle).
pub const RPDO_OBJECTS: [u16; 6] = [
    od::CONTROLWORD,
    od::TARGET_POSITION,
    od::TARGET_VELOCITY,
    od::TARGET_TORQUE,
    od::TORQUE_OFFSET,
    od::MODES_OF_OPERATION,
];

/// The target object of `mode`.
pub fn target_object(mode: OpMode) -> u16 {
    match mode {
        OpMode::Csp => od::TARGET_POSITION,
        OpMode::Csv => od::TARGET_VELOCITY,
        OpMode::Cst => od::TARGET_TORQUE,
    }
}

/// `period_s` as 0x60C2's (value, index): value · 10^index s, the value in 1..=255, exact to 1 ns.
pub fn interpolation_period(period_s: f64) -> Option<(u8, i8)> {
    (-6..=0).rev().find_map(|index: i32| {
        let v = period_s / 10f64.powi(index);
        let r = v.round();
        ((1.0..=255.0).contains(&r) && (v - r).abs() * 10f64.powi(index) < 1e-9).then_some((r as u8, index as i8))
    })
}

impl BootPlan {
    /// The steps in order.
    pub fn steps(&self) -> impl Iterator<Item = &BootStep> {
        self.steps[..self.n].iter().flatten()
    }

    /// Step `k`.
    pub fn step(&self, k: usize) -> Option<BootStep> {
        self.steps.get(k).copied().flatten()
    }

    /// Number of steps.
    pub fn len(&self) -> usize {
        self.n
    }

    /// True without steps (never: the identity is always read).
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Plans the boot-up of `setup` on a drive described by `device`; checks everything that can
    /// be checked before the bus is touched.
    pub fn build(setup: &NodeSetup, device: &DeviceFile) -> Result<Self, BootError> {
        let node = setup.node;
        let refuse = |object: String, reason: String| BootError { node, object, reason };
        let at = |index: u16, sub: u8| format!("{index:#06x}:{sub}");
        let file = &device.path;
        if let Some(n) = device.node_id {
            if n != node {
                return Err(refuse(file.clone(), format!("the DCF is for node {n}")));
            }
        }
        let mut plan = BootPlan {
            steps: [None; MAX_BOOT_STEPS],
            n: 0,
            mode: setup.mode,
            rpdo: PdoMapping::default(),
            tpdo: PdoMapping::default(),
        };
        let push = |plan: &mut BootPlan, step: BootStep| -> Result<(), BootError> {
            if plan.n >= MAX_BOOT_STEPS {
                return Err(refuse(
                    file.clone(),
                    format!("more than {MAX_BOOT_STEPS} SDO steps at boot-up"),
                ));
            }
            plan.steps[plan.n] = Some(step);
            plan.n += 1;
            Ok(())
        };
        let need = |index: u16, sub: u8, why: &str| -> Result<&EdsEntry, BootError> {
            device
                .get(index, sub)
                .ok_or_else(|| refuse(at(index, sub), format!("not in {file} ({why})")))
        };
        let read = |index, sub, expect| BootStep {
            job: SdoJob::Read { index, sub },
            expect,
        };
        // a write of `value` to an object the file must have as writable
        let write = |index: u16, sub: u8, value: &SdoValue, why: &str| -> Result<BootStep, BootError> {
            let e = need(index, sub, why)?;
            if !e.access.writable() {
                return Err(refuse(
                    at(index, sub),
                    format!("{} is {:?} in {file}, not writable", e.name, e.access),
                ));
            }
            let data = match (value, e.data_type.size()) {
                (SdoValue::Int(v), Some(n)) => {
                    let (lo, hi) = e.data_type.range();
                    let lo = e.low.map_or(lo, |l| l.max(lo));
                    let hi = e.high.map_or(hi, |h| h.min(hi));
                    if *v < lo || *v > hi {
                        return Err(refuse(
                            at(index, sub),
                            format!("value {v} outside {lo}..={hi} of {} in {file}", e.name),
                        ));
                    }
                    SdoData::int(*v as u64, n as usize)
                }
                (SdoValue::Text(t), None) => SdoData::from_bytes(t.as_bytes()).ok_or_else(|| {
                    refuse(
                        at(index, sub),
                        format!(
                            "{} bytes, at most {} per transfer",
                            t.len(),
                            crate::canopen::sdo::SDO_BUFFER
                        ),
                    )
                })?,
                (SdoValue::Text(_), Some(_)) => {
                    return Err(refuse(
                        at(index, sub),
                        format!("{} is a number in {file}, not a text", e.name),
                    ))
                }
                (SdoValue::Int(_), None) => {
                    return Err(refuse(
                        at(index, sub),
                        format!("{} is a text in {file}, not a number", e.name),
                    ))
                }
            };
            Ok(BootStep {
                job: SdoJob::Write { index, sub, data },
                expect: None,
            })
        };
        let int = |v: u32| SdoValue::Int(v as i64);

        // identity and profile
        let id = &device.info;
        for (sub, v) in [(1u8, id.vendor_number), (2, id.product_number), (3, id.revision_number)] {
            if let Some(v) = v {
                need(od::IDENTITY, sub, "identity")?;
                push(
                    &mut plan,
                    read(
                        od::IDENTITY,
                        sub,
                        Some(Expect {
                            mask: u32::MAX,
                            value: v,
                        }),
                    ),
                )?;
            }
        }
        if device.get(od::DEVICE_NAME, 0).is_some() {
            // the name the drive gives itself, for the log (a segmented upload when > 4 bytes)
            push(&mut plan, read(od::DEVICE_NAME, 0, None))?;
        }
        need(od::DEVICE_TYPE, 0, "device type")?;
        push(
            &mut plan,
            read(
                od::DEVICE_TYPE,
                0,
                Some(Expect {
                    mask: 0xFFFF,
                    value: 402,
                }),
            ),
        )?;
        let mode_bit = 1u32 << (setup.mode.code() - 1);
        if let Some(e) = device.get(od::SUPPORTED_MODES, 0) {
            if let Some(v) = e.value().and_then(|v| v.int(node)) {
                if v as u32 & mode_bit == 0 {
                    return Err(refuse(
                        at(od::SUPPORTED_MODES, 0),
                        format!(
                            "{file} says the drive does not support mode {:?} (0x6502 = {v:#x})",
                            setup.mode
                        ),
                    ));
                }
            }
            push(
                &mut plan,
                read(
                    od::SUPPORTED_MODES,
                    0,
                    Some(Expect {
                        mask: mode_bit,
                        value: mode_bit,
                    }),
                ),
            )?;
        }
        // the DCF's parameter values, then the initialisation list
        for e in device.entries() {
            let pdo_object = (0x1400..0x1C00).contains(&e.index);
            if let (Some(v), false, true) = (&e.parameter_value, pdo_object, e.access.writable()) {
                let value = match (v, e.data_type.size()) {
                    (crate::canopen::eds::EdsValue::Text(t), None) => SdoValue::Text(t.clone()),
                    (v, _) => match v.int(node) {
                        Some(x) => SdoValue::Int(x),
                        None => continue,
                    },
                };
                push(&mut plan, write(e.index, e.sub, &value, "DCF parameter value")?)?;
            }
        }
        for s in &setup.sdo {
            push(&mut plan, write(s.index, s.sub, &s.value, "SDO initialisation list")?)?;
        }
        // PDO mappings
        let default_rpdo: Vec<(u16, u8)> = PdoMapping::default_rpdo(setup.mode)
            .entries()
            .iter()
            .map(|e| (e.index, e.sub))
            .collect();
        let default_tpdo: Vec<(u16, u8)> = PdoMapping::default_tpdo()
            .entries()
            .iter()
            .map(|e| (e.index, e.sub))
            .collect();
        let rpdo_list = setup.rpdo.clone().unwrap_or(default_rpdo);
        let tpdo_list = setup.tpdo.clone().unwrap_or(default_tpdo);
        let mapping = |list: &[(u16, u8)], rx: bool| -> Result<PdoMapping, BootError> {
            let what = if rx { "RPDO1" } else { "TPDO1" };
            if list.len() > MAX_MAP_ENTRIES {
                return Err(refuse(
                    what.into(),
                    format!("{} objects, at most {MAX_MAP_ENTRIES}", list.len()),
                ));
            }
            let mut entries = Vec::new();
            for &(index, sub) in list {
                let e = need(index, sub, &format!("mapped to {what}"))?;
                if !e.pdo_mapping {
                    return Err(refuse(
                        at(index, sub),
                        format!("{} is not PDO-mappable in {file}", e.name),
                    ));
                }
                if rx && !e.access.writable() || !rx && !e.access.readable() {
                    return Err(refuse(
                        at(index, sub),
                        format!("{} is {:?} in {file}: cannot be mapped to an {what}", e.name, e.access),
                    ));
                }
                if rx && !RPDO_OBJECTS.contains(&index) {
                    return Err(refuse(
                        at(index, sub),
                        format!(
                            "{} in {what}: ttctl writes only 0x6040, 0x607A, 0x60FF, 0x6071, 0x60B2, 0x6060",
                            e.name
                        ),
                    ));
                }
                let bits = e
                    .data_type
                    .size()
                    .map(|n| 8 * n)
                    .ok_or_else(|| refuse(at(index, sub), format!("{} has no fixed size", e.name)))?;
                entries.push(MapEntry { index, sub, bits });
            }
            let bits: u32 = entries.iter().map(|e| e.bits as u32).sum();
            if bits > 64 {
                let list: Vec<String> = entries.iter().map(|e| format!("{e} ({} bits)", e.bits)).collect();
                return Err(refuse(
                    what.into(),
                    format!(
                        "{} = {bits} bits, over the 64 bits (8 bytes) of a PDO; split the objects or map fewer",
                        list.join(" + ")
                    ),
                ));
            }
            PdoMapping::new(&entries).map_err(|e| refuse(what.into(), e.to_string()))
        };
        plan.rpdo = mapping(&rpdo_list, true)?;
        plan.tpdo = mapping(&tpdo_list, false)?;
        for (what, m, needed) in [
            ("RPDO1", &plan.rpdo, [od::CONTROLWORD, target_object(setup.mode)]),
            ("TPDO1", &plan.tpdo, [od::STATUSWORD, od::POSITION_ACTUAL]),
        ] {
            for index in needed {
                if m.position(index, 0).is_none() {
                    return Err(refuse(
                        at(index, 0),
                        format!(
                            "{what} must carry it in {:?} (mapped: {:?})",
                            setup.mode,
                            m.entries().iter().map(|e| e.to_string()).collect::<Vec<_>>()
                        ),
                    ));
                }
            }
        }
        for (comm, map, base, m, first_other) in [
            (od::RPDO1_COMM, od::RPDO1_MAP, 0x200u32, plan.rpdo, 0x1401u16),
            (od::TPDO1_COMM, od::TPDO1_MAP, 0x180, plan.tpdo, 0x1801),
        ] {
            let cob = base + node as u32;
            need(comm, 1, "PDO COB-ID")?;
            need(comm, 2, "PDO transmission type")?;
            need(map, 0, "PDO mapping")?;
            push(&mut plan, write(comm, 1, &int(COB_INVALID | cob), "PDO COB-ID")?)?;
            push(&mut plan, write(map, 0, &int(0), "PDO mapping")?)?;
            for (k, e) in m.entries().iter().enumerate() {
                push(&mut plan, write(map, k as u8 + 1, &int(e.word()), "PDO mapping entry")?)?;
            }
            push(&mut plan, write(map, 0, &int(m.entries().len() as u32), "PDO mapping")?)?;
            push(&mut plan, write(comm, 2, &int(1), "PDO transmission type")?)?;
            push(&mut plan, write(comm, 1, &int(cob), "PDO COB-ID")?)?;
            // every other PDO of the file: invalid (no traffic the budget does not count)
            for other in first_other..first_other + 0x1FF {
                let Some(e) = device.get(other, 1) else { continue };
                if let Some(v) = e.value().and_then(|v| v.int(node)) {
                    if v as u32 & COB_INVALID == 0 && e.access.writable() {
                        push(&mut plan, write(other, 1, &int(v as u32 | COB_INVALID), "PDO COB-ID")?)?;
                    }
                }
            }
        }
        if device.has_object(od::INTERPOLATION_PERIOD) {
            let (v, i) = interpolation_period(setup.cycle_s).ok_or_else(|| {
                refuse(
                    at(od::INTERPOLATION_PERIOD, 1),
                    format!(
                        "the cycle {} s is not value · 10^index s with value 1..=255, index -6..=0",
                        setup.cycle_s
                    ),
                )
            })?;
            push(
                &mut plan,
                write(
                    od::INTERPOLATION_PERIOD,
                    1,
                    &SdoValue::Int(v as i64),
                    "interpolation period",
                )?,
            )?;
            push(
                &mut plan,
                write(
                    od::INTERPOLATION_PERIOD,
                    2,
                    &SdoValue::Int(i as i64),
                    "interpolation period",
                )?,
            )?;
        }
        push(
            &mut plan,
            write(
                od::MODES_OF_OPERATION,
                0,
                &SdoValue::Int(setup.mode.code() as i64),
                "mode of operation",
            )?,
        )?;
        if device.get(od::FOLLOWING_ERROR_WINDOW, 0).is_some() {
            push(
                &mut plan,
                write(
                    od::FOLLOWING_ERROR_WINDOW,
                    0,
                    &int(setup.following_window),
                    "following-error window",
                )?,
            )?;
        }
        push(
            &mut plan,
            write(
                od::HEARTBEAT_TIME,
                0,
                &SdoValue::Int(setup.heartbeat_ms as i64),
                "heartbeat",
            )?,
        )?;
        Ok(plan)
    }
}

/// `ttdrive-sim`'s shipped device file, parsed (the default when a node names none).
pub fn default_device() -> DeviceFile {
    // the shipped file is checked by the eds tests: it parses
    DeviceFile::parse(crate::canopen::eds::TTDRIVE_SIM_EDS, "ttdrive-sim.eds").unwrap_or_else(|e| panic!("{e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn setup() -> NodeSetup {
        NodeSetup {
            node: 3,
            mode: OpMode::Csp,
            rpdo: None,
            tpdo: None,
            sdo: vec![],
            heartbeat_ms: 100,
            following_window: 5000,
            cycle_s: 4e-3,
        }
    }

    #[test]
    fn interpolation_periods() {
        assert_eq!(interpolation_period(1e-3), Some((1, -3)));
        assert_eq!(interpolation_period(4e-3), Some((4, -3)));
        assert_eq!(interpolation_period(2.5e-3), Some((25, -4)));
        assert_eq!(interpolation_period(1e-4), Some((1, -4)));
        assert_eq!(interpolation_period(1.0 / 3000.0), None);
    }

    #[test]
    fn default_plan_checks_identity_remaps_both_pdos_and_ends_with_the_heartbeat() {
        let p = BootPlan::build(&setup(), &default_device()).unwrap();
        let jobs: Vec<SdoJob> = p.steps().map(|s| s.job).collect();
        assert_eq!(jobs[0], SdoJob::Read { index: 0x1018, sub: 1 });
        assert_eq!(
            p.step(1).unwrap().expect,
            Some(Expect {
                mask: u32::MAX,
                value: od::IDENTITY_VALUES[1]
            })
        );
        let w = |i, s, n, v| SdoJob::write_int(i, s, n, v);
        let k = jobs.iter().position(|j| *j == w(0x1400, 1, 4, 0x8000_0203)).unwrap();
        assert_eq!(
            jobs[k..k + 7],
            [
                w(0x1400, 1, 4, 0x8000_0203),
                w(0x1600, 0, 1, 0),
                w(0x1600, 1, 4, 0x607A_0020),
                w(0x1600, 2, 4, 0x60B2_0010),
                w(0x1600, 3, 4, 0x6040_0010),
                w(0x1600, 0, 1, 3),
                w(0x1400, 2, 1, 1),
            ]
        );
        assert!(jobs.contains(&w(0x60C2, 1, 1, 4)) && jobs.contains(&w(0x60C2, 2, 1, (-3i8) as u8 as u32)));
        assert_eq!(*jobs.last().unwrap(), w(0x1017, 0, 2, 100));
        assert_eq!(p.rpdo, PdoMapping::default_rpdo(OpMode::Csp));
    }

    #[test]
    fn every_refusal_names_node_object_and_reason() {
        let dev = default_device();
        let err = |s: NodeSetup| BootPlan::build(&s, &dev).unwrap_err().to_string();
        let mut s = setup();
        s.rpdo = Some(vec![(0x6040, 0), (0x607A, 0), (0x60FF, 0), (0x60B2, 0)]);
        assert_eq!(
            err(s),
            "node 3: RPDO1: 0x6040:0 (16 bits) + 0x607a:0 (32 bits) + 0x60ff:0 (32 bits) + 0x60b2:0 (16 bits) = 96 bits, over the 64 bits (8 bytes) of a PDO; split the objects or map fewer"
        );
        let mut s = setup();
        s.tpdo = Some(vec![(0x6041, 0), (0x6064, 0), (0x2345, 0)]);
        assert_eq!(err(s), "node 3: 0x2345:0: not in ttdrive-sim.eds (mapped to TPDO1)");
        let mut s = setup();
        s.tpdo = Some(vec![(0x6041, 0), (0x6065, 0)]);
        assert_eq!(
            err(s),
            "node 3: 0x6065:0: Following error window is not PDO-mappable in ttdrive-sim.eds"
        );
        let mut s = setup();
        s.rpdo = Some(vec![(0x6040, 0), (0x6041, 0)]);
        assert!(
            err(s).starts_with("node 3: 0x6041:0: Statusword is Ro in ttdrive-sim.eds: cannot be mapped to an RPDO1")
        );
        let mut s = setup();
        s.rpdo = Some(vec![(0x6040, 0), (0x60FF, 0)]);
        assert!(err(s).starts_with("node 3: 0x607a:0: RPDO1 must carry it in Csp"));
        let mut s = setup();
        s.sdo = vec![SdoInit {
            index: 0x6060,
            sub: 0,
            value: SdoValue::Int(3),
        }];
        assert_eq!(
            err(s),
            "node 3: 0x6060:0: value 3 outside 8..=10 of Modes of operation in ttdrive-sim.eds"
        );
        let mut s = setup();
        s.sdo = vec![SdoInit {
            index: 0x1008,
            sub: 0,
            value: SdoValue::Text("x".into()),
        }];
        assert_eq!(
            err(s),
            "node 3: 0x1008:0: Manufacturer device name is Const in ttdrive-sim.eds, not writable"
        );
    }
}
