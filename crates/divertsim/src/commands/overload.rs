//! `divertsim overload`: the worst-case parcel's impulse against belt speed for the
//! scenario's cycle time, with free-fall references (paper Fig. 16), computed by
//! `divertsim_core::analysis::paper::overload` for the `[design.overload]` parcel; with `--search`
//! also the searched worst case at each speed (`divertsim_core::analysis::design::worst_case`: any
//! parcel of the `[design.search]` class, pose, arrival and start position); a table,
//! overload.csv, overload.svg, or JSON.

use std::path::Path;

use super::analysis::{self, View};
use super::common::{OutputArgs, ScenarioArgs};
use crate::flags::OptionArgs;
use divertsim_api::analyses::overload::{Overload, OverloadReport};
use divertsim_figures::charts::line_chart;
use divertsim_figures::plot::PlotError;

/// Worst-case impulse against belt speed, with free-fall references: the scenario, the
/// analysis's options (from [`divertsim_api::analyses::overload::OverloadOptions`]) and the
/// outputs.
#[derive(Debug, Clone, clap::Args)]
pub struct OverloadArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub output: OutputArgs,
    #[command(flatten)]
    pub options: OptionArgs<Overload>,
}

/// overload.svg (or .png): [`divertsim_report::paper::overload`].
pub fn draw(r: &OverloadReport, path: &Path) -> Result<(), PlotError> {
    line_chart(path, &divertsim_report::paper::overload(r))
}

/// `divertsim overload`.
pub fn run(args: &OverloadArgs) -> i32 {
    analysis::run::<Overload>(
        &args.scenario,
        None,
        &args.output,
        &args.options,
        View::new(&|report, path| draw(report, path).map_err(|e| e.to_string())),
    )
}
