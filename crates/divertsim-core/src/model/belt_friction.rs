//! Dry friction of the flat rectangular footprint on the belt: sliding and spinning coupled
//! (Contensou effect), physics.md §3.
//!
//! The exact law integrates Coulomb's law over the footprint with uniform pressure (closed
//! form of §3.2, asymptotic branch for a far instantaneous centre, §3.2–3.3). The "seed" law is
//! the paper's tanh/exp surrogate with the corrections of §3.4 and coefficients derived from
//! the footprint. The coefficient may depend on the relative speed, μ_1(v_o), from a table.

use glam::DVec2;

/// Which footprint friction law to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FrictionModel {
    /// Exact uniform-pressure Coulomb integrals (physics.md §3.2).
    #[default]
    Exact,
    /// The paper's tanh/exp law, corrected (physics.md §3.4).
    Seed,
}

/// μ_b: the belt friction coefficient, constant or a function of the relative speed v_o.
#[derive(Debug, Clone, PartialEq)]
pub enum FrictionCoefficient {
    /// A single kinetic coefficient.
    Constant(f64),
    /// μ_1(v_o) as [relative speed m/s, μ] points, speeds strictly increasing; linear between
    /// points, constant beyond the ends.
    Table(Vec<(f64, f64)>),
}

impl FrictionCoefficient {
    /// μ at relative speed `speed` [m/s].
    pub fn at(&self, speed: f64) -> f64 {
        let _ = speed;
        todo!("helper: belt friction")
    }
}

/// The friction wrench of the belt on a parcel footprint.
#[derive(Debug, Clone)]
pub struct BeltFriction {
    _private: (),
}

impl BeltFriction {
    /// Footprint `length` a × `width` b [m], normal force N = m g [N].
    pub fn new(
        length: f64,
        width: f64,
        normal_force: f64,
        coefficient: FrictionCoefficient,
        model: FrictionModel,
    ) -> BeltFriction {
        let _ = (length, width, normal_force, coefficient, model);
        todo!("helper: belt friction")
    }

    /// Force F′ (body axes) [N] and moment M_b [N·m] for the relative velocity of the centre
    /// in body axes v′ [m/s] and the spin ω [rad/s]. Zero when both are zero (stick is the
    /// caller's business, physics.md §3.5).
    pub fn wrench_body(&self, v_rel_body: DVec2, omega: f64) -> (DVec2, f64) {
        let _ = (v_rel_body, omega);
        todo!("helper: belt friction")
    }

    /// Force F (frame axes) [N] and moment M_b [N·m] for the relative velocity
    /// v_r = v_G − V_b in frame axes, spin ω and orientation φ (physics.md §4).
    pub fn wrench(&self, v_rel: DVec2, omega: f64, angle: f64) -> (DVec2, f64) {
        let _ = (v_rel, omega, angle);
        todo!("helper: belt friction")
    }

    /// ⟨ρ⟩: mean distance of footprint points from the centre [m] (physics.md §3.3).
    pub fn mean_radius(&self) -> f64 {
        todo!("helper: belt friction")
    }

    /// μ N at rest (the coefficient at zero relative speed times the normal force) [N].
    pub fn max_force(&self) -> f64 {
        todo!("helper: belt friction")
    }
}
