//! The machine-settings problem of the paper's §4.3 as a [`Problem`]: maximise the
//! sorting capacity W over the decision variables (v, t_c, R_s, S_d) subject to every design
//! case being diverted and the worst-case impulse staying below the free-fall reference.
//!
//! Decision variables, in this order (a variable is fixed by giving it equal bounds):
//! `x = [v (belt_speed) m/s, t_c (cycle_time) s, R_s (start_position) m, S_d (light_barrier) m]`.
//!
//! Objectives (minimised):
//! - single-objective methods: f = −W / 1000 (W in parcels per hour; scaled so that a
//!   penalty weight of order one balances margins of order 0.01 m);
//! - NSGA-II ([`Objectives::TradeOff`]): (−W/1000, S/S_fall, −d), where d is the smallest
//!   divert overshoot over the cases (see [`overshoot`]): capacity against overload margin
//!   against divert margin.
//!
//! Constraints g ≤ 0, continuous margins (see [`crate::analysis::design::design_set`]):
//! - one divert constraint per design case, g = −d with d the case's divert overshoot
//!   ([`crate::analysis::design::design_set::divert_overshoot`]). On the infeasible side this *is* the paper's
//!   margin P_max − max_lateral \[m]; on the feasible side it is minus the estimated lateral
//!   reserve v_y²/(2 μ_b g) of the diverted parcel instead of the margin's flat 0, so that a
//!   case near its divert boundary shows as an active constraint and local methods (COBYLA)
//!   see a slope from both sides. g ≤ 0 iff the case is diverted, as with the margin;
//! - the overload margin S/S_fall − 1;
//! - the barrier order S_d − R_s \[m];
//! - with a drive-torque limit T_max (issue 26), T/T_max − 1 for the largest peak drive
//!   torque T over the checks ([`crate::sim::arm_loads`]).
//!
//! Each evaluation runs every design case (in parallel) and the closed-form worst-case strike;
//! it is deterministic, so the solvers' parallel batches give the same numbers for any
//! thread count.

use crate::analysis::design::design_set::{evaluate, DesignEvaluation, DesignPoint, DesignSet};
use crate::model::params::Scenario;
use crate::optimize::{Bounds, Evaluation, OptimizeError, Problem};

/// Names of the decision variables, in order, as the CLI spells them.
pub const VARIABLES: [&str; 4] = [
    "belt_speed",
    "cycle_time",
    "start_position",
    "light_barrier",
];

/// Short symbols of the variables (the paper's), in the order of [`VARIABLES`].
pub const SYMBOLS: [&str; 4] = ["v", "t_c", "R_s", "S_d"];
/// Units of the variables, in the order of [`VARIABLES`].
pub const UNITS: [&str; 4] = ["m/s", "s", "m", "m"];

/// Setting names of the variables that must stay positive (v, t_c).
const LOWER_BOUND_NAMES: [&str; 2] = ["bounds.belt_speed", "bounds.cycle_time"];

/// Which objectives the problem reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Objectives {
    /// −W/1000 only.
    Capacity,
    /// (−W/1000, overload ratio S/S_fall, −divert overshoot) for NSGA-II.
    TradeOff,
}

/// The settings problem on a fixed base scenario and design set.
#[derive(Debug, Clone)]
pub struct SettingsProblem {
    base: Scenario,
    set: DesignSet,
    bounds: Bounds,
    objectives: Objectives,
}

/// A decision vector's setting.
pub fn point_of(x: &[f64]) -> DesignPoint {
    DesignPoint {
        belt_speed: x[0],
        cycle_time: x[1],
        start_position: x[2],
        light_barrier: x[3],
    }
}

/// W of a decision vector \[parcels/h] (the paper's formula, exactly).
pub fn capacity_of(x: &[f64]) -> f64 {
    crate::analysis::design::design_set::capacity(&point_of(x))
}

/// d_min: the smallest divert overshoot over the cases of a design evaluation \[m] (≥ 0 iff
/// every case is diverted; see [`crate::analysis::design::design_set::divert_overshoot`]).
pub fn overshoot(e: &DesignEvaluation) -> f64 {
    e.cases
        .iter()
        .map(|c| c.overshoot)
        .fold(f64::INFINITY, f64::min)
}

impl SettingsProblem {
    /// Bounds must have the four variables of [`VARIABLES`]; the belt speed and cycle time
    /// must stay positive.
    pub fn new(
        base: Scenario,
        set: DesignSet,
        bounds: Bounds,
        objectives: Objectives,
    ) -> Result<SettingsProblem, OptimizeError> {
        bounds.validate()?;
        if bounds.lower.len() != VARIABLES.len() {
            return Err(OptimizeError::BoundsLength {
                lower: bounds.lower.len(),
                upper: bounds.upper.len(),
            });
        }
        for (i, name) in LOWER_BOUND_NAMES.iter().enumerate() {
            if bounds.lower[i] <= 0.0 {
                return Err(OptimizeError::InvalidSetting {
                    name,
                    reason: format!("the lower bound must be > 0, got {}", bounds.lower[i]),
                });
            }
        }
        Ok(SettingsProblem {
            base,
            set,
            bounds,
            objectives,
        })
    }

    /// The design set the problem evaluates.
    pub fn design_set(&self) -> &DesignSet {
        &self.set
    }

    /// The names of the constraints, in order: `divert:<case>`…, `overload`, `barrier`, and
    /// `drive_torque` with a torque limit.
    pub fn constraint_names(&self) -> Vec<String> {
        let mut names: Vec<String> = self
            .set
            .cases
            .iter()
            .map(|c| format!("divert:{}", c.name))
            .chain((1..=self.set.worst_poses.len()).map(|k| format!("divert:worst{k}")))
            .collect();
        names.push("overload".into());
        names.push("barrier".into());
        if self.set.margins.drive_torque.is_some() {
            names.push("drive_torque".into());
        }
        names
    }

    /// The full design evaluation of `x` (what the report shows for the best point).
    pub fn design_evaluation(&self, x: &[f64]) -> DesignEvaluation {
        evaluate(&self.base, &self.set, &point_of(x))
    }

    /// The objectives and constraints of a design evaluation (module notes).
    pub fn evaluation_of(&self, e: &DesignEvaluation) -> Evaluation {
        let d = self.set.margins.divert;
        let mut constraints: Vec<f64> = e.cases.iter().map(|c| d - c.overshoot).collect();
        constraints.push(e.overload_margin);
        constraints.push(e.barrier_margin);
        if self.set.margins.drive_torque.is_some() {
            constraints.push(e.torque_margin);
        }
        let w = -e.capacity / 1000.0;
        let objectives = match self.objectives {
            Objectives::Capacity => vec![w],
            Objectives::TradeOff => vec![w, e.overload_ratio, -overshoot(e)],
        };
        Evaluation {
            objectives,
            constraints,
        }
    }

    /// The base scenario (machine, materials, limits).
    pub fn base(&self) -> &Scenario {
        &self.base
    }

    /// Which objectives the problem reports.
    pub fn objectives(&self) -> Objectives {
        self.objectives
    }
}

impl Problem for SettingsProblem {
    fn bounds(&self) -> &Bounds {
        &self.bounds
    }

    fn objective_count(&self) -> usize {
        match self.objectives {
            Objectives::Capacity => 1,
            Objectives::TradeOff => 3,
        }
    }

    fn constraint_count(&self) -> usize {
        self.set.check_count() + 2 + usize::from(self.set.margins.drive_torque.is_some())
    }

    fn evaluate(&self, x: &[f64]) -> Evaluation {
        self.evaluation_of(&self.design_evaluation(x))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::design::design_set::{
        capacity, case_scenario, divert_overshoot, FAILED_MARGIN,
    };
    use crate::optimize::ga::{self, GaSettings};
    use crate::optimize::RecordLog;
    use crate::sim::{simulate, Outcome};

    fn problem_with(objectives: Objectives, lower: [f64; 4], upper: [f64; 4]) -> SettingsProblem {
        let base = Scenario::paper_default();
        let set = DesignSet::paper(base.machine.belt_width);
        let bounds = Bounds::new(lower.to_vec(), upper.to_vec()).unwrap();
        SettingsProblem::new(base, set, bounds, objectives).unwrap()
    }

    fn problem(objectives: Objectives) -> SettingsProblem {
        problem_with(objectives, [1.0, 1.0, 0.0, 0.0], [2.3, 1.5, 0.9, 0.0])
    }

    /// Issue 26: with a drive-torque limit the problem has one more constraint, last,
    /// named `drive_torque`: the design evaluation's torque margin.
    #[test]
    fn a_torque_limit_adds_the_drive_torque_constraint() {
        let base = Scenario::paper_default();
        let mut set = DesignSet::paper(base.machine.belt_width);
        set.margins.drive_torque = Some(5.0);
        let bounds = Bounds::new(vec![1.0, 1.0, 0.0, 0.0], vec![2.3, 1.5, 0.9, 0.0]).unwrap();
        let p = SettingsProblem::new(base, set, bounds, Objectives::Capacity).unwrap();
        let plain = problem(Objectives::Capacity);
        assert_eq!(p.constraint_count(), plain.constraint_count() + 1);
        assert_eq!(
            p.constraint_names().last().map(String::as_str),
            Some("drive_torque")
        );
        let x = [2.0, 1.36, 0.0, 0.0];
        let (ev, d) = (p.evaluate(&x), p.design_evaluation(&x));
        assert_eq!(ev.constraints.last(), Some(&d.torque_margin));
        assert!(
            d.torque_margin > 0.0,
            "the default stroke needs more than 5 N·m"
        );
        assert_eq!(
            ev.constraints[..plain.constraint_count()],
            plain.evaluate(&x).constraints[..]
        );
    }

    /// f = −W/1000 exactly; the divert constraints are −d of each case, equal to the margin
    /// P_max − max_lateral when not diverted and ≤ 0 iff diverted; overload and barrier are the
    /// design evaluation's margins; feasibility agrees. The points cover both verdicts.
    #[test]
    fn objective_is_minus_capacity_and_constraints_are_the_margins() {
        let p = problem(Objectives::Capacity);
        let n = p.set.cases.len();
        let (mut diverted, mut missed) = (0, 0);
        for x in [
            [2.0, 1.36, 0.0, 0.0],
            [1.0, 1.5, 0.9, 0.0],
            [2.3, 1.0, 0.5, 0.0],
            [1.6, 1.3, 0.2, 0.0],
        ] {
            let ev = p.evaluate(&x);
            let d = p.design_evaluation(&x);
            assert_eq!(ev.objectives, vec![-capacity(&point_of(&x)) / 1000.0]);
            assert_eq!(ev.objectives[0], -d.capacity / 1000.0);
            assert_eq!(ev.constraints.len(), p.constraint_count());
            assert_eq!(p.constraint_names().len(), p.constraint_count());
            for (g, c) in ev.constraints.iter().zip(&d.cases) {
                assert_eq!(*g, -c.overshoot);
                match c.outcome {
                    Outcome::Diverted => {
                        diverted += 1;
                        assert!(*g <= 0.0, "{c:?}");
                    }
                    Outcome::NotDiverted(_) => {
                        missed += 1;
                        assert!(*g > 0.0);
                        assert_eq!(*g, c.margin);
                    }
                    Outcome::Failed(_) => assert_eq!(*g, FAILED_MARGIN),
                }
            }
            assert_eq!(ev.constraints[n], d.overload_margin);
            assert_eq!(ev.constraints[n + 1], d.barrier_margin);
            assert_eq!(ev.feasible(), d.feasible);
        }
        assert!(diverted > 0 && missed > 0, "{diverted} {missed}");
    }

    /// The overshoot of a diverted case recomputed by hand from the final state of the same
    /// run: v_y²/(2 μ_b g) with μ_b at the slip speed (constant μ on the built-in machine).
    #[test]
    fn overshoot_of_a_diverted_case_by_hand() {
        let p = problem(Objectives::Capacity);
        let x = [2.0, 1.36, 0.0, 0.0];
        let d = p.design_evaluation(&x);
        let mut checked = 0;
        for (c, case) in d.cases.iter().zip(&p.set.cases) {
            let s = case_scenario(&p.base, &case.parcel, &point_of(&x));
            let r = simulate(&s);
            assert_eq!(c.overshoot, divert_overshoot(&s, &r));
            if r.outcome == Outcome::Diverted {
                let f = r.final_state;
                let mu = s.materials.belt_friction.at(0.0);
                let by_hand = f.vy.max(0.0).powi(2) / (2.0 * mu * crate::GRAVITY);
                assert!((c.overshoot - by_hand).abs() <= 1e-12 * by_hand.max(1.0));
                assert!(c.overshoot > 0.0);
                checked += 1;
            }
        }
        assert!(checked > 0);
    }

    #[test]
    fn trade_off_has_three_objectives_matching_the_design_evaluation() {
        let p = problem(Objectives::TradeOff);
        let x = [1.8, 1.3, 0.1, 0.0];
        let ev = p.evaluate(&x);
        let d = p.design_evaluation(&x);
        assert_eq!(ev.objectives.len(), 3);
        assert_eq!(p.objective_count(), 3);
        assert_eq!(ev.objectives[0], -d.capacity / 1000.0);
        assert!((ev.objectives[1] - (d.overload_margin + 1.0)).abs() < 1e-12);
        let d_min = d
            .cases
            .iter()
            .map(|c| c.overshoot)
            .fold(f64::INFINITY, f64::min);
        assert_eq!(ev.objectives[2], -d_min);
        assert_eq!(overshoot(&d), d_min);
    }

    /// A tiny GA with t_c and S_d fixed: every candidate keeps the fixed values, and the run
    /// is bitwise identical on one thread and on the default pool.
    #[test]
    fn fixed_variables_and_thread_independence() {
        let p = problem_with(
            Objectives::Capacity,
            [1.5, 1.3, 0.1, 0.1],
            [2.3, 1.3, 0.5, 0.1],
        );
        let settings = GaSettings {
            population: 4,
            generations: 1,
            seed: 7,
            ..GaSettings::default()
        };
        let mut log = RecordLog::default();
        let many = ga::solve(&p, &settings, &mut log).unwrap();
        assert_eq!(log.0.len(), many.evaluations);
        assert!(log.0.len() >= 4);
        for r in &log.0 {
            assert_eq!(r.x[1], 1.3);
            assert_eq!(r.x[3], 0.1);
            assert!((1.5..=2.3).contains(&r.x[0]) && (0.1..=0.5).contains(&r.x[2]));
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let mut log1 = RecordLog::default();
        let one = pool.install(|| ga::solve(&p, &settings, &mut log1).unwrap());
        assert_eq!(many, one);
        assert_eq!(log.0, log1.0);
    }

    #[test]
    fn bad_bounds_are_errors() {
        let base = Scenario::paper_default();
        let set = DesignSet::paper(0.7);
        let b = Bounds::new(vec![0.0, 1.0, 0.0, 0.0], vec![2.3, 1.5, 0.9, 0.0]).unwrap();
        assert!(matches!(
            SettingsProblem::new(base.clone(), set.clone(), b, Objectives::Capacity),
            Err(OptimizeError::InvalidSetting {
                name: "bounds.belt_speed",
                ..
            })
        ));
        let b = Bounds::new(vec![1.0, 0.0, 0.0, 0.0], vec![2.3, 1.5, 0.9, 0.0]).unwrap();
        assert!(SettingsProblem::new(base.clone(), set.clone(), b, Objectives::Capacity).is_err());
        let b = Bounds::new(vec![1.0, 1.0, 0.0], vec![2.3, 1.5, 0.9]).unwrap();
        assert!(matches!(
            SettingsProblem::new(base, set, b, Objectives::Capacity),
            Err(OptimizeError::BoundsLength { lower: 3, .. })
        ));
    }
}
