//! One run of a scenario as every edge shows it: the per-parcel (adaptive) trigger choosing
//! R_s first when the scenario asks for it (`divertsim_core::analysis::adaptive_trigger`),
//! then the hybrid simulation (`divertsim_core::sim::simulate`), and the self-describing
//! summary (outcome, stages, impacts, overload; the trigger; version, units, the resolved
//! scenario) that `divertsim simulate --json` prints and Python's `Result.summary` holds.

use crate::config::mix::TriggerConfig;
use crate::config::Loaded;
use crate::output;
use divertsim_core::analysis::adaptive_trigger::{best_start, BestStart};
use divertsim_core::model::params::Scenario;
use divertsim_core::sim::{simulate, SimResult};
use serde_json::Value;

/// A finished run.
#[derive(Debug, Clone)]
pub struct Run {
    /// The scenario that ran (R_s chosen by the adaptive trigger where it applies).
    pub scenario: Scenario,
    pub result: SimResult,
    /// The adaptive trigger's search, when `machine.trigger = "adaptive"`.
    pub trigger: Option<BestStart>,
}

/// Run a loaded scenario; with the adaptive trigger, this parcel's own best R_s first
/// (never upstream of the light barrier S_d).
pub fn run(loaded: &Loaded) -> Run {
    let mut scenario = loaded.scenario.clone();
    let trigger = (loaded.file.machine.trigger == TriggerConfig::Adaptive).then(|| {
        let best = best_start(
            &scenario,
            &scenario.parcel,
            &loaded.file.machine.adaptive.search(),
        );
        scenario.machine.start_position = best.start.max(scenario.machine.light_barrier);
        best
    });
    let result = simulate(&scenario);
    Run {
        scenario,
        result,
        trigger,
    }
}

/// The summary of a run: [`output::summary_json`], the adaptive trigger's choice, and
/// what makes it self-describing ([`output::describe`]).
pub fn summary(loaded: &Loaded, run: &Run) -> Value {
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
    output::describe(summary, "simulate", &loaded.file)
}
