//! Multi-rate scheduling: the current loop runs every base tick, the speed and position loops every
//! n-th tick. Used by one axis ([`crate::sim`]), many axes ([`crate::stepper`], [`crate::coupled`])
//! and the CAN runtime alike; it knows nothing of axes.

use crate::error::{positive, Error, Result};

/// Loop rates, Hz: current ≥ speed ≥ position, each an integer multiple of the next. Serialised
/// as `{ current_hz, speed_hz, position_hz }`, checked by [`Rates::new`] when read.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "RatesHz", into = "RatesHz")]
pub struct Rates {
    current_hz: f64,
    speed_divider: u32,
    position_divider: u32,
}

impl Rates {
    /// Validates the rates: finite, positive, and `current_hz / speed_hz`, `speed_hz / position_hz`
    /// integers (to 1e-9 relative) between 1 and 10 000.
    pub fn new(current_hz: f64, speed_hz: f64, position_hz: f64) -> Result<Self> {
        positive("current loop rate (Hz)", current_hz)?;
        positive("speed loop rate (Hz)", speed_hz)?;
        positive("position loop rate (Hz)", position_hz)?;
        let divider = |fast: f64, slow: f64, names: &str| -> Result<u32> {
            let r = fast / slow;
            let n = r.round();
            if !(1.0..=10_000.0).contains(&n) || (r - n).abs() > 1e-9 * r {
                return Err(Error::Rates(format!(
                    "{names}: {fast} Hz / {slow} Hz = {r} is not an integer between 1 and 10000"
                )));
            }
            Ok(n as u32)
        };
        Ok(Rates {
            current_hz,
            speed_divider: divider(current_hz, speed_hz, "current/speed")?,
            position_divider: divider(speed_hz, position_hz, "speed/position")?,
        })
    }

    /// Current-loop (base) rate, Hz.
    pub fn current_hz(&self) -> f64 {
        self.current_hz
    }

    /// Speed-loop rate, Hz.
    pub fn speed_hz(&self) -> f64 {
        self.current_hz / self.speed_divider as f64
    }

    /// Position-loop rate, Hz.
    pub fn position_hz(&self) -> f64 {
        self.speed_hz() / self.position_divider as f64
    }

    /// Loop periods [current, speed, position], s.
    pub fn periods(&self) -> [f64; 3] {
        [1.0 / self.current_hz(), 1.0 / self.speed_hz(), 1.0 / self.position_hz()]
    }

    /// Base ticks per speed-loop step.
    pub fn speed_divider(&self) -> u32 {
        self.speed_divider
    }

    /// Base ticks per position-loop step.
    pub fn position_ticks(&self) -> u32 {
        self.speed_divider * self.position_divider
    }
}

impl Default for Rates {
    /// 20 kHz current, 5 kHz speed, 1 kHz position.
    fn default() -> Self {
        Rates {
            current_hz: 20_000.0,
            speed_divider: 4,
            position_divider: 5,
        }
    }
}

/// Which of the slower loops are due on this base tick (the current loop always is).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Due {
    /// The speed loop runs on this tick.
    pub speed: bool,
    /// The position loop runs on this tick.
    pub position: bool,
}

impl Due {
    /// All loops due (the first tick, and the worst case for timing).
    pub const ALL: Due = Due {
        speed: true,
        position: true,
    };
}

/// Counts base ticks and says which loops are due; tick 0 runs every loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Scheduler {
    speed_divider: u32,
    position_ticks: u32,
    speed_count: u32,
    position_count: u32,
    ticks: u64,
}

impl Scheduler {
    /// Scheduler for `rates`, starting at tick 0.
    pub fn new(rates: &Rates) -> Self {
        Scheduler {
            speed_divider: rates.speed_divider(),
            position_ticks: rates.position_ticks(),
            speed_count: 0,
            position_count: 0,
            ticks: 0,
        }
    }

    /// Which loops are due on the next call of [`Scheduler::next_tick`], without advancing.
    #[inline]
    pub fn peek(&self) -> Due {
        Due {
            speed: self.speed_count == 0,
            position: self.position_count == 0,
        }
    }

    /// Which loops are due now; advances to the next tick.
    #[inline]
    pub fn next_tick(&mut self) -> Due {
        let due = Due {
            speed: self.speed_count == 0,
            position: self.position_count == 0,
        };
        self.speed_count += 1;
        if self.speed_count == self.speed_divider {
            self.speed_count = 0;
        }
        self.position_count += 1;
        if self.position_count == self.position_ticks {
            self.position_count = 0;
        }
        self.ticks += 1;
        due
    }

    /// Base ticks run so far.
    pub fn ticks(&self) -> u64 {
        self.ticks
    }
}

/// The serialised form of [`Rates`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RatesHz {
    /// Current-loop rate, Hz.
    pub current_hz: f64,
    /// Speed-loop rate, Hz.
    pub speed_hz: f64,
    /// Position-loop rate, Hz.
    pub position_hz: f64,
}

impl TryFrom<RatesHz> for Rates {
    type Error = Error;
    fn try_from(r: RatesHz) -> Result<Self> {
        Rates::new(r.current_hz, r.speed_hz, r.position_hz)
    }
}

impl From<Rates> for RatesHz {
    fn from(r: Rates) -> Self {
        RatesHz {
            current_hz: r.current_hz(),
            speed_hz: r.speed_hz(),
            position_hz: r.position_hz(),
        }
    }
}
