//! The simulated sensors' noise source: SplitMix64 (Steele, Lea & Flood 2014) with the
//! Box–Muller transform, seeded explicitly, allocation-free, both values of each pair used.
//! Used by the plant models ([`crate::motor`]) and the coupled simulation ([`crate::coupled`]);
//! never by a control loop.

use std::f64::consts::PI;

/// A seeded standard-normal generator (SplitMix64 + Box–Muller).
#[derive(Debug, Clone, PartialEq)]
pub struct Gaussian {
    state: u64,
    spare: Option<f64>,
}

impl Gaussian {
    /// A generator whose sequence is fixed by `seed`.
    pub fn new(seed: u64) -> Self {
        Gaussian {
            state: seed,
            spare: None,
        }
    }

    /// The next 64 random bits (SplitMix64).
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in (0, 1] (never 0, so that its logarithm is finite).
    pub fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 1.0) / (1u64 << 53) as f64
    }

    /// A standard normal sample: the cosine value of a fresh Box–Muller pair, then its sine value.
    pub fn normal(&mut self) -> f64 {
        if let Some(v) = self.spare.take() {
            return v;
        }
        let (a, b) = (self.uniform(), self.uniform());
        let r = (-2.0 * a.ln()).sqrt();
        let (sin, cos) = (2.0 * PI * b).sin_cos();
        self.spare = Some(r * sin);
        r * cos
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_same_seed_gives_the_same_sequence_and_the_moments_of_a_standard_normal() {
        let (mut a, mut b) = (Gaussian::new(7), Gaussian::new(7));
        let n = 200_000;
        let (mut s1, mut s2, mut s4) = (0.0, 0.0, 0.0);
        for _ in 0..n {
            let x = a.normal();
            assert_eq!(x.to_bits(), b.normal().to_bits());
            assert!(x.is_finite());
            s1 += x;
            s2 += x * x;
            s4 += x * x * x * x;
        }
        let nf = n as f64;
        assert!((s1 / nf).abs() < 0.01, "mean {}", s1 / nf);
        assert!((s2 / nf - 1.0).abs() < 0.02, "variance {}", s2 / nf);
        assert!((s4 / nf - 3.0).abs() < 0.1, "fourth moment {}", s4 / nf);
        assert_ne!(Gaussian::new(8).normal(), Gaussian::new(7).normal());
    }

    #[test]
    fn uniform_is_in_the_half_open_unit_interval() {
        let mut g = Gaussian::new(0);
        for _ in 0..100_000 {
            let u = g.uniform();
            assert!(u > 0.0 && u <= 1.0);
        }
    }
}
