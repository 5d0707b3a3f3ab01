//! Settings that stay feasible against the searched worst case (issue 10): the standard
//! outer approximation of robust optimisation.
//!
//! The constraint "every parcel of the class, in every pose and arrival, is diverted and
//! struck no harder than the free fall" is a maximum over the pose box inside every
//! evaluation. Paying a full worst-case search ([`crate::analysis::design::worst_case`]) per candidate setting
//! is out of reach, so:
//!
//! 1. optimise (or map) against a finite worst-pose set `P` (empty at first) added to the
//!    design cases ([`DesignSet::worst_poses`]): each pose is one more simulated check with a
//!    divert and an overload constraint;
//! 2. at the result (the optimiser's incumbent; every feasible cell's chosen setting of a
//!    map), search the pose box for the largest impulse and the smallest divert reserve;
//! 3. if a searched pose violates a limit, add it (and the best violating pose of every
//!    search start) to `P` and repeat; otherwise (for an optimisation, once a confirmation
//!    search with a larger budget and another seed agrees) stop: the result is feasible
//!    against the search. The optimiser keeps a [`SLACK`] against `P` so that the rounds
//!    end: a longer search finds slightly worse neighbours of the bound poses.
//!
//! A map asks only whether each chosen setting holds, so its rounds spend less (issue 28):
//! a setting is first run against the poses this round has already found (a violated one
//! needs no search: the next map drops it), each search stops at its first violating pose
//! ([`screen`]), and a setting verified clean in an earlier round is not searched again
//! (the search does not depend on `P`). The last round, where no search finds a
//! violation, runs every search whole, as before. Each round's map also resumes the checks
//! the round before ran at the same settings ([`CheckCache`]): only the new poses are run,
//! at the settings that passed the old ones.
//!
//! The search explores the design set's [`PoseBox`](crate::analysis::design::worst_case::PoseBox), widened by a [`Scatter`] when the
//! setting must also hold under scatter of the belt speed, trigger phase and μ_b.
//!
//! Reference: A. Mutapcic, S. Boyd, "Cutting-set methods for robust convex optimization with
//! pessimizing oracles", Optim. Methods Softw. 24 (2009) 381–406; J. W. Blankenship,
//! J. E. Falk, "Infinitely constrained optimization problems", JOTA 19 (1976) 261–281.

use crate::analysis::design::capacity::{
    capacity_map_resumed, CapacityError, CapacityMap, CapacityOptions, CheckCache,
};
use crate::analysis::design::design_set::{DesignPoint, DesignSet};
use crate::analysis::design::settings_problem::{point_of, SettingsProblem};
use crate::analysis::design::worst_case::{
    search, search_until, setting_scenario, Pose, Scatter, SearchSettings, WorstCase,
    WorstObjective,
};
use crate::model::params::Scenario;
use crate::optimize::{OptimizeError, SolverResult};
use crate::run::memo::Memo;
use crate::run::sweep::Progress;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Slack the optimiser keeps against the worst-pose set [ratio for the overload, m for the
/// divert reserve]: it solves with both margins raised by this much, while a searched pose
/// violates as soon as it exceeds the user's limits. A worst pose bound at the optimum then
/// leaves room for the slightly worse neighbours a longer search finds, and the rounds stop.
pub const SLACK: f64 = 2e-3;

/// How the outer approximation runs.
#[derive(Debug, Clone, PartialEq)]
pub struct RobustSettings {
    /// The worst-case search at each verified setting.
    pub search: SearchSettings,
    /// Scatter the setting must hold under.
    pub scatter: Scatter,
    /// Largest number of rounds (default 16).
    pub max_rounds: usize,
    /// Budget multiplier of the confirmation search an optimisation runs, with another seed,
    /// before it calls a round final (default 4; 0: none).
    pub confirm: usize,
}

impl Default for RobustSettings {
    fn default() -> Self {
        RobustSettings {
            search: SearchSettings::default(),
            scatter: Scatter::default(),
            max_rounds: 16,
            confirm: 4,
        }
    }
}

/// The verification of one setting: the worst impulse and the worst reserve found there.
#[derive(Debug, Clone, PartialEq)]
pub struct Verification {
    pub point: DesignPoint,
    pub impulse: WorstCase,
    pub reserve: WorstCase,
    /// The largest peak drive torque, searched when the set has a torque limit.
    pub torque: Option<WorstCase>,
    /// The searched poses that violated a limit (added to the pose set).
    pub violating: Vec<Pose>,
}

impl Verification {
    /// S/S_fall found − the allowed ratio (≤ 0: no overload violation).
    pub fn overload_excess(&self, set: &DesignSet) -> f64 {
        self.impulse.value - set.margins.ratio_limit()
    }
    /// Required reserve − the reserve found (≤ 0: no divert violation) \[m].
    pub fn divert_shortfall(&self, set: &DesignSet) -> f64 {
        set.margins.divert - self.reserve.value
    }
    /// T/T_max − 1 for the largest torque found (≤ 0: within the limit; 0 without a
    /// limit).
    pub fn torque_excess(&self, set: &DesignSet) -> f64 {
        self.torque
            .as_ref()
            .map_or(0.0, |t| set.margins.torque_margin(Some(t.value)))
    }
}

/// Search both worst cases at a setting over the set's pose box (as it is: see
/// [`robust_set`] for the scatter) and collect the violating poses: the refined worst and
/// the best of every start that violates too (several bad parcel classes per round).
pub fn verify(
    base: &Scenario,
    set: &DesignSet,
    point: &DesignPoint,
    settings: &RobustSettings,
    progress: Progress<'_>,
) -> Result<Verification, OptimizeError> {
    let setting = setting_scenario(base, point);
    let pose_box = &set.search;
    let impulse = search(
        &setting,
        pose_box,
        WorstObjective::Impulse,
        &settings.search,
        progress,
    )?;
    let reserve = search(
        &setting,
        pose_box,
        WorstObjective::Reserve,
        &settings.search,
        progress,
    )?;
    let torque = match set.margins.drive_torque {
        None => None,
        Some(_) => Some(search(
            &setting,
            pose_box,
            WorstObjective::Torque,
            &settings.search,
            progress,
        )?),
    };
    let violating = violating_poses(set, [Some(&impulse), Some(&reserve), torque.as_ref()]);
    let v = Verification {
        point: *point,
        impulse,
        reserve,
        torque,
        violating,
    };
    Ok(v)
}

/// The searched poses beyond a limit: each search's result and the best of each of its
/// starts, in that order, without repeats.
fn violating_poses(set: &DesignSet, searches: [Option<&WorstCase>; 3]) -> Vec<Pose> {
    let mut violating: Vec<Pose> = Vec::new();
    for w in searches.into_iter().flatten() {
        let starts = w.start_poses.iter().zip(&w.start_values);
        for (p, &x) in std::iter::once((&w.pose, &w.value)).chain(starts) {
            if beyond(set, w.objective, x) && !violating.contains(p) {
                violating.push(p.clone());
            }
        }
    }
    violating
}

/// Whether a searched value violates its limit.
fn beyond(set: &DesignSet, objective: WorstObjective, x: f64) -> bool {
    match objective {
        WorstObjective::Impulse => x > set.margins.ratio_limit(),
        WorstObjective::Reserve => x < set.margins.divert,
        WorstObjective::Torque => set.margins.torque_margin(Some(x)) > 0.0,
    }
}

/// The limit a search for any violation of `objective` stops beyond (`None`: no limit set).
fn limit_of(set: &DesignSet, objective: WorstObjective) -> Option<f64> {
    match objective {
        WorstObjective::Impulse => Some(set.margins.ratio_limit()),
        WorstObjective::Reserve => Some(set.margins.divert),
        WorstObjective::Torque => set.margins.drive_torque,
    }
}

/// What a verification that asks only for feasibility found (see [`screen`]).
#[derive(Debug, Clone, PartialEq)]
pub enum Screening {
    /// No search found a violation: the whole verification, [`verify`]'s own bit for bit.
    Clean(Box<Verification>),
    /// A search found poses beyond a limit (it stopped there; later objectives were not
    /// searched).
    Violated {
        poses: Vec<Pose>,
        /// The searches made, in objective order, the last one violated (its value is the
        /// first violation found, not the worst).
        searches: Vec<WorstCase>,
        /// Simulations of the searches made.
        simulations: usize,
    },
}

/// [`verify`] where only feasibility is asked, as in the rounds of a map (issue 28): each
/// search stops at the first pose beyond its limit ([`search_until`]), and once one
/// objective is violated the next ones are not searched. A setting with no violation costs
/// what [`verify`] costs and gives its result; a violated one usually costs a few DE
/// generations instead of whole searches.
pub fn screen(
    base: &Scenario,
    set: &DesignSet,
    point: &DesignPoint,
    settings: &RobustSettings,
    progress: Progress<'_>,
) -> Result<Screening, OptimizeError> {
    let setting = setting_scenario(base, point);
    let mut searches: Vec<WorstCase> = Vec::new();
    // Searches `objective` and keeps it; the screening's end if it found a violation.
    let mut next = |objective: WorstObjective| -> Result<Option<Screening>, OptimizeError> {
        let w = search_until(
            &setting,
            &set.search,
            objective,
            &settings.search,
            limit_of(set, objective),
            progress,
        )?;
        // A search that stopped saw a violation, even where its pose's own run (the
        // torque's recomputed at the pose's mass) rounds back to the limit.
        let violated = w.stopped
            || beyond(set, objective, w.value)
            || w.start_values.iter().any(|&x| beyond(set, objective, x));
        searches.push(w);
        if !violated {
            return Ok(None);
        }
        let mut made = searches.iter();
        let poses = violating_poses(set, [made.next(), made.next(), made.next()]);
        Ok(Some(Screening::Violated {
            poses,
            simulations: searches.iter().map(|w| w.evaluations).sum(),
            searches: std::mem::take(&mut searches),
        }))
    };
    if let Some(v) = next(WorstObjective::Impulse)? {
        return Ok(v);
    }
    if let Some(v) = next(WorstObjective::Reserve)? {
        return Ok(v);
    }
    if set.margins.drive_torque.is_some() {
        if let Some(v) = next(WorstObjective::Torque)? {
            return Ok(v);
        }
    }
    let mut made = searches.into_iter();
    match (made.next(), made.next(), made.next()) {
        (Some(impulse), Some(reserve), torque) => Ok(Screening::Clean(Box::new(Verification {
            point: *point,
            impulse,
            reserve,
            torque,
            violating: Vec::new(),
        }))),
        _ => Err(OptimizeError::InvalidSetting {
            name: "search",
            reason: "the impulse and reserve searches did not both run".into(),
        }),
    }
}

/// Whether a setting passes every run of `poses` (each at its phases; stops at the first
/// failure), counting the simulations: the cheap test before a search, with the poses a
/// round has found so far.
fn passes_poses(
    base: &Scenario,
    set: &DesignSet,
    point: &DesignPoint,
    poses: &[Pose],
    simulations: &mut usize,
) -> bool {
    if poses.is_empty() {
        return true;
    }
    let only = DesignSet {
        cases: Vec::new(),
        worst_poses: poses.to_vec(),
        ..set.clone()
    };
    let profile = set.stroke_profile(base, point.cycle_time);
    crate::analysis::design::capacity::all_pass(base, &only, point, profile.as_ref(), simulations).0
}

/// Two poses of the same parcel class: every searched variable but the phase (which the
/// checks sample anyway) within [`SIMILAR`] of its band in the box.
pub fn similar(
    a: &Pose,
    b: &Pose,
    pose_box: &crate::analysis::design::worst_case::PoseBox,
) -> bool {
    let close = |x: f64, y: f64, band: (f64, f64)| {
        let w = band.1 - band.0;
        (x - y).abs() <= SIMILAR * if w > 0.0 { w } else { 1.0 }
    };
    let arm = pose_box.arm_friction.unwrap_or((0.0, 0.0));
    let e = pose_box.restitution.unwrap_or((0.0, 0.0));
    close(a.length, b.length, pose_box.length)
        && close(a.width, b.width, pose_box.width)
        && close(a.angle_deg, b.angle_deg, pose_box.angle_deg)
        && close(a.offset, b.offset, (0.0, 1.0))
        && close(
            a.belt_speed_scale,
            b.belt_speed_scale,
            pose_box.belt_speed_scale,
        )
        && close(
            a.belt_friction_scale,
            b.belt_friction_scale,
            pose_box.belt_friction_scale,
        )
        && close(a.arm_friction, b.arm_friction, arm)
        && close(a.restitution, b.restitution, e)
}

/// Mixed into the search seed of a confirmation search.
const CONFIRM_SEED: u64 = 0x5EED_C0FF_EE00_0001;

/// Fraction of a band within which two poses are the same class (see [`similar`]).
pub const SIMILAR: f64 = 0.02;

/// Add `new` poses to `into`, skipping one of the same class as a pose added in this round
/// (`round_start`.. of `into`). A pose like an *older* one is still added: the older one
/// did not stop the violation, so the round must not end on it.
fn add_distinct(
    into: &mut Vec<Pose>,
    round_start: usize,
    new: &[Pose],
    pose_box: &crate::analysis::design::worst_case::PoseBox,
) -> usize {
    let mut added = 0;
    for p in new {
        if into[round_start..].iter().any(|q| similar(p, q, pose_box)) || into.contains(p) {
            continue;
        }
        into.push(p.clone());
        added += 1;
    }
    added
}

/// The design set a robust run works on: its pose box widened by the scatter.
pub fn robust_set(set: &DesignSet, settings: &RobustSettings) -> DesignSet {
    let mut s = set.clone();
    s.search = set.search.with_scatter(&settings.scatter);
    s
}

/// One round of the outer approximation of an optimisation.
#[derive(Debug, Clone, PartialEq)]
pub struct OptimizeRound {
    /// Worst poses the round optimised against.
    pub poses: usize,
    /// The solver's result on that set.
    pub result: SolverResult,
    /// The search at its best point.
    pub verification: Verification,
}

/// The robust optimisation.
#[derive(Debug, Clone, PartialEq)]
pub struct RobustOptimum {
    pub rounds: Vec<OptimizeRound>,
    /// The design set with the final worst-pose set.
    pub set: DesignSet,
    /// The design set the last round's problem was solved on (its poses, margins + slack).
    pub solved: DesignSet,
    /// No searched pose violates a limit at the final result. False when the rounds ran
    /// out, or when the optimiser could not satisfy the poses already found (no setting in
    /// the bounds holds against them: the last result is infeasible on its pose set).
    pub converged: bool,
}

impl RobustOptimum {
    /// The last round (the reported optimum).
    pub fn last(&self) -> &OptimizeRound {
        self.rounds.last().expect("at least one round")
    }
}

/// Optimise with `solve` (any solver on the settings problem it is given) against a growing
/// worst-pose set (module notes). `make_problem` builds the problem for a design set (the
/// bounds and objectives are the caller's). `progress` ticks once per search simulation.
pub fn robust_optimize(
    base: &Scenario,
    set: &DesignSet,
    settings: &RobustSettings,
    make_problem: &dyn Fn(DesignSet) -> Result<SettingsProblem, OptimizeError>,
    solve: &mut dyn FnMut(&SettingsProblem) -> Result<SolverResult, OptimizeError>,
    progress: Progress<'_>,
) -> Result<RobustOptimum, OptimizeError> {
    let mut set = robust_set(set, settings);
    let mut rounds = Vec::new();
    loop {
        let mut solved = set.clone();
        solved.margins.overload += SLACK;
        solved.margins.divert += SLACK;
        // The torque limit is a ratio's denominator: the same slack on g = T/T_max − 1.
        solved.margins.drive_torque = solved.margins.drive_torque.map(|t| t / (1.0 + SLACK));
        let problem = make_problem(solved.clone())?;
        let result = solve(&problem)?;
        let point = point_of(&result.best_x);
        let mut verification = verify(base, &set, &point, settings, progress)?;
        if verification.violating.is_empty() && settings.confirm > 0 {
            // A longer search with another seed before the round may end the run.
            let confirm = RobustSettings {
                search: settings
                    .search
                    .scaled(settings.confirm, settings.search.seed ^ CONFIRM_SEED),
                ..settings.clone()
            };
            verification = verify(base, &set, &point, &confirm, progress)?;
        }
        let poses = set.worst_poses.len();
        let added = add_distinct(
            &mut set.worst_poses,
            poses,
            &verification.violating,
            &set.search,
        );
        let clean = verification.violating.is_empty();
        rounds.push(OptimizeRound {
            poses,
            result,
            verification,
        });
        // Either the search finds nothing (converged), or it finds only poses the set
        // already holds: the optimiser could not satisfy them (no setting in the bounds
        // holds against them), and another round would change nothing; or the rounds ran
        // out.
        if clean || added == 0 || rounds.len() >= settings.max_rounds.max(1) {
            return Ok(RobustOptimum {
                rounds,
                set,
                solved,
                converged: clean,
            });
        }
    }
}

/// One round of the outer approximation of a capacity map.
#[derive(Debug, Clone, PartialEq)]
pub struct MapRound {
    /// Worst poses the map was computed against.
    pub poses: usize,
    /// Distinct settings verified.
    pub verified: usize,
    /// Of those, the settings searched: the others were verified clean in an earlier round
    /// (a search does not depend on the pose set) or fail a pose this round found before
    /// reaching them.
    pub searched: usize,
    /// Poses added after this round.
    pub added: usize,
    /// Simulations of the map and of the searches.
    pub simulations: usize,
}

/// The capacity map against the searched worst case.
#[derive(Debug, Clone, PartialEq)]
pub struct RobustMap {
    pub map: CapacityMap,
    pub rounds: Vec<MapRound>,
    /// The design set with the final worst-pose set.
    pub set: DesignSet,
    /// The last round's verifications that found no violation: when converged, one per
    /// distinct chosen setting.
    pub verifications: Vec<Verification>,
    /// The last round's searches that found a violation (empty when converged): each
    /// setting's searches as made, stopped at the first violating pose.
    pub violations: Vec<(DesignPoint, Vec<WorstCase>)>,
    pub converged: bool,
}

/// Why a robust map failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RobustMapError {
    #[error("{0}")]
    Capacity(#[from] CapacityError),
    #[error("{0}")]
    Search(#[from] OptimizeError),
}

/// The distinct settings a map chose, in cell order (S_d does not change a run).
fn chosen_settings(map: &CapacityMap) -> Vec<DesignPoint> {
    let mut points: Vec<DesignPoint> = Vec::new();
    for c in map.cells.iter().filter(|c| c.feasible) {
        let (Some(v), Some(r)) = (c.belt_speed, c.start_position) else {
            continue;
        };
        let p = DesignPoint {
            belt_speed: v,
            cycle_time: c.cycle_time,
            start_position: r,
            light_barrier: r,
        };
        if !points.contains(&p) {
            points.push(p);
        }
    }
    points
}

/// The capacity map, re-computed until the worst-case search finds no violating pose at any
/// feasible cell's chosen setting (module notes). `progress` ticks once per finished piece
/// of each round's map (see [`crate::analysis::design::capacity::pieces`]) and once per search simulation;
/// `announce(n)` says, before each phase after the first round's map, how many ticks it
/// brings (a progress bar's length grows with it). The maps keep their pieces in `memo`
/// (see [`crate::analysis::design::capacity::capacity_map_kept`]); the searches are run again on a resume.
pub fn robust_capacity_map(
    base: &Scenario,
    set: &DesignSet,
    options: &CapacityOptions,
    settings: &RobustSettings,
    progress: Progress<'_>,
    announce: &(dyn Fn(u64) + Sync),
    memo: &dyn Memo,
) -> Result<RobustMap, RobustMapError> {
    let mut set = robust_set(set, settings);
    let mut rounds = Vec::new();
    // Settings verified clean in earlier rounds: the search does not depend on the pose
    // set, so their verification holds as it is.
    let mut clean: Vec<Verification> = Vec::new();
    // The checks each round's map ran, for the next round's map.
    let mut checks = CheckCache::default();
    let searches = if set.margins.drive_torque.is_some() {
        3
    } else {
        2
    };
    let budget = searches * settings.search.evaluations;
    loop {
        if !rounds.is_empty() {
            announce(crate::analysis::design::capacity::pieces(options) as u64);
        }
        let map = capacity_map_resumed(base, &set, options, progress, memo, Some(&mut checks))?;
        let points = chosen_settings(&map);
        announce((points.len() * budget) as u64);
        let mut verifications = Vec::with_capacity(points.len());
        let mut poses = set.worst_poses.clone();
        let before = poses.len();
        let (mut search_sims, mut searched, mut violated) = (0, 0, 0);
        let mut violations = Vec::new();
        for p in &points {
            // Ticks the searches' budget whole, whatever they spent (progress's length).
            let ticks = AtomicUsize::new(0);
            let counted = || {
                ticks.fetch_add(1, Ordering::Relaxed);
                progress()
            };
            if let Some(v) = clean.iter().find(|v| v.point == *p) {
                verifications.push(v.clone());
            } else if !passes_poses(base, &set, p, &poses[before..], &mut search_sims) {
                // A pose of this round defeats it: the next map drops it without a search.
                violated += 1;
            } else {
                searched += 1;
                match screen(base, &set, p, settings, &counted)? {
                    Screening::Clean(v) => {
                        search_sims += v.impulse.evaluations
                            + v.reserve.evaluations
                            + v.torque.as_ref().map_or(0, |t| t.evaluations);
                        clean.push((*v).clone());
                        verifications.push(*v);
                    }
                    Screening::Violated {
                        poses: found,
                        searches,
                        simulations,
                    } => {
                        search_sims += simulations;
                        violations.push((*p, searches));
                        violated += 1;
                        add_distinct(&mut poses, before, &found, &set.search);
                    }
                }
            }
            for _ in ticks.into_inner()..budget {
                progress();
            }
        }
        let added = poses.split_off(before);
        rounds.push(MapRound {
            poses: set.worst_poses.len(),
            verified: points.len(),
            searched,
            added: added.len(),
            simulations: map.simulations + search_sims,
        });
        let done = violated == 0;
        // No new pose (only exact repeats): another round would give the same map.
        if done || added.is_empty() || rounds.len() >= settings.max_rounds.max(1) {
            return Ok(RobustMap {
                map,
                rounds,
                set,
                verifications,
                violations,
                converged: done,
            });
        }
        set.worst_poses.extend(added);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::design::capacity::capacity_map_kept;
    use crate::analysis::design::design_set::WorstDefinition;
    use crate::analysis::design::settings_problem::Objectives;
    use crate::analysis::design::worst_case::PoseBox;
    use crate::analysis::test_support::{far_side_pose, paper_machine};
    use crate::optimize::de::{self, DeSettings};
    use crate::optimize::{Bounds, NoObserver};

    fn paper() -> (Scenario, DesignSet) {
        let s = paper_machine();
        let mut set = DesignSet::paper(0.7);
        set.worst = WorstDefinition::Search;
        (s, set)
    }

    fn small_settings() -> RobustSettings {
        RobustSettings {
            search: SearchSettings {
                evaluations: 200,
                starts: 2,
                population: 8,
                refinement: 20,
                seed: 5,
            },
            scatter: Scatter::default(),
            max_rounds: 3,
            confirm: 1,
        }
    }

    fn optimise(base: &Scenario, set: &DesignSet) -> RobustOptimum {
        let bounds = Bounds::new(vec![1.0, 1.0, 0.0, 0.0], vec![2.3, 1.5, 0.9, 0.0]).unwrap();
        let make = |set: DesignSet| {
            SettingsProblem::new(base.clone(), set, bounds.clone(), Objectives::Capacity)
        };
        let de = DeSettings {
            population: 8,
            generations: 2,
            polish: None,
            seed: 3,
            ..DeSettings::default()
        };
        let mut solve = |p: &SettingsProblem| de::solve(p, &de, &mut NoObserver);
        robust_optimize(base, set, &small_settings(), &make, &mut solve, &|| {}).unwrap()
    }

    /// The rounds, poses and optimum are bitwise the same on one thread and on several; each
    /// round optimises against every pose found before it, and a round that adds no pose
    /// ends the run.
    #[test]
    fn robust_optimisation_is_deterministic_and_grows_the_pose_set() {
        let (base, set) = paper();
        let (one, many) = crate::run::sweep::one_and_many_threads(|| optimise(&base, &set));
        assert_eq!(many, one);
        // Each round optimises against every earlier pose: the counts never fall, and a
        // round that added poses had a violating search.
        for w in many.rounds.windows(2) {
            assert!(w[1].poses > w[0].poses);
            assert!(!w[0].verification.violating.is_empty());
        }
        let last = many.rounds.last().unwrap();
        if many.converged {
            assert_eq!(many.set.worst_poses.len(), last.poses);
        } else {
            assert_eq!(many.rounds.len(), 3);
            assert!(many.set.worst_poses.len() > last.poses);
        }
        // The last problem carries the slack.
        assert_eq!(many.solved.margins.overload, SLACK);
        assert_eq!(many.solved.margins.divert, SLACK);
    }

    /// A violating pose is added even when it is like an older one (the older one did not
    /// stop the violation); within a round, one pose per class.
    #[test]
    fn distinct_poses_within_a_round_only() {
        let b = PoseBox::paper();
        let p = far_side_pose();
        let near = Pose {
            angle_deg: -8.5,
            phase: -0.01,
            ..p.clone()
        };
        let far = Pose {
            angle_deg: -20.0,
            ..p.clone()
        };
        assert!(similar(&p, &near, &b));
        assert!(!similar(&p, &far, &b));
        let mut v = vec![p.clone()];
        assert_eq!(
            add_distinct(&mut v, 1, &[near.clone(), far.clone(), near.clone()], &b),
            2
        );
        assert_eq!(v, vec![p.clone(), near.clone(), far.clone()]);
        assert_eq!(
            add_distinct(&mut v, 3, std::slice::from_ref(&p), &b),
            0,
            "already there"
        );
    }

    /// [`robust_capacity_map`] without progress or memo.
    fn quiet_map(
        base: &Scenario,
        set: &DesignSet,
        options: &CapacityOptions,
        settings: &RobustSettings,
    ) -> RobustMap {
        robust_capacity_map(
            base,
            set,
            options,
            settings,
            &|| {},
            &|_| {},
            &crate::run::memo::NoMemo,
        )
        .unwrap()
    }

    /// The rounds of a map as they ran before issue 28: every chosen setting searched whole
    /// ([`verify`]) in every round.
    fn map_searching_every_setting(
        base: &Scenario,
        set: &DesignSet,
        options: &CapacityOptions,
        settings: &RobustSettings,
    ) -> (CapacityMap, usize) {
        let mut set = robust_set(set, settings);
        let mut searches = 0;
        loop {
            let map =
                capacity_map_kept(base, &set, options, &|| {}, &crate::run::memo::NoMemo).unwrap();
            searches += map.simulations;
            let mut poses = set.worst_poses.clone();
            let before = poses.len();
            let mut clean = true;
            for p in chosen_settings(&map) {
                let v = verify(base, &set, &p, settings, &|| {}).unwrap();
                searches += v.impulse.evaluations + v.reserve.evaluations;
                clean &= v.violating.is_empty();
                add_distinct(&mut poses, before, &v.violating, &set.search);
            }
            let added = poses.split_off(before);
            if clean || added.is_empty() {
                return (map, searches);
            }
            set.worst_poses.extend(added);
        }
    }

    /// Issue 28: a clean setting's screening is its whole verification, bit for bit; a
    /// violated one stops early with poses that do violate.
    #[test]
    fn screening_a_clean_setting_is_its_whole_verification() {
        let (base, set) = paper();
        let settings = small_settings();
        let gentle = DesignPoint {
            belt_speed: 1.0,
            cycle_time: 1.5,
            start_position: 0.65,
            light_barrier: 0.65,
        };
        let whole = verify(&base, &set, &gentle, &settings, &|| {}).unwrap();
        assert!(whole.violating.is_empty(), "{:?}", whole.violating);
        assert_eq!(
            screen(&base, &set, &gentle, &settings, &|| {}).unwrap(),
            Screening::Clean(Box::new(whole))
        );
        let hard = DesignPoint {
            belt_speed: 2.3,
            cycle_time: 1.0,
            start_position: 0.0,
            light_barrier: 0.0,
        };
        let whole = verify(&base, &set, &hard, &settings, &|| {}).unwrap();
        let Screening::Violated {
            poses, simulations, ..
        } = screen(&base, &set, &hard, &settings, &|| {}).unwrap()
        else {
            panic!("the hard setting holds");
        };
        assert!(simulations < whole.impulse.evaluations + whole.reserve.evaluations);
        let setting = setting_scenario(&base, &hard);
        for p in &poses {
            let r = crate::analysis::design::worst_case::run_pose(&setting, p);
            assert!(
                r.overload_ratio > set.margins.ratio_limit() || r.reserve < set.margins.divert,
                "{p:?}: {r:?}"
            );
        }
    }

    /// Issue 28: the screened rounds (pose checks before a search, searches stopped at the
    /// first violation, clean settings not searched again) give the map of the rounds that
    /// search every chosen setting whole, in fewer simulations.
    #[test]
    fn screened_rounds_keep_the_map_of_whole_searches() {
        let (base, set) = paper();
        let options = CapacityOptions {
            cycle_times: vec![1.2, 1.5],
            light_barriers: vec![0.1, 0.4, 0.7],
            belt_speeds: vec![1.0, 1.5, 2.0],
            start_min: 0.0,
            start_max: 0.9,
            start_step: 0.1,
            start_tolerance: 0.02,
        };
        let mut settings = small_settings();
        settings.max_rounds = 16;
        let (reference, simulations) =
            map_searching_every_setting(&base, &set, &options, &settings);
        let r = quiet_map(&base, &set, &options, &settings);
        assert!(r.converged, "{:?}", r.rounds);
        let key = |m: &CapacityMap| {
            m.cells
                .iter()
                .map(|c| (c.feasible, c.capacity, c.belt_speed, c.start_position))
                .collect::<Vec<_>>()
        };
        assert_eq!(key(&r.map), key(&reference));
        assert!(reference.cells.iter().any(|c| c.feasible));
        assert!(reference.cells.iter().any(|c| !c.feasible));
        let screened: usize = r.rounds.iter().map(|m| m.simulations).sum();
        assert!(screened < simulations, "{screened} vs {simulations}");
    }

    /// On a tiny grid the robust map converges: at every feasible cell's setting the last
    /// round's search finds no pose beyond the limits.
    #[test]
    fn robust_map_converges_on_a_tiny_grid() {
        let (base, set) = paper();
        let options = CapacityOptions {
            cycle_times: vec![1.5],
            light_barriers: vec![0.4],
            belt_speeds: vec![1.0, 1.2],
            start_min: 0.4,
            start_max: 0.9,
            start_step: 0.1,
            start_tolerance: 0.02,
        };
        let mut settings = small_settings();
        settings.max_rounds = 6;
        let r = quiet_map(&base, &set, &options, &settings);
        assert!(r.converged, "{:?}", r.rounds);
        assert_eq!(r.rounds.last().unwrap().added, 0);
        for v in &r.verifications {
            assert!(v.violating.is_empty());
            assert!(v.impulse.value <= 1.0 && v.reserve.value >= 0.0, "{v:?}");
        }
    }
}
