//! Per-joint tables as users hold them (one column of numbers per quantity, one row per joint)
//! turned into model data, and the same chain rebuilt with them: [`Chain::with_inertials`],
//! [`Chain::with_drives`]. The defaults of a missing column live here, nowhere else.

use nalgebra::{Matrix3, Vector3};

use crate::chain::Chain;
use crate::error::{check_finite, check_vector, Error, Result};
use crate::inertial::Inertial;
use crate::joint::{Drive, Joint, Limits};

/// Link inertias of n links from columns: `mass` (n) kg, `com` (n × 3 row-major) m and
/// `inertia` (n × 9, row-major 3 × 3 per link) kg·m² about the centre of mass, link frames.
pub fn inertials_from_columns(mass: &[f64], com: &[f64], inertia: &[f64]) -> Result<Vec<Inertial>> {
    let n = mass.len();
    check_vector("mass", mass, n)?;
    check_vector("com", com, 3 * n)?;
    check_vector("inertia", inertia, 9 * n)?;
    Ok((0..n)
        .map(|k| Inertial {
            mass: mass[k],
            com: Vector3::new(com[3 * k], com[3 * k + 1], com[3 * k + 2]),
            inertia: Matrix3::from_row_slice(&inertia[9 * k..9 * k + 9]),
        })
        .collect())
}

/// Columns of n drives; `None` columns take their defaults (rotor inertia, viscous and Coulomb
/// friction 0; torque constant unknown).
#[derive(Debug, Clone, Copy, Default)]
pub struct DriveColumns<'a> {
    /// Gear ratio G per joint (> 0).
    pub gear_ratio: &'a [f64],
    /// Rotor inertia, motor side, kg·m² (default 0).
    pub rotor_inertia: Option<&'a [f64]>,
    /// Viscous friction b, joint side (default 0).
    pub viscous: Option<&'a [f64]>,
    /// Coulomb friction f_c, joint side (default 0).
    pub coulomb: Option<&'a [f64]>,
    /// Torque constant k_t, N·m/A; NaN for unknown (default unknown).
    pub torque_constant: Option<&'a [f64]>,
}

impl DriveColumns<'_> {
    /// The drives, one per row; every column must have the length of `gear_ratio`.
    pub fn drives(&self) -> Result<Vec<Drive>> {
        let n = self.gear_ratio.len();
        check_vector("gear_ratio", self.gear_ratio, n)?;
        let column = |c: Option<&[f64]>, what: &str| -> Result<Vec<f64>> {
            match c {
                None => Ok(vec![0.0; n]),
                Some(v) => check_vector(what, v, n).map(|_| v.to_vec()),
            }
        };
        let (j, b, c) = (
            column(self.rotor_inertia, "rotor_inertia")?,
            column(self.viscous, "viscous")?,
            column(self.coulomb, "coulomb")?,
        );
        let kt: Vec<Option<f64>> = match self.torque_constant {
            None => vec![None; n],
            Some(v) if v.len() != n => {
                return Err(Error::shape(
                    "torque_constant",
                    format!("({n},)"),
                    format!("({},)", v.len()),
                ))
            }
            Some(v) => v.iter().map(|&x| (!x.is_nan()).then_some(x)).collect(),
        };
        if let Some(v) = self.torque_constant {
            let known: Vec<f64> = v.iter().copied().filter(|x| !x.is_nan()).collect();
            check_finite("torque_constant", &known)?;
        }
        Ok((0..n)
            .map(|k| Drive {
                gear_ratio: self.gear_ratio[k],
                rotor_inertia: j[k],
                viscous: b[k],
                coulomb: c[k],
                torque_constant: kt[k],
                ..Drive::geared(self.gear_ratio[k])
            })
            .collect())
    }
}

/// The mechanical entries of one drive, the row of [`DriveColumns`] (serde: a record with every
/// key, `torque_constant` None when unknown).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DriveRow {
    /// Gear ratio G (> 0).
    pub gear_ratio: f64,
    /// Rotor inertia, motor side, kg·m².
    pub rotor_inertia: f64,
    /// Viscous friction b, joint side (N·m·s/rad or N·s/m).
    pub viscous: f64,
    /// Coulomb friction f_c, joint side (N·m or N).
    pub coulomb: f64,
    /// Torque constant k_t, N·m/A, None when unknown.
    pub torque_constant: Option<f64>,
}

impl Chain {
    /// Each joint's [`DriveRow`], None for a joint without a drive.
    pub fn drive_rows(&self) -> Vec<Option<DriveRow>> {
        self.joints()
            .iter()
            .map(|j| {
                j.drive().map(|d| DriveRow {
                    gear_ratio: d.gear_ratio,
                    rotor_inertia: d.rotor_inertia,
                    viscous: d.viscous,
                    coulomb: d.coulomb,
                    torque_constant: d.torque_constant,
                })
            })
            .collect()
    }

    /// The same chain whose links carry `inertials` (one per joint, link frames; validated).
    pub fn with_inertials(&self, inertials: &[Inertial]) -> Result<Chain> {
        self.rebuilt(inertials, |j, i| j.with_inertial(*i))
    }

    /// The same chain whose joints are driven by `drives` (one per joint; validated).
    pub fn with_drives(&self, drives: &[Drive]) -> Result<Chain> {
        self.rebuilt(drives, |j, d| j.with_drive(*d))
    }

    /// Rotor inertia reflected to each joint, G²·J (kg·m² or kg; 0 for a joint without a drive).
    pub fn armatures(&self) -> Vec<f64> {
        self.joints()
            .iter()
            .map(|j| j.drive().map_or(0.0, Drive::armature))
            .collect()
    }

    /// Link masses (kg; NaN where a link has no inertial).
    pub fn masses(&self) -> Vec<f64> {
        self.joints()
            .iter()
            .map(|j| j.inertial().map_or(f64::NAN, |i| i.mass))
            .collect()
    }

    /// One optional limit of every joint, `f` picking it (infinity where a joint has none).
    pub fn limit_column(&self, f: impl Fn(&Limits) -> Option<f64>) -> Vec<f64> {
        self.limits().iter().map(|l| f(l).unwrap_or(f64::INFINITY)).collect()
    }

    fn rebuilt<T>(&self, items: &[T], f: impl Fn(Joint, &T) -> Result<Joint>) -> Result<Chain> {
        if items.len() != self.dof() {
            return Err(Error::shape("per-joint table", self.dof(), items.len()));
        }
        let joints = self
            .joints()
            .iter()
            .zip(items)
            .map(|(j, x)| f(j.clone(), x))
            .collect::<Result<Vec<_>>>()?;
        self.with_joints(joints, *self.base(), *self.tool())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rebuilding a robot with its own inertias and drives gives the same dynamics.
    #[test]
    fn rebuilt_chain_has_the_same_model() {
        let ur5 = crate::robots::ur5();
        let ins: Vec<Inertial> = ur5.joints().iter().map(|j| *j.inertial().unwrap()).collect();
        let (mass, com, inertia): (Vec<f64>, Vec<f64>, Vec<f64>) = (
            ins.iter().map(|i| i.mass).collect(),
            ins.iter()
                .flat_map(|i| i.com.iter().copied().collect::<Vec<_>>())
                .collect(),
            ins.iter()
                .flat_map(|i| i.inertia.transpose().iter().copied().collect::<Vec<_>>())
                .collect(),
        );
        let rebuilt = ur5
            .with_inertials(&inertials_from_columns(&mass, &com, &inertia).unwrap())
            .unwrap();
        assert_eq!(rebuilt, ur5);
        let g = vec![50.0; 6];
        let kt = vec![0.1, f64::NAN, 0.1, 0.1, 0.1, 0.1];
        let d = DriveColumns {
            gear_ratio: &g,
            torque_constant: Some(&kt),
            ..Default::default()
        }
        .drives()
        .unwrap();
        assert_eq!(d[1].torque_constant, None);
        assert_eq!(d[0].viscous, 0.0);
        assert!(ur5.with_drives(&d[..5]).is_err());
        assert_eq!(ur5.masses(), mass);
        assert!(ur5.armatures().iter().all(|a| a.is_finite() && *a >= 0.0));
        assert_eq!(ur5.limit_column(|_| None), vec![f64::INFINITY; 6]);
        assert_eq!(
            ur5.limit_column(|l| Some(l.lower)),
            ur5.limits().iter().map(|l| l.lower).collect::<Vec<_>>()
        );
    }
}
