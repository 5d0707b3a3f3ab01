//! Constants of one run derived from the scenario: the parcel's mass properties, the belt,
//! the arm and its drive, the friction laws.

use crate::geometry::Rect;
use crate::model::belt_friction::BeltFriction;
use crate::model::drive::ArmDrive;
use crate::model::impact::ImpactLaw;
use crate::model::params::{NearSide, Scenario};
use crate::GRAVITY;

/// Everything a run needs that does not change during it.
pub struct Context {
    /// The parcel footprint a × b.
    pub rect: Rect,
    /// c/2: half the footprint's diagonal, the farthest a parcel point is from G \[m].
    pub half_diagonal: f64,
    /// m \[kg]
    pub mass: f64,
    /// I [kg·m²]
    pub inertia: f64,
    /// m g \[N]
    pub weight: f64,
    /// v [m/s]
    pub belt_speed: f64,
    /// P_max \[m]
    pub belt_width: f64,
    /// R_z \[m]
    pub arm_length: f64,
    /// μ_a (arm and guide)
    pub arm_friction: f64,
    /// e*
    pub restitution: f64,
    pub impact_law: ImpactLaw,
    /// ℓ = ⟨ρ⟩: turns spin into a slip speed \[m]
    pub slip_scale: f64,
    /// μ_b(0) g: the belt's deceleration of a sliding parcel at small slip [m/s²]
    pub belt_decel: f64,
    /// Bound on the acceleration of a parcel point by belt friction alone, without its
    /// centripetal part [m/s²]: μ_max g (1 + 2 (c/2)²/i²), from |F| ≤ μN and
    /// |M_b| ≤ 2 μN c/2 (μN c/2 for the exact law; the seed law's moment stays below twice
    /// that), c the diagonal. NaN if μ is unknown (then nothing is skipped).
    pub free_point_accel: f64,
    pub friction: BeltFriction,
    /// `None` when the arm is disabled.
    pub drive: Option<ArmDrive>,
    /// Bound on |α̇| over the cycle [rad/s] (0 without an arm): [`ArmDrive::rate_bound`].
    pub arm_rate_max: f64,
    /// Bound on |α̈| over the cycle [rad/s²] (0 without an arm): [`ArmDrive::accel_bound`].
    pub arm_accel_max: f64,
    /// x where the pivot-side guide ends \[m]: 0 (open downstream of the pivot) or +∞.
    pub guide_end: f64,
}

impl Context {
    pub fn new(s: &Scenario) -> Result<Context, String> {
        let drive = if s.run.arm {
            Some(
                ArmDrive::new(&s.machine.drive, s.machine.cycle_time)
                    .map_err(|e| format!("invalid drive: {e}"))?,
            )
        } else {
            None
        };
        let weight = s.parcel.mass * GRAVITY;
        let friction = BeltFriction::new(
            s.parcel.length,
            s.parcel.width,
            weight,
            s.materials.belt_friction.clone(),
            s.materials.friction_model,
        );
        // Proven bounds of the drive law (the guard culling of `motion` trusts them).
        let (arm_rate_max, arm_accel_max) = drive
            .as_ref()
            .map_or((0.0, 0.0), |d| (d.rate_bound(), d.accel_bound()));
        let rect = s.footprint();
        let half_diag_sq = 0.25 * (rect.length * rect.length + rect.width * rect.width);
        Ok(Context {
            half_diagonal: half_diag_sq.sqrt(),
            rect,
            mass: s.parcel.mass,
            inertia: s.inertia(),
            weight,
            belt_speed: s.machine.belt_speed,
            belt_width: s.machine.belt_width,
            arm_length: s.machine.arm_length,
            arm_friction: s.materials.arm_friction,
            restitution: s.materials.restitution,
            impact_law: s.materials.impact_law,
            slip_scale: friction.mean_radius(),
            belt_decel: friction.max_force() / s.parcel.mass,
            free_point_accel: {
                s.materials.belt_friction.max_value()
                    * GRAVITY
                    * (1.0 + 2.0 * half_diag_sq / rect.gyration_sq())
            },
            friction,
            arm_rate_max,
            arm_accel_max,
            drive,
            guide_end: match s.machine.near_side {
                NearSide::Open => 0.0,
                NearSide::Guide => f64::INFINITY,
            },
        })
    }

    /// Whether the pivot-side edge is open downstream of the pivot.
    pub fn near_side_open(&self) -> bool {
        self.guide_end.is_finite()
    }

    /// t_c, or `None` without an arm.
    pub fn arm_end(&self) -> Option<f64> {
        self.drive.as_ref().map(ArmDrive::cycle_time)
    }
}
