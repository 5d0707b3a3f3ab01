//! `divertsim trigger` (paper Fig. 4): for each belt speed, the start position R_s that gives
//! the parcel the same transverse displacement as the reference setting (v = 0.65 m/s,
//! t_c = 1.36 s, R_s = 0.8 m). The computation is `divertsim_core::analysis::paper::trigger`; this
//! file parses the options, prints the table and writes trigger.csv and trigger.svg.

use super::analysis::{self, View};
use super::common::{self, OutputArgs, ScenarioArgs};
use crate::flags::OptionArgs;
use divertsim_api::analyses::trigger::TriggerCalibration;
use divertsim_core::analysis::paper::trigger::TriggerCurve;
use divertsim_figures::charts::line_chart;
use std::path::Path;

/// Options of `divertsim trigger`: the scenario, the analysis's options (from
/// [`divertsim_api::analyses::trigger::TriggerOptions`]) and the outputs.
#[derive(Debug, Clone, clap::Args)]
pub struct TriggerArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub resume: common::ResumeArgs,
    #[command(flatten)]
    pub options: OptionArgs<TriggerCalibration>,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// trigger.svg (or .png): [`divertsim_report::paper::trigger`].
pub fn draw(curve: &TriggerCurve, path: &Path) -> Result<(), String> {
    line_chart(path, &divertsim_report::paper::trigger(curve)).map_err(|e| e.to_string())
}

/// `divertsim trigger`: returns the exit code.
pub fn run(args: &TriggerArgs) -> i32 {
    analysis::run::<TriggerCalibration>(
        &args.scenario,
        Some(&args.resume),
        &args.output,
        &args.options,
        View::new(&draw),
    )
}
