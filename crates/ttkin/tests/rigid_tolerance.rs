//! `isometry_from_matrix_within` (issue 14): a rotation rounded to float32 is rigid to float32's
//! precision, is accepted with a tolerance of that size and comes back orthonormal to float64's.

use nalgebra::{Matrix3, Matrix4, Rotation3, Vector3};
use proptest::prelude::*;
use ttkin::transform::{isometry_from_matrix, isometry_from_matrix_within, RIGID_TOLERANCE};

fn rounded_to_f32(axis: [f64; 3], angle: f64, p: [f64; 3]) -> Matrix4<f64> {
    let r = Rotation3::from_scaled_axis(Vector3::from(axis).normalize() * angle);
    let mut m = Matrix4::identity();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(r.matrix());
    m.fixed_view_mut::<3, 1>(0, 3).copy_from(&Vector3::from(p));
    m.map(|v| f64::from(v as f32))
}

proptest! {
    #[test]
    fn float32_rotations_are_accepted_and_reorthonormalised(
        axis in prop::array::uniform3(-1.0..1.0f64).prop_filter("non-zero", |a| a.iter().map(|v| v * v).sum::<f64>() > 1e-3),
        angle in -3.1..3.1f64,
        p in prop::array::uniform3(-2.0..2.0f64),
    ) {
        let m = rounded_to_f32(axis, angle, p);
        let t = isometry_from_matrix_within("T", &m, 16.0 * f64::from(f32::EPSILON)).unwrap();
        let r = t.rotation.matrix();
        prop_assert!((r.transpose() * r - Matrix3::identity()).abs().max() < 1e-14);
        prop_assert!((r - m.fixed_view::<3, 3>(0, 0)).abs().max() < 1e-6);
        prop_assert!((t.translation.vector - m.fixed_view::<3, 1>(0, 3)).abs().max() == 0.0);
    }
}

#[test]
fn float64_keeps_its_tolerance_and_coarse_errors_stay_refused() {
    let mut m = rounded_to_f32([0.3, -0.2, 0.9], 1.1, [0.1, 0.2, 0.3]);
    // float32 rounding: above 1e-9, so refused at float64's tolerance
    assert!(isometry_from_matrix("T", &m).is_err());
    let exact = Matrix4::<f64>::identity();
    assert!(isometry_from_matrix("T", &exact).is_ok());
    m[(0, 0)] += 1e-3;
    let e = isometry_from_matrix_within("T", &m, 16.0 * f64::from(f32::EPSILON)).unwrap_err();
    assert!(e.to_string().contains("orthonormal"), "{e}");
    assert_eq!(RIGID_TOLERANCE, 1e-9);
}
