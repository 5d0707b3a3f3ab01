//! The machine-settings problem of the paper's §4.3 as an [`optimize::Problem`]: maximise the
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
//! Constraints g ≤ 0 (continuous margins, see [`super::design`]): one divert margin per design
//! case (P_max − max_lateral [m]), the overload margin S/S_fall − 1 and the barrier order
//! S_d − R_s [m].
//!
//! Each evaluation runs every design case (in parallel) and the closed-form worst-case strike;
//! it is deterministic, so the solvers' parallel batches give the same numbers for any
//! thread count.

use super::design::{evaluate, DesignEvaluation, DesignPoint, DesignSet};
use crate::model::params::Scenario;
use crate::optimize::{Bounds, Evaluation, OptimizeError, Problem};

/// Names of the decision variables, in order, as the CLI spells them.
pub const VARIABLES: [&str; 4] = ["belt_speed", "cycle_time", "start_position", "light_barrier"];

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

/// The divert overshoot of a design evaluation [m]: for each case, −margin (how far the centre
/// went past P_max, 0 when it just crossed, negative when it fell short), minimum over cases.
/// A diverted run stops at the crossing, so diverted cases all give 0 here; the overshoot
/// then is the lateral stopping distance the centre would still slide across with its exit
/// velocity, v_y²/(2 μ_b g) — an estimate of how much reserve the push had.
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
            return Err(OptimizeError::BoundsLength);
        }
        for (i, name) in VARIABLES.iter().enumerate().take(2) {
            if bounds.lower[i] <= 0.0 {
                return Err(OptimizeError::InvalidSetting {
                    name: format!("bounds.{name}"),
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

    /// The names of the constraints, in order: `divert:<case>`…, `overload`, `barrier`.
    pub fn constraint_names(&self) -> Vec<String> {
        let mut names: Vec<String> = self
            .set
            .cases
            .iter()
            .map(|c| format!("divert:{}", c.name))
            .collect();
        names.push("overload".into());
        names.push("barrier".into());
        names
    }

    /// The full design evaluation of `x` (what the report shows for the best point).
    pub fn design_evaluation(&self, x: &[f64]) -> DesignEvaluation {
        evaluate(&self.base, &self.set, &point_of(x))
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
        self.set.cases.len() + 2
    }

    fn evaluate(&self, x: &[f64]) -> Evaluation {
        let e = self.design_evaluation(x);
        let mut constraints: Vec<f64> = e.cases.iter().map(|c| c.margin).collect();
        constraints.push(e.overload_margin);
        constraints.push(e.barrier_margin);
        let w = -e.capacity / 1000.0;
        let objectives = match self.objectives {
            Objectives::Capacity => vec![w],
            Objectives::TradeOff => vec![w, e.overload_margin + 1.0, -overshoot(&e)],
        };
        Evaluation {
            objectives,
            constraints,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn problem(objectives: Objectives) -> SettingsProblem {
        let base = Scenario::paper_default();
        let set = DesignSet::paper(base.machine.belt_width);
        let bounds = Bounds::new(vec![1.0, 1.0, 0.0, 0.0], vec![2.3, 1.5, 0.9, 0.0]).unwrap();
        SettingsProblem::new(base, set, bounds, objectives).unwrap()
    }

    #[test]
    fn objective_is_minus_capacity_and_constraints_are_the_margins() {
        let p = problem(Objectives::Capacity);
        let x = [2.0, 1.36, 0.0, 0.0];
        let ev = p.evaluate(&x);
        // W = 3600 / (0/2 + 1.36).
        assert!((ev.objectives[0] + 3600.0 / 1.36 / 1000.0).abs() < 1e-12);
        assert_eq!(ev.constraints.len(), p.constraint_count());
        assert_eq!(p.constraint_names().len(), p.constraint_count());
        let d = p.design_evaluation(&x);
        assert_eq!(ev.feasible(), d.feasible);
        assert_eq!(ev.constraints[p.constraint_count() - 1], 0.0);
    }

    #[test]
    fn trade_off_has_three_objectives_matching_the_design_evaluation() {
        let p = problem(Objectives::TradeOff);
        let x = [1.8, 1.3, 0.1, 0.0];
        let ev = p.evaluate(&x);
        let d = p.design_evaluation(&x);
        assert_eq!(ev.objectives.len(), 3);
        assert!((ev.objectives[1] - (d.overload_margin + 1.0)).abs() < 1e-12);
        assert!((ev.objectives[2] + overshoot(&d)).abs() < 1e-12);
    }

    #[test]
    fn bad_bounds_are_errors() {
        let base = Scenario::paper_default();
        let set = DesignSet::paper(0.7);
        let b = Bounds::new(vec![0.0, 1.0, 0.0, 0.0], vec![2.3, 1.5, 0.9, 0.0]).unwrap();
        assert!(SettingsProblem::new(base.clone(), set.clone(), b, Objectives::Capacity).is_err());
        let b = Bounds::new(vec![1.0, 1.0, 0.0], vec![2.3, 1.5, 0.9]).unwrap();
        assert!(SettingsProblem::new(base, set, b, Objectives::Capacity).is_err());
    }
}
