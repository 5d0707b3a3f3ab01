//! `divertsim worst-case`: the searched worst case of one machine setting (issue 10): the
//! largest impulse and the smallest divert reserve over the `[design.search]` pose box, by
//! `divertsim_core::analysis::design::worst_case`, next to the paper's closed-form definition; the
//! worst poses as scenario files that `simulate` reproduces exactly.

use divertsim_api::analyses::worst_case::{pose_toml, WorstCaseReport, WorstCaseSearch};
use divertsim_api::config::Loaded;
use divertsim_core::sim::simulate;
use std::path::Path;

use super::analysis::{self, View};
use super::common::{OutputArgs, ScenarioArgs};
use crate::flags::OptionArgs;
use divertsim_api::output;
use divertsim_core::run::memo::Memo;
use divertsim_figures::plot::{self, PlotOptions};

/// Search the worst case of one setting.
#[derive(Debug, Clone, clap::Args)]
pub struct WorstCaseArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub options: OptionArgs<WorstCaseSearch>,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// The worst poses as scenario files that `simulate` reproduces, their trajectories, top
/// views and animations.
fn pose_files(
    report: &WorstCaseReport,
    loaded: &Loaded,
    staging: &Path,
    _: &dyn Memo,
) -> Result<(), String> {
    for w in [&report.impulse, &report.reserve]
        .into_iter()
        .chain(report.torque.as_ref())
    {
        let name = format!("worst_{}", w.objective.label());
        let toml = pose_toml(loaded, &report.setting, w)
            .map_err(|e| format!("cannot write {name}.toml: {e}"))?;
        let s = w.pose.scenario(&report.setting);
        let r = simulate(&s);
        let csv = output::trajectory_csv(&s, &r)
            .map_err(|e| format!("cannot format {name}_trajectory.csv: {e}"))?;
        let write = |file: String, bytes: &[u8]| {
            std::fs::write(staging.join(&file), bytes).map_err(|e| format!("{file}: {e}"))
        };
        write(format!("{name}.toml"), toml.as_bytes())?;
        write(format!("{name}_trajectory.csv"), &csv)?;
        for ext in ["svg", "png"] {
            plot::top_view(
                &s,
                &r,
                &staging.join(format!("{name}.{ext}")),
                &PlotOptions::default(),
            )
            .map_err(|e| e.to_string())?;
        }
        // The worst run animated, with its resolved scenario.
        write(
            format!("{name}.html"),
            divertsim_report::run::single(&s, &r, &toml).as_bytes(),
        )?;
    }
    Ok(())
}

/// `divertsim worst-case`.
pub fn run(args: &WorstCaseArgs) -> i32 {
    analysis::run::<WorstCaseSearch>(
        &args.scenario,
        None,
        &args.output,
        &args.options,
        View::files(&pose_files),
    )
}
