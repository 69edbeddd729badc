//! Racket poses in the robot's base frame for one plan: the base placement and the rolls' sines
//! and cosines computed once per plan, not once per pose (a plan asks for a few hundred poses).

use super::super::reach::racket_rotation_turned;
use super::ReturnPlanner;
use nalgebra::{IsometryMatrix3, Translation3, Vector3};

/// The planner's placement inverted and its rolls as (sine, cosine), fixed for one plan.
pub(super) struct RacketPoses {
    base_from_world: IsometryMatrix3<f64>,
    rolls: Vec<(f64, f64)>,
}

impl RacketPoses {
    /// The poses of `planner` as its placement and rolls are now.
    pub(super) fn new(planner: &ReturnPlanner) -> Self {
        RacketPoses {
            base_from_world: planner.placement.world_from_base().inverse(),
            rolls: planner
                .rolls
                .iter()
                .map(|&r| if r == 0.0 { (0.0, 1.0) } else { r.sin_cos() })
                .collect(),
        }
    }

    /// Number of rolls.
    pub(super) fn rolls(&self) -> usize {
        self.rolls.len()
    }

    /// [`ReturnPlanner::base_pose_rolled`] for the racket centre `c` and normal `n` (m, world) with
    /// the planner's roll number `k`: the same pose.
    pub(super) fn pose(&self, c: &Vector3<f64>, n: &Vector3<f64>, k: usize) -> IsometryMatrix3<f64> {
        let world = IsometryMatrix3::from_parts(Translation3::from(*c), racket_rotation_turned(n, self.rolls[k]));
        self.base_from_world * world
    }
}

#[cfg(test)]
mod tests {
    use super::super::super::flight::Flight;
    use super::*;

    #[test]
    fn poses_are_the_planners_base_poses() {
        let mut pl = ReturnPlanner::new(crate::robots::gantry6(), Flight::default()).unwrap();
        pl.placement.yaw = 0.3;
        pl.rolls = vec![0.0, 0.5, -1.1];
        let poses = RacketPoses::new(&pl);
        let mut rng = fastrand::Rng::with_seed(2);
        for _ in 0..100 {
            let c = Vector3::new(rng.f64(), rng.f64(), rng.f64());
            let n = Vector3::new(rng.f64() - 0.5, rng.f64() - 0.5, rng.f64() - 0.5);
            for (k, &roll) in pl.rolls.iter().enumerate() {
                assert_eq!(poses.pose(&c, &n, k), pl.base_pose_rolled(&c, &n, roll));
            }
        }
    }
}
