//! Arm drive: the prescribed arm angle α(t) and its derivatives over one working cycle.
//!
//! Kinds (physics.md §6): the crank-rocker four-bar (§6.1–6.2, vector-loop closure, crank at
//! constant speed 2π/t_c starting from the retracted dead centre) and the cam laws of §6.3
//! (simple harmonic, cycloidal, 3-4-5 polynomial; rise in t_c/2, symmetric return), plus a
//! tabulated α(t). Every kind starts and ends the cycle at rest at α = 0; outside [0, t_c]
//! the arm rests at α = 0.

/// α, α̇, α̈ of the arm at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ArmState {
    /// α: arm angle from the belt axis [rad]
    pub angle: f64,
    /// α̇: arm angular velocity [rad/s]
    pub rate: f64,
    /// α̈: arm angular acceleration [rad/s²]
    pub accel: f64,
}

/// Link lengths of a crank-rocker four-bar whose rocker is the arm (physics.md §6.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FourBar {
    /// a: crank length [m]
    pub crank: f64,
    /// b: coupler length [m]
    pub coupler: f64,
    /// c: rocker length [m]
    pub rocker: f64,
    /// d: ground link O₂O₄ [m]
    pub ground: f64,
}

/// Which motion law drives the arm, with its parameters.
#[derive(Debug, Clone, PartialEq)]
pub enum DriveSpec {
    /// Crank-rocker four-bar, crank at 2π/t_c.
    CrankRocker(FourBar),
    /// Cycloidal rise to `max_swing` [rad] in t_c/2, symmetric return.
    Cycloidal { max_swing: f64 },
    /// Simple harmonic rise and return.
    Harmonic { max_swing: f64 },
    /// 3-4-5 polynomial rise and return.
    Poly345 { max_swing: f64 },
    /// Tabulated α(t): `times` [s] strictly increasing from 0, `angles` [rad], starting and
    /// ending at 0. The time axis is scaled so that the last time equals t_c.
    Table { times: Vec<f64>, angles: Vec<f64> },
}

/// Why a drive cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DriveError {
    #[error("{0}")]
    Invalid(String),
}

/// A drive ready to evaluate: the spec plus the cycle time and anything precomputed.
#[derive(Debug, Clone)]
pub struct ArmDrive {
    _private: (),
}

impl FourBar {
    /// The centred (time ratio 1) design for a swing ψ [rad] with the given coupler b and
    /// rocker c: a = c sin(ψ/2), d = √(b² + c² cos²(ψ/2)) (physics.md §6.1–6.2).
    pub fn centred(swing: f64, coupler: f64, rocker: f64) -> FourBar {
        let _ = (swing, coupler, rocker);
        todo!("helper: drive")
    }

    /// ψ: the swing of the rocker.
    pub fn swing(&self) -> Result<f64, DriveError> {
        todo!("helper: drive")
    }

    /// The default design of physics.md §6.2: ψ = 45°, b = 0.3 m, c = 0.15 m.
    pub fn paper_default() -> FourBar {
        FourBar::centred(std::f64::consts::FRAC_PI_4, 0.3, 0.15)
    }
}

impl ArmDrive {
    /// Build a drive for one cycle of length `cycle_time` [s].
    pub fn new(spec: &DriveSpec, cycle_time: f64) -> Result<ArmDrive, DriveError> {
        let _ = (spec, cycle_time);
        todo!("helper: drive")
    }

    /// α, α̇, α̈ at time `t` [s] from the arm start; at rest at 0 outside [0, t_c].
    pub fn state(&self, t: f64) -> ArmState {
        let _ = t;
        todo!("helper: drive")
    }

    /// t_c: the cycle time [s].
    pub fn cycle_time(&self) -> f64 {
        todo!("helper: drive")
    }

    /// α_max: the largest arm angle over the cycle [rad].
    pub fn max_swing(&self) -> f64 {
        todo!("helper: drive")
    }
}
