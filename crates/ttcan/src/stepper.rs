//! N axes on one multi-rate schedule ([`crate::schedule`]): one [`Stepper`] call per base tick
//! turns N measurements into N duty cycles, allocation free.

use crate::axis::Axis;
use crate::error::{Error, Result};
use crate::motor::Measurement;
pub use crate::schedule::{Due, Rates, Scheduler};

/// N axes on one schedule: one call per base tick turns N measurements into N duty cycles.
#[derive(Debug, Clone)]
pub struct Stepper<const N: usize> {
    axes: [Axis; N],
    scheduler: Scheduler,
}

impl<const N: usize> Stepper<N> {
    /// Takes the axes; they must share one set of loop rates.
    pub fn new(axes: [Axis; N]) -> Result<Self> {
        let Some(first) = axes.first() else {
            return Err(Error::Stepper("needs at least one axis".into()));
        };
        let rates = *first.rates();
        if let Some(k) = axes.iter().position(|a| *a.rates() != rates) {
            return Err(Error::Stepper(format!("axis {k} has loop rates different from axis 0")));
        }
        Ok(Stepper {
            axes,
            scheduler: Scheduler::new(&rates),
        })
    }

    /// One base tick for every axis: measurements in, duty cycles (in [−1, 1]) out.
    #[inline]
    pub fn cycle(&mut self, measurements: &[Measurement; N], duties: &mut [f64; N]) {
        let due = self.scheduler.next_tick();
        for ((axis, m), d) in self.axes.iter_mut().zip(measurements).zip(duties.iter_mut()) {
            *d = axis.tick(*m, due);
        }
    }

    /// The axes (to read their state).
    pub fn axes(&self) -> &[Axis; N] {
        &self.axes
    }

    /// The axes (to enable them, set references, clear faults).
    pub fn axes_mut(&mut self) -> &mut [Axis; N] {
        &mut self.axes
    }

    /// The schedule.
    pub fn scheduler(&self) -> &Scheduler {
        &self.scheduler
    }
}
