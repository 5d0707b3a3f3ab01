//! The hybrid driver: integrates the parcel through its stages, handles events, records the
//! trajectory and returns the verdict.
//!
//! A run is a sequence of smooth segments separated by events (docs/model.md §6–§7). Each
//! segment has one mode — riding with the belt (closed form), free sliding F2 (integrated) —
//! and ends at the first guard event, at a time breakpoint (the arm's cycle end), or at the
//! run's duration. Events are bounded in number and the integrator in steps, so a run always
//! ends with a verdict; numerical trouble becomes `Outcome::Failed` with a reason.

pub mod arm_loads;
pub(crate) mod context;
pub(crate) mod drift;
pub mod group;
pub mod meter;
pub(crate) mod motion;
pub(crate) mod recorder;
pub mod result;
pub(crate) mod ride;
pub(crate) mod settle;
pub(crate) mod tolerances;

pub use result::{
    stage_legend, ContactCheck, Event, EventKind, Impact, Jam, NotDivertedReason, Obstacle,
    Outcome, Overload, Sample, SimResult, Stage, State,
};

use crate::geometry::cross;
use crate::integrate::{self, EventHit, Options, StopReason};
use crate::model::contact::{self, ContactKind};
use crate::model::impact::{equivalent_drop_height, free_fall_impulse};
use crate::model::params::Scenario;
use crate::model::trigger::Trigger;
use crate::GRAVITY;
use context::Context;
use motion::{Motion, Watch};
pub use recorder::Recording;
use recorder::{state_of, Recorder};
use settle::{settle, Settled, Unsettled};
use tolerances::{AT_TIP, FACE_CROSSING_SPEED};

/// Upper bound on events in one run; reaching it fails the run instead of looping.
pub const MAX_EVENTS: usize = 10_000;
/// Largest integrator step \[s]: bounds how long a guard can go unsampled.
pub const MAX_STEP: f64 = 0.02;

/// Integrator options for a scenario's tolerance. The state's components (m, rad, m/s,
/// rad/s) are of order one in a diverter; the absolute tolerance is a tenth of the relative
/// one. Much smaller would hold the slip and spin to absolute 1e-10 as they vanish at a belt
/// stop (where the free slide is not analytic) for no physical gain; equal to it lost a belt
/// stop in the 100 000-run property test.
pub fn integrator_options(rtol: f64) -> Options {
    integrator_options_for(rtol, 0.0)
}

/// [`integrator_options`] for a run of `duration` seconds: the step budget of one segment
/// covers the whole duration at the largest step several times over (a frictionless slide
/// takes [`MAX_STEP`] steps all the way), and never falls below 50 000.
pub fn integrator_options_for(rtol: f64, duration: f64) -> Options {
    let budget = (4.0 * duration / MAX_STEP).ceil();
    Options {
        rtol,
        atol: 0.1 * rtol,
        h_max: MAX_STEP,
        h_min: 1e-14,
        h_init: None,
        max_steps: if budget > 50_000.0 {
            budget.min(1e9) as usize
        } else {
            50_000
        },
    }
}

/// Run one scenario to its verdict, with the dense trajectory.
pub fn simulate(scenario: &Scenario) -> SimResult {
    simulate_with(scenario, Recording::Full)
}

/// Run one scenario to its verdict without a trajectory (batch work): every other field of
/// the result is bitwise that of [`simulate`].
pub fn simulate_verdict(scenario: &Scenario) -> SimResult {
    simulate_with(scenario, Recording::VerdictOnly)
}

/// How far a cycle may start before the one before it has ended \[s]: the rounding of start
/// times shifted to a run's own t = 0 (a line's back-to-back cycles).
pub const CYCLE_OVERLAP_TOL: f64 = 1e-9;

/// Whether a cycle that starts at `later` starts before the one started at `earlier` has
/// ended (t_c = `cycle_time`, within [`CYCLE_OVERLAP_TOL`]): a machine cannot do that.
pub fn starts_in_cycle(earlier: f64, later: f64, cycle_time: f64) -> bool {
    later < earlier + cycle_time - CYCLE_OVERLAP_TOL
}

/// The reason of the failed run of a scenario whose adaptive trigger is not resolved.
pub const UNRESOLVED_TRIGGER: &str = "the adaptive trigger is not resolved: the arm's start depends on the parcel; run adaptive_trigger::resolve (the api's runs::run does) first";

/// Run one scenario to its verdict, recording as asked. A scenario with an unresolved
/// adaptive trigger is a failed run ([`UNRESOLVED_TRIGGER`]).
pub fn simulate_with(scenario: &Scenario, recording: Recording) -> SimResult {
    meter::count_one();
    let mut rec = Recorder::new(recording);
    let y0 = initial_state(scenario);
    let mut jam = None;
    let outcome = match &scenario.machine.trigger {
        // Running it at the file's R_s would be another parcel's run than the machine's.
        Trigger::Adaptive(_) => Outcome::Failed(UNRESOLVED_TRIGGER.into()),
        Trigger::Fixed => match run(scenario, &y0, &mut rec) {
            Ok(outcome) => outcome,
            Err(Unsettled::Failed(reason)) => Outcome::Failed(reason),
            Err(Unsettled::Jammed(j)) => {
                rec.event(j.t, EventKind::Jammed);
                jam = Some(j);
                Outcome::NotDiverted(NotDivertedReason::Jammed)
            }
        },
    };
    let final_state = rec.last.unwrap_or_else(|| state_of(0.0, &y0));
    let max_lateral = if rec.max_lateral.is_finite() {
        rec.max_lateral
    } else {
        y0[1]
    };
    let along_range = if rec.along.0 <= rec.along.1 {
        rec.along
    } else {
        (y0[0], y0[0])
    };
    let overload = overload(scenario, &rec.impacts);
    // A parcel no taller than the arm face's bottom ran without the arm (Context::new).
    let outcome = match outcome {
        Outcome::NotDiverted(_) if scenario.run.arm && scenario.arm_contact_height().is_none() => {
            Outcome::NotDiverted(NotDivertedReason::UnderArm)
        }
        o => o,
    };
    SimResult {
        outcome,
        stages: rec.stages,
        events: rec.events,
        trajectory: rec.samples,
        final_state,
        max_lateral,
        along_range,
        impacts: rec.impacts,
        overload,
        contact_check: rec.contact_check,
        tipping: rec.tipping,
        arm_torque: rec.arm_torque,
        arm_strikes: rec.arm_strikes,
        jam,
    }
}

/// (x, y, φ, ẋ, ẏ, ω) at t = 0.
pub fn initial_state(scenario: &Scenario) -> [f64; 6] {
    let g = scenario.initial_centre();
    let v = scenario.initial_velocity();
    [
        g.x,
        g.y,
        scenario.parcel.angle,
        v.x,
        v.y,
        scenario.parcel.spin,
    ]
}

/// Where a cycle under way at t = 0 (a start in `run.cycle_starts` before 0) puts the arm
/// across the parcel: (α at t = 0 \[rad], depth \[m]) when the arm segment, its face
/// band reaching the parcel, crosses the footprint's interior, the depth being how far the
/// footprint would have to move across the arm line to clear it. `None` when the arm is
/// clear of the parcel (always at rest: α = 0 lies along the belt's edge). Such a start is
/// no state a machine can be in: the run would begin with a "strike" from inside the parcel.
pub fn arm_across_parcel_at_start(scenario: &Scenario) -> Option<(f64, f64)> {
    // Only a cycle started before t = 0 and still running then can put the arm anywhere
    // but at rest (most scenarios: no context is built).
    let t_c = scenario.machine.cycle_time;
    let under_way = scenario
        .run
        .cycle_starts
        .iter()
        .any(|&s| s < 0.0 && s + t_c > 0.0);
    if !under_way || !scenario.run.arm || scenario.arm_contact_height().is_none() {
        return None;
    }
    let ctx = Context::new(scenario).ok()?;
    let alpha = context::arm_state(&ctx, 0.0).angle;
    if alpha == 0.0 {
        return None;
    }
    let y = initial_state(scenario);
    let corners = ctx.rect.corners(glam::DVec2::new(y[0], y[1]), y[2]);
    let dir = glam::DVec2::new(alpha.cos(), alpha.sin());
    let normal = dir.perp();
    // The arm line O + s·dir, s in [0, R_z], clipped to the convex footprint.
    let (mut s0, mut s1) = (0.0_f64, ctx.arm_length);
    let centre = corners.iter().copied().sum::<glam::DVec2>() / 4.0;
    for k in 0..4 {
        let (a, b) = (corners[k], corners[(k + 1) % 4]);
        let mut inward = (b - a).perp();
        if inward.dot(centre - a) < 0.0 {
            inward = -inward;
        }
        // Inside where inward·(p − a) > 0 along p = s·dir.
        let (num, den) = (inward.dot(-a), inward.dot(dir));
        if den.abs() < 1e-15 {
            if num <= 0.0 {
                return None;
            }
        } else if den > 0.0 {
            s0 = s0.max(-num / den);
        } else {
            s1 = s1.min(-num / den);
        }
    }
    let gap = tolerances::GAP_TOL;
    if s1 - s0 <= gap {
        return None;
    }
    let side: Vec<f64> = corners.iter().map(|c| c.dot(normal)).collect();
    let front = side.iter().copied().fold(0.0, f64::max);
    let back = -side.iter().copied().fold(0.0, f64::min);
    let depth = front.min(back);
    (depth > gap).then_some((alpha, depth))
}

/// The overload figures of model.md §5 from the strikes.
pub fn overload(s: &Scenario, impacts: &[Impact]) -> Overload {
    let (m, e, h0) = (s.parcel.mass, s.materials.restitution, s.limits.drop_height);
    let max_impulse = impacts.iter().map(|i| i.impulse).fold(0.0, f64::max);
    let fall = free_fall_impulse(m, e, h0);
    let max_work = impacts
        .iter()
        .map(|i| i.compression_work.abs())
        .fold(0.0, f64::max);
    let arm = impacts.iter().filter(|i| i.obstacle.is_arm());
    Overload {
        max_impulse,
        fall_impulse: fall,
        overload_ratio: max_impulse / fall,
        equivalent_drop_height: equivalent_drop_height(max_impulse, m, e),
        energy_ratio: max_work / (m * GRAVITY * h0),
        arm_max_impulse: arm.clone().map(|i| i.impulse).fold(0.0, f64::max),
        arm_total_impulse: arm.map(|i| i.impulse).fold(0.0, |a, b| a + b),
    }
}

/// Which face of the arm each corner starts on: the working face, unless the corner starts
/// strictly behind the arm line within the arm's length (impossible at α(0) = 0 for a parcel
/// on the belt, but kept general).
fn initial_sides(ctx: &Context, y: &[f64; 6]) -> [i8; 4] {
    let kin = ctx.kinematics(0.0, y);
    std::array::from_fn(|k| {
        let f = contact::frame(
            ContactKind::CornerArm {
                corner: k as u8,
                side: 1,
            },
            &kin,
        );
        if f.gap < -tolerances::GAP_TOL && contact::in_range(&f) {
            -1
        } else {
            1
        }
    })
}

/// Whether a riding parcel is beyond the arm's reach, downstream.
fn escaped(ctx: &Context, y: &[f64; 6]) -> bool {
    ctx.drive.is_some() && y[0] > 0.0 && ctx.distance_from_pivot(y) > ctx.arm_length
}

/// The run's outcome; a jam (or a failure) at an event as its error, the pose there
/// sampled as the run's last.
fn run(scenario: &Scenario, y0: &[f64; 6], rec: &mut Recorder) -> Result<Outcome, Unsettled> {
    if let Some(problem) = basic_problem(scenario) {
        return Err(format!("invalid scenario: {problem}").into());
    }
    let ctx = Context::new(scenario)?;
    let arm_angle = |t: f64| context::arm_state(&ctx, t).angle;
    let arm_end = ctx.arm_end();
    let options = integrator_options_for(scenario.run.tolerance, scenario.run.duration);
    let t_end = scenario.run.duration;

    let mut t = 0.0;
    let mut y = *y0;
    let mut sides = initial_sides(&ctx, &y);
    let mut motion = Motion::new(&ctx, sides);
    // Where the arm starts and ends its cycles: integration segments end there (α̈ may jump)
    // and the event is recorded. Those up to t = 0 are behind (a cycle starting at 0 is
    // recorded now, one under way is not).
    let boundaries = ctx.cycle_boundaries();
    let next = boundaries.partition_point(|&(b, _)| b <= 0.0);
    if boundaries.iter().any(|&(b, start)| start && b == 0.0) {
        rec.event(0.0, EventKind::ArmStart);
    }
    let arm_of = |tt: f64| context::arm_state(&ctx, tt);
    let start = y;
    let first = settle(&ctx, t, &mut y, sides, None, &[], &arm_of)
        .inspect_err(|e| jam_sample(rec, e, t, &start, arm_angle(t), Stage::Ride))?;
    strike_checks(&ctx, rec, &mut motion, t, (&start, &y), &first);
    let mut stage = apply(rec, &mut motion, t, &y, &first, None);
    rec.sample(t, &y, arm_angle(t), stage);
    let mut cycles = Cycles {
        boundaries,
        next,
        arm_done: arm_end.is_none_or(|te| te <= 0.0),
    };

    for _ in 0..MAX_EVENTS {
        if motion.riding() && escaped(&ctx, &y) && !cycles.arm_done {
            rec.event(t, EventKind::Escape);
            return Ok(Outcome::NotDiverted(NotDivertedReason::Escaped));
        }
        if motion.riding() && cycles.arm_done {
            // Nothing can disturb a riding parcel once the arm is done; a tilt left from
            // before settles (or goes over) unloaded.
            if motion.ride_out(t, (t_end - t).max(0.0)) {
                motion.drain(rec);
                if ctx.tip_rule == crate::model::params::TippingRule::Verdict {
                    rec.event(rec.tipping.t, EventKind::Tipped);
                    return Ok(Outcome::NotDiverted(NotDivertedReason::Tipped));
                }
            }
            ride_samples(rec, &y, t, t_end, ctx.belt_speed, &arm_angle);
            return Ok(Outcome::NotDiverted(NotDivertedReason::LeftOnBelt));
        }
        if t >= t_end {
            return Ok(Outcome::NotDiverted(NotDivertedReason::DurationReached));
        }
        let t_break = match cycles.boundaries.get(cycles.next) {
            Some(&(b, _)) if b < t_end => b,
            _ => t_end,
        };
        let seg_stage = stage;
        let active: Vec<ContactKind> = motion.active().map(|c| c.kind).collect();
        let points_at = |tt: f64, yy: &[f64; 6]| contact_points(&ctx, &active, tt, yy);
        let stop = match integrate::integrate(&mut motion, t, y, t_break, &options, |step| {
            rec.step(step, seg_stage, arm_angle, points_at)
        }) {
            Ok(stop) => stop,
            Err(e) => {
                let reason = format!("integration failed in {}: {e}", seg_stage.label());
                let unsettled = integration_failure(&ctx, &active, rec, reason);
                if matches!(unsettled, Unsettled::Jammed(_)) {
                    // A jam is a run's end like any other: what the probes measured up to
                    // the last accepted step (the arm's torque, the tipping margin) stays.
                    motion.drain(rec);
                }
                return Err(unsettled);
            }
        };
        if stop.reason != StopReason::Halt {
            // The state just before the event is checked too (issue 47, F2).
            motion.close_stretch(stop.t, &stop.y);
        }
        motion.drain(rec);
        t = stop.t;
        y = stop.y;
        if stop.reason == StopReason::Halt || motion.stopped_by_probe() {
            // The box went over (TippingRule::Verdict): the run ends here, the event at the
            // instant it went over.
            motion.drain(rec);
            rec.event(rec.tipping.t.min(t), EventKind::Tipped);
            return Ok(Outcome::NotDiverted(NotDivertedReason::Tipped));
        }
        let stop_reason = match stop.reason {
            StopReason::Event(hit) if motion.watch(hit.index) == Watch::SlipEnd => {
                // A free slide about to stop: the rest in closed form, then the belt stop.
                let (dt, y_stop) = motion.stop_tail(t, &y);
                t = (t + dt).min(t_break);
                y = y_stop;
                motion.tail_to(t);
                match motion.guard_of(Watch::BeltStop) {
                    Some(index) => StopReason::Event(EventHit { index, t }),
                    None => StopReason::End,
                }
            }
            reason => reason,
        };
        if y.iter().any(|v| !v.is_finite()) {
            return Err(format!("non-finite state at t = {t} s").into());
        }
        let (kind, sides_flipped) = match stop_meaning(
            &ctx,
            &mut motion,
            rec,
            stop_reason,
            (t, &y),
            &mut sides,
            &mut cycles,
        ) {
            Stopped::Ends(outcome) => return Ok(outcome),
            Stopped::Goes => continue,
            Stopped::Settles {
                kind,
                sides_flipped,
            } => (kind, sides_flipped),
        };
        let before = y;
        let touched = match stop_reason {
            StopReason::Event(hit) => match motion.watch(hit.index) {
                Watch::Gap(k) => Some(k),
                _ => None,
            },
            StopReason::End | StopReason::Halt => None,
        };
        let held: Vec<ContactKind> = motion.active().map(|c| c.kind).collect();
        let settled = settle(&ctx, t, &mut y, sides, touched, &held, &arm_of)
            .inspect_err(|e| jam_sample(rec, e, t, &before, arm_angle(t), stage))?;
        if let (StopReason::Event(hit), true) = (
            stop_reason,
            unchanged(&motion, &settled, &before, &y, sides_flipped),
        ) {
            // Nothing happened (a crossing that is no contact, a slip that only turned):
            // go on, with this guard silent until it has crossed.
            motion.mute(hit.index);
            continue;
        }
        strike_checks(&ctx, rec, &mut motion, t, (&before, &y), &settled);
        stage = apply(rec, &mut motion, t, &y, &settled, kind);
        let active: Vec<ContactKind> = motion.active().map(|c| c.kind).collect();
        rec.sample_with(
            t,
            &y,
            arm_angle(t),
            stage,
            contact_points(&ctx, &active, t, &y),
        );
    }
    Err(format!("more than {MAX_EVENTS} events").into())
}

/// What a stretch's stop means for the run.
enum Stopped {
    /// The run ends with this outcome.
    Ends(Outcome),
    /// Nothing to settle: integrate on.
    Goes,
    /// Settle the mode after an event of `kind` (none: nothing to record), the corners'
    /// faces flipped or not.
    Settles {
        kind: Option<EventKind>,
        sides_flipped: bool,
    },
}

/// The arm's cycle boundaries: where integration segments end (α̈ may jump), the next one
/// ahead, and whether the arm has finished.
struct Cycles {
    boundaries: Vec<(f64, bool)>,
    next: usize,
    arm_done: bool,
}

/// What the stop of a stretch at (t, y) for `reason` means: the run's end (the far edge,
/// the near edge, an escape), a cycle boundary (its event recorded), or an event whose mode
/// must be settled. A corner crossing the arm's line beyond the tip, or handed over by the
/// tip leaving an edge, changes `sides`.
fn stop_meaning(
    ctx: &Context,
    motion: &mut Motion<'_>,
    rec: &mut Recorder,
    reason: StopReason,
    (t, y): (f64, &[f64; 6]),
    sides: &mut [i8; 4],
    cycles: &mut Cycles,
) -> Stopped {
    let mut sides_flipped = false;
    let kind = match reason {
        // Returned above.
        StopReason::Halt => None,
        StopReason::End => match cycles.boundaries.get(cycles.next) {
            Some(&(b, start)) if t >= b => {
                cycles.next += 1;
                cycles.arm_done = cycles.next == cycles.boundaries.len();
                rec.event(
                    t,
                    if start {
                        EventKind::ArmStart
                    } else {
                        EventKind::ArmEnd
                    },
                );
                None
            }
            _ => return Stopped::Goes,
        },
        StopReason::Event(hit) => match motion.watch(hit.index) {
            Watch::Exit => {
                rec.event(t, EventKind::Exit);
                return Stopped::Ends(Outcome::Diverted);
            }
            Watch::NearEdge => {
                // Off the belt the belt friction no longer acts: the parcel falls off.
                rec.event(t, EventKind::OffNearSide);
                return Stopped::Ends(Outcome::NotDiverted(NotDivertedReason::OffNearSide));
            }
            Watch::Reach => {
                // The guard's crossing is the escape: at its located left root the parcel
                // is still a hair within reach, so the distance is not tested again (it
                // was, and a parcel riding out of reach mid-cycle was then reported
                // left on the belt at the arm's end instead).
                if !cycles.arm_done && y[0] > 0.0 {
                    rec.event(t, EventKind::Escape);
                    return Stopped::Ends(Outcome::NotDiverted(NotDivertedReason::Escaped));
                }
                None
            }
            Watch::Gap(ContactKind::CornerArm { corner, side }) => {
                let f = contact::frame(
                    ContactKind::CornerArm { corner, side },
                    &ctx.kinematics(t, y),
                );
                // The event logic's end rule: a corner crossing the line at the tip while
                // moving outward passes beyond the arm (settle would not take it either).
                let held: Vec<ContactKind> = motion.active().map(|c| c.kind).collect();
                let ends = settle::end_tolerances(&ctx.kinematics(t, y), &held);
                let past_tip = f.along > f.extent.1
                    || (f.along >= f.extent.1 - ends[usize::from(corner % 4)]
                        && f.along_rate > tolerances::LEAVE_SPEED);
                if !past_tip {
                    Some(EventKind::ContactStart)
                } else if f.normal_speed.abs() <= FACE_CROSSING_SPEED {
                    // A corner hovering on the line beyond the tip (a side lying along
                    // the arm and overhanging it) has not crossed: keep its face.
                    None
                } else {
                    // The corner crossed the arm's line beyond the arm: it is now on the
                    // other face's side.
                    sides[corner as usize] = -side;
                    motion.sides = *sides;
                    sides_flipped = true;
                    None
                }
            }
            Watch::Gap(_) => Some(EventKind::ContactStart),
            Watch::BeltStop | Watch::BeltSlow => Some(EventKind::RideStart),
            // Replaced by the belt stop above.
            Watch::SlipEnd => None,
            Watch::Release(_) => Some(EventKind::Release),
            Watch::RangeLow(i) | Watch::RangeHigh(i) => {
                // The tip leaving an edge at a parcel corner hands that corner to the arm
                // on the side of the arm's line that holds the parcel's centre (the
                // convex parcel cannot lie on both sides there without the arm inside it).
                let leaving_tip_edge = motion
                    .active()
                    .nth(i)
                    .is_some_and(|c| matches!(c.kind, ContactKind::TipEdge { .. }));
                if leaving_tip_edge {
                    let tip = ctx.arm_tip(t);
                    let centre = glam::DVec2::new(y[0], y[1]);
                    let centre_side = if cross(tip, centre) >= 0.0 { 1 } else { -1 };
                    for (k, c) in ctx.rect.corners(centre, y[2]).iter().enumerate() {
                        if (*c - tip).length() < AT_TIP && sides[k] != centre_side {
                            sides[k] = centre_side;
                            motion.sides = *sides;
                            sides_flipped = true;
                        }
                    }
                }
                Some(EventKind::ContactEnd)
            }
            Watch::SlipStop(_) => Some(EventKind::SlipStop),
            Watch::StickBreak(_) => Some(EventKind::StickBreak),
        },
    };
    Stopped::Settles {
        kind,
        sides_flipped,
    }
}

/// The checks of a settled mode's strike, if any, at t that took the parcel from `before`
/// to `after` (impulse P = m Δv less a pivot's belt impulse): the impulsive tipping check
/// ([`crate::model::tipping::TipGeometry::strike`]) and the angular impulse the arm took
/// about the pivot, J_c = −Σ Qᵢ × Pᵢ over its own contacts' impulses
/// ([`Settled::arm_angular_impulse`], kept in `rec.arm_strikes`). A strike only starts or
/// changes a tilt: whether the box goes over is the tilt's to say, later.
fn strike_checks(
    ctx: &Context,
    rec: &mut Recorder,
    motion: &mut Motion<'_>,
    t: f64,
    (before, after): (&[f64; 6], &[f64; 6]),
    s: &Settled,
) {
    if s.impact.is_none() {
        return;
    }
    // The arm's and the guide's impulses: a pivot's belt impulse (§12a) is not a strike's.
    let impulse =
        ctx.mass * glam::DVec2::new(after[3] - before[3], after[4] - before[4]) - s.pivot_impulse;
    motion.strike(t, after[2], impulse);
    if let Some(jc) = s.arm_angular_impulse {
        rec.arm_strikes.push((t, jc));
    }
}

/// The points of up to two active contacts at (t, y), for the trajectory output.
fn contact_points(
    ctx: &Context,
    active: &[ContactKind],
    t: f64,
    y: &[f64; 6],
) -> [Option<[f64; 2]>; 2] {
    let mut pts = [None, None];
    if active.is_empty() {
        return pts;
    }
    let corners = ctx.rect.corners(glam::DVec2::new(y[0], y[1]), y[2]);
    for (slot, kind) in pts.iter_mut().zip(active) {
        *slot = Some(contact_point(ctx, &corners, *kind, t));
    }
    pts
}

/// Where contact `kind` touches at t, the parcel's corners being `corners`: the corner, or
/// the arm's tip (x, y) \[m].
fn contact_point(ctx: &Context, corners: &[glam::DVec2; 4], kind: ContactKind, t: f64) -> [f64; 2] {
    let p = match kind {
        ContactKind::CornerArm { corner, .. } | ContactKind::CornerGuide { corner } => {
            corners[(corner % 4) as usize]
        }
        ContactKind::TipEdge { .. } => ctx.arm_tip(t),
    };
    [p.x, p.y]
}

/// A stretch's integration failure, with `active` the contacts it held. Where they hold the
/// parcel between the arm and the guide, the arm closing on it, it is a jam (docs/model.md
/// §6b): as the wedge locks,
/// the forces that keep the arm's prescribed motion grow without bound, and so do the
/// accelerations, until the step size or the state gives out. Its place: the contacts at
/// the last accepted step.
fn integration_failure(
    ctx: &Context,
    active: &[ContactKind],
    rec: &Recorder,
    reason: String,
) -> Unsettled {
    let Some(last) = rec.last else {
        return reason.into();
    };
    let corners = ctx.rect.corners(glam::DVec2::new(last.x, last.y), last.phi);
    let held: Vec<(ContactKind, [f64; 2])> = active
        .iter()
        .map(|&k| (k, contact_point(ctx, &corners, k, last.t)))
        .collect();
    settle::unsettled(last.t, &held, context::arm_state(ctx, last.t).rate, reason)
}

/// A jam at an event ends the run at the pose before it (`y`, sampled at `t`); a failure
/// leaves the record as it was.
fn jam_sample(rec: &mut Recorder, e: &Unsettled, t: f64, y: &[f64; 6], angle: f64, stage: Stage) {
    if matches!(e, Unsettled::Jammed(_)) {
        rec.sample(t, y, angle, stage);
    }
}

/// Whether settling left the mode and the state as they were.
fn unchanged(
    motion: &Motion<'_>,
    s: &Settled,
    before: &[f64; 6],
    after: &[f64; 6],
    sides_flipped: bool,
) -> bool {
    !sides_flipped
        && s.impact.is_none()
        && s.riding == motion.riding()
        && before == after
        && s.active.len() == motion.active().count()
        && s.active.iter().zip(motion.active()).all(|(a, b)| a == b)
}

/// Record a settled mode's strike, if any (F1 the first, F3 later ones); returns its stage.
fn record_impact(rec: &mut Recorder, t: f64, s: &Settled) -> Option<Stage> {
    let mut imp = s.impact?;
    imp.stage = if rec.impacts.is_empty() {
        Stage::F1
    } else {
        Stage::F3
    };
    rec.enter(imp.stage);
    rec.event(t, EventKind::Impact);
    rec.impacts.push(imp);
    Some(imp.stage)
}

/// Put a settled mode into effect and record its events; returns the new stage.
fn apply(
    rec: &mut Recorder,
    motion: &mut Motion<'_>,
    t: f64,
    y: &[f64; 6],
    s: &Settled,
    cause: Option<EventKind>,
) -> Stage {
    record_impact(rec, t, s);
    match cause {
        Some(EventKind::ContactStart) if s.impact.is_some() || s.active.is_empty() => {}
        Some(EventKind::RideStart) if !s.riding => {}
        Some(kind) => rec.event(t, kind),
        None => {}
    }
    motion.configure(s.riding, &s.active, t, y);
    let stage = settle::stage_of(s.riding, &s.active);
    rec.enter(stage);
    stage
}
/// Trajectory points of a riding segment: closed form, sampled for output.
fn ride_samples(
    rec: &mut Recorder,
    y: &[f64; 6],
    t0: f64,
    t1: f64,
    v: f64,
    arm_angle: &impl Fn(f64) -> f64,
) {
    if t1 <= t0 {
        return;
    }
    if !rec.keeps_samples() {
        // Riding keeps y: only the end state matters.
        rec.sample(t1, &ride::advance(y, t1 - t0, v), 0.0, Stage::Ride);
        return;
    }
    let pieces = ((t1 - t0) / 0.02).ceil().clamp(1.0, 500.0) as usize;
    for k in 1..=pieces {
        let t = if k == pieces {
            t1
        } else {
            t0 + (t1 - t0) * k as f64 / pieces as f64
        };
        rec.sample(t, &ride::advance(y, t - t0, v), arm_angle(t), Stage::Ride);
    }
}

/// The few checks the core makes itself so that it never panics on a bad library call; the
/// command line validates every key with its allowed range before it gets here.
fn basic_problem(s: &Scenario) -> Option<String> {
    let p = &s.parcel;
    let m = &s.machine;
    let positive = [
        ("parcel.length", p.length),
        ("parcel.width", p.width),
        ("parcel.mass", p.mass),
        ("machine.belt_width", m.belt_width),
        ("machine.cycle_time", m.cycle_time),
        ("machine.arm_length", m.arm_length),
        ("run.duration", s.run.duration),
        ("run.tolerance", s.run.tolerance),
    ];
    for (key, v) in positive {
        if !(v.is_finite() && v > 0.0) {
            return Some(format!("{key} = {v} must be a finite number > 0"));
        }
    }
    let finite = [
        ("machine.belt_speed", m.belt_speed),
        ("machine.start_position", m.start_position),
        ("parcel.offset", p.offset),
        ("parcel.angle", p.angle),
        ("parcel.spin", p.spin),
    ];
    for (key, v) in finite {
        if !v.is_finite() {
            return Some(format!("{key} = {v} must be finite"));
        }
    }
    if let Some(v) = p.velocity {
        if !v.is_finite() {
            return Some("parcel.velocity must be finite".into());
        }
    }
    let starts = &s.run.cycle_starts;
    if starts.is_empty() || starts.iter().any(|t| !t.is_finite()) {
        return Some(format!(
            "run.cycle_starts = {starts:?} must be one finite time or more"
        ));
    }
    if starts
        .windows(2)
        .any(|w| starts_in_cycle(w[0], w[1], m.cycle_time))
    {
        return Some(format!(
            "run.cycle_starts = {starts:?}: a cycle starts before the one before it has ended \
             (t_c = {} s)",
            m.cycle_time
        ));
    }
    None
}
