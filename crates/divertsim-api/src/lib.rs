//! # divertsim-api
//!
//! The one library API every edge calls (the `divertsim` CLI, the Python package): the
//! scenario contract ([`config`]: files with their base chain, defaults, dotted overrides,
//! validation listing every problem), the presets built from `configs/`, result views
//! ([`output`]), the reliability sample table ([`samples`]), track files ([`tracks`]) and
//! every analysis ([`analyses`]), with one contract per analysis ([`contract`]). The physics
//! is in `divertsim-core`, re-exported as [`core`]; [`prelude`] has what a first program needs.
//!
//! ## One run
//!
//! A scenario is loaded with the one [`config::ScenarioBuilder`] (here the built-in default,
//! with one key overridden as a file or `--set` would), then run to its verdict. [`run`](analyses::runs::run)
//! runs it as its machine would: with `machine.trigger = "adaptive"` the arm starts at the
//! parcel's own best R_s (the trigger policy is part of the core's scenario, and the core's
//! `simulate` reports an unresolved one as a failed run rather than running another parcel).
//!
//! ```
//! use divertsim_api::prelude::*;
//!
//! let loaded = ScenarioBuilder::new()
//!     .set("machine.belt_speed=1.5")
//!     .load()
//!     .expect("a valid scenario");
//! let done = run(&loaded, Recording::Full);
//! assert!(done.result.max_lateral > 0.0);
//! println!("{} after stages {:?}", done.result.outcome.label(), done.result.stages);
//!
//! // The adaptive trigger: the run starts at this parcel's own R_s.
//! let adaptive = ScenarioBuilder::new().set("machine.trigger=\"adaptive\"").load().unwrap();
//! let machine_run = run(&adaptive, Recording::VerdictOnly);
//! assert!(machine_run.trigger.is_some());
//! assert!(matches!(simulate(&adaptive.scenario).outcome, Outcome::Failed(_)));
//! ```
//!
//! ## A sweep
//!
//! One source read once ([`config::ScenarioBuilder::merged`]), a variant per value, the
//! runs in parallel: the results are the same bit for bit whatever the thread count.
//!
//! ```
//! use divertsim_api::prelude::*;
//! use divertsim_api::analyses::runs::simulate_verdicts;
//!
//! let base = ScenarioBuilder::new().merged().unwrap();
//! let speeds = [1.0, 1.5, 2.0];
//! let scenarios: Vec<Scenario> = speeds
//!     .iter()
//!     .map(|&v| {
//!         let l = base.clone().value("machine.belt_speed", toml::Value::Float(v));
//!         l.load().unwrap().scenario
//!     })
//!     .collect();
//! let one = simulate_verdicts(&scenarios, Some(1));
//! let two = simulate_verdicts(&scenarios, Some(2));
//! for (a, b) in one.iter().zip(&two) {
//!     assert_eq!(a.final_state, b.final_state);
//! }
//! ```
//!
//! ## An analysis on the contract
//!
//! Each analysis has one options type (serde, `Default`, JSON Schema), a check that keys
//! every problem by option name, and a run with [`contract::Hooks`] (progress, stop,
//! checkpoint memo, threads). The trigger calibration of the paper's Fig. 4 at two speeds:
//!
//! ```
//! use divertsim_api::prelude::*;
//! use divertsim_api::analyses::trigger::{TriggerCalibration, TriggerOptions};
//!
//! let fig06 = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/paper/fig06.toml");
//! let loaded = load(Some(fig06.as_ref()), &[]).unwrap();
//! let options = TriggerOptions {
//!     speeds: ValueList::List(vec![0.65, 1.1]),
//!     search: Interval(0.4, 0.84),
//!     scan_step: 0.04,
//!     ..Default::default()
//! };
//! let checked = TriggerCalibration::validate(&options).expect("valid options");
//! // Bound to the scenario: what a run takes (a sweep's points, tracks: derived once).
//! let bound = TriggerCalibration::bind(checked, &loaded).expect("bound to the scenario");
//! let curve = TriggerCalibration::run(&loaded, &bound, &Hooks::none()).unwrap();
//! assert_eq!(curve.points.len(), 2);
//!
//! // A bad option is a problem named after it, not a panic.
//! let bad = TriggerOptions { scan_step: 0.0, ..Default::default() };
//! let problems = TriggerCalibration::validate(&bad).unwrap_err();
//! assert_eq!(problems[0].key, "scan_step");
//! ```
//!
//! ## Any analysis by name, with JSON options
//!
//! What the Python package and a server call: the [`analyses::registry::REGISTRY`] by name, options
//! as JSON, the summary and tables back.
//!
//! ```
//! use divertsim_api::prelude::*;
//!
//! let entry = divertsim_api::analyses::registry::find("overload").unwrap();
//! let loader = |extra: &[String]| load(None, extra);
//! let options = serde_json::json!({"speeds": "1.0:2.0/3", "drop_heights": [0.3]});
//! let report = (entry.execute)(&loader, &options, 1_000_000, &Hooks::none()).unwrap();
//! assert_eq!(report.summary["divertsim"]["command"], "overload");
//! assert_eq!(report.tables[0].0, "overload.csv");
//! ```
//!
//! ## A reliability study
//!
//! Divert and overload rates over a parcel mix with exact 95 % intervals: sample i depends
//! only on (seed, i), so the run may be split over threads, processes or machines.
//!
//! ```
//! use divertsim_api::prelude::*;
//! use divertsim_api::analyses::reliability::{Options, Reliability, CONFIDENCE};
//!
//! let hub = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/mix/hub.toml");
//! let loaded = ScenarioBuilder::file(hub).load().unwrap();
//! let options = Options { samples: 300, shard: 100, ..Default::default() };
//! let checked = Reliability::validate(&options).unwrap();
//! let bound = Reliability::bind(checked, &loaded).unwrap();
//! let study = Reliability::run(&loaded, &bound, &Hooks::none()).unwrap();
//! let rate = study.results[0].0.tally.divert_rate(CONFIDENCE);
//! assert!(rate.lower <= rate.estimate && rate.estimate <= rate.upper);
//! ```

/// The physics core, re-exported: one dependency is enough.
pub use divertsim_core as core;

/// What a first program needs: loading a scenario, running it as its machine would, and the
/// analysis contract.
pub mod prelude {
    pub use crate::analyses::runs::{run, Run};
    pub use crate::config::{load, load_with, Loaded, Problem, Problems, ScenarioBuilder};
    pub use crate::contract::{Analysis, Error, Hooks, Interval, ValueList};
    pub use divertsim_core::model::params::Scenario;
    pub use divertsim_core::model::trigger::Trigger;
    pub use divertsim_core::sim::{
        simulate, simulate_verdict, Outcome, Recording, SimResult, Stage,
    };
}

pub mod analyses;
pub mod config;
pub mod contract;
pub mod output;
pub mod pieces;
pub mod presets;
pub mod samples;
pub mod threads;
pub mod tracks;
