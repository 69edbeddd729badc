//! The one place where SI values become CiA 402 integers and back: positions in increments
//! (objects 0x6064, 0x607A), velocities in increments/s (0x60FF), torques in per-mille of the
//! rated torque (0x6071, 0x60B2, object 0x6076), currents in per-mille of the rated current
//! (0x6078, object 0x6075). A value that does not fit its integer is an error, never wrapped.

use super::ProtocolError;

/// Scale factors of one axis between SI (joint side: rad or m, N·m or N, A) and CiA 402 integers.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Units {
    /// Position increments per joint unit (rad or m).
    pub increments_per_unit: f64,
    /// Rated torque (object 0x6076), N·m (or N for a prismatic joint), at the joint.
    pub rated_torque: f64,
    /// Rated current (object 0x6075), A.
    pub rated_current: f64,
}

impl Default for Units {
    /// 10⁵ increments per rad (10 µrad), rated torque 1 N·m, rated current 1.2 A.
    fn default() -> Self {
        Units {
            increments_per_unit: 1e5,
            rated_torque: 1.0,
            rated_current: 1.2,
        }
    }
}

/// `value` as per-mille of `rated` (the CiA 402 torque and current unit), named `what` when out of
/// the i16 range.
fn to_permille(what: &'static str, value: f64, rated: f64) -> Result<i16, ProtocolError> {
    Ok(to_int(what, value / rated * 1000.0, i16::MIN as f64, i16::MAX as f64)? as i16)
}

fn to_int(what: &'static str, x: f64, lo: f64, hi: f64) -> Result<i64, ProtocolError> {
    let r = x.round();
    if r.is_finite() && r >= lo && r <= hi {
        Ok(r as i64)
    } else {
        Err(ProtocolError::OutOfRange {
            what,
            value: if x.is_finite() {
                r.clamp(i64::MIN as f64, i64::MAX as f64) as i64
            } else {
                i64::MAX
            },
        })
    }
}

impl Units {
    /// Checks that every factor is finite and positive.
    pub fn validate(&self) -> Result<(), ProtocolError> {
        for (what, v) in [
            ("increments per unit", self.increments_per_unit),
            ("rated torque", self.rated_torque),
            ("rated current", self.rated_current),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(ProtocolError::OutOfRange { what, value: v as i64 });
            }
        }
        Ok(())
    }

    /// Joint position (rad or m) → increments.
    pub fn position_to_increments(&self, q: f64) -> Result<i32, ProtocolError> {
        let v = to_int(
            "position",
            q * self.increments_per_unit,
            i32::MIN as f64,
            i32::MAX as f64,
        )?;
        Ok(v as i32)
    }

    /// Increments → joint position (rad or m).
    pub fn increments_to_position(&self, inc: i32) -> f64 {
        inc as f64 / self.increments_per_unit
    }

    /// Joint velocity (rad/s or m/s) → increments/s.
    pub fn velocity_to_increments(&self, qd: f64) -> Result<i32, ProtocolError> {
        let v = to_int(
            "velocity",
            qd * self.increments_per_unit,
            i32::MIN as f64,
            i32::MAX as f64,
        )?;
        Ok(v as i32)
    }

    /// Increments/s → joint velocity (rad/s or m/s).
    pub fn increments_to_velocity(&self, inc: i32) -> f64 {
        inc as f64 / self.increments_per_unit
    }

    /// Joint torque (N·m or N) → per-mille of the rated torque.
    pub fn torque_to_permille(&self, tau: f64) -> Result<i16, ProtocolError> {
        to_permille("torque", tau, self.rated_torque)
    }

    /// Per-mille of the rated torque → joint torque (N·m or N).
    pub fn permille_to_torque(&self, p: i16) -> f64 {
        p as f64 * self.rated_torque / 1000.0
    }

    /// Motor current (A) → per-mille of the rated current.
    pub fn current_to_permille(&self, i: f64) -> Result<i16, ProtocolError> {
        to_permille("current", i, self.rated_current)
    }

    /// Per-mille of the rated current → motor current (A).
    pub fn permille_to_current(&self, p: i16) -> f64 {
        p as f64 * self.rated_current / 1000.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn position_round_trip_within_half_an_increment(q in -2.0e4f64..2.0e4) {
            let u = Units::default();
            let inc = u.position_to_increments(q).unwrap();
            prop_assert!((u.increments_to_position(inc) - q).abs() <= 0.5 / u.increments_per_unit + 1e-12);
        }

        #[test]
        fn torque_and_current_round_trip_within_half_a_permille(x in -30.0f64..30.0) {
            let u = Units::default();
            let t = u.permille_to_torque(u.torque_to_permille(x).unwrap());
            prop_assert!((t - x).abs() <= 0.5e-3 * u.rated_torque + 1e-12);
            let i = u.permille_to_current(u.current_to_permille(x).unwrap());
            prop_assert!((i - x).abs() <= 0.5e-3 * u.rated_current + 1e-12);
        }
    }

    #[test]
    fn values_that_do_not_fit_are_errors() {
        let u = Units::default();
        assert!(u.position_to_increments(3.0e4).is_err());
        assert!(u.position_to_increments(f64::NAN).is_err());
        assert!(u.torque_to_permille(40.0).is_err());
        assert!(u.current_to_permille(f64::INFINITY).is_err());
        assert!(Units {
            rated_current: 0.0,
            ..u
        }
        .validate()
        .is_err());
    }
}
