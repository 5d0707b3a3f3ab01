//! Constants of one run derived from the scenario: the parcel's mass properties, the belt,
//! the arm and its drive, the friction laws.

use super::tolerances::CONTACT_SLIP_REG;
use crate::geometry::Rect;
use crate::model::active_set::ContactRow;
use crate::model::belt_friction::BeltFriction;
use crate::model::contact::{ContactFrame, ContactKind, Kinematics};
use crate::model::drive::ArmDrive;
use crate::model::drive::ArmState;
use crate::model::impact::ImpactLaw;
use crate::model::params::{NearSide, Scenario, TippingRule};
use crate::model::tipping::TipGeometry;
use crate::GRAVITY;
use glam::DVec2;

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
    /// Start times of the arm's cycles \[s], increasing, none overlapping the next
    /// (`run.cycle_starts`).
    pub cycle_starts: Vec<f64>,
    /// Bound on |α̇| over the cycle [rad/s] (0 without an arm): [`ArmDrive::rate_bound`].
    pub arm_rate_max: f64,
    /// Bound on |α̈| over the cycle [rad/s²] (0 without an arm): [`ArmDrive::accel_bound`].
    pub arm_accel_max: f64,
    /// x where the pivot-side guide ends \[m]: 0 (open downstream of the pivot) or +∞.
    pub guide_end: f64,
    /// The tipping check's geometry; `None` when the arm's face passes over the parcel
    /// (then the run has no arm).
    pub tip: Option<TipGeometry>,
    /// What a tip-over does.
    pub tip_rule: TippingRule,
}

impl Context {
    pub fn new(s: &Scenario) -> Result<Context, String> {
        let p = &s.parcel;
        let tip = crate::model::tipping::band_overlap(
            p.height,
            s.machine.arm_face_bottom,
            s.machine.arm_face_top,
        )
        .map(|band| TipGeometry {
            half: DVec2::new(0.5 * p.length, 0.5 * p.width),
            height: p.height,
            com_height: p.com_height(),
            band,
            mass: p.mass,
            belt_friction: s.materials.belt_friction.at(0.0),
        });
        let drive = if s.run.arm && tip.is_some() {
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
            cycle_starts: s.run.cycle_starts.clone(),
            guide_end: match s.machine.near_side {
                NearSide::Open => 0.0,
                NearSide::Guide => f64::INFINITY,
            },
            tip,
            tip_rule: s.limits.tipping,
        })
    }

    /// Whether the pivot-side edge is open downstream of the pivot.
    pub fn near_side_open(&self) -> bool {
        self.guide_end.is_finite()
    }

    /// The end of the arm's last cycle \[s] (t_c for the paper's one cycle), or `None` without
    /// an arm.
    pub fn arm_end(&self) -> Option<f64> {
        let last = self.cycle_starts.last().copied().unwrap_or(0.0);
        self.drive.as_ref().map(|d| last + d.cycle_time())
    }

    /// The start of the cycle under way at t \[s], if any (a cycle runs over [s, s + t_c)).
    fn cycle_at(&self, t: f64, cycle_time: f64) -> Option<f64> {
        // Few cycles (one for the paper, a handful on a line): a scan from the last.
        let s = *self.cycle_starts.iter().rev().find(|&&s| s <= t)?;
        (t < s + cycle_time).then_some(s)
    }

    /// The cycles' starts and ends in order, each with whether it is a start: where the arm's
    /// acceleration may jump, so where integration segments end.
    pub fn cycle_boundaries(&self) -> Vec<(f64, bool)> {
        let Some(d) = &self.drive else {
            return Vec::new();
        };
        // A cycle that runs into the next one (back to back, to rounding) has no end of
        // its own: the arm goes straight on.
        let mut out = Vec::with_capacity(2 * self.cycle_starts.len());
        for (k, &s) in self.cycle_starts.iter().enumerate() {
            out.push((s, true));
            let end = s + d.cycle_time();
            if self.cycle_starts.get(k + 1).is_none_or(|&next| end < next) {
                out.push((end, false));
            }
        }
        out
    }
}

/// The arm's state at t, or at rest when the arm is disabled.
///
/// From the end of its cycle on (t ≥ t_c) the arm is at rest: the drive's value at t_c
/// itself still carries the cycle's α̈ (a crank-rocker's dead centre), and the motion and
/// the event logic after the cycle must both see the arm that no longer moves.
pub fn arm_state(ctx: &Context, t: f64) -> ArmState {
    arm_state_trig(ctx, t).0
}

/// [`arm_state`] with (sin α, cos α) (see [`ArmDrive::state_trig`]).
///
/// [`ArmDrive::state_trig`]: crate::model::drive::ArmDrive::state_trig
pub fn arm_state_trig(ctx: &Context, t: f64) -> (ArmState, (f64, f64)) {
    match &ctx.drive {
        Some(d) => match ctx.cycle_at(t, d.cycle_time()) {
            // t − s is t itself for the paper's cycle at 0, bit for bit.
            Some(s) => d.state_trig(t - s),
            None => (ArmState::default(), (0.0, 1.0)),
        },
        None => (ArmState::default(), (0.0, 1.0)),
    }
}

impl Context {
    /// The kinematics of the parcel and the arm at (t, y).
    pub fn kinematics(&self, t: f64, y: &[f64; 6]) -> Kinematics {
        self.kinematics_with(arm_state(self, t), y)
    }

    /// The kinematics of the parcel at state y with a given arm state.
    pub fn kinematics_with(&self, arm: ArmState, y: &[f64; 6]) -> Kinematics {
        Kinematics {
            centre: DVec2::new(y[0], y[1]),
            angle: y[2],
            velocity: DVec2::new(y[3], y[4]),
            omega: y[5],
            arm,
            arm_length: self.arm_length,
            rect: self.rect,
            guide_end: self.guide_end,
        }
    }

    /// T = R_z t(α): the arm tip at time t \[m].
    pub fn arm_tip(&self, t: f64) -> DVec2 {
        let (sa, ca) = arm_state(self, t).angle.sin_cos();
        self.arm_length * DVec2::new(ca, sa)
    }

    /// The belt friction wrench (F_x, F_y, M) at state y when no contact is active: the exact
    /// footprint law (model.md §3).
    pub fn free_belt_wrench(&self, y: &[f64; 6]) -> [f64; 3] {
        let (f, m) = self
            .friction
            .wrench(DVec2::new(y[3] - self.belt_speed, y[4]), y[5], y[2]);
        [f.x, f.y, m]
    }

    /// The belt friction wrench while contacts are active: the footprint law ramped linearly
    /// to zero below [`CONTACT_SLIP_REG`] of slip, because a contact can hold the parcel at
    /// zero belt slip, where the exact law's set-valued friction would make the motion
    /// chatter. The one law of contact motion: the integrator and the event logic
    /// (`settle`) both use it, so a contact force found compressive at an event stays so
    /// in the motion that follows, and a release found in the motion is a release at the
    /// event.
    pub fn contact_belt_wrench(&self, y: &[f64; 6]) -> [f64; 3] {
        let [fx, fy, m] = self.free_belt_wrench(y);
        let scale = (slip_of(self, y) / CONTACT_SLIP_REG).min(1.0);
        [scale * fx, scale * fy, scale * m]
    }

    /// The constraint row of a contact frame (μ_a for the arm and the guide).
    pub fn row(&self, f: &ContactFrame) -> ContactRow {
        ContactRow {
            normal: f.jacobian,
            beta: f.beta,
            tangent: f.jacobian_t,
            beta_t: f.beta_t,
            friction: self.arm_friction,
            slip: f.slip,
        }
    }

    /// Whether a candidate pair can occur at all (arm pairs need an arm).
    pub fn candidate_enabled(&self, kind: ContactKind) -> bool {
        match kind {
            ContactKind::CornerGuide { .. } => true,
            _ => self.drive.is_some(),
        }
    }

    /// Distance from the pivot to the nearest point of the parcel's footprint \[m].
    pub fn distance_from_pivot(&self, y: &[f64; 6]) -> f64 {
        let rel = crate::geometry::rotate(DVec2::new(-y[0], -y[1]), -y[2]);
        let ha = 0.5 * self.rect.length;
        let hb = 0.5 * self.rect.width;
        let dx = (rel.x.abs() - ha).max(0.0);
        let dy = (rel.y.abs() - hb).max(0.0);
        (dx * dx + dy * dy).sqrt()
    }
}

/// |w| = |(v_r, ℓω)|: the slip of the parcel on the belt [m/s].
pub fn slip_of(ctx: &Context, y: &[f64; 6]) -> f64 {
    let w = slip_vector_of(ctx, y);
    (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt()
}

/// w = (v_r, ℓω) [m/s].
#[inline]
pub fn slip_vector_of(ctx: &Context, y: &[f64; 6]) -> [f64; 3] {
    [y[3] - ctx.belt_speed, y[4], ctx.slip_scale * y[5]]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::params::Scenario;

    #[test]
    fn the_mass_properties_are_the_rectangles() {
        let s = Scenario::paper_default();
        let c = Context::new(&s).unwrap();
        let (a, b, m) = (s.parcel.length, s.parcel.width, s.parcel.mass);
        assert!((c.inertia - m * (a * a + b * b) / 12.0).abs() < 1e-15);
        assert!((c.half_diagonal - 0.5 * (a * a + b * b).sqrt()).abs() < 1e-15);
        assert!((c.weight - m * GRAVITY).abs() < 1e-12);
        assert_eq!(c.belt_speed, s.machine.belt_speed);
        assert_eq!(c.arm_length, s.machine.arm_length);
    }

    #[test]
    fn the_near_side_sets_where_the_guide_ends() {
        let mut s = Scenario::paper_default();
        s.machine.near_side = NearSide::Open;
        let open = Context::new(&s).unwrap();
        assert!(open.near_side_open() && open.guide_end == 0.0);
        s.machine.near_side = NearSide::Guide;
        let guided = Context::new(&s).unwrap();
        assert!(!guided.near_side_open() && guided.guide_end == f64::INFINITY);
    }

    #[test]
    fn without_an_arm_there_is_no_drive_and_no_rate_bound() {
        let mut s = Scenario::paper_default();
        s.run.arm = false;
        let c = Context::new(&s).unwrap();
        assert!(c.drive.is_none() && c.arm_end().is_none());
        assert_eq!((c.arm_rate_max, c.arm_accel_max), (0.0, 0.0));
        s.run.arm = true;
        let c = Context::new(&s).unwrap();
        assert_eq!(c.arm_end(), Some(s.machine.cycle_time));
        assert!(c.arm_rate_max > 0.0 && c.arm_accel_max > 0.0);
    }
}
