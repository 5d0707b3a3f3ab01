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
//! A scenario is loaded (here the built-in default, with one key overridden as a file or
//! `--set` would), then simulated to its verdict:
//!
//! ```
//! use divertsim_api::prelude::*;
//!
//! let loaded = load(None, &["machine.belt_speed=1.5".to_string()]).expect("a valid scenario");
//! let run = simulate(&loaded.scenario);
//! assert!(run.max_lateral > 0.0);
//! println!("{} after stages {:?}", run.outcome.label(), run.stages);
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
//! use divertsim_api::analyses::trigger::{Trigger, TriggerOptions};
//!
//! let fig06 = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/paper/fig06.toml");
//! let loaded = load(Some(fig06.as_ref()), &[]).unwrap();
//! let options = TriggerOptions {
//!     speeds: ValueList::List(vec![0.65, 1.1]),
//!     search: Interval(0.4, 0.84),
//!     scan_step: 0.04,
//!     ..Default::default()
//! };
//! let checked = Trigger::validate(&options).expect("valid options");
//! let curve = Trigger::run(&loaded, &checked, &Hooks::none()).unwrap();
//! assert_eq!(curve.points.len(), 2);
//!
//! // A bad option is a problem named after it, not a panic.
//! let bad = TriggerOptions { scan_step: 0.0, ..Default::default() };
//! let problems = Trigger::validate(&bad).unwrap_err();
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

/// The physics core, re-exported: one dependency is enough.
pub use divertsim_core as core;

/// What a first program needs: loading a scenario, running it, and the analysis contract.
pub mod prelude {
    pub use crate::config::{load, load_with, Loaded, Problem, Problems};
    pub use crate::contract::{Analysis, Error, Hooks, Interval, ValueList};
    pub use divertsim_core::model::params::Scenario;
    pub use divertsim_core::sim::{simulate, simulate_verdict, Outcome, SimResult, Stage};
}

pub mod analyses;
pub mod config;
pub mod contract;
pub mod output;
pub mod presets;
pub mod samples;
pub mod threads;
pub mod tracks;
