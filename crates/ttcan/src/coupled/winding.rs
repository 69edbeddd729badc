//! The electrical side of one joint's actuator in the coupled simulation: its winding, stepped
//! exactly for a voltage held over one period (driven, or bridge off through the diodes).

/// The electrical side of one joint's actuator, as simulated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Winding {
    pub(super) resistance: f64,
    pub(super) inductance: f64,
    pub(super) torque_constant: f64,
    pub(super) back_emf_constant: f64,
    pub(super) gear: f64,
    pub(super) bus_voltage: f64,
    pub(super) counts_per_rev: f64,
    pub(super) current_noise: f64,
    pub(super) decay: f64,
}

/// Exact winding step with net voltage `v` (u − back-EMF) held over `t`: (end current, mean
/// current, mean square current).
#[inline]
pub(super) fn winding_step(w: &Winding, i0: f64, v: f64, t: f64) -> (f64, f64, f64) {
    let inf = v / w.resistance;
    let a = w.decay;
    let i1 = inf + (i0 - inf) * a;
    let tau = w.inductance / w.resistance;
    let d = i0 - inf;
    // i(s) = inf + d e^{−s/τ}: mean and mean square over [0, t].
    let e1 = (1.0 - a) * tau / t;
    let e2 = (1.0 - a * a) * tau / (2.0 * t);
    (i1, inf + d * e1, inf * inf + 2.0 * inf * d * e1 + d * d * e2)
}

/// Bridge off: diodes conduct while current flows (applied voltage −V_bus·sign(i)), or when the
/// back-EMF exceeds the bus; otherwise the winding is open. Returns (u, i1, mean, mean square).
pub(super) fn open_winding_step(w: &Winding, i0: f64, emf: f64, t: f64) -> (f64, f64, f64, f64) {
    if i0 == 0.0 && emf.abs() <= w.bus_voltage {
        return (0.0, 0.0, 0.0, 0.0);
    }
    let dir = if i0 != 0.0 { i0.signum() } else { -emf.signum() };
    let u = -dir * w.bus_voltage;
    let (i1, mean, mean_sq) = winding_step(w, i0, u - emf, t);
    if i1 * dir < 0.0 {
        // The current reached zero inside the period: the diodes block from then on.
        let frac = (i0 / (i0 - i1)).clamp(0.0, 1.0);
        let m = 0.5 * i0 * frac;
        return (u, 0.0, m, i0 * i0 * frac / 3.0);
    }
    (u, i1, mean, mean_sq)
}
