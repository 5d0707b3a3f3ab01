//! The true worst case of one machine setting: a global search over the variables nobody
//! controls (issue 10) for the largest simulated impulse and for the smallest divert reserve.
//!
//! The paper's worst case ([`crate::analysis::paper::overload`]: the 15 kg parcel parallel to the belt, struck
//! on its corner by the arm tip at the largest α̇) is one closed-form strike. Full simulations
//! beat it: an inclined parcel struck near the middle of an edge has an effective mass of
//! about m and gains the belt's velocity component. So the search simulates.
//!
//! **The pose box** ([`PoseBox`]): for each arriving parcel the size within its class
//! (a ∈ [a_lo, a_hi], b ∈ [b_lo, min(b_hi, a)], so b ≤ a), the mass, the angle φ, the offset
//! ΔP anywhere on the belt (a fraction of the room P_max − extent(a, b, φ) left beside it),
//! its arrival phase δt relative to the trigger (a light-barrier timing error: the parcel
//! front is at R_s + v δt when the arm starts), and optionally the belt speed (a factor on
//! v), μ_b (a factor on the law), μ_a and e* within bands.
//!
//! **The mass** is not searched: with a kinematically driven arm, Coulomb friction
//! proportional to the weight and a restitution law, every force and impulse scales with m,
//! so the path, the ratio S/S_fall and the reserve do not depend on it (checked in the tests
//! to 1e-12 relative: round-off). The search fixes it at the class's largest mass, where the impulse S
//! itself is largest, and spends its budget on the variables that matter.
//!
//! **The objectives**: the overload ratio S/S_fall of the run (maximised), the divert
//! reserve d of [`crate::analysis::design::design_set::divert_overshoot`] (minimised: d < 0 is a parcel left on
//! the belt), or the stroke's peak drive torque at the arm (maximised, issue 26;
//! [`crate::sim::arm_loads`]). The parcel's share of that torque scales with m like every
//! force, the arm's own inertia share I α̈ does not: |I α̈ − m k(t)| is convex in m at
//! every instant, so its peak over the stroke is largest at one end of the class's mass
//! band. One run gives both ends (the path does not depend on m): the torque objective
//! takes the larger, and the worst pose states that mass. A run that fails numerically counts as harmless (ratio 0, reserve
//! [`FAILED_MARGIN`]) and is counted in [`WorstCase::failed_runs`], so numerical trouble never
//! poses as a worst case.
//!
//! **The method**: the landscape is discontinuous (stage sequences change, strikes appear and
//! vanish), so `starts` independent runs of the project's feasibility-first DE, each with its
//! own seed and an equal share of the budget, then a compass search
//! ([`crate::optimize::pattern`]) from the best point as the local refinement. Every batch is
//! evaluated in parallel in a fixed order: the result does not depend on the thread count.
//!
//! **Exact reproduction**: a [`Pose`] holds the resolved values a scenario file states (the
//! angle in degrees, converted with `to_radians` as the file loader does), and
//! [`Pose::scenario`] applies them, so a file written from a pose reproduces the run bit for
//! bit.

use crate::analysis::design::design_set::{
    case_scenario, divert_overshoot, DesignPoint, FAILED_MARGIN,
};
pub use crate::analysis::design::pose::{
    extent_across, pose_of, scale_friction, search_bounds, Band, Pose, PoseBox, Scatter, DIM,
    VARIABLES,
};
use crate::model::params::Scenario;
use crate::optimize::de::{self, DeSettings};
use crate::optimize::pattern::{self, PatternSettings};
use crate::optimize::{Bounds, Evaluation, NoObserver, OptimizeError, Problem};
use crate::run::sweep::Progress;
use crate::sim::arm_loads::StrokeProfile;
use crate::sim::{simulate_verdict, Outcome, SimResult};
use std::sync::atomic::{AtomicUsize, Ordering};

/// What to search for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WorstObjective {
    /// The largest overload ratio S/S_fall.
    Impulse,
    /// The smallest divert reserve d \[m].
    Reserve,
    /// The largest peak drive torque at the arm over the stroke \[N·m].
    Torque,
}

impl WorstObjective {
    /// The name tables and files use.
    pub fn label(self) -> &'static str {
        match self {
            WorstObjective::Impulse => "impulse",
            WorstObjective::Reserve => "reserve",
            WorstObjective::Torque => "torque",
        }
    }
}

/// The figures of one pose's run.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseRun {
    pub outcome: Outcome,
    /// S/S_fall of the run (0 for a failed run) [-]
    pub overload_ratio: f64,
    /// d: divert reserve \[m] ([`FAILED_MARGIN`] for a failed run)
    pub reserve: f64,
    /// The stroke's peak drive torque max |M_d| \[N·m] (0 for a failed run; `None` where
    /// not asked for).
    pub drive_torque: Option<f64>,
}

/// A pose's run with its peak drive torque at the larger of the mass band's ends (module
/// notes): (the run, with the torque there; that mass). The pose is at the band's top
/// mass; `lightest` = the pose's mass gives its own torque.
fn run_pose_torque(
    setting: &Scenario,
    pose: &Pose,
    profile: &StrokeProfile,
    lightest: f64,
) -> (PoseRun, f64) {
    let s = pose.scenario(setting);
    let r = simulate_verdict(&s);
    let mut run = pose_run(&s, &r);
    if matches!(r.outcome, Outcome::Failed(_)) {
        run.drive_torque = Some(0.0);
        return (run, pose.mass);
    }
    let heavy = r.arm_loads_with(&s, profile).peak_torque;
    let light = r
        .arm_loads_scaled(&s, profile, lightest / pose.mass)
        .peak_torque;
    let (t, m) = if light > heavy {
        (light, lightest)
    } else {
        (heavy, pose.mass)
    };
    run.drive_torque = Some(if t.is_finite() { t } else { 0.0 });
    (run, m)
}

/// Simulate a pose at a setting (verdict only).
pub fn run_pose(setting: &Scenario, pose: &Pose) -> PoseRun {
    let s = pose.scenario(setting);
    pose_run(&s, &simulate_verdict(&s))
}

/// The figures of a finished run.
pub fn pose_run(s: &Scenario, r: &SimResult) -> PoseRun {
    if matches!(r.outcome, Outcome::Failed(_)) {
        return PoseRun {
            outcome: r.outcome.clone(),
            overload_ratio: 0.0,
            reserve: FAILED_MARGIN,
            drive_torque: None,
        };
    }
    let ratio = r.overload.overload_ratio;
    PoseRun {
        outcome: r.outcome.clone(),
        overload_ratio: if ratio.is_finite() { ratio } else { 0.0 },
        reserve: divert_overshoot(s, r),
        drive_torque: None,
    }
}

/// Budget and seed of a search.
#[derive(Debug, Clone, PartialEq)]
pub struct SearchSettings {
    /// Total simulations, the refinement included (default 2,400).
    pub evaluations: usize,
    /// Independent DE runs (default 3).
    pub starts: usize,
    /// DE population (default 24).
    pub population: usize,
    /// Simulations of the local refinement (default 240).
    pub refinement: usize,
    /// Random seed (each start derives its own).
    pub seed: u64,
}

impl Default for SearchSettings {
    fn default() -> Self {
        SearchSettings {
            evaluations: 2400,
            starts: 3,
            population: 24,
            refinement: 240,
            seed: 1,
        }
    }
}

impl SearchSettings {
    /// The settings with the budget (and refinement) multiplied by `k` and another seed.
    pub fn scaled(&self, k: usize, seed: u64) -> SearchSettings {
        SearchSettings {
            evaluations: self.evaluations * k,
            refinement: self.refinement * k,
            seed,
            ..self.clone()
        }
    }

    /// Whether the settings can run: ≥ 1 start, a population ≥ 4, and a budget that holds
    /// the refinement plus one population per start.
    pub fn validate(&self) -> Result<(), OptimizeError> {
        let bad =
            |name: &'static str, reason: String| OptimizeError::InvalidSetting { name, reason };
        if self.starts == 0 {
            return Err(bad("starts", "must be ≥ 1".into()));
        }
        if self.population < 4 {
            return Err(bad("population", "must be ≥ 4".into()));
        }
        if self.evaluations < self.refinement + self.starts * self.population {
            return Err(bad(
                "evaluations",
                format!(
                    "{} is less than the refinement ({}) plus one population ({}) per start ({})",
                    self.evaluations, self.refinement, self.population, self.starts
                ),
            ));
        }
        Ok(())
    }
}

/// The worst case found.
#[derive(Debug, Clone, PartialEq)]
pub struct WorstCase {
    pub objective: WorstObjective,
    /// The worst pose.
    pub pose: Pose,
    /// Its run.
    pub run: PoseRun,
    /// The worst value: S/S_fall for [`WorstObjective::Impulse`], d \[m] for
    /// [`WorstObjective::Reserve`], the peak drive torque \[N·m] for
    /// [`WorstObjective::Torque`].
    pub value: f64,
    /// The best value of each DE start, before the refinement (their spread shows how
    /// rugged the landscape is).
    pub start_values: Vec<f64>,
    /// The best pose of each DE start.
    pub start_poses: Vec<Pose>,
    /// Simulations made.
    pub evaluations: usize,
    /// Runs that failed numerically (counted as harmless).
    pub failed_runs: usize,
    /// The search stopped at a pose beyond its limit ([`search_until`]): its value is a
    /// violation found, not the worst.
    pub stopped: bool,
}

/// The search as an optimisation problem: minimise −ratio or d over the pose vector, with
/// one constraint: the parcel fits on the belt.
struct PoseProblem<'a> {
    setting: &'a Scenario,
    pose_box: &'a PoseBox,
    bounds: Bounds,
    objective: WorstObjective,
    /// The setting's stroke profile, for the torque objective.
    profile: Option<StrokeProfile>,
    failed: AtomicUsize,
    progress: Progress<'a>,
    /// Stop at the first pose beyond this (in the minimised sign), if set.
    target: Option<f64>,
}

impl PoseProblem<'_> {
    fn value(&self, run: &PoseRun) -> f64 {
        match self.objective {
            WorstObjective::Impulse => -run.overload_ratio,
            WorstObjective::Reserve => run.reserve,
            WorstObjective::Torque => -run.drive_torque.unwrap_or(0.0),
        }
    }
}

impl Problem for PoseProblem<'_> {
    fn bounds(&self) -> &Bounds {
        &self.bounds
    }
    fn constraint_count(&self) -> usize {
        1
    }
    fn target(&self) -> Option<f64> {
        self.target
    }
    fn evaluate(&self, x: &[f64]) -> Evaluation {
        let (pose, too_wide) = pose_of(x, self.pose_box, self.setting.machine.belt_width);
        let f = if too_wide > 0.0 {
            0.0
        } else {
            let run = match &self.profile {
                Some(p) => run_pose_torque(self.setting, &pose, p, self.pose_box.mass.0).0,
                None => run_pose(self.setting, &pose),
            };
            if matches!(run.outcome, Outcome::Failed(_)) {
                self.failed.fetch_add(1, Ordering::Relaxed);
            }
            self.value(&run)
        };
        (self.progress)();
        Evaluation {
            objectives: vec![f],
            constraints: vec![too_wide.max(0.0)],
        }
    }
}

/// A seed for start `k` of a search seeded `seed` (SplitMix64 of both: distinct streams).
fn start_seed(seed: u64, k: u64) -> u64 {
    crate::stats::splitmix::mix(
        seed.wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add(k.wrapping_add(1).wrapping_mul(0xBF58_476D_1CE4_E5B9)),
    )
}

/// Search the pose box for the worst case of `objective` at the setting `setting` (a
/// scenario whose machine, materials and run are the setting; its parcel only lends its
/// height). `progress` is called once per simulation.
pub fn search(
    setting: &Scenario,
    pose_box: &PoseBox,
    objective: WorstObjective,
    settings: &SearchSettings,
    progress: Progress<'_>,
) -> Result<WorstCase, OptimizeError> {
    search_until(setting, pose_box, objective, settings, None, progress)
}

/// [`search`], stopped as soon as a pose beyond `limit` is found (a ratio or torque above
/// it, a reserve below it), where only feasibility is asked (issue 28): the DE start that
/// finds it ends with its generation, and the later starts and the refinement are not run.
/// The result's value is then that violating pose's, not the worst; a search that finds
/// no violation is [`search`]'s own, bit for bit. `None`: [`search`].
pub fn search_until(
    setting: &Scenario,
    pose_box: &PoseBox,
    objective: WorstObjective,
    settings: &SearchSettings,
    limit: Option<f64>,
    progress: Progress<'_>,
) -> Result<WorstCase, OptimizeError> {
    settings.validate()?;
    if let Some((key, msg)) = pose_box.problems().into_iter().next() {
        return Err(OptimizeError::InvalidSetting {
            name: key,
            reason: msg,
        });
    }
    let problem = PoseProblem {
        setting,
        pose_box,
        bounds: search_bounds(pose_box, setting)?,
        objective,
        profile: match objective {
            WorstObjective::Torque => Some(StrokeProfile::of(setting).ok_or(
                OptimizeError::InvalidSetting {
                    name: "run.arm",
                    reason: "the torque objective needs the arm (run.arm = true)".into(),
                },
            )?),
            _ => None,
        },
        failed: AtomicUsize::new(0),
        progress,
        target: limit.map(|l| sign(objective) * l),
    };
    let violates =
        |e: &Evaluation| e.feasible() && problem.target.is_some_and(|t| e.objectives[0] < t);
    let per_start = (settings.evaluations - settings.refinement) / settings.starts;
    let mut best: Option<(Vec<f64>, Evaluation)> = None;
    let mut start_values = Vec::with_capacity(settings.starts);
    let mut start_poses = Vec::with_capacity(settings.starts);
    let mut evaluations = 0;
    for k in 0..settings.starts {
        let de = DeSettings {
            population: settings.population,
            generations: per_start,
            polish: None,
            max_evaluations: Some(per_start),
            seed: start_seed(settings.seed, k as u64),
            ..DeSettings::default()
        };
        let r = de::solve(&problem, &de, &mut NoObserver)?;
        evaluations += r.evaluations;
        start_values.push(sign(objective) * r.best.objectives[0]);
        start_poses.push(pose_of(&r.best_x, pose_box, setting.machine.belt_width).0);
        if best
            .as_ref()
            .is_none_or(|(_, b)| crate::optimize::deb_cmp(&r.best, b).is_lt())
        {
            best = Some((r.best_x, r.best));
        }
        if best.as_ref().is_some_and(|(_, e)| violates(e)) {
            break;
        }
    }
    let (mut x, mut e) = best.expect("at least one start");
    if settings.refinement > 0 && !violates(&e) {
        let p = PatternSettings {
            start: Some(x.clone()),
            initial_step: 0.02,
            min_step: 1e-6,
            max_evaluations: settings.refinement,
        };
        let r = pattern::solve(&problem, &p, &mut NoObserver)?;
        evaluations += r.evaluations;
        if crate::optimize::deb_cmp(&r.best, &e).is_lt() {
            x = r.best_x;
            e = r.best;
        }
    }
    let (mut pose, too_wide) = pose_of(&x, pose_box, setting.machine.belt_width);
    if too_wide > 0.0 {
        return Err(OptimizeError::InvalidSetting {
            name: "width",
            reason: format!(
                "no parcel of the class fits on the {} m belt at any searched angle (the best found spans {:.4} m across it)",
                setting.machine.belt_width,
                setting.machine.belt_width + too_wide
            ),
        });
    }
    let stopped = violates(&e);
    let mut value = sign(objective) * e.objectives[0];
    let run = match &problem.profile {
        Some(p) => {
            // The worst pose states the mass its torque was found at, and its own run's
            // torque (the same to round-off) is the value a file of it reproduces.
            pose.mass = run_pose_torque(setting, &pose, p, pose_box.mass.0).1;
            let (run, _) = run_pose_torque(setting, &pose, p, pose.mass);
            value = run.drive_torque.unwrap_or(value);
            run
        }
        None => run_pose(setting, &pose),
    };
    Ok(WorstCase {
        objective,
        value,
        pose,
        run,
        start_values,
        start_poses,
        evaluations,
        failed_runs: problem.failed.load(Ordering::Relaxed),
        stopped,
    })
}

/// +1 or −1: the problem minimises −ratio for the impulse.
fn sign(objective: WorstObjective) -> f64 {
    match objective {
        WorstObjective::Impulse | WorstObjective::Torque => -1.0,
        WorstObjective::Reserve => 1.0,
    }
}

/// The scenario of a machine setting (v, t_c, R_s, S_d) on `base`, its parcel kept.
pub fn setting_scenario(base: &Scenario, point: &DesignPoint) -> Scenario {
    case_scenario(base, &base.parcel, point)
}

/// One speed of the searched overload curve.
#[derive(Debug, Clone, PartialEq)]
pub struct SearchedOverload {
    /// v [m/s]
    pub belt_speed: f64,
    /// R_s + v δt of the worst run: the parcel front when the arm starts \[m]
    pub start_position: f64,
    /// The worst impulse found.
    pub worst: WorstCase,
}

/// The searched worst impulse at each belt speed at the scenario's t_c, over every start
/// position R_s in `starts` = [R_lo, R_hi] \[m] (like the paper's definition, which strikes
/// with the arm tip wherever the parcel is): the setting starts at R_lo and the phase band
/// is widened by (R_hi − R_lo)/v, so the worst pose's R_s + v δt covers the range plus the
/// timing error. The speeds in turn, each search parallel inside; `progress` ticks once per
/// simulation.
pub fn searched_overload_curve(
    base: &Scenario,
    pose_box: &PoseBox,
    speeds: &[f64],
    starts: Band,
    settings: &SearchSettings,
    progress: Progress<'_>,
) -> Result<Vec<SearchedOverload>, OptimizeError> {
    speeds
        .iter()
        .map(|&v| {
            if !(v.is_finite() && v > 0.0) {
                return Err(OptimizeError::InvalidSetting {
                    name: "belt_speed",
                    reason: format!("{v} m/s: the search needs a moving belt (> 0)"),
                });
            }
            let mut setting = base.clone();
            setting.machine.belt_speed = v;
            setting.machine.start_at(starts.0);
            let mut b = pose_box.clone();
            b.phase.1 += (starts.1 - starts.0) / v;
            let worst = search(&setting, &b, WorstObjective::Impulse, settings, progress)?;
            Ok(SearchedOverload {
                belt_speed: v,
                start_position: worst.pose.scenario(&setting).machine.start_position,
                worst,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::test_support::{far_side_pose, paper_machine};
    use crate::model::belt_friction::FrictionCoefficient;
    use crate::model::params::Scenario;
    use crate::run::sweep::no_progress;

    fn paper_setting() -> Scenario {
        let mut s = paper_machine();
        s.machine.belt_speed = 2.0;
        s.machine.start_position = 0.0;
        s
    }

    /// Every pose of a search vector fits: b ≤ a, b in its band, ΔP + extent ≤ P_max; a
    /// vector at the far corner of the offset puts the parcel against the far edge.
    #[test]
    fn poses_of_search_vectors_fit_the_class_and_the_belt() {
        let bx = PoseBox::paper();
        let s = paper_setting();
        let b = search_bounds(&bx, &s).unwrap();
        let mut rng = 12345u64;
        let mut next = || {
            rng = start_seed(rng, 0);
            (rng >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..2000 {
            let x: Vec<f64> = (0..DIM)
                .map(|i| b.lower[i] + next() * (b.upper[i] - b.lower[i]))
                .collect();
            let (p, too_wide) = pose_of(&x, &bx, 0.7);
            assert!(too_wide <= 0.0, "{p:?}");
            assert!(
                p.width <= p.length && p.width >= 0.1 && p.width <= 0.26,
                "{p:?}"
            );
            let extent = extent_across(p.length, p.width, p.angle_deg.to_radians());
            assert!(p.offset >= 0.0 && p.offset + extent <= 0.7 + 1e-12, "{p:?}");
            assert_eq!(p.arm_friction, 0.38);
        }
        let mut x = b.lower.clone();
        x[0] = 0.4;
        x[1] = 1.0;
        x[4] = 1.0;
        let (p, _) = pose_of(&x, &bx, 0.7);
        assert!(
            (p.offset + extent_across(0.4, 0.26, p.angle_deg.to_radians()) - 0.7).abs() < 1e-12
        );
    }

    /// A class whose lengths start below its widths still gives b ≤ a.
    #[test]
    fn width_never_exceeds_length() {
        let bx = PoseBox {
            length: (0.05, 0.7),
            ..PoseBox::paper()
        };
        for (l, u) in [(0.05, 0.0), (0.05, 1.0), (0.15, 1.0), (0.5, 0.5)] {
            let x = [l, u, 15.0, 0.0, 0.5, 0.0, 1.0, 1.0, 0.3, 0.3];
            let (p, _) = pose_of(&x, &bx, 0.7);
            assert!(p.width <= p.length && p.width >= 0.1, "{p:?}");
        }
    }

    /// The pose's scenario moves the parcel front by v δt and scales v and μ_b.
    #[test]
    fn pose_scenario_applies_phase_and_scales() {
        let s = paper_setting();
        let p = Pose {
            length: 0.3,
            width: 0.2,
            mass: 4.0,
            angle_deg: 10.0,
            offset: 0.1,
            phase: 0.01,
            belt_speed_scale: 1.02,
            belt_friction_scale: 0.9,
            arm_friction: 0.2,
            restitution: 0.4,
            height: None,
        };
        let q = p.scenario(&s);
        assert_eq!(q.machine.belt_speed, 2.0 * 1.02);
        assert_eq!(q.machine.start_position, 0.0 + 2.04 * 0.01);
        assert_eq!(
            q.materials.belt_friction,
            FrictionCoefficient::Constant(0.5 * 0.9)
        );
        assert_eq!(q.parcel.angle, 10f64.to_radians());
        assert_eq!(
            (q.parcel.length, q.parcel.width, q.parcel.mass),
            (0.3, 0.2, 4.0)
        );
        assert_eq!(
            (q.materials.arm_friction, q.materials.restitution),
            (0.2, 0.4)
        );
        assert_eq!(q.machine.cycle_time, s.machine.cycle_time);
        assert_eq!(q.parcel.height, s.parcel.height);
        let tall = Pose {
            height: Some(0.37),
            ..p
        };
        assert_eq!(tall.scenario(&s).parcel.height, 0.37);
    }

    /// A height band adds the eleventh variable at the end, and the pose takes it; a box
    /// without one keeps ten (its random stream unchanged).
    #[test]
    fn a_height_band_is_the_eleventh_search_variable() {
        let s = paper_setting();
        let flat = PoseBox::paper();
        assert_eq!(search_bounds(&flat, &s).unwrap().lower.len(), DIM);
        let tall = PoseBox {
            height: Some((0.1, 0.4)),
            ..PoseBox::paper()
        };
        let b = search_bounds(&tall, &s).unwrap();
        assert_eq!((b.lower[DIM], b.upper[DIM]), (0.1, 0.4));
        let mut x = b.lower.clone();
        x[DIM] = 0.33;
        let (p, _) = pose_of(&x, &tall, 0.7);
        assert_eq!(p.height, Some(0.33));
        assert_eq!(p.scenario(&s).parcel.height, 0.33);
        assert_eq!(pose_of(&x[..DIM], &flat, 0.7).0.height, None);
        let bad = PoseBox {
            height: Some((0.0, 0.4)),
            ..PoseBox::paper()
        };
        assert_eq!(bad.problems()[0].0, "height");
    }

    /// A small search beats the paper's closed-form worst case at v = 2 m/s on the paper
    /// machine, and its pose reproduces the value exactly.
    #[test]
    fn a_small_search_beats_the_paper_definition_and_reproduces() {
        let s = paper_setting();
        let settings = SearchSettings {
            evaluations: 400,
            starts: 2,
            population: 16,
            refinement: 60,
            seed: 3,
        };
        let w = search(
            &s,
            &PoseBox::paper(),
            WorstObjective::Impulse,
            &settings,
            &no_progress,
        )
        .unwrap();
        let paper = crate::analysis::paper::overload::worst_case_overload(
            &s,
            &crate::analysis::design::design_set::DesignSet::paper(0.7).overload_parcel,
            s.machine.cycle_time,
            2.0,
        )
        .unwrap();
        assert!(w.value > paper.ratio, "{} vs {}", w.value, paper.ratio);
        assert!(w.evaluations <= 400);
        assert_eq!(w.start_values.len(), 2);
        assert!(w.start_values.iter().all(|v| *v <= w.value));
        let again = simulate_verdict(&w.pose.scenario(&s));
        assert_eq!(again.overload.overload_ratio, w.value);
        assert_eq!(w.run.overload_ratio, w.value);
    }

    /// Issue 28: a search for any violation stops at the generation that finds the first
    /// pose beyond the limit (a fraction of the budget, no later start, no refinement), and
    /// that pose's own run is beyond it; with a limit no pose reaches, the search is the
    /// whole search, bit for bit.
    #[test]
    fn a_search_until_a_limit_stops_at_the_first_violation() {
        let s = paper_setting();
        let settings = SearchSettings {
            evaluations: 400,
            starts: 2,
            population: 16,
            refinement: 60,
            seed: 3,
        };
        let until = |objective: WorstObjective, limit: Option<f64>| {
            search_until(
                &s,
                &PoseBox::paper(),
                objective,
                &settings,
                limit,
                &no_progress,
            )
            .unwrap()
        };
        let run = |limit: Option<f64>| until(WorstObjective::Impulse, limit);
        let whole = run(None);
        // Half the worst ratio: plenty of poses beyond it.
        let early = run(Some(0.5 * whole.value));
        assert!(early.value > 0.5 * whole.value, "{}", early.value);
        assert!(
            early.evaluations < whole.evaluations / 4,
            "{}",
            early.evaluations
        );
        assert_eq!(
            early.evaluations % settings.population,
            0,
            "whole generations"
        );
        assert_eq!(early.start_values.len(), 1, "no later start");
        assert!(early.stopped && !whole.stopped);
        assert_eq!(
            simulate_verdict(&early.pose.scenario(&s))
                .overload
                .overload_ratio,
            early.value
        );
        // Out of reach: nothing stops the search early.
        assert_eq!(run(Some(10.0 * whole.value)), whole);
        // The reserve stops below its limit, in the other sign.
        let reserve = |limit: Option<f64>| until(WorstObjective::Reserve, limit);
        let worst = reserve(None);
        // The first start's best is below this: the search ends within that start.
        let limit = worst.start_values[0] + 0.01;
        let r = reserve(Some(limit));
        assert!(r.value < limit && r.evaluations < worst.evaluations);
    }

    /// Issue 26: the torque search finds a stroke at least as hard on the drive as the
    /// paper's default parcel, and its pose gives that torque again.
    #[test]
    fn the_torque_search_finds_a_harder_stroke_and_reproduces_it() {
        let mut s = paper_setting();
        s.machine.arm_inertia = 2.0;
        let settings = SearchSettings {
            evaluations: 300,
            starts: 2,
            population: 12,
            refinement: 40,
            seed: 5,
        };
        let w = search(
            &s,
            &PoseBox::paper(),
            WorstObjective::Torque,
            &settings,
            &no_progress,
        )
        .unwrap();
        let mut default = s.clone();
        default.parcel = Scenario::paper_default().parcel;
        let plain = crate::sim::simulate(&default).arm_loads(&default).unwrap();
        assert!(
            w.value >= plain.peak_torque,
            "{} vs {}",
            w.value,
            plain.peak_torque
        );
        let again = w.pose.scenario(&s);
        let loads = crate::sim::simulate(&again).arm_loads(&again).unwrap();
        assert_eq!(loads.peak_torque, w.value);
        assert_eq!(w.run.drive_torque, Some(w.value));
        assert!(w.start_values.iter().all(|v| *v <= w.value * (1.0 + 1e-9)));
        // The pose states the mass its torque is at: an end of the band, and no mass of
        // the band (the same path, forces scaled) loads the drive more.
        let (lo, hi) = PoseBox::paper().mass;
        assert!(w.pose.mass == lo || w.pose.mass == hi, "{}", w.pose.mass);
        let profile = StrokeProfile::of(&again).unwrap();
        let r = crate::sim::simulate(&again);
        for k in 0..=10 {
            let m = lo + (hi - lo) * k as f64 / 10.0;
            let t = r
                .arm_loads_scaled(&again, &profile, m / w.pose.mass)
                .peak_torque;
            assert!(t <= w.value * (1.0 + 1e-9), "{m} kg: {t} > {}", w.value);
        }
        // Without the arm there is no torque to search.
        s.run.arm = false;
        assert!(search(
            &s,
            &PoseBox::paper(),
            WorstObjective::Torque,
            &settings,
            &no_progress
        )
        .is_err());
    }

    /// The ratio and the reserve do not depend on the mass (why the search fixes it).
    #[test]
    fn ratio_and_reserve_do_not_depend_on_the_mass() {
        let s = paper_setting();
        let p = far_side_pose();
        let heavy = run_pose(&s, &p);
        assert!(heavy.overload_ratio > 1.0, "{heavy:?}");
        for mass in [0.5, 3.0] {
            let light = run_pose(&s, &Pose { mass, ..p.clone() });
            assert!(
                (light.overload_ratio - heavy.overload_ratio).abs() <= 1e-12 * heavy.overload_ratio
            );
            assert!((light.reserve - heavy.reserve).abs() <= 1e-12 * heavy.reserve.abs());
            assert_eq!(light.outcome, heavy.outcome);
        }
    }

    /// The same seed gives the same worst case on one thread and on several.
    #[test]
    fn deterministic_across_threads() {
        let s = paper_setting();
        let settings = SearchSettings {
            evaluations: 120,
            starts: 2,
            population: 8,
            refinement: 20,
            seed: 9,
        };
        let run = || {
            search(
                &s,
                &PoseBox::paper(),
                WorstObjective::Reserve,
                &settings,
                &no_progress,
            )
            .unwrap()
        };
        let (one, many) = crate::run::sweep::one_and_many_threads(run);
        assert_eq!(many, one);
    }

    /// Scatter widens the phase by seconds and the speed and μ_b factors by fractions, and
    /// leaves the class alone.
    #[test]
    fn scatter_widens_the_box() {
        let b = PoseBox::paper().with_scatter(&Scatter {
            belt_speed: 0.02,
            phase: 0.01,
            belt_friction: 0.05,
        });
        assert_eq!(b.phase, (-0.02, 0.02));
        assert_eq!(b.belt_speed_scale, (0.98, 1.02));
        assert_eq!(b.belt_friction_scale, (0.95, 1.05));
        assert_eq!(
            (b.length, b.width, b.angle_deg),
            (
                PoseBox::paper().length,
                PoseBox::paper().width,
                PoseBox::paper().angle_deg
            )
        );
        assert!(b.problems().is_empty());
    }

    #[test]
    fn bad_boxes_and_budgets_are_errors() {
        let s = paper_setting();
        let mut bx = PoseBox::paper();
        bx.width = (0.8, 0.9);
        assert!(search(
            &s,
            &bx,
            WorstObjective::Impulse,
            &SearchSettings::default(),
            &no_progress
        )
        .is_err());
        let mut bx = PoseBox::paper();
        bx.length = (0.75, 0.8);
        bx.width = (0.72, 0.75);
        bx.angle_deg = (0.0, 0.0);
        let e = search(
            &s,
            &bx,
            WorstObjective::Impulse,
            &SearchSettings::default(),
            &no_progress,
        );
        assert!(
            format!("{e:?}").contains("no parcel of the class fits"),
            "{e:?}"
        );
        let mut bx = PoseBox::paper();
        bx.mass = (2.0, 1.0);
        assert_eq!(bx.problems()[0].0, "mass");
        let tiny = SearchSettings {
            evaluations: 10,
            ..SearchSettings::default()
        };
        assert!(search(
            &s,
            &PoseBox::paper(),
            WorstObjective::Impulse,
            &tiny,
            &no_progress
        )
        .is_err());
    }
}
