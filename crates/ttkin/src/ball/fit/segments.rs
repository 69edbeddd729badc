//! The flights' frames: the camera's frame period from the tracker's velocities, the height of
//! the bounces, and the segment of a flight the fit uses (first frame through its first bounce).

use super::Recording;
use crate::error::{Error, Result};
use nalgebra::Vector3;

/// The frame period (s) from positions and tracker velocities: the median over frames of
/// Δp·v̄ / |v̄|² (v̄ the mean of the two frames' velocities), frames near a bounce excluded (the
/// vertical velocity changes sign there). Needs velocities.
pub fn estimate_period(recordings: &[Recording]) -> Result<f64> {
    let mut ratios = Vec::new();
    for r in recordings {
        if r.velocities.len() != r.positions.len() {
            continue;
        }
        for k in 1..r.positions.len() {
            let (v0, v1) = (Vector3::from(r.velocities[k - 1]), Vector3::from(r.velocities[k]));
            if v0.z * v1.z < 0.0 && v0.z < 0.0 {
                continue;
            }
            let vb = 0.5 * (v0 + v1);
            let dp = Vector3::from(r.positions[k]) - Vector3::from(r.positions[k - 1]);
            let q = dp.dot(&vb) / vb.norm_squared();
            if q.is_finite() {
                ratios.push(q);
            }
        }
    }
    if ratios.is_empty() {
        return Err(Error::invalid(
            "recordings",
            "no frames with velocities: give the frame period instead",
        ));
    }
    Ok(median(&mut ratios))
}

/// The median of `v` (sorts `v` in place).
pub(super) fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The first bounce-like height minimum of a flight (frame index) within `band` of `level` (any
/// when `level` is NaN): the lowest frame of its ±3 neighbours, with the height falling by more
/// than 2 cm over the 3 frames before and rising by more than 2 cm over the 3 after (a bounce at
/// ≥ 1 m/s; the noise around an apex does neither).
fn first_minimum(z: &[f64], level: f64, band: f64) -> Option<usize> {
    (3..z.len().saturating_sub(3)).find(|&k| {
        let lowest = (k - 3..=k + 3).all(|j| z[j] >= z[k]);
        lowest && z[k - 3] - z[k] > 0.02 && z[k + 3] - z[k] > 0.02 && (level.is_nan() || (z[k] - level).abs() <= band)
    })
}

/// The height (m) of the bounces' lowest frames: the median over flights of the first local
/// minimum of the height (the ball gun shoots upward, so the first minimum is the bounce).
pub fn bounce_level(recordings: &[Recording]) -> Result<f64> {
    let mut lows: Vec<f64> = recordings
        .iter()
        .filter_map(|r| {
            let z: Vec<f64> = r.positions.iter().map(|p| p[2]).collect();
            first_minimum(&z, f64::NAN, 0.0).map(|k| z[k])
        })
        .collect();
    if lows.is_empty() {
        return Err(Error::invalid(
            "recordings",
            "no flight has a height minimum (a bounce)",
        ));
    }
    Ok(median(&mut lows))
}

/// The segment of a flight (see the module doc): (frames used, bounce frame), or `None` without a
/// bounce near `level`.
pub fn segment(r: &Recording, level: f64, band: f64) -> Option<(usize, usize)> {
    let z: Vec<f64> = r.positions.iter().map(|p| p[2]).collect();
    if z.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let b = first_minimum(&z, level, band)?;
    let mut end = z.len();
    for k in b + 2..z.len() {
        if z[k] < z[k - 1] && z[k] < level + band {
            end = k;
            break;
        }
    }
    (end > b + 3 && b >= 4).then_some((end, b))
}
