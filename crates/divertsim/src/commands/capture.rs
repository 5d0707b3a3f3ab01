//! `divertsim capture` (paper Fig. 5): does the arm catch a parcel riding with the belt? The
//! arm angle α(t) against the polar angle γ_p(t) of the parcel's front corner, the reach angle
//! α_z, the kinematic capture time, and the full simulation's first arm strike, per belt
//! speed. The analysis is `divertsim_api::analyses::capture`; this file parses the options, prints
//! the table and writes capture.csv and capture.svg.

use super::analysis::{self, View};
use super::common::{OutputArgs, ScenarioArgs};
use crate::flags::OptionArgs;
use divertsim_api::analyses::capture::{Capture, CaptureResult};
use divertsim_figures::charts::line_chart;
use std::path::Path;

/// Options of `divertsim capture`: the scenario, the analysis's options (from
/// [`divertsim_api::analyses::capture::CaptureOptions`]) and the outputs.
#[derive(Debug, Clone, clap::Args)]
pub struct CaptureArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub options: OptionArgs<Capture>,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// capture.svg (or .png): [`divertsim_report::paper::capture`].
pub fn draw(result: &CaptureResult, path: &Path) -> Result<(), String> {
    line_chart(path, &divertsim_report::paper::capture(result)).map_err(|e| e.to_string())
}

/// `divertsim capture`: returns the exit code.
pub fn run(args: &CaptureArgs) -> i32 {
    analysis::run::<Capture>(
        &args.scenario,
        None,
        &args.output,
        &args.options,
        View::new(&draw),
    )
}
