//! The design set and one design evaluation (paper §4.2–4.3): the limiting parcels in their
//! worst poses, the worst-case overload parcel, and for a machine setting (v, t_c, R_s, S_d)
//! the capacity W, the divert verdict and margin of every design case, the worst-case
//! overload and its margin. Shared by `divertsim capacity` and the optimiser.
//!
//! **Capacity** (paper line 67: "during the scraper's working cycle t_c there is only one
//! package within the working area – the boundary of the scraper reaction area is determined
//! by the position of the light barrier S_d"): a parcel front passes the light barrier S_d,
//! rides (R_s − S_d)/v to the start position R_s, where the arm starts its cycle t_c; the next
//! parcel may pass the barrier when the cycle ends, so
//!
//!   W = 3600 / ((R_s − S_d)/v + t_c)  [parcels/h].
//!
//! No refinement (such as a minimum gap between parcels) is added: this is the paper's
//! formula. v ≤ 0 gives W = 0 (no parcel arrives).
//!
//! **Margins** (continuous, ≤ 0 feasible, never NaN), for constraint-handling optimisers:
//! - divert, per case: g = P_max − max_lateral \[m]. A diverted run ends when the centre
//!   crosses P_max, so g = 0 there (clamped to ≤ 0 against rounding); a parcel left on the belt
//!   has g > 0 (at least [`MIN_MISS_MARGIN`]); a failed run gets [`FAILED_MARGIN`].
//! - overload: g = S/S_fall − 1 for the worst case of [`crate::analysis::paper::overload`]; [`FAILED_MARGIN`]
//!   if it cannot be computed.
//! - barrier order: g = S_d − R_s \[m] (the light barrier must not lie downstream of R_s).
//!
//! `feasible` = every case diverted, overload margin ≤ 0 and S_d ≤ R_s.
//!
//! **Design set of the paper** ([`DesignSet::paper`]), all parallel to the belt (φ = 0) and
//! riding with it:
//! - "smallest" 0.2 × 0.1 × 0.1 m, 0.5 kg, farthest from the pivot, ΔP = P_max − 0.1 m: the
//!   hardest to catch (the arm's reach is shortest relative to the parcel there, paper Fig. 5);
//! - "slender" 0.7 × 0.1 × 0.1 m, 1.5 kg, nearest, ΔP = 0: the hardest to push across (it
//!   must travel the whole belt, and it turns on the arm, paper Fig. 13a);
//! - "compact" 0.4 × 0.26 × 0.15 m, 3 kg, nearest, ΔP = 0. The compact parcel is *not* also
//!   taken at the far edge: there its centre is only 0.13 m from P_max and its 0.26 m width
//!   reaches down to y = P_max − 0.26 m, so the arm catches it earlier and nearer the pivot than
//!   the smallest parcel at the same edge. Checked on the built-in machine when this set was
//!   chosen: `divertsim capacity` (default 20 × 20 grid, 20 × 14 (t_c, v) settings, R_s grid
//!   0–0.9 m every 0.05 m, 5 mm bisection) with a fourth case "compact, far" gave the same
//!   feasible R_s intervals at all 280 settings and the same capacity map (only the margins
//!   of infeasible cells changed), for 24 541 instead of 18 635 simulations;
//! - overload parcel: the compact size with the worst-case mass 15 kg.
//!
//! Masses: docs/model.md §1.

use crate::analysis::design::pose::{Pose, PoseBox};
use crate::analysis::paper::overload::{worst_case_overload, WorstCaseOverload};
use crate::model::params::{default_duration, Parcel, Scenario};
use crate::run::sweep::{no_progress, par_map, Progress};
use crate::sim::arm_loads::StrokeProfile;
use crate::sim::{simulate_verdict, Outcome, SimResult};

/// Margin given to a constraint whose run or computation failed: larger than any physical
/// margin (metres or ratios of order one), finite so that penalty functions stay finite.
pub const FAILED_MARGIN: f64 = 1.0e3;
/// Smallest divert margin of a parcel that was not diverted \[m] (keeps g > 0 strictly).
pub const MIN_MISS_MARGIN: f64 = 1.0e-9;

/// One limiting parcel in its pose.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignCase {
    /// A short name for tables ("smallest", "slender", ...).
    pub name: String,
    /// The parcel, pose included (ΔP = offset, φ = angle); `velocity: None` rides with the
    /// belt.
    pub parcel: Parcel,
}

/// The parcels every setting must divert, and the worst-case overload parcel.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignSet {
    pub cases: Vec<DesignCase>,
    /// The parcel of the worst-case strike (its pose is not used, see
    /// [`crate::analysis::paper::overload`]).
    pub overload_parcel: Parcel,
    /// The parcel class and arrival scatter the worst-case search explores
    /// ([`crate::analysis::design::worst_case`]).
    pub search: PoseBox,
    /// Which worst case the overload constraint uses.
    pub worst: WorstDefinition,
    /// Worst poses found by searches (the outer approximation of [`crate::analysis::design::robust`]): each
    /// must be diverted and stay below the overload limit at every setting, like a case.
    pub worst_poses: Vec<Pose>,
    /// Safety margins on the constraints.
    pub margins: Margins,
}

/// The definition of the worst-case overload (issue 10).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WorstDefinition {
    /// The paper's closed-form strike ([`crate::analysis::paper::overload`]).
    Paper,
    /// The largest simulated S/S_fall over the design cases and the worst poses.
    Search,
}

impl WorstDefinition {
    /// The name the CLI uses.
    pub fn label(self) -> &'static str {
        match self {
            WorstDefinition::Paper => "paper",
            WorstDefinition::Search => "search",
        }
    }
}

pub use crate::model::trigger::Margins;

impl Margins {
    /// The largest allowed overload ratio.
    pub fn ratio_limit(&self) -> f64 {
        1.0 - self.overload
    }

    /// g = T/T_max − 1 for a run's peak drive torque T (≤ 0 allowed; a ratio, like the
    /// overload margin); 0 without a limit, [`FAILED_MARGIN`] for a torque that could not
    /// be computed (`None`, or not finite).
    pub fn torque_margin(&self, peak: Option<f64>) -> f64 {
        match self.drive_torque {
            None => 0.0,
            Some(limit) => {
                let g = peak.map_or(f64::NAN, |t| t / limit - 1.0);
                if g.is_finite() {
                    g
                } else {
                    FAILED_MARGIN
                }
            }
        }
    }
}

/// A machine setting: the decision variables of paper §4.2–4.3.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DesignPoint {
    /// v: belt speed [m/s]
    pub belt_speed: f64,
    /// t_c: arm working cycle \[s]
    pub cycle_time: f64,
    /// R_s: parcel front x when the arm starts \[m]
    pub start_position: f64,
    /// S_d: light barrier x \[m]
    pub light_barrier: f64,
}

/// One design case run at one setting.
#[derive(Debug, Clone, PartialEq)]
pub struct CaseEvaluation {
    pub name: String,
    pub outcome: Outcome,
    /// Largest y of the centre \[m].
    pub max_lateral: f64,
    /// g = P_max − max_lateral \[m], ≤ 0 when diverted (see the module notes).
    pub margin: f64,
    /// d: divert overshoot \[m], ≥ 0 iff diverted (see [`divert_overshoot`]): for a diverted
    /// case the lateral distance the centre would still slide beyond P_max, v_y²/(2 μ_b g);
    /// otherwise −(P_max − max_lateral); −[`FAILED_MARGIN`] for a failed run.
    pub overshoot: f64,
    /// S/S_fall of the run's largest strike (0 for a failed run) [-]
    pub overload_ratio: f64,
    /// The stroke's peak drive torque max |M_d| \[N·m]; `None` when no torque limit asked
    /// for it or the run failed.
    pub drive_torque: Option<f64>,
}

impl CaseEvaluation {
    /// Diverted with at least the required reserve.
    pub fn passes_divert(&self, margins: &Margins) -> bool {
        self.outcome == Outcome::Diverted && self.overshoot >= margins.divert
    }

    /// Within the drive-torque limit (always, without one).
    pub fn passes_torque(&self, margins: &Margins) -> bool {
        margins.torque_margin(self.drive_torque) <= 0.0
    }
}

/// Everything about one setting.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignEvaluation {
    pub point: DesignPoint,
    /// W: capacity [parcels/h]
    pub capacity: f64,
    /// The design cases, in the set's order.
    pub cases: Vec<CaseEvaluation>,
    /// The paper's worst-case strike, or why it could not be computed (reported with either
    /// definition).
    pub overload: Result<WorstCaseOverload, String>,
    /// The worst case the overload constraint uses.
    pub worst: WorstDefinition,
    /// The overload ratio the constraint uses: the paper's strike, or the largest simulated
    /// S/S_fall over the cases and worst poses [-]
    pub overload_ratio: f64,
    /// g = S/S_fall − (1 − margin) (≤ 0 allowed); [`FAILED_MARGIN`] if the overload failed.
    pub overload_margin: f64,
    /// g = S_d − R_s \[m] (≤ 0 allowed).
    pub barrier_margin: f64,
    /// The largest peak drive torque over the checks \[N·m] (`None` without a torque limit,
    /// or when a check's run failed).
    pub drive_torque: Option<f64>,
    /// g = T/T_max − 1 for that torque (0 without a limit).
    pub torque_margin: f64,
    /// Every case diverted, overload allowed, S_d ≤ R_s, the drive torque within its limit.
    pub feasible: bool,
}

impl DesignSet {
    /// The paper's limiting parcels in their worst poses for a belt of width P_max \[m] (see
    /// the module notes).
    pub fn paper(belt_width: f64) -> DesignSet {
        let parcel = |length: f64, width: f64, height: f64, mass: f64, offset: f64| {
            Parcel::riding(length, width, height, mass, offset, 0.0)
        };
        DesignSet {
            cases: vec![
                DesignCase {
                    name: "smallest".into(),
                    parcel: parcel(0.2, 0.1, 0.1, 0.5, belt_width - 0.1),
                },
                DesignCase {
                    name: "slender".into(),
                    parcel: parcel(0.7, 0.1, 0.1, 1.5, 0.0),
                },
                DesignCase {
                    name: "compact".into(),
                    parcel: parcel(0.4, 0.26, 0.15, 3.0, 0.0),
                },
            ],
            overload_parcel: parcel(0.4, 0.26, 0.15, 15.0, 0.0),
            search: PoseBox::paper(),
            worst: WorstDefinition::Paper,
            worst_poses: Vec::new(),
            margins: Margins::default(),
        }
    }

    /// Every run a setting must pass, as (check index, name, scenario): the design cases,
    /// then each worst pose (named `worst1`, `worst2`, …) at its own phase and at
    /// [`PHASE_SAMPLES`] phases spread over the search box's phase band, all under the same
    /// check index. A pose found at one setting is a bad parcel *class* (size, angle,
    /// offset); sampling its arrival keeps a small change of R_s from dodging it, so the
    /// outer approximation of [`crate::analysis::design::robust`] converges in few rounds.
    pub fn checks(&self, base: &Scenario, point: &DesignPoint) -> Vec<(usize, String, Scenario)> {
        self.checks_from(base, point, 0).collect()
    }

    /// [`DesignSet::checks`] from the `from`-th on, one at a time, each scenario built only
    /// when it is reached: a loop that stops at the first failure, or skips the runs it
    /// already knows, builds no more (issue 28).
    pub fn checks_from<'a>(
        &'a self,
        base: &'a Scenario,
        point: &'a DesignPoint,
        from: usize,
    ) -> impl Iterator<Item = (usize, String, Scenario)> + 'a {
        // What each check is (a case, or a pose at a phase), cheap to list and to skip.
        let cases = (0..self.cases.len()).map(|i| (i, None));
        let poses = self.worst_poses.iter().enumerate().flat_map(move |(k, p)| {
            self.pose_phases(p)
                .into_iter()
                .map(move |phase| (self.cases.len() + k, Some((k, phase))))
        });
        let setting = std::cell::OnceCell::new();
        cases
            .chain(poses)
            .skip(from)
            .map(move |(i, pose)| match pose {
                None => {
                    let c = &self.cases[i];
                    (i, c.name.clone(), case_scenario(base, &c.parcel, point))
                }
                Some((k, phase)) => {
                    let setting = setting.get_or_init(|| case_scenario(base, &base.parcel, point));
                    let q = Pose {
                        phase,
                        ..self.worst_poses[k].clone()
                    };
                    (i, format!("worst{}", k + 1), q.scenario(setting))
                }
            })
    }

    /// The phases a worst pose is run at: its own, then [`PHASE_SAMPLES`] spread over the
    /// search box's phase band (those equal to its own left out).
    fn pose_phases(&self, p: &Pose) -> Vec<f64> {
        let (lo, hi) = self.search.phase;
        let mut phases = vec![p.phase];
        if hi > lo {
            phases.extend(
                (0..PHASE_SAMPLES)
                    .map(|j| {
                        let t = j as f64 / (PHASE_SAMPLES - 1) as f64;
                        (1.0 - t) * lo + t * hi
                    })
                    .filter(|&phase| phase != p.phase),
            );
        }
        phases
    }

    /// Number of runs [`DesignSet::checks`] gives at any setting.
    pub fn run_count(&self) -> usize {
        self.cases.len()
            + self
                .worst_poses
                .iter()
                .map(|p| self.pose_phases(p).len())
                .sum::<usize>()
    }

    /// The arm's stroke profile at cycle time `cycle_time` when a drive-torque limit asks
    /// for the runs' torques (`None` otherwise, or without an arm): built once for all the
    /// runs of one t_c.
    pub fn stroke_profile(&self, base: &Scenario, cycle_time: f64) -> Option<StrokeProfile> {
        self.margins.drive_torque?;
        let mut s = base.clone();
        s.machine.cycle_time = cycle_time;
        StrokeProfile::of(&s)
    }

    /// Number of checks (design cases + worst poses): the constraints they give.
    pub fn check_count(&self) -> usize {
        self.cases.len() + self.worst_poses.len()
    }
}

/// Phases at which each worst pose is run besides its own (see [`DesignSet::checks`]).
pub const PHASE_SAMPLES: usize = 5;

/// W = 3600/((R_s − S_d)/v + t_c) [parcels/h]; 0 for v ≤ 0 or a non-finite result.
pub fn capacity(point: &DesignPoint) -> f64 {
    if point.belt_speed.is_nan() || point.belt_speed <= 0.0 {
        return 0.0;
    }
    let w = 3600.0
        / ((point.start_position - point.light_barrier) / point.belt_speed + point.cycle_time);
    if w.is_finite() && w > 0.0 {
        w
    } else {
        0.0
    }
}

/// The scenario of one parcel at one setting: `base` with v, t_c, R_s, S_d and the parcel
/// replaced. The run lasts at least the cycle plus 2 s (the default), or `base`'s duration if
/// longer.
pub fn case_scenario(base: &Scenario, parcel: &Parcel, point: &DesignPoint) -> Scenario {
    let mut s = base.clone();
    s.machine.belt_speed = point.belt_speed;
    s.machine.cycle_time = point.cycle_time;
    s.machine.start_at(point.start_position);
    s.machine.light_barrier = point.light_barrier;
    s.parcel = parcel.clone();
    s.run.duration = s.run.duration.max(default_duration(point.cycle_time));
    s
}

/// g = P_max − max_lateral for a run (module notes): ≤ 0 if diverted, ≥ [`MIN_MISS_MARGIN`]
/// if not, [`FAILED_MARGIN`] if the run failed or gave a non-finite value.
pub fn divert_margin(belt_width: f64, result: &SimResult) -> f64 {
    let g = belt_width - result.max_lateral;
    match result.outcome {
        _ if !g.is_finite() => FAILED_MARGIN,
        Outcome::Diverted => g.min(0.0),
        Outcome::NotDiverted(_) => g.max(MIN_MISS_MARGIN),
        Outcome::Failed(_) => FAILED_MARGIN,
    }
}

/// d: the divert overshoot of a run \[m], continuous across the diverted/not-diverted boundary
/// and ≥ 0 iff diverted.
///
/// A diverted run stops when the centre crosses P_max, so its margin is 0 whatever the
/// reserve of the push; the reserve is estimated from the final state as the lateral distance
/// the centre would still slide with its exit velocity under belt friction alone,
/// v_y²/(2 μ_b g), μ_b taken at the slip speed |v − v_belt| of the final state. A parcel left
/// on the belt gets −(P_max − max_lateral) (≤ −[`MIN_MISS_MARGIN`]); a failed run
/// −[`FAILED_MARGIN`]; a diverted run with a non-finite final state 0. Capped at
/// [`FAILED_MARGIN`].
pub fn divert_overshoot(scenario: &Scenario, result: &SimResult) -> f64 {
    match result.outcome {
        Outcome::Diverted => {
            let f = &result.final_state;
            let slip = (f.vx - scenario.machine.belt_speed).hypot(f.vy);
            let mu = scenario.materials.belt_friction.at(slip);
            if !f.vy.is_finite() || mu.is_nan() {
                // Diverted all the same: no reserve can be estimated.
                return 0.0;
            }
            let vy = f.vy.max(0.0);
            if mu <= 0.0 {
                // No friction to stop it: the reserve is unbounded (if it moves at all).
                return if vy > 0.0 { FAILED_MARGIN } else { 0.0 };
            }
            (vy * vy / (2.0 * mu * crate::GRAVITY)).min(FAILED_MARGIN)
        }
        Outcome::NotDiverted(_) => -divert_margin(scenario.machine.belt_width, result),
        Outcome::Failed(_) => -FAILED_MARGIN,
    }
}

/// Run one design case at one setting.
pub fn run_case(base: &Scenario, case: &DesignCase, point: &DesignPoint) -> CaseEvaluation {
    run_check(&case.name, &case_scenario(base, &case.parcel, point), None)
}

/// Run one check (a case or a worst pose, see [`DesignSet::checks`]), with its peak drive
/// torque when `profile` ([`DesignSet::stroke_profile`]) is given.
pub fn run_check(name: &str, s: &Scenario, profile: Option<&StrokeProfile>) -> CaseEvaluation {
    let r = simulate_verdict(s);
    let ratio = r.overload.overload_ratio;
    let failed = matches!(r.outcome, Outcome::Failed(_));
    CaseEvaluation {
        drive_torque: match profile {
            Some(p) if !failed => Some(r.arm_loads_with(s, p).peak_torque),
            _ => None,
        },
        name: name.to_string(),
        margin: divert_margin(s.machine.belt_width, &r),
        overshoot: divert_overshoot(s, &r),
        max_lateral: r.max_lateral,
        overload_ratio: if failed || !ratio.is_finite() {
            0.0
        } else {
            ratio
        },
        outcome: r.outcome,
    }
}

/// Whether one design case is diverted at one setting (one simulation).
pub fn diverts(base: &Scenario, parcel: &Parcel, point: &DesignPoint) -> bool {
    simulate_verdict(&case_scenario(base, parcel, point)).outcome == Outcome::Diverted
}

/// Evaluate a setting (cases in parallel, results in order; deterministic).
pub fn evaluate(base: &Scenario, set: &DesignSet, point: &DesignPoint) -> DesignEvaluation {
    evaluate_with_progress(base, set, point, &no_progress)
}

/// [`evaluate`], calling `progress` once per simulation.
pub fn evaluate_with_progress(
    base: &Scenario,
    set: &DesignSet,
    point: &DesignPoint,
    progress: Progress<'_>,
) -> DesignEvaluation {
    let checks = set.checks(base, point);
    let profile = set.stroke_profile(base, point.cycle_time);
    let runs = par_map(&checks, progress, |(_, name, s)| {
        run_check(name, s, profile.as_ref())
    });
    // One evaluation per check: the worst of its runs (least reserve, largest ratio).
    let mut cases: Vec<CaseEvaluation> = Vec::with_capacity(set.check_count());
    for ((i, _, _), r) in checks.iter().zip(runs) {
        match cases.get_mut(*i) {
            None => cases.push(r),
            Some(c) => {
                let ratio = c.overload_ratio.max(r.overload_ratio);
                // A failed run's missing torque stays missing: a failed margin.
                let torque = c.drive_torque.zip(r.drive_torque).map(|(a, b)| a.max(b));
                if r.overshoot < c.overshoot {
                    *c = r;
                }
                c.overload_ratio = ratio;
                c.drive_torque = torque;
            }
        }
    }
    let overload = worst_case_overload(
        base,
        &set.overload_parcel,
        point.cycle_time,
        point.belt_speed,
    )
    .map_err(|e| e.to_string());
    let overload_ratio = match set.worst {
        WorstDefinition::Paper => match &overload {
            Ok(o) => o.ratio,
            Err(_) => f64::NAN,
        },
        WorstDefinition::Search => cases.iter().map(|c| c.overload_ratio).fold(0.0, f64::max),
    };
    let overload_margin = overload_ratio - set.margins.ratio_limit();
    let overload_margin = if overload_margin.is_finite() {
        overload_margin
    } else {
        FAILED_MARGIN
    };
    let barrier_margin = point.light_barrier - point.start_position;
    let barrier_margin = if barrier_margin.is_finite() {
        barrier_margin
    } else {
        FAILED_MARGIN
    };
    let (drive_torque, torque_margin) = match set.margins.drive_torque {
        None => (None, 0.0),
        Some(_) => {
            // A failed run's missing torque is a failed margin, not a pass.
            let worst = cases
                .iter()
                .map(|c| set.margins.torque_margin(c.drive_torque))
                .fold(f64::NEG_INFINITY, f64::max);
            let peak = cases
                .iter()
                .map(|c| c.drive_torque)
                .try_fold(0.0, |m: f64, t| t.map(|t| m.max(t)));
            (peak, worst)
        }
    };
    let feasible = cases.iter().all(|c| c.passes_divert(&set.margins))
        && overload_margin <= 0.0
        && barrier_margin <= 0.0
        && torque_margin <= 0.0;
    DesignEvaluation {
        point: *point,
        capacity: capacity(point),
        cases,
        overload,
        worst: set.worst,
        overload_ratio,
        overload_margin,
        barrier_margin,
        drive_torque,
        torque_margin,
        feasible,
    }
}

impl DesignEvaluation {
    /// The largest divert margin over the cases \[m] (≤ 0: all diverted).
    pub fn divert_margin(&self) -> f64 {
        self.cases
            .iter()
            .map(|c| c.margin)
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// The largest of every margin (divert, overload, barrier): ≤ 0 iff feasible, up to the
    /// zero divert margin of a diverted case.
    pub fn worst_margin(&self) -> f64 {
        self.divert_margin()
            .max(self.overload_margin)
            .max(self.barrier_margin)
            .max(self.torque_margin)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use proptest::prelude::*;

    /// Issue 26: a drive-torque limit is a constraint of its own, g = T/T_max − 1 with T
    /// the largest of the checks' peak drive torques, each its run's own
    /// (`SimResult::arm_loads`); without a limit no torque is computed and nothing changes.
    #[test]
    fn a_drive_torque_limit_is_a_constraint_of_its_own() {
        let base = Scenario::paper_default();
        let mut set = DesignSet::paper(0.7);
        let p = point(2.0, 1.36, 0.0, 0.0);
        let free = evaluate(&base, &set, &p);
        assert!(free.drive_torque.is_none() && free.torque_margin == 0.0);
        assert!(free.cases.iter().all(|c| c.drive_torque.is_none()));
        set.margins.drive_torque = Some(1e6);
        let loose = evaluate(&base, &set, &p);
        assert_eq!(loose.feasible, free.feasible);
        let peak = loose
            .cases
            .iter()
            .map(|c| c.drive_torque.unwrap())
            .fold(0.0, f64::max);
        assert!(peak > 0.0);
        assert_eq!(loose.drive_torque, Some(peak));
        for (case, e) in set.cases.iter().zip(&loose.cases) {
            let s = case_scenario(&base, &case.parcel, &p);
            let own = crate::sim::simulate(&s).arm_loads(&s).unwrap().peak_torque;
            assert_eq!(e.drive_torque, Some(own), "{}", case.name);
        }
        set.margins.drive_torque = Some(0.5 * peak);
        let tight = evaluate(&base, &set, &p);
        assert!(!tight.feasible);
        assert_relative_eq!(tight.torque_margin, 1.0, max_relative = 1e-12);
        assert!(tight.worst_margin() >= tight.torque_margin);
        assert!(!tight.cases.iter().all(|c| c.passes_torque(&set.margins)));
    }

    fn point(v: f64, tc: f64, rs: f64, sd: f64) -> DesignPoint {
        DesignPoint {
            belt_speed: v,
            cycle_time: tc,
            start_position: rs,
            light_barrier: sd,
        }
    }

    #[test]
    fn case_scenario_sets_the_point() {
        let base = Scenario::paper_default();
        let set = DesignSet::paper(0.7);
        let s = case_scenario(&base, &set.cases[1].parcel, &point(1.1, 1.2, 0.4, 0.1));
        assert_eq!(s.machine.belt_speed, 1.1);
        assert_eq!(s.machine.cycle_time, 1.2);
        assert_eq!(s.machine.start_position, 0.4);
        assert_eq!(s.machine.light_barrier, 0.1);
        assert_eq!(s.parcel, set.cases[1].parcel);
        assert_eq!(s.run.duration, 1.2f64.max(1.36) + 2.0);
        assert_eq!(s.materials, base.materials);
    }

    #[test]
    fn paper_set_poses() {
        let set = DesignSet::paper(0.7);
        let names: Vec<&str> = set.cases.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["smallest", "slender", "compact"]);
        let s = &set.cases[0].parcel;
        // Farthest: the far side of the parcel on the far belt edge.
        assert_relative_eq!(s.offset + s.width, 0.7, epsilon = 1e-15);
        assert_eq!(set.cases[1].parcel.offset, 0.0);
        assert_eq!(set.cases[2].parcel.offset, 0.0);
        assert!(set
            .cases
            .iter()
            .all(|c| c.parcel.angle == 0.0 && c.parcel.velocity.is_none()));
        assert_eq!(set.overload_parcel.mass, 15.0);
        assert_eq!(
            (set.overload_parcel.length, set.overload_parcel.width),
            (0.4, 0.26)
        );
    }

    /// W by hand: R_s − S_d = 0.3 m at 1.5 m/s is 0.2 s; + 1.3 s = 1.5 s ⇒ 2400 parcels/h.
    #[test]
    fn capacity_by_hand() {
        assert_relative_eq!(capacity(&point(1.5, 1.3, 0.5, 0.2)), 2400.0, epsilon = 1e-9);
        assert_relative_eq!(capacity(&point(2.0, 1.36, 0.0, 0.0)), 3600.0 / 1.36);
        assert_eq!(capacity(&point(0.0, 1.36, 0.5, 0.0)), 0.0);
        assert_eq!(capacity(&point(f64::NAN, 1.36, 0.5, 0.0)), 0.0);
    }

    /// The paper's optimum (v = 2 m/s, t_c = 1.36 s, R_s = S_d = 0) on the built-in machine:
    /// W = 3600/1.36, the margins follow the verdicts, feasibility follows the margins.
    #[test]
    fn evaluation_of_the_paper_optimum() {
        let base = Scenario::paper_default();
        let set = DesignSet::paper(0.7);
        let e = evaluate(&base, &set, &point(2.0, 1.36, 0.0, 0.0));
        assert_eq!(e.cases.len(), 3);
        assert_relative_eq!(e.capacity, 3600.0 / 1.36);
        for c in &e.cases {
            match c.outcome {
                Outcome::Diverted => {
                    assert!(c.margin <= 0.0 && c.margin > -1e-6, "{c:?}");
                    assert!((c.max_lateral - 0.7).abs() < 1e-6);
                }
                Outcome::NotDiverted(_) => {
                    assert_relative_eq!(c.margin, 0.7 - c.max_lateral);
                    assert!(c.margin > 0.0);
                }
                Outcome::Failed(_) => assert_eq!(c.margin, FAILED_MARGIN),
            }
        }
        // The verdicts are those of the case scenarios run directly.
        for (c, case) in e.cases.iter().zip(&set.cases) {
            let s = case_scenario(&base, &case.parcel, &e.point);
            assert_eq!(c.outcome, crate::sim::simulate(&s).outcome);
        }
        let o = e.overload.as_ref().unwrap();
        assert_relative_eq!(e.overload_margin, o.ratio - 1.0);
        assert_eq!(e.barrier_margin, 0.0);
        let all = e.cases.iter().all(|c| c.outcome == Outcome::Diverted);
        assert_eq!(e.feasible, all && o.ratio <= 1.0);
        assert_eq!(e.feasible, e.worst_margin() <= 0.0);
    }

    /// Evaluations on one thread and on many are bitwise identical.
    #[test]
    fn deterministic_across_threads() {
        let base = Scenario::paper_default();
        let set = DesignSet::paper(0.7);
        let p = point(1.4, 1.2, 0.3, 0.1);
        let (one, many) = crate::run::sweep::one_and_many_threads(|| evaluate(&base, &set, &p));
        assert_eq!(many, one);
    }

    #[test]
    fn margins_of_bad_input_are_finite() {
        let base = Scenario::paper_default();
        let set = DesignSet::paper(0.7);
        // A barrier downstream of R_s is infeasible whatever the verdicts.
        let e = evaluate(&base, &set, &point(2.0, 1.36, 0.0, 0.2));
        assert!(!e.feasible);
        assert_relative_eq!(e.barrier_margin, 0.2);
        // A non-positive cycle time: every run fails, every margin is the failure value.
        let e = evaluate(&base, &set, &point(2.0, -1.0, 0.0, 0.0));
        assert!(!e.feasible);
        assert!(e.cases.iter().all(|c| c.margin == FAILED_MARGIN));
        assert_eq!(e.overload_margin, FAILED_MARGIN);
        assert!(e.worst_margin().is_finite());
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]
        /// W rises as R_s − S_d shrinks and as t_c shrinks, never exceeds 3600/t_c for
        /// R_s ≥ S_d, and is 3600/t_c exactly at R_s = S_d.
        #[test]
        fn capacity_is_monotone(v in 0.1f64..3.0, tc in 0.5f64..2.0, sd in -0.5f64..1.0,
                                gap in 0.0f64..1.0, dg in 0.001f64..0.5) {
            let w = capacity(&point(v, tc, sd + gap, sd));
            prop_assert!(w <= 3600.0 / tc * (1.0 + 1e-12));
            prop_assert!(capacity(&point(v, tc, sd + gap + dg, sd)) < w);
            prop_assert!(capacity(&point(v, tc * 0.9, sd + gap, sd)) > w);
            prop_assert_eq!(capacity(&point(v, tc, sd, sd)), 3600.0 / tc);
        }
    }
}
