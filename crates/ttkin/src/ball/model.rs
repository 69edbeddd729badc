//! Ball and table constants: the flight model a = g − k_d·|v|·v + k_m·(ω × v) and ITTF geometry.
//!
//! **Default: measured** (issue 28). The constants are fitted on 219 measured flights of the MPI
//! for Intelligent Systems' PAM table-tennis setup (ball gun, 291 recorded flights, every fourth
//! held out; `ttmanip ball fit`, [`super::fit`], docs/ball.md "Calibration"): k_d = 0.1229 ± 0.0003
//! /m, k_m = 0.00159 ± 0.00002, table restitution e = 0.964 ± 0.0002 (one standard deviation from
//! the fit's covariance, the per-flight states and spins marginalised). Table friction is not
//! identified by those flights (every bounce ends rolling for any μ ≥ 0.163), so μ = 0.25 of
//! Nakashima et al. (2010) is kept. On the 72 held-out flights, predicted from their first 20
//! frames through the bounce, the median RMS error after the bounce is 5.7 cm with these constants
//! against 9.8 cm (Mülling's k_d = 0.1414, k_m = 0.001), 9.9 cm (TT3D) and 12.9 cm (the previous
//! default below).
//!
//! **Presets** (flight constants as published; bounce e = 0.93, μ = 0.25): [`BallModel::aero`],
//! the previous default from the aerodynamics of a sphere at the stated air density:
//! k_d = ρ·C_D·A / (2m) with C_D = 0.50 (smooth sphere, subcritical Reynolds number ≈ 1e4–6e4 at
//! 4–20 m/s), and k_m = ρ·C_L'·A·r / (2m) from a lift coefficient linear in the spin parameter,
//! C_L = C_L'·(rω/|v|) with C_L' = 1.0, so that the Magnus force ½ρ·C_L·A·|v|² becomes
//! k_m·|ω × v| for spin perpendicular to v; at ρ = 1.184 kg/m³ (dry air, 25 °C, 101.325 kPa)
//! k_d = 0.1377 /m and k_m = 0.00551 (about 3.5× the measured k_m). [`BallModel::muelling`]
//! (k_d = 0.1414, k_m = 0.001, Mülling et al., MPI Tübingen), [`BallModel::mpi`] (k_d = 0.129,
//! k_m = 0.00807) and [`BallModel::tt3d`] (k_d = 0.141, k_m = 0.0018).
//! Spin is constant in flight (its aerodynamic decay time is several seconds, far longer than
//! one flight of ≤ 1 s).

use crate::error::{Error, Result};
use nalgebra::Vector3;

/// Ball, air and contact parameters (SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BallModel {
    /// Ball mass (kg): 2.7 g (ITTF 40+ ball).
    pub mass: f64,
    /// Ball radius (m): 20 mm.
    pub radius: f64,
    /// Gravitational acceleration (m/s², along −z of the world frame).
    pub gravity: f64,
    /// Air density (kg/m³) the coefficients were derived at (documentation; not used directly).
    pub air_density: f64,
    /// Drag coefficient k_d (1/m): a_drag = −k_d·|v|·v.
    pub k_drag: f64,
    /// Magnus coefficient k_m (dimensionless): a_magnus = k_m·(ω × v).
    pub k_magnus: f64,
    /// Normal restitution of the table (ratio of normal speeds): 0.964 measured (module doc);
    /// 0.93 in the presets (Nakashima et al. 2010).
    pub table_restitution: f64,
    /// Coulomb friction coefficient ball–table: 0.25 (Nakashima et al. 2010; not identified by
    /// the measured flights, module doc).
    pub table_friction: f64,
}

impl Default for BallModel {
    fn default() -> Self {
        BallModel::measured()
    }
}

impl BallModel {
    /// Mass and radius of the ITTF 40+ ball, used by every preset.
    const MASS: f64 = 0.0027;
    const RADIUS: f64 = 0.020;

    /// Model from air density ρ (kg/m³), drag coefficient C_D and lift slope C_L' (C_L = C_L'·rω/|v|).
    pub fn from_air(air_density: f64, drag_coefficient: f64, lift_slope: f64) -> Self {
        let area = std::f64::consts::PI * Self::RADIUS * Self::RADIUS;
        BallModel {
            mass: Self::MASS,
            radius: Self::RADIUS,
            gravity: 9.81,
            air_density,
            k_drag: air_density * drag_coefficient * area / (2.0 * Self::MASS),
            k_magnus: air_density * lift_slope * area * Self::RADIUS / (2.0 * Self::MASS),
            table_restitution: 0.93,
            table_friction: 0.25,
        }
    }

    /// The default: constants fitted on the measured flights of the MPI PAM setup (module doc):
    /// k_d = 0.1229 /m, k_m = 0.00159, table restitution 0.964, friction 0.25.
    pub fn measured() -> Self {
        BallModel {
            k_drag: 0.1229,
            k_magnus: 0.00159,
            table_restitution: 0.964,
            table_friction: 0.25,
            ..Self::aero()
        }
    }

    /// The previous default, from sphere aerodynamics: ρ = 1.184 kg/m³, C_D = 0.5, C_L' = 1
    /// (k_d = 0.1377 /m, k_m = 0.00551), table restitution 0.93, friction 0.25.
    pub fn aero() -> Self {
        BallModel::from_air(1.184, 0.50, 1.0)
    }

    /// Mülling et al. (MPI Tübingen): k_d = 0.1414 /m, k_m = 0.001.
    pub fn muelling() -> Self {
        BallModel {
            k_drag: 0.1414,
            k_magnus: 0.001,
            ..Self::aero()
        }
    }

    /// MPI ball models: k_d = 0.129 /m, k_m = 0.00807.
    pub fn mpi() -> Self {
        BallModel {
            k_drag: 0.129,
            k_magnus: 0.00807,
            ..Self::aero()
        }
    }

    /// TT3D: k_d = 0.141 /m, k_m = 0.0018.
    pub fn tt3d() -> Self {
        BallModel {
            k_drag: 0.141,
            k_magnus: 0.0018,
            ..Self::aero()
        }
    }

    /// No air (k_d = k_m = 0): a pure parabola, for tests and closed forms.
    pub fn vacuum() -> Self {
        BallModel {
            k_drag: 0.0,
            k_magnus: 0.0,
            ..Self::aero()
        }
    }

    /// Model by name: "default" (= "measured"), "aero", "muelling", "mpi", "tt3d" or "vacuum".
    pub fn by_name(name: &str) -> Result<Self> {
        match name {
            "default" | "measured" => Ok(Self::default()),
            "aero" => Ok(Self::aero()),
            "muelling" => Ok(Self::muelling()),
            "mpi" => Ok(Self::mpi()),
            "tt3d" => Ok(Self::tt3d()),
            "vacuum" => Ok(Self::vacuum()),
            _ => Err(Error::invalid(
                "model",
                format!("unknown ball model {name:?}; expected default, measured, aero, muelling, mpi, tt3d or vacuum"),
            )),
        }
    }

    /// Checks that every parameter is finite and physical.
    pub fn validate(&self) -> Result<()> {
        let positive = [("mass", self.mass), ("radius", self.radius), ("gravity", self.gravity)];
        for (what, v) in positive {
            if !(v > 0.0) || !v.is_finite() {
                return Err(Error::invalid(what, format!("must be finite and > 0, got {v}")));
            }
        }
        let nonneg = [
            ("k_drag", self.k_drag),
            ("k_magnus", self.k_magnus),
            ("table_friction", self.table_friction),
            ("air_density", self.air_density),
        ];
        for (what, v) in nonneg {
            if !(v >= 0.0) || !v.is_finite() {
                return Err(Error::invalid(what, format!("must be finite and ≥ 0, got {v}")));
            }
        }
        if !(self.table_restitution >= 0.0 && self.table_restitution <= 1.0) {
            return Err(Error::invalid(
                "table_restitution",
                format!("must lie in [0, 1], got {}", self.table_restitution),
            ));
        }
        Ok(())
    }

    /// Acceleration (m/s², world frame) of a ball at velocity `v` (m/s) with spin `w` (rad/s).
    #[inline]
    pub fn acceleration(&self, v: &Vector3<f64>, w: &Vector3<f64>) -> Vector3<f64> {
        Vector3::new(0.0, 0.0, -self.gravity) - self.k_drag * v.norm() * v + self.k_magnus * w.cross(v)
    }

    /// Moment of inertia (kg·m²) of the ball, a thin spherical shell: (2/3)·m·r².
    pub fn inertia(&self) -> f64 {
        2.0 / 3.0 * self.mass * self.radius * self.radius
    }
}

/// ITTF table and net geometry in the world frame (m): surface at z = 0, centred at the origin.
/// A serde form may leave fields out: they are the default table's.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Table {
    /// Playing-surface length along x (m): 2.74.
    pub length: f64,
    /// Playing-surface width along y (m): 1.525.
    pub width: f64,
    /// Surface height above the floor (m): 0.76 (the floor is at z = −height).
    pub height: f64,
    /// Thickness of the table top (m) for edge contacts: 0.025.
    pub thickness: f64,
    /// Net height above the surface (m): 0.1525.
    pub net_height: f64,
    /// How far the net extends beyond each side line (m): 0.1525.
    pub net_overhang: f64,
}

/// A table's outline for drawing ([`Table::outline`]), points in m (world frame).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TableOutline {
    /// The playing surface's corners, a closed loop (the first corner again at the end).
    pub surface: [[f64; 3]; 5],
    /// The centre line's ends (the doubles line, x from end line to end line at y = 0).
    pub centre_line: [[f64; 3]; 2],
    /// The net's outline in the plane x = 0 (overhang included), a closed loop from the surface
    /// to the net's top.
    pub net: [[f64; 3]; 5],
}

impl Default for Table {
    fn default() -> Self {
        Table {
            length: 2.74,
            width: 1.525,
            height: 0.76,
            thickness: 0.025,
            net_height: 0.1525,
            net_overhang: 0.1525,
        }
    }
}

impl Table {
    /// Half length (m): the robot's end line is x = −half_length, the opponent's x = +half_length.
    pub fn half_length(&self) -> f64 {
        0.5 * self.length
    }

    /// Half width (m): the side lines are y = ±half_width.
    pub fn half_width(&self) -> f64 {
        0.5 * self.width
    }

    /// Whether the point (x, y) (m, world) lies on the opponent's half (x > 0) of the surface.
    pub fn on_opponent_half(&self, x: f64, y: f64) -> bool {
        x > 0.0 && x <= self.half_length() && y.abs() <= self.half_width()
    }

    /// Whether the point (x, y) (m, world) lies on the robot's half (x < 0) of the surface.
    pub fn on_robot_half(&self, x: f64, y: f64) -> bool {
        x < 0.0 && x >= -self.half_length() && y.abs() <= self.half_width()
    }

    /// The outline to draw (m, world): the playing surface and the net as closed loops, and the
    /// centre line.
    pub fn outline(&self) -> TableOutline {
        let (l, w) = (self.half_length(), self.half_width());
        let n = w + self.net_overhang;
        let h = self.net_height;
        TableOutline {
            surface: [[-l, -w, 0.0], [l, -w, 0.0], [l, w, 0.0], [-l, w, 0.0], [-l, -w, 0.0]],
            centre_line: [[-l, 0.0, 0.0], [l, 0.0, 0.0]],
            net: [[0.0, -n, 0.0], [0.0, n, 0.0], [0.0, n, h], [0.0, -n, h], [0.0, -n, 0.0]],
        }
    }

    /// Checks that the geometry is finite and positive.
    pub fn validate(&self) -> Result<()> {
        for (what, v) in [
            ("length", self.length),
            ("width", self.width),
            ("height", self.height),
            ("thickness", self.thickness),
            ("net_height", self.net_height),
        ] {
            if !(v > 0.0) || !v.is_finite() {
                return Err(Error::invalid(what, format!("must be finite and > 0, got {v}")));
            }
        }
        if !(self.net_overhang >= 0.0) || !self.net_overhang.is_finite() {
            return Err(Error::invalid("net_overhang", "must be finite and ≥ 0"));
        }
        Ok(())
    }
}
