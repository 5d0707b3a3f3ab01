//! Runs of single scenarios: `divertsim simulate` (one run, its trigger resolved, its JSON
//! summary) and batches of independent scenarios (the Python package's `simulate_many`).
//!
//! Batches are order-preserving parallel maps ([`par_map`]) in a local rayon pool, so every
//! result depends only on its own scenario: the output is the same bit for bit whatever the
//! number of threads, and equal to running the scenarios one by one.

use crate::config::{Loaded, ScenarioFile};
use crate::output;
use divertsim_core::analysis::population::adaptive_trigger::{resolve, BestStart};
use divertsim_core::model::params::Scenario;
use divertsim_core::run::sweep::par_map;
use divertsim_core::sim::{simulate_with, Recording, SimResult};

/// One finished run: the scenario as run (R_s of an adaptive trigger resolved), its result
/// and, for an adaptive trigger, the search that chose R_s.
#[derive(Debug, Clone)]
pub struct Run {
    /// The scenario as run.
    pub scenario: Scenario,
    pub result: SimResult,
    /// The adaptive trigger's R_s search (`machine.trigger = "adaptive"`), else `None`.
    pub trigger: Option<BestStart>,
}

/// The scenario a loaded file runs: the core's [`resolve`] of its trigger. With
/// `machine.trigger = "adaptive"` the arm starts at this parcel's own best R_s (never
/// upstream of the light barrier S_d); with the fixed trigger it is `loaded.scenario`
/// unchanged.
pub fn scenario_to_run(loaded: &Loaded) -> (Scenario, Option<BestStart>) {
    resolve(&loaded.scenario)
}

/// Run a loaded scenario as `divertsim simulate` does ([`scenario_to_run`], then the
/// simulation, recording as asked).
pub fn run(loaded: &Loaded, recording: Recording) -> Run {
    let (scenario, trigger) = scenario_to_run(loaded);
    let result = simulate_with(&scenario, recording);
    Run {
        scenario,
        result,
        trigger,
    }
}

/// The JSON summary of a run: what `divertsim simulate --json` prints (the result, the
/// adaptive trigger's search if any, the tool, the units and the resolved scenario `file`).
pub fn summary(run: &Run, file: &ScenarioFile) -> serde_json::Value {
    let mut summary = output::summary_json(&run.scenario, &run.result);
    if let Some(best) = &run.trigger {
        summary["trigger"] = serde_json::json!({
            "kind": "adaptive",
            "start_position": run.scenario.machine.start_position,
            "passing_interval": [best.interval.0, best.interval.1],
            "feasible": best.feasible,
            "simulations": best.simulations,
        });
    }
    output::describe(summary, "simulate", file)
}

/// Simulate every scenario with its full trajectory, in parallel on `threads` workers;
/// results in input order, each bitwise that of `simulate(&scenarios[i])`.
pub fn simulate_many(scenarios: &[Scenario], threads: Option<usize>) -> Vec<SimResult> {
    crate::threads::with_threads(threads, || {
        par_map(scenarios, &|| {}, |s| simulate_with(s, Recording::Full))
    })
}

/// [`simulate_many`] without trajectories (`simulate_verdict`): every other field of each
/// result (outcome, stages, events, strikes, overload, final state) is bitwise that of a
/// full run, at a fraction of the memory. What a table of runs needs.
pub fn simulate_verdicts(scenarios: &[Scenario], threads: Option<usize>) -> Vec<SimResult> {
    crate::threads::with_threads(threads, || {
        par_map(scenarios, &|| {}, |s| {
            simulate_with(s, Recording::VerdictOnly)
        })
    })
}

/// Run every loaded scenario as `divertsim simulate` does ([`run`]), in parallel on
/// `threads` workers, results in input order.
pub fn run_many(loaded: &[Loaded], threads: Option<usize>, recording: Recording) -> Vec<Run> {
    crate::threads::with_threads(threads, || par_map(loaded, &|| {}, |l| run(l, recording)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{load, ScenarioBuilder};
    use divertsim_core::sim::simulate;
    use std::path::Path;

    /// 24 scenarios over the default: belt speed, offset, angle and mass varied.
    fn scenarios() -> Vec<Scenario> {
        (0..24)
            .map(|i| {
                let f = f64::from(i);
                let sets = vec![
                    (
                        "machine.belt_speed".to_string(),
                        toml::Value::Float(1.2 + 0.05 * f),
                    ),
                    ("parcel.offset".to_string(), toml::Value::Float(0.01 * f)),
                    (
                        "parcel.angle_deg".to_string(),
                        toml::Value::Float(-20.0 + 1.7 * f),
                    ),
                    ("parcel.mass".to_string(), toml::Value::Float(0.5 + 0.6 * f)),
                ];
                ScenarioBuilder::new()
                    .values(&sets)
                    .load()
                    .unwrap()
                    .scenario
            })
            .collect()
    }

    #[test]
    fn many_equals_one_by_one_whatever_the_threads() {
        let s = scenarios();
        let one_by_one: Vec<SimResult> = s.iter().map(simulate).collect();
        let full = simulate_many(&s, Some(2));
        assert_eq!(full, one_by_one);
        for threads in [Some(1), Some(3), None] {
            let v = simulate_verdicts(&s, threads);
            assert_eq!(v.len(), s.len());
            for (a, b) in v.iter().zip(&one_by_one) {
                // Bitwise equal but for the trajectory, which a verdict run does not keep.
                assert!(a.trajectory.is_empty());
                let b = SimResult {
                    trajectory: Vec::new(),
                    ..b.clone()
                };
                assert_eq!(*a, b);
            }
        }
    }

    #[test]
    fn summary_of_the_default_run() {
        let loaded = load(None, &[]).unwrap();
        let r = run(&loaded, Recording::Full);
        assert!(r.trigger.is_none());
        let s = summary(&r, &loaded.file);
        assert_eq!(s["outcome"], "diverted");
        assert_eq!(s["divertsim"]["command"], "simulate");
        assert!(s["scenario"]["machine"]["belt_speed"].is_number());
        let many = run_many(&[loaded.clone(), loaded], Some(2), Recording::VerdictOnly);
        assert_eq!(many[0].result.overload, r.result.overload);
        assert_eq!(many[1].result.final_state, r.result.final_state);
    }

    #[test]
    fn table_overrides_equal_set_text() {
        let a = load(None, &["machine.belt_speed=1.7".into()]).unwrap();
        let b = ScenarioBuilder::table(toml::Table::new(), "test", Path::new(""))
            .value("machine.belt_speed", toml::Value::Float(1.7))
            .load()
            .unwrap();
        assert_eq!(a.file, b.file);
        let e = ScenarioBuilder::table(toml::Table::new(), "test", Path::new(""))
            .value("machine.belt_speed", toml::Value::Float(-1.0))
            .value("machine.bogus", toml::Value::Integer(1))
            .load()
            .unwrap_err();
        let e2 = load(
            None,
            &["machine.belt_speed=-1.0".into(), "machine.bogus=1".into()],
        )
        .unwrap_err();
        assert_eq!(e, e2);
        assert_eq!(e.0.len(), 2);
    }
}
