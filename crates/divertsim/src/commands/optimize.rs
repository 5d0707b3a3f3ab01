//! `divertsim optimize`: the machine-settings optimisation (paper §4.3) on the api's
//! contract ([`divertsim_api::analyses::optimize::Optimize`]): its flags, checks, runs,
//! tables, summary and text are the api's; this edge draws the figures. Three experiments:
//! - one run (`--method`): evaluations.csv, history.csv + history.svg/png (best capacity and
//!   variables against generation, paper Figs 10/11 style), for NSGA-II front.csv +
//!   front.svg/png, summary.json, and optimum.toml (the scenario at the best point);
//! - `--paper-experiment`: the paper's three GA and three gradient runs (fig10_ga,
//!   fig11_gradient, paper_experiment.csv/.json, each run's history and evaluations);
//! - `--compare`: every method over `--seeds` seeds on the same problem (comparison.csv,
//!   comparison_medians.csv, summary.json);
//! - `--objective line`: one run on the throughput of the scenario's `[line]`
//!   (evaluations.csv, history.csv + history.svg/png, summary.json, optimum.toml).
//!
//! With `--out`, each run's evaluations are also streamed into the checkpoint folder as
//! `evaluations-N.csv` while it goes.

use std::path::Path;

use divertsim_api::analyses::optimize::{Method, Optimize, OptimizeResult};
use divertsim_api::config::Loaded;
use divertsim_figures::optimize::{
    draw_front, draw_history, draw_history_of, HistoryObjective, HistoryRun,
};

use super::analysis::{self, View};
use super::common::{self, OutputArgs, ScenarioArgs};
use crate::flags::OptionArgs;
use divertsim_core::run::memo::Memo;

/// Optimise the machine settings (v, t_c, R_s, S_d) for capacity.
#[derive(Debug, Clone, clap::Args)]
pub struct OptimizeArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub resume: common::ResumeArgs,
    #[command(flatten)]
    pub options: OptionArgs<Optimize>,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// The figures of each experiment, into the staging folder of `--out`.
fn figures(r: &OptimizeResult, _: &Loaded, staging: &Path, _: &dyn Memo) -> Result<(), String> {
    let e = |e: divertsim_figures::plot::PlotError| e.to_string();
    for ext in ["svg", "png"] {
        match r {
            OptimizeResult::Single {
                run, optimum_toml, ..
            } => {
                if ext == "svg" {
                    std::fs::write(staging.join("optimum.toml"), optimum_toml)
                        .map_err(|e| format!("optimum.toml: {e}"))?;
                }
                let x_label = match run.method {
                    Method::Gradient => "iteration",
                    _ => "generation",
                };
                draw_history(
                    &staging.join(format!("history.{ext}")),
                    &format!(
                        "divertsim optimize --method {}: best point against {x_label}",
                        run.method.name()
                    ),
                    x_label,
                    &[HistoryRun {
                        label: format!("{} (seed or start as given)", run.method.name()),
                        history: &run.result.history,
                    }],
                )
                .map_err(e)?;
                if let Some(front) = &run.front {
                    draw_front(&staging.join(format!("front.{ext}")), front, &run.log)
                        .map_err(e)?;
                }
            }
            OptimizeResult::Paper { runs, .. } => {
                let of = |m: Method| -> Vec<HistoryRun<'_>> {
                    runs.iter()
                        .filter(|r| r.outcome.method == m)
                        .map(|r| HistoryRun {
                            label: format!("{}: {}", r.label, r.description),
                            history: &r.outcome.result.history,
                        })
                        .collect()
                };
                draw_history(
                    &staging.join(format!("fig10_ga.{ext}")),
                    "GA (paper Fig. 10): best point against generation, dashed while infeasible",
                    "generation",
                    &of(Method::Ga),
                )
                .map_err(e)?;
                draw_history(
                    &staging.join(format!("fig11_gradient.{ext}")),
                    "Penalised steepest descent (paper Fig. 11): best point against iteration, dashed while infeasible",
                    "iteration",
                    &of(Method::Gradient),
                )
                .map_err(e)?;
            }
            OptimizeResult::Compare { .. } => {}
            OptimizeResult::Line(r) => {
                if ext == "svg" {
                    std::fs::write(staging.join("optimum.toml"), &r.optimum_toml)
                        .map_err(|e| format!("optimum.toml: {e}"))?;
                }
                draw_history_of(
                    &staging.join(format!("history.{ext}")),
                    &format!(
                        "divertsim optimize --objective line --method {}: best point against generation",
                        r.run.method.name()
                    ),
                    "generation",
                    &[HistoryRun {
                        label: format!(
                            "{} on {} parcels (seed {})",
                            r.run.method.name(),
                            r.problem.objective.parcels,
                            r.problem.seed()
                        ),
                        history: &r.run.result.history,
                    }],
                    HistoryObjective::Throughput,
                )
                .map_err(e)?;
            }
        }
    }
    Ok(())
}

/// `divertsim optimize`.
pub fn run(args: &OptimizeArgs) -> i32 {
    analysis::run::<Optimize>(
        &args.scenario,
        Some(&args.resume),
        &args.output,
        &args.options,
        View::files(&figures),
    )
}
