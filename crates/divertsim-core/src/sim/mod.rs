//! The hybrid driver: integrates the parcel through its stages, handles events, records the
//! trajectory and returns the verdict.
//!
//! A run is a sequence of smooth segments separated by events (physics.md §5.6–5.7). Each
//! segment has one mode — riding with the belt (closed form), free sliding F2 (integrated) —
//! and ends at the first guard event, at a time breakpoint (the arm's cycle end), or at the
//! run's duration. Events are bounded in number and the integrator in steps, so a run always
//! ends with a verdict; numerical trouble becomes `Outcome::Failed` with a reason.

pub mod free_motion;
pub mod recorder;
pub mod result;
pub mod ride;

pub use result::{
    Event, EventKind, Impact, NotDivertedReason, Obstacle, Outcome, Overload, Sample, SimResult, Stage, State,
};

use crate::integrate::{self, Options, StopReason};
use crate::model::belt_friction::BeltFriction;
use crate::model::drive::ArmDrive;
use crate::model::params::Scenario;
use crate::GRAVITY;
use free_motion::FreeMotion;
use recorder::{state_of, Recorder};

/// Upper bound on events in one run; reaching it fails the run instead of looping.
pub const MAX_EVENTS: usize = 10_000;
/// Largest integrator step [s]: bounds how long a guard can go unsampled.
pub const MAX_STEP: f64 = 0.02;

/// Integrator options for a scenario's tolerance.
pub fn integrator_options(rtol: f64) -> Options {
    Options {
        rtol,
        atol: rtol * 1e-2,
        h_max: MAX_STEP,
        h_min: 1e-14,
        h_init: None,
        max_steps: 1_000_000,
    }
}

/// Run one scenario to its verdict.
pub fn simulate(scenario: &Scenario) -> SimResult {
    let mut rec = Recorder::new();
    let y0 = initial_state(scenario);
    let outcome = match run(scenario, &y0, &mut rec) {
        Ok(outcome) => outcome,
        Err(reason) => Outcome::Failed(reason),
    };
    let final_state = rec.samples.last().map(|s| s.state).unwrap_or_else(|| state_of(0.0, &y0));
    let max_lateral = if rec.max_lateral.is_finite() { rec.max_lateral } else { y0[1] };
    SimResult {
        outcome,
        stages: rec.stages,
        events: rec.events,
        trajectory: rec.samples,
        final_state,
        max_lateral,
        impacts: Vec::new(),
        overload: Default::default(),
    }
}

/// (x, y, φ, ẋ, ẏ, ω) at t = 0.
pub fn initial_state(scenario: &Scenario) -> [f64; 6] {
    let g = scenario.initial_centre();
    let v = scenario.initial_velocity();
    [g.x, g.y, scenario.parcel.angle, v.x, v.y, scenario.parcel.spin]
}

/// The mode of the current smooth segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    Ride,
    Free,
}

impl Mode {
    fn stage(self) -> Stage {
        match self {
            Mode::Ride => Stage::Ride,
            Mode::Free => Stage::F2,
        }
    }
}

fn run(scenario: &Scenario, y0: &[f64; 6], rec: &mut Recorder) -> Result<Outcome, String> {
    if let Some(problem) = basic_problem(scenario) {
        return Err(format!("invalid scenario: {problem}"));
    }
    let machine = &scenario.machine;
    let drive = if scenario.run.arm {
        Some(ArmDrive::new(&machine.drive, machine.cycle_time).map_err(|e| format!("invalid drive: {e}"))?)
    } else {
        None
    };
    let arm_angle = |t: f64| drive.as_ref().map_or(0.0, |d| d.state(t).angle);
    let arm_end = drive.as_ref().map(|d| d.cycle_time());
    let friction = BeltFriction::new(
        scenario.parcel.length,
        scenario.parcel.width,
        scenario.parcel.mass * GRAVITY,
        scenario.materials.belt_friction.clone(),
        scenario.materials.friction_model,
    );
    let mut free = FreeMotion::new(
        &friction,
        machine.belt_speed,
        scenario.parcel.mass,
        scenario.inertia(),
        machine.belt_width,
    );
    let options = integrator_options(scenario.run.tolerance);
    let t_end = scenario.run.duration;

    let mut t = 0.0;
    let mut y = *y0;
    let mut mode = if free.slip(&y) <= ride::RIDE_SLIP { Mode::Ride } else { Mode::Free };
    if mode == Mode::Ride {
        y = ride::snap(&y, machine.belt_speed);
    }
    rec.enter(mode.stage());
    rec.sample(t, &y, arm_angle(t), mode.stage());
    if drive.is_some() {
        rec.event(0.0, EventKind::ArmStart);
    }
    let mut arm_end_recorded = arm_end.is_none();

    loop {
        if rec.events.len() > MAX_EVENTS {
            return Err(format!("more than {MAX_EVENTS} events"));
        }
        if !arm_end_recorded && t >= arm_end.unwrap_or(f64::INFINITY) {
            rec.event(t, EventKind::ArmEnd);
            arm_end_recorded = true;
        }
        let arm_done = arm_end_recorded;
        if t >= t_end {
            return Ok(Outcome::NotDiverted(match mode {
                Mode::Ride => NotDivertedReason::LeftOnBelt,
                Mode::Free => NotDivertedReason::DurationReached,
            }));
        }
        // Next time breakpoint: the arm's cycle end, else the run's end.
        let t_break = match arm_end {
            Some(te) if !arm_done && te < t_end => te,
            _ => t_end,
        };
        match mode {
            Mode::Ride => {
                // Nothing can disturb a riding parcel once the arm is done: the verdict is
                // settled, and the rest of the run is closed-form.
                let t_next = if arm_done { t_end } else { t_break };
                ride_samples(rec, &y, t, t_next, machine.belt_speed, &arm_angle);
                y = ride::advance(&y, t_next - t, machine.belt_speed);
                t = t_next;
            }
            Mode::Free => {
                let stage = mode.stage();
                let stop = integrate::integrate(&mut free, t, y, t_break, &options, |step| {
                    rec.step(step, stage, arm_angle)
                })
                .map_err(|e| format!("integration failed in {}: {e}", stage.label()))?;
                t = stop.t;
                y = stop.y;
                if y.iter().any(|v| !v.is_finite()) {
                    return Err(format!("non-finite state at t = {t} s"));
                }
                match stop.reason {
                    StopReason::End => {}
                    StopReason::Event(hit) if hit.index == free_motion::GUARD_EXIT => {
                        rec.event(t, EventKind::Exit);
                        return Ok(Outcome::Diverted);
                    }
                    StopReason::Event(_) => {
                        // Slip reached zero (or, rarely, turned by 90° within a step: then
                        // simply go on sliding with a fresh reference direction).
                        if free.slip(&y) <= stop_tolerance(&free, scenario) {
                            y = ride::snap(&y, machine.belt_speed);
                            mode = Mode::Ride;
                            rec.event(t, EventKind::RideStart);
                            rec.enter(mode.stage());
                            rec.sample(t, &y, arm_angle(t), mode.stage());
                        }
                    }
                }
            }
        }
    }
}

/// Slip left at a located stop that still counts as a stop [m/s]. The located left root
/// is within ~1e-12 s of the true stop, where the slip decays at ≈ μ g.
fn stop_tolerance(free: &FreeMotion<'_>, scenario: &Scenario) -> f64 {
    let mu = free.friction.max_force() / (scenario.parcel.mass * GRAVITY);
    (1e-6 * mu.max(1e-3) * GRAVITY).max(10.0 * ride::RIDE_SLIP)
}

/// Trajectory points of a riding segment: closed form, sampled for output.
fn ride_samples(rec: &mut Recorder, y: &[f64; 6], t0: f64, t1: f64, v: f64, arm_angle: &impl Fn(f64) -> f64) {
    if t1 <= t0 {
        return;
    }
    let pieces = ((t1 - t0) / 0.02).ceil().clamp(1.0, 500.0) as usize;
    for k in 1..=pieces {
        let t = if k == pieces { t1 } else { t0 + (t1 - t0) * k as f64 / pieces as f64 };
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
    None
}
