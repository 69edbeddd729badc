//! Calibration of the ball model on recorded flights: drag, Magnus, table restitution and
//! friction, with the table height and the camera's frame period, by Levenberg–Marquardt over
//! every flight at once; and the prediction error of a model on flights it was not fitted on.
//!
//! **Data.** A [`Recording`] is one flight: ball-centre positions (m) at equally spaced camera
//! frames in the recording's own frame (z up, gravity along −z; no time stamps), optionally the
//! tracker's velocities (m/s; used only to estimate the frame period and to start the fit).
//!
//! **Segment.** Each flight is used from its first frame through its first table bounce (the first
//! local height minimum within [`FitOptions::bounce_band`] of the median first minimum over all
//! flights) up to the frame before the ball comes down to within `bounce_band` of that height
//! again (a second bounce, or the ball leaving the table's end and falling past its surface): one
//! bounce per segment, on an unbounded plane z = surface. Flights without such a bounce are left
//! out and counted.
//!
//! **Model.** Flight as in [`super::flight`] (a = g − k_d·|v|·v + k_m·ω × v, RK4 at ≤ 2 ms steps,
//! spin constant in flight), the bounce where the centre reaches surface + r (located by
//! bisection) by [`super::contact::impulse`] (restitution e, Coulomb friction μ with the rolling
//! cap), or, for published models of that form, [`Bounce::Linear`]. Parameters: the globals
//! θ = (k_d, k_m, e, μ, surface, period) and per flight the nuisance x_i = (p0, v0, ω) at its
//! first frame. Residuals: the simulated minus the observed position at every frame of the
//! segment (m), and a weak prior on the spin, ω/σ_ω·s (σ_ω = [`FitOptions::spin_prior`], s = 5
//! mm): spin along the velocity makes no Magnus force and shows only through the bounce.
//!
//! **Solver.** Levenberg–Marquardt (Marquardt's diagonal scaling) on the block-arrow normal
//! matrix: per flight U_i = A_iᵀA_i (9 × 9), W_i = A_iᵀB_i, and V = Σ B_iᵀB_i for the globals;
//! the globals' step from the Schur complement S = V − Σ W_iᵀU_i⁻¹W_i, then each flight's step.
//! Jacobians by forward differences. Robust: three rounds, the first unweighted, then Huber
//! weights per frame (threshold 3 × the median residual distance) from the previous round's
//! residuals. The
//! globals' covariance is σ²·S⁻¹ (undamped, the nuisance marginalised), σ² = Σ w·r² / (N − P).
//!
//! **Prediction error** ([`prediction_error`]): a flight's state is fitted on its first `k`
//! frames (the model's constants fixed, the same spin prior), then the flight is predicted from
//! there through the bounce; the error is the distance between predicted and observed positions
//! at the later frames of the segment: RMS over those after the bounce, and over all of them.

mod calibrate;
mod experiment;
mod path;
mod prediction;
mod problem;
mod report;
mod segments;

pub use calibrate::calibrate;
pub use experiment::{experiment, held_out, published, Comparison, Experiment, FRAME_PERIOD_RANGE, WINDOW};
pub use path::MIN_REBOUND_SPEED;
pub use prediction::{prediction_error, PredictionError, MIN_WINDOW};
pub use segments::{bounce_level, estimate_period, segment};

use super::flight::BallState;
use super::model::BallModel;
use crate::error::{Error, Result};

/// One recorded flight: positions (m) at equally spaced frames and, optionally, the tracker's
/// velocities (m/s) at the same frames (empty when not recorded); recording frame, z up.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// Name (e.g. the file), for reports.
    pub name: String,
    /// Ball-centre positions (m), one per frame.
    pub positions: Vec<[f64; 3]>,
    /// The tracker's velocity estimates (m/s), one per frame, or empty.
    pub velocities: Vec<[f64; 3]>,
}

/// How the ball leaves the table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bounce {
    /// The impulse model of [`super::contact::impulse`] with the model's table restitution and friction.
    Impulse,
    /// A linear map of the velocity, v' = (c_x·v_x, c_y·v_y, −c_z·v_z), spin unchanged (the form of
    /// the MPI table-tennis code's table contact, no spin).
    Linear([f64; 3]),
}

/// A ball model as the fit sees it: flight and bounce constants, the table surface height (m,
/// recording frame) and the frame period (s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitModel {
    /// Flight constants (k_d, k_m) and, for [`Bounce::Impulse`], restitution and friction.
    pub model: BallModel,
    /// The bounce law.
    pub bounce: Bounce,
    /// Height (m) of the table surface in the recording frame.
    pub surface: f64,
    /// Camera frame period (s).
    pub period: f64,
}

/// Fit settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitOptions {
    /// Largest RK4 step (s).
    pub step: f64,
    /// Prior standard deviation of each spin component (rad/s).
    pub spin_prior: f64,
    /// Height band (m) around the median first minimum that counts as a table bounce.
    pub bounce_band: f64,
    /// Levenberg–Marquardt iterations per round.
    pub iterations: usize,
    /// Which globals are fitted: k_d, k_m, e, μ, surface, period.
    pub free: [bool; 6],
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            step: 0.002,
            spin_prior: 300.0,
            bounce_band: 0.05,
            iterations: 30,
            free: [true; 6],
        }
    }
}

/// Names of the globals, in the order of [`Calibration::globals`].
pub const GLOBAL_NAMES: [&str; 6] = [
    "k_drag",
    "k_magnus",
    "table_restitution",
    "table_friction",
    "surface",
    "period",
];

/// One flight's fitted state and residual.
#[derive(Debug, Clone, PartialEq)]
pub struct FlightFit {
    /// Index of the recording.
    pub index: usize,
    /// State at the first frame (t = 0; position m, velocity m/s, spin rad/s).
    pub state: BallState,
    /// Frames used (the segment).
    pub frames: usize,
    /// Frame of the bounce (the observed minimum).
    pub bounce_frame: usize,
    /// RMS position residual (m) over the segment.
    pub rms: f64,
    /// The friction coefficient above which its first bounce ends rolling (the rolling cap's
    /// impulse over the normal impulse: |u|/κ / ((1+e)·|v_n|)); NaN without a bounce.
    pub friction_to_roll: f64,
}

/// The result of [`calibrate`].
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// The fitted model (impulse bounce).
    pub fit: FitModel,
    /// The globals (k_d, k_m, e, μ, surface, period), as in [`GLOBAL_NAMES`].
    pub globals: [f64; 6],
    /// Their standard deviations (NaN where not fitted or not identified).
    pub std: [f64; 6],
    /// Their correlation matrix (row-major 6 × 6; NaN where not fitted).
    pub correlation: [[f64; 6]; 6],
    /// Residual standard deviation σ (m) of the final round.
    pub sigma: f64,
    /// RMS position residual (m) over every fitted frame.
    pub rms: f64,
    /// Per-flight results.
    pub flights: Vec<FlightFit>,
    /// Levenberg–Marquardt iterations, all rounds.
    pub iterations: usize,
    /// Frames in the fit.
    pub observations: usize,
    /// The fitted spins' mean and standard deviation in each flight's axes at its first frame
    /// ([`SpinPrior`]): the population prior for a new flight of the same source.
    pub spin: SpinPrior,
}
/// The spin prior of a flight's state fitted from its first frames, in the flight axes of its
/// first velocity (along the horizontal velocity, horizontal across it, vertical): mean and
/// standard deviation per axis (rad/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpinPrior {
    /// Mean (rad/s, flight axes).
    pub mean: [f64; 3],
    /// Standard deviation (rad/s, flight axes).
    pub std: [f64; 3],
}
impl Recording {
    /// Recordings from parallel columns: `names` (F,), `positions` (F lists of frames, m) and
    /// optionally `velocities` (F lists, m/s; each recording's velocities empty when None).
    pub fn from_columns(
        names: Vec<String>,
        positions: Vec<Vec<[f64; 3]>>,
        velocities: Option<Vec<Vec<[f64; 3]>>>,
    ) -> Result<Vec<Recording>> {
        let f = names.len();
        if positions.len() != f || velocities.as_ref().is_some_and(|v| v.len() != f) {
            return Err(Error::invalid(
                "ball_fit",
                format!(
                    "{f} names, {} position arrays and {} velocity arrays: give one of each per flight",
                    positions.len(),
                    velocities.as_ref().map_or(f, Vec::len)
                ),
            ));
        }
        let velocities = velocities.unwrap_or_else(|| vec![Vec::new(); f]);
        Ok(names
            .into_iter()
            .zip(positions)
            .zip(velocities)
            .map(|((name, positions), velocities)| Recording {
                name,
                positions,
                velocities,
            })
            .collect())
    }
}
