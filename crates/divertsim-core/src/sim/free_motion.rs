//! F2: free flat motion of the parcel on the belt, in frame-fixed axes (physics.md §4).
//!
//! State y = (x, y, φ, ẋ, ẏ, ω). The only load is the belt friction wrench of §3, evaluated
//! from the belt-relative velocity v_r = v_G − V_b and the spin ω:
//! m ẍ = F_x, m ÿ = F_y, I φ̈ = M_b.
//!
//! Coulomb friction stops the slip in finite time, and the law is discontinuous at zero slip.
//! To locate the stop precisely the right-hand side is *continued* past it: the friction law
//! is homogeneous of degree 0 and odd in w = (v_r, ℓω), so evaluating it at −w once w has
//! passed through zero (w·d_ref < 0, d_ref the slip direction at the step start) keeps the
//! force it had just before the stop. The guard w·d_ref then crosses zero transversally and
//! the event locator finds the stop to the integrator's event precision.

use crate::integrate::{Direction, HybridSystem};
use crate::model::belt_friction::BeltFriction;
use glam::DVec2;

/// Index of the guard "slip reaches zero" (w·d_ref, falling).
pub const GUARD_STOP: usize = 0;
/// Index of the guard "centre crosses the far belt edge" (y − P_max, rising).
pub const GUARD_EXIT: usize = 1;

/// The F2 right-hand side and its guards.
pub struct FreeMotion<'a> {
    pub friction: &'a BeltFriction,
    /// v: belt speed [m/s]
    pub belt_speed: f64,
    /// m [kg]
    pub mass: f64,
    /// I [kg·m²]
    pub inertia: f64,
    /// ℓ: length that turns spin into a slip speed, ⟨ρ⟩ [m]
    pub slip_scale: f64,
    /// P_max [m]
    pub belt_width: f64,
    /// Unit slip direction in (v_r, ℓω) space at the current step start.
    d_ref: [f64; 3],
}

impl<'a> FreeMotion<'a> {
    pub fn new(
        friction: &'a BeltFriction,
        belt_speed: f64,
        mass: f64,
        inertia: f64,
        belt_width: f64,
    ) -> Self {
        FreeMotion {
            friction,
            belt_speed,
            mass,
            inertia,
            slip_scale: friction.mean_radius(),
            belt_width,
            d_ref: [1.0, 0.0, 0.0],
        }
    }

    /// w = (v_r, ℓω): the slip of the parcel relative to the belt [m/s].
    #[inline]
    pub fn slip_vector(&self, y: &[f64; 6]) -> [f64; 3] {
        [y[3] - self.belt_speed, y[4], self.slip_scale * y[5]]
    }

    /// |w| [m/s].
    pub fn slip(&self, y: &[f64; 6]) -> f64 {
        let w = self.slip_vector(y);
        (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt()
    }

    #[inline]
    fn along_ref(&self, y: &[f64; 6]) -> f64 {
        let w = self.slip_vector(y);
        w[0] * self.d_ref[0] + w[1] * self.d_ref[1] + w[2] * self.d_ref[2]
    }
}

impl HybridSystem<6> for FreeMotion<'_> {
    #[inline]
    fn rhs(&self, _t: f64, y: &[f64; 6]) -> [f64; 6] {
        let mut v_rel = DVec2::new(y[3] - self.belt_speed, y[4]);
        let mut omega = y[5];
        if self.along_ref(y) < 0.0 {
            // Past the stop: continue with the pre-stop force (see the module docs).
            v_rel = -v_rel;
            omega = -omega;
        }
        let (force, moment) = self.friction.wrench(v_rel, omega, y[2]);
        [
            y[3],
            y[4],
            y[5],
            force.x / self.mass,
            force.y / self.mass,
            moment / self.inertia,
        ]
    }

    fn guard_count(&self) -> usize {
        2
    }

    fn guard(&self, i: usize, _t: f64, y: &[f64; 6]) -> f64 {
        match i {
            GUARD_STOP => self.along_ref(y),
            _ => y[1] - self.belt_width,
        }
    }

    fn guard_direction(&self, i: usize) -> Direction {
        match i {
            GUARD_STOP => Direction::Falling,
            _ => Direction::Rising,
        }
    }

    fn begin_step(&mut self, _t: f64, y: &[f64; 6]) {
        let w = self.slip_vector(y);
        let n = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
        if n > 0.0 {
            self.d_ref = [w[0] / n, w[1] / n, w[2] / n];
        }
    }
}
