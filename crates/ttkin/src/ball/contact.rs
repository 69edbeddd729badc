//! Contacts of the ball with the table (surface, edges, sides), the net and the floor, and the
//! impulse model of a bounce.
//!
//! Geometry as signed distances: the table top is the box |x| ≤ L/2, |y| ≤ W/2,
//! −thickness ≤ z ≤ 0; the net is a 2 mm thick box at x = 0, |y| ≤ W/2 + overhang, 0 ≤ z ≤ net
//! height. The ball touches a body when the distance of its centre to the body falls to its radius;
//! the contact normal is the direction from the body's closest point to the ball centre (the surface
//! normal +z on the playing surface, a radial direction at an edge).
//!
//! Bounce (Nakashima et al., "Modeling of rebound phenomenon of a rigid ball with friction and
//! elastic effects", ACC 2010; the rigid-ball part of their model): with relative velocity v of the
//! ball centre, normal n, spin ω and slip velocity of the contact point u = v_t + ω × (−r·n):
//! the normal speed reverses with restitution e, v_n' = −e·v_n; the tangential impulse per unit
//! mass j is Coulomb friction μ(1+e)|v_n| against the slip, capped at the impulse that makes the
//! ball roll, −u/κ with κ = 1 + m·r²/I = 5/2 for a thin shell (I = 2/3·m·r²). Then
//! v' = v + (1+e)|v_n|·n + j and ω' = ω + (m·r/I)·(j × n). The rolling cap makes the model
//! dissipative: kinetic plus rotational energy never increases.

use super::model::{BallModel, Table};
use nalgebra::Vector3;

/// Closest point of the axis-aligned box [lo, hi] to `p` and the signed distance (negative inside)
/// with its outward normal.
fn box_distance(p: &Vector3<f64>, lo: &Vector3<f64>, hi: &Vector3<f64>) -> (f64, Vector3<f64>) {
    let q = Vector3::new(p.x.clamp(lo.x, hi.x), p.y.clamp(lo.y, hi.y), p.z.clamp(lo.z, hi.z));
    let d = p - q;
    let dist = d.norm();
    if dist > 0.0 {
        return (dist, d / dist);
    }
    // Inside: the nearest face.
    let mut best = (f64::INFINITY, Vector3::z());
    for k in 0..3 {
        let below = p[k] - lo[k];
        let above = hi[k] - p[k];
        if below < best.0 {
            let mut n = Vector3::zeros();
            n[k] = -1.0;
            best = (below, n);
        }
        if above < best.0 {
            let mut n = Vector3::zeros();
            n[k] = 1.0;
            best = (above, n);
        }
    }
    (-best.0, best.1)
}

/// Signed distance (m) of `p` (world) to the table top and the outward contact normal there.
pub fn table_distance(table: &Table, p: &Vector3<f64>) -> (f64, Vector3<f64>) {
    let lo = Vector3::new(-table.half_length(), -table.half_width(), -table.thickness);
    let hi = Vector3::new(table.half_length(), table.half_width(), 0.0);
    box_distance(p, &lo, &hi)
}

/// Signed distance (m) of `p` (world) to the net and the outward normal there.
pub fn net_distance(table: &Table, p: &Vector3<f64>) -> (f64, Vector3<f64>) {
    let half = table.half_width() + table.net_overhang;
    let lo = Vector3::new(-0.001, -half, 0.0);
    let hi = Vector3::new(0.001, half, table.net_height);
    box_distance(p, &lo, &hi)
}

/// Height (m) of the ball centre above its resting height on the floor (z = −table height + r).
pub fn floor_distance(table: &Table, model: &BallModel, p: &Vector3<f64>) -> f64 {
    p.z + table.height - model.radius
}

/// Velocity and spin after an impulsive contact (Nakashima-type friction with a rolling cap).
///
/// `v_rel` is the ball centre's velocity relative to the contact surface (m/s), `w` the spin
/// (rad/s), `n` the unit normal out of the surface toward the ball, `e` the normal restitution,
/// `mu` the Coulomb friction coefficient. Returns the change (Δv, Δω) of the ball's velocity and
/// spin. A ball not approaching the surface (v_rel·n ≥ 0) is unchanged.
pub fn impulse(
    model: &BallModel,
    v_rel: &Vector3<f64>,
    w: &Vector3<f64>,
    n: &Vector3<f64>,
    e: f64,
    mu: f64,
) -> (Vector3<f64>, Vector3<f64>) {
    let vn = v_rel.dot(n);
    if vn >= 0.0 {
        return (Vector3::zeros(), Vector3::zeros());
    }
    let r = model.radius;
    let slip = (v_rel - vn * n) + w.cross(&(-r * n));
    let kappa = 1.0 + model.mass * r * r / model.inertia();
    let normal_impulse = (1.0 + e) * (-vn); // per unit mass
    let roll = slip / kappa;
    let friction = mu * normal_impulse;
    let j = if roll.norm() <= friction {
        -roll
    } else {
        -friction * slip / slip.norm()
    };
    let dv = normal_impulse * n + j;
    let dw = (model.mass * r / model.inertia()) * j.cross(n);
    (dv, dw)
}

/// Kinetic plus rotational energy (J) of the ball with velocity `v` (m/s) and spin `w` (rad/s).
pub fn energy(model: &BallModel, v: &Vector3<f64>, w: &Vector3<f64>) -> f64 {
    0.5 * model.mass * v.norm_squared() + 0.5 * model.inertia() * w.norm_squared()
}
