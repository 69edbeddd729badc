//! Chains from Denavit–Hartenberg tables ([`Chain::from_dh`]) and the text forms of joint types,
//! DH conventions and Jacobian frames as users type them (`"PRRRRR"`, `"modified"`, `"tool"`).

use std::str::FromStr;

use nalgebra::IsometryMatrix3;

use crate::chain::{Chain, JacobianFrame};
use crate::error::{Error, Result};
use crate::joint::{Dh, DhConvention, Geometry, Joint, JointType, Limits};

impl FromStr for JointType {
    type Err = Error;

    /// Parses `"R"`/`"revolute"` or `"P"`/`"prismatic"` (any case).
    fn from_str(s: &str) -> Result<Self> {
        match s.to_ascii_lowercase().as_str() {
            "r" | "revolute" => Ok(JointType::Revolute),
            "p" | "prismatic" => Ok(JointType::Prismatic),
            other => Err(Error::invalid(
                "types",
                format!("unknown joint type '{other}'; use 'R'/'revolute' or 'P'/'prismatic'"),
            )),
        }
    }
}

impl JointType {
    /// Joint types from a string of letters such as `"PRRRRR"`, one per joint.
    pub fn from_letters(letters: &str) -> Result<Vec<JointType>> {
        letters.chars().map(|c| c.to_string().parse()).collect()
    }
}

impl FromStr for DhConvention {
    type Err = Error;

    /// Parses `"standard"` (distal) or `"modified"`/`"craig"` (proximal).
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "standard" => Ok(DhConvention::Standard),
            "modified" | "craig" => Ok(DhConvention::Modified),
            other => Err(Error::invalid(
                "convention",
                format!("expected 'standard' or 'modified', got '{other}'"),
            )),
        }
    }
}

impl FromStr for JacobianFrame {
    type Err = Error;

    /// Parses `"base"`/`"world"` or `"tool"`/`"local"` (Pinocchio's names accepted too).
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "base" | "world" => Ok(JacobianFrame::Base),
            "tool" | "local" => Ok(JacobianFrame::Tool),
            other => Err(Error::invalid(
                "frame",
                format!("expected 'base' or 'tool', got '{other}'"),
            )),
        }
    }
}

impl Chain {
    /// A chain from a DH table: one `(type, row)` per joint in `convention`; `theta` (revolute)
    /// or `d` (prismatic) of a row is the joint offset at q = 0. `limits` gives (lower, upper)
    /// position limits per joint (m, rad; `None`: unbounded), `names` the joint names (`None`:
    /// `joint1`, `joint2`, …); `base` maps the base frame to frame 0, `tool` the last link frame
    /// to the tool frame.
    pub fn from_dh(
        name: &str,
        convention: DhConvention,
        rows: &[(JointType, Dh)],
        limits: Option<&[(f64, f64)]>,
        names: Option<Vec<String>>,
        base: IsometryMatrix3<f64>,
        tool: IsometryMatrix3<f64>,
    ) -> Result<Chain> {
        let n = rows.len();
        if let Some(l) = limits {
            if l.len() != n {
                return Err(Error::shape("limits", format!("({n}, 2)"), format!("({}, 2)", l.len())));
            }
        }
        let names = match names {
            Some(v) if v.len() != n => return Err(Error::shape("names", format!("{n} names"), v.len())),
            Some(v) => v,
            None => (1..=n).map(|i| format!("joint{i}")).collect(),
        };
        let mut joints = Vec::with_capacity(n);
        for (i, (name, &(kind, row))) in names.into_iter().zip(rows).enumerate() {
            let mut j = Joint::new(name, kind, Geometry::Dh(convention, row))?;
            if let Some(l) = limits {
                j = j.with_limits(Limits::position(l[i].0, l[i].1))?;
            }
            joints.push(j);
        }
        Chain::new(name, joints, base, tool)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A DH chain built here equals the hand-built UR5 of `robots`, joint by joint in FK.
    #[test]
    fn from_dh_matches_a_hand_built_chain() {
        let ur5 = crate::robots::ur5();
        let rows: Vec<(JointType, Dh)> = ur5
            .joints()
            .iter()
            .map(|j| match j.geometry() {
                Geometry::Dh(_, dh) => (j.kind(), *dh),
                _ => unreachable!("ur5 is a DH robot"),
            })
            .collect();
        let conv = match ur5.joints()[0].geometry() {
            Geometry::Dh(c, _) => *c,
            _ => unreachable!(),
        };
        let lims: Vec<(f64, f64)> = ur5.limits().iter().map(|l| (l.lower, l.upper)).collect();
        let c = Chain::from_dh("ur5", conv, &rows, Some(&lims), None, *ur5.base(), *ur5.tool()).unwrap();
        let q = [0.3, -0.2, 0.9, 1.1, -0.7, 0.4];
        assert!((c.fk(&q).unwrap().to_homogeneous() - ur5.fk(&q).unwrap().to_homogeneous()).norm() < 1e-14);
        assert_eq!(c.joints()[2].name(), "joint3");
    }

    /// Text forms parse, and a bad one names the argument.
    #[test]
    fn text_forms_parse() {
        assert_eq!(
            JointType::from_letters("PrR").unwrap(),
            vec![JointType::Prismatic, JointType::Revolute, JointType::Revolute]
        );
        assert!(JointType::from_letters("RX")
            .unwrap_err()
            .to_string()
            .starts_with("types:"));
        assert_eq!("craig".parse::<DhConvention>().unwrap(), DhConvention::Modified);
        assert_eq!("local".parse::<JacobianFrame>().unwrap(), JacobianFrame::Tool);
        assert!("elbow"
            .parse::<JacobianFrame>()
            .unwrap_err()
            .to_string()
            .starts_with("frame:"));
    }
}
