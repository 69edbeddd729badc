//! A dynamic model built lazily from a chain on first use, with one shared scratch space, for an
//! owner that holds a [`Chain`] and calls dynamics now and then (a Python `Robot`, a planner).
//! Thread-safe: a second thread that finds the scratch space busy uses a fresh one rather than
//! wait.

use std::sync::{Arc, Mutex, OnceLock};

use super::model::{Dynamics, DynamicsData};
use crate::chain::Chain;
use crate::error::{Error, Result};

/// The lazily built [`Dynamics`] of one chain and a reusable [`DynamicsData`].
#[derive(Debug, Default)]
pub struct DynamicsCache {
    model: OnceLock<std::result::Result<Arc<Dynamics>, Error>>,
    scratch: Mutex<Option<DynamicsData>>,
}

impl DynamicsCache {
    /// An empty cache (nothing is built until the first call).
    pub fn new() -> Self {
        Self::default()
    }

    /// The dynamic model of `chain`, built on the first call (an error names the first link without
    /// inertia, and is returned again on every later call). Always pass the same chain.
    #[inline]
    pub fn model(&self, chain: &Chain) -> Result<&Arc<Dynamics>> {
        self.model
            .get_or_init(|| Dynamics::new(chain).map(Arc::new))
            .as_ref()
            .map_err(Clone::clone)
    }

    /// Runs `f` with the model of `chain` and a scratch space (the shared one when free).
    pub fn with_data<T>(&self, chain: &Chain, f: impl FnOnce(&Dynamics, &mut DynamicsData) -> T) -> Result<T> {
        let dy = self.model(chain)?;
        let mut guard = self.scratch.try_lock().ok();
        Ok(match guard.as_deref_mut() {
            Some(slot) => f(dy, slot.get_or_insert_with(|| DynamicsData::new(dy))),
            None => f(dy, &mut DynamicsData::new(dy)),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The model is built once and the scratch space gives the same result as a fresh one.
    #[test]
    fn cached_model_matches_a_fresh_one() {
        let chain = crate::robots::ur5();
        let cache = DynamicsCache::new();
        let q = [0.1, -0.4, 0.7, 0.2, -0.3, 0.5];
        let a = cache
            .with_data(&chain, |dy, d| {
                dy.gravity(d, &q, &super::super::EARTH_GRAVITY).unwrap().clone()
            })
            .unwrap();
        let dy = Dynamics::new(&chain).unwrap();
        let b = dy
            .gravity(&mut DynamicsData::new(&dy), &q, &super::super::EARTH_GRAVITY)
            .unwrap()
            .clone();
        assert_eq!(a, b);
        assert!(Arc::ptr_eq(cache.model(&chain).unwrap(), cache.model(&chain).unwrap()));
    }

    /// A chain without inertias gives the same model error on every call.
    #[test]
    fn missing_inertia_error_is_kept() {
        let joint = crate::joint::Joint::revolute(
            "j1",
            crate::joint::DhConvention::Standard,
            crate::joint::Dh {
                a: 0.1,
                alpha: 0.0,
                d: 0.0,
                theta: 0.0,
            },
        )
        .unwrap();
        let iso = nalgebra::IsometryMatrix3::identity();
        let bare = Chain::new("bare", vec![joint], iso, iso).unwrap();
        let cache = DynamicsCache::new();
        assert!(cache.model(&bare).is_err());
        assert!(cache.model(&bare).is_err());
    }
}
