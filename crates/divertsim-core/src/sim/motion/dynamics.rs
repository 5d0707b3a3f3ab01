//! The bodies' dynamics in one mode: the right-hand side of y = (x, y, φ, ẋ, ẏ, ω) for a
//! parcel riding with the belt, sliding freely (F2), or sliding against the active contacts
//! (F4, F5, F6, ...; docs/model.md §4, §6), and what an instant of it yields: the contact
//! forces, the arm's wrench, the slip. One body today: the state, the belt wrench and the
//! active-set problem are the body's, and the contacts name their obstacles, so a second
//! body is a second `Body` in the same problem, not a second kind of motion.
//!
//! **Belt stop.** Coulomb friction stops the slip in finite time and is discontinuous at zero
//! slip. The right-hand side is *continued* past the stop: the footprint law is homogeneous
//! of degree 0 and odd in w = (v_r, ℓω), so evaluating it at −w once w·d_ref < 0 (d_ref the
//! slip direction at the step start) keeps the pre-stop force, and the guard w·d_ref crosses
//! zero transversally (docs/model.md §4). The approach to the stop is not smooth (the slip
//! direction converges like a power of the time left): free sliding reports the time left to
//! the integrator ([`crate::integrate::HybridSystem::time_to_singularity`]), which scales its
//! steps with it, and the last 1e-7 m/s of slip are closed in closed form
//! ([`Dynamics::stop_tail`]).

use super::cache::{EvalCache, FreeDerivative, Geo, GeoCache};
use super::contacts::{ActiveContact, ContactSet};
use crate::model::active_set::{self, Body, ContactRow};
use crate::model::contact::{self, ContactKind};
use crate::sim::context::{arm_state_trig, slip_of, slip_vector_of, Context};
use crate::sim::tolerances::{CONTACT_SLIP_REG, DRIFT_TOL, GAP_TOL};
use glam::DVec2;

/// What the right-hand side, the guards and the probes need of one (t, y) in a contact mode.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Evaluation {
    pub accel: [f64; 3],
    /// Per active contact: where along its obstacle it is and its slip.
    pub frames: [Option<FrameSummary>; active_set::MAX_CONTACTS],
    pub normal_force: [f64; active_set::MAX_CONTACTS],
    pub tangential_force: [f64; active_set::MAX_CONTACTS],
    /// The arm's contacts' force on the parcel (x, y) \[N] and its moment about G \[N·m].
    pub arm: [f64; 3],
    /// Per active contact: its force on the parcel (x, y) \[N].
    pub forces: [[f64; 2]; active_set::MAX_CONTACTS],
}

/// The parts of a [`contact::ContactFrame`] the guards watch.
#[derive(Debug, Clone, Copy)]
pub(crate) struct FrameSummary {
    pub along: f64,
    pub extent: (f64, f64),
    pub slip: f64,
}

/// One mode's dynamics.
pub(crate) struct Dynamics<'a> {
    pub ctx: &'a Context,
    /// Riding with the belt (no contacts).
    pub riding: bool,
    pub contacts: ContactSet,
    /// The slip's direction at the step start (the belt stop's continuation).
    d_ref: [f64; 3],
    evals: EvalCache<Evaluation>,
    geos: GeoCache,
    last_free: FreeDerivative,
}

impl<'a> Dynamics<'a> {
    pub fn new(ctx: &'a Context) -> Self {
        Dynamics {
            ctx,
            riding: false,
            contacts: ContactSet::default(),
            d_ref: [1.0, 0.0, 0.0],
            evals: EvalCache::new(),
            geos: GeoCache::new(),
            last_free: FreeDerivative::new(),
        }
    }

    /// Enter a mode: riding or not, and the active contacts.
    pub fn set_mode(&mut self, riding: bool, active: &[ActiveContact]) {
        self.riding = riding;
        self.contacts = ContactSet::new(active);
        self.evals.clear();
    }

    /// Free sliding: not riding and no active contact.
    #[inline]
    pub fn is_free(&self) -> bool {
        !self.riding && self.contacts.is_empty()
    }

    /// The cached geometry at (t, φ).
    #[inline]
    pub fn geo(&self, t: f64, phi: f64) -> Geo {
        self.geos.get(t, phi, || {
            let (arm, arm_sc) = arm_state_trig(self.ctx, t);
            Geo {
                t,
                phi,
                arm,
                phi_sc: phi.sin_cos(),
                arm_sc,
            }
        })
    }

    /// The contact kinematics at (t, y) with their geometry.
    #[inline]
    pub fn kinematics(&self, t: f64, y: &[f64; 6]) -> (Geo, contact::Kinematics) {
        let g = self.geo(t, y[2]);
        (g, self.ctx.kinematics_with(g.arm, y))
    }

    /// w = (v_r, ℓω): the slip of the parcel on the belt [m/s].
    #[inline]
    pub fn slip_vector(&self, y: &[f64; 6]) -> [f64; 3] {
        slip_vector_of(self.ctx, y)
    }

    /// |w| [m/s].
    pub fn slip(&self, y: &[f64; 6]) -> f64 {
        slip_of(self.ctx, y)
    }

    /// w·d_ref: the slip along its direction at the step start.
    #[inline]
    pub fn along_ref(&self, y: &[f64; 6]) -> f64 {
        let w = self.slip_vector(y);
        w[0] * self.d_ref[0] + w[1] * self.d_ref[1] + w[2] * self.d_ref[2]
    }

    /// A step starts at y: the slip's direction there is the belt stop's reference.
    pub fn begin_step(&mut self, y: &[f64; 6]) {
        let w = self.slip_vector(y);
        let n = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
        if n > 0.0 {
            self.d_ref = [w[0] / n, w[1] / n, w[2] / n];
        }
    }

    /// Belt friction wrench (F_x, F_y, M). Free sliding: continued past the stop. With
    /// active contacts: ramped linearly to zero below [`CONTACT_SLIP_REG`] of slip, because
    /// a contact can hold the parcel at zero belt slip, where the exact law's set-valued
    /// friction would make the motion chatter.
    pub fn belt_wrench(&self, y: &[f64; 6]) -> [f64; 3] {
        if !self.contacts.is_empty() {
            return self.ctx.contact_belt_wrench(y);
        }
        let sign = if self.along_ref(y) < 0.0 { -1.0 } else { 1.0 };
        let v_rel = sign * DVec2::new(y[3] - self.ctx.belt_speed, y[4]);
        let (f, m) = self.ctx.friction.wrench(v_rel, sign * y[5], y[2]);
        [f.x, f.y, m]
    }

    /// The evaluation at (t, y), a copy (once per step: the force check at a step's start).
    pub fn evaluate(&self, t: f64, y: &[f64; 6]) -> Evaluation {
        self.evaluated(t, y, |e| *e)
    }

    /// What `read` takes of the evaluation at (t, y), from the cache when it holds (t, y).
    #[inline]
    pub fn evaluated<R>(&self, t: f64, y: &[f64; 6], read: impl FnOnce(&Evaluation) -> R) -> R {
        self.evals.read(t, y, || self.evaluation(t, y), read)
    }

    /// Free sliding: dy/dt at (t, y) if it is the last one computed (first same as last).
    pub fn free_derivative_at(&self, t: f64, y: &[f64; 6]) -> Option<[f64; 6]> {
        self.last_free.at(t, y)
    }

    /// The acceleration with the contacts active, apart from the right-hand side so that
    /// the free slide's path through it stays short.
    #[inline(never)]
    fn contact_accel(&self, t: f64, y: &[f64; 6]) -> [f64; 3] {
        self.evaluated(t, y, |e| e.accel)
    }

    /// The evaluation at (t, y), computed.
    fn evaluation(&self, t: f64, y: &[f64; 6]) -> Evaluation {
        let f = self.belt_wrench(y);
        let body = Body {
            mass: self.ctx.mass,
            inertia: self.ctx.inertia,
            external: f,
        };
        let mut e = Evaluation {
            accel: body.free_accel(),
            frames: [None; active_set::MAX_CONTACTS],
            normal_force: [0.0; active_set::MAX_CONTACTS],
            tangential_force: [0.0; active_set::MAX_CONTACTS],
            arm: [0.0; 3],
            forces: [[0.0; 2]; active_set::MAX_CONTACTS],
        };
        if self.contacts.is_empty() {
            return e;
        }
        let (g, kin) = self.kinematics(t, y);
        let mut rows = [ContactRow {
            normal: [0.0; 3],
            beta: 0.0,
            tangent: [0.0; 3],
            beta_t: 0.0,
            friction: 0.0,
            slip: 0.0,
        }; active_set::MAX_CONTACTS];
        let mut modes = [None; active_set::MAX_CONTACTS];
        for (i, c) in self.contacts.slots().iter().enumerate() {
            if let Some(c) = c {
                let fr = contact::frame_with(c.kind, &kin, g.phi_sc, g.arm_sc);
                rows[i] = self.ctx.row(&fr);
                modes[i] = Some(c.mode);
                e.frames[i] = Some(FrameSummary {
                    along: fr.along,
                    extent: fr.extent,
                    slip: fr.slip,
                });
            }
        }
        match active_set::solve(&body, &rows, &modes) {
            Some(sol) => {
                e.accel = sol.accel;
                e.normal_force = sol.normal_force;
                e.tangential_force = sol.tangential_force;
                // J_n, J_t carry r×n, r×t: the moment about G comes with the force.
                for (i, c) in self.contacts.slots().iter().enumerate() {
                    let Some(c) = c else { continue };
                    let (ln, lt) = (sol.normal_force[i], sol.tangential_force[i]);
                    for k in 0..2 {
                        e.forces[i][k] = ln * rows[i].normal[k] + lt * rows[i].tangent[k];
                    }
                    if c.kind.is_arm() {
                        for k in 0..3 {
                            e.arm[k] += ln * rows[i].normal[k] + lt * rows[i].tangent[k];
                        }
                    }
                }
            }
            None => e.accel = [f64::NAN; 3],
        }
        e
    }

    /// dy/dt at (t, y).
    pub fn rhs(&self, t: f64, y: &[f64; 6]) -> [f64; 6] {
        if self.riding {
            return [y[3], y[4], y[5], 0.0, 0.0, 0.0];
        }
        if self.contacts.is_empty() {
            // Free sliding: the belt wrench alone, without building an `Evaluation`.
            let f = self.belt_wrench(y);
            let dy = [
                y[3],
                y[4],
                y[5],
                f[0] / self.ctx.mass,
                f[1] / self.ctx.mass,
                f[2] / self.ctx.inertia,
            ];
            self.last_free.keep(t, y, dy);
            return dy;
        }
        let a = self.contact_accel(t, y);
        [y[3], y[4], y[5], a[0], a[1], a[2]]
    }

    /// In contact: Coulomb friction damps the slip's free directions at about μ_b g / |w| (the
    /// force turns with the slip; a spin mode is damped alike, ⟨ρ²⟩ being about the
    /// footprint's i²), |w| no smaller than the regularised band. On the slender parcel
    /// squeezed between arm and guide from the arm's start (fig08) the explicit steps show the
    /// true rate within a factor 1.5 of this. Free sliding and riding are not stiff (a free
    /// slide's approach to its stop is the singularity's business).
    pub fn stiffness(&self, y: &[f64; 6]) -> f64 {
        if self.riding || self.is_free() {
            return 0.0;
        }
        self.ctx.belt_decel / self.slip(y).max(CONTACT_SLIP_REG)
    }

    /// Free sliding: the time left to the belt stop at the present deceleration.
    pub fn time_to_singularity(&self, t: f64, y: &[f64; 6]) -> f64 {
        if !self.is_free() {
            return f64::INFINITY;
        }
        // Below END_SLIP (a free segment can start there if riding was refused) the stop is
        // crossed and located by the belt-stop guard instead.
        if self.slip(y) <= crate::sim::tolerances::END_SLIP {
            return f64::INFINITY;
        }
        // The derivative at a step start is the last one computed (first same as last);
        // without it (a segment's first step) say nothing rather than pay for it.
        match self.free_derivative_at(t, y) {
            Some(dy) => self.time_to_stop(y, &dy),
            None => f64::INFINITY,
        }
    }

    /// Free sliding: the time the slip would take to vanish at its present rate,
    /// |w|²/(−w·ẇ) \[s], given dy/dt at y; infinite if the slip does not decrease. Coulomb
    /// friction decreases both |v_r| and |ω| (the footprint is centrally symmetric, model.md
    /// §3), so w·ẇ < 0 whenever w ≠ 0.
    fn time_to_stop(&self, y: &[f64; 6], dy: &[f64; 6]) -> f64 {
        let w = self.slip_vector(y);
        let l = self.ctx.slip_scale;
        let q2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
        let decay = -(w[0] * dy[3] + w[1] * dy[4] + w[2] * l * dy[5]);
        if decay > 0.0 {
            q2 / decay
        } else {
            f64::INFINITY
        }
    }

    /// The end of a free slide from a state y with a slip of about
    /// [`crate::sim::tolerances::END_SLIP`]: the time left, Δt = |w|²/(−w·ẇ) (constant
    /// deceleration along the present direction), and the riding state at the stop, moved by
    /// the mean velocity over Δt (the slip falling linearly to zero). The errors are a
    /// fraction of Δt ≈ 2.5e-8 s in time and of Δt |w| / 2 ≈ 1e-15 m in position.
    pub fn stop_tail(&self, t: f64, y: &[f64; 6]) -> (f64, [f64; 6]) {
        let dy = self.rhs(t, y);
        let dt = self.time_to_stop(y, &dy);
        if !dt.is_finite() {
            return (0.0, *y);
        }
        let v = self.ctx.belt_speed;
        let mut z = *y;
        z[0] += 0.5 * (y[3] + v) * dt;
        z[1] += 0.5 * y[4] * dt;
        z[2] += 0.5 * y[5] * dt;
        (dt, crate::sim::ride::snap(&z, v))
    }

    /// The active contacts' drift from their obstacles, put back between steps
    /// ([`crate::sim::drift::remove_drift`]): acceleration-level constraints let a long push
    /// drift 1e-6 m into the arm between two events. `watched` are the inactive pairs whose
    /// gaps are watched: those touching now keep their gaps.
    pub fn project(
        &self,
        t: f64,
        y: &mut [f64; 6],
        watched: impl Iterator<Item = ContactKind>,
    ) -> bool {
        if self.riding || self.contacts.is_empty() {
            return false;
        }
        let mut held = [ContactKind::TipEdge { edge: 0 }; active_set::MAX_CONTACTS];
        let mut n = 0;
        for kind in self.contacts.kinds() {
            held[n] = kind;
            n += 1;
        }
        // Cheaply first: most steps have nothing to remove.
        let (g, kin) = self.kinematics(t, y);
        let drifted = held[..n].iter().any(|&k| {
            let (gap, _, _) = contact::gap_and_range_with(k, &kin, g.phi_sc, g.arm_sc);
            gap.abs() > DRIFT_TOL
        });
        if !drifted {
            return false;
        }
        let keep: Vec<ContactKind> = watched
            .filter(|&kind| {
                let (gap, along, (lo, hi)) = contact::gap_and_range(kind, &kin);
                gap.abs() <= GAP_TOL && along >= lo && along <= hi
            })
            .collect();
        crate::sim::drift::remove_drift(self.ctx, g.arm, y, &held[..n], &keep)
    }
}
