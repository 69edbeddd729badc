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

    /// Joint types from their names, one per joint (`"revolute"`, `"prismatic"`, or a letter).
    pub fn from_names<S: AsRef<str>>(names: &[S]) -> Result<Vec<JointType>> {
        names.iter().map(|s| s.as_ref().parse()).collect()
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

/// A DH table as users hold it: one column per parameter, one entry per joint, with the defaults
/// of what is left out (all joints revolute, no position limits, `joint1`… names, identity base
/// and tool).
#[derive(Clone, Debug, Default)]
pub struct DhColumns<'a> {
    /// Link lengths a (m), one per joint; the table has as many joints as this column.
    pub a: &'a [f64],
    /// Link twists α (rad).
    pub alpha: &'a [f64],
    /// Link offsets d (m).
    pub d: &'a [f64],
    /// Joint angles θ (rad).
    pub theta: &'a [f64],
    /// Joint types (`None`: all revolute).
    pub types: Option<&'a [JointType]>,
    /// Lower and upper position limits, n × 2 row-major (m, rad; `None`: unbounded).
    pub limits: Option<&'a [f64]>,
    /// Base frame → frame 0 (`None`: identity).
    pub base: Option<IsometryMatrix3<f64>>,
    /// Last link frame → tool frame (`None`: identity).
    pub tool: Option<IsometryMatrix3<f64>>,
}

impl DhColumns<'_> {
    /// The chain `name` of this table in `convention`; `names` as in [`Chain::from_dh`].
    pub fn chain(&self, name: &str, convention: DhConvention, names: Option<Vec<String>>) -> Result<Chain> {
        let n = self.a.len();
        if n == 0 {
            return Err(Error::shape("a", "(n,) with n ≥ 1", "(0,)"));
        }
        for (what, col) in [("alpha", self.alpha), ("d", self.d), ("theta", self.theta)] {
            if col.len() != n {
                return Err(Error::shape(what, format!("({n},)"), format!("({},)", col.len())));
            }
        }
        let types = match self.types {
            Some(t) if t.len() != n => return Err(Error::shape("types", format!("{n} joint types"), t.len())),
            Some(t) => t.to_vec(),
            None => vec![JointType::Revolute; n],
        };
        let limits: Option<Vec<(f64, f64)>> = match self.limits {
            Some(l) if l.len() != 2 * n => {
                return Err(Error::shape(
                    "limits",
                    format!("({n}, 2)"),
                    format!("{} values", l.len()),
                ))
            }
            Some(l) => Some(l.chunks_exact(2).map(|r| (r[0], r[1])).collect()),
            None => None,
        };
        let rows: Vec<(JointType, Dh)> = (0..n)
            .map(|i| {
                let (a, alpha, d, theta) = (self.a[i], self.alpha[i], self.d[i], self.theta[i]);
                (types[i], Dh { a, alpha, d, theta })
            })
            .collect();
        let identity = IsometryMatrix3::identity;
        let (base, tool) = (self.base.unwrap_or_else(identity), self.tool.unwrap_or_else(identity));
        Chain::from_dh(name, convention, &rows, limits.as_deref(), names, base, tool)
    }
}

impl JointType {
    /// The word users read: "revolute" or "prismatic".
    pub fn name(self) -> &'static str {
        match self {
            JointType::Revolute => "revolute",
            JointType::Prismatic => "prismatic",
        }
    }

    /// The one-letter form of [`JointType::from_letters`]: 'R' or 'P'.
    pub fn letter(self) -> char {
        match self {
            JointType::Revolute => 'R',
            JointType::Prismatic => 'P',
        }
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
        let col = |f: fn(&Dh) -> f64| rows.iter().map(|(_, r)| f(r)).collect::<Vec<f64>>();
        let (a, alpha, d, theta) = (col(|r| r.a), col(|r| r.alpha), col(|r| r.d), col(|r| r.theta));
        let flat: Vec<f64> = lims.iter().flat_map(|l| [l.0, l.1]).collect();
        let table = DhColumns {
            a: &a,
            alpha: &alpha,
            d: &d,
            theta: &theta,
            limits: Some(&flat),
            ..Default::default()
        };
        let bounds = |c: &Chain| c.limits().iter().map(|l| (l.lower, l.upper)).collect::<Vec<_>>();
        assert_eq!(bounds(&table.chain("ur5", conv, None).unwrap()), lims);
        let with_frames = DhColumns {
            base: Some(*ur5.base()),
            tool: Some(*ur5.tool()),
            ..table.clone()
        };
        let t = with_frames.chain("ur5", conv, None).unwrap();
        assert!((t.fk(&q).unwrap().to_homogeneous() - ur5.fk(&q).unwrap().to_homogeneous()).norm() < 1e-14);
        let short = DhColumns {
            d: &d[..5],
            ..table.clone()
        };
        assert!(short.chain("x", conv, None).unwrap_err().to_string().starts_with("d:"));
        assert!(DhColumns::default().chain("x", conv, None).is_err());
        assert_eq!(t.joints()[0].kind().name(), "revolute");
        assert_eq!(JointType::Prismatic.letter(), 'P');
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
