//! `divertsim calibrate`: unknown material and machine values fitted to filmed tracks, on the
//! api's contract ([`divertsim_api::analyses::measurement::Calibrate`]: a profile-likelihood
//! interval for each value, a warning for each value the tracks cannot pin down, and a
//! scenario file of the fitted values that `simulate` runs directly). This edge writes that
//! file, draws each track over its run at the fitted values and the animated report.

use std::path::Path;

use super::analysis::{self, View};
use super::common::{OutputArgs, ScenarioArgs};
use super::compare::draw_overlay;
use crate::flags::OptionArgs;
use divertsim_api::analyses::calibration::measured_points;
use divertsim_api::analyses::measurement::{Calibrate, Calibrated};
use divertsim_api::config::Loaded;
use divertsim_core::run::memo::Memo;

/// Fit values to filmed tracks.
#[derive(Debug, Clone, clap::Args)]
pub struct CalibrateArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub options: OptionArgs<Calibrate>,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// calibrated.toml, each track over its run at the fitted values, the animated report.
fn files(r: &Calibrated, _: &Loaded, staging: &Path, _: &dyn Memo) -> Result<(), String> {
    std::fs::write(staging.join("calibrated.toml"), &r.calibrated_toml)
        .map_err(|e| format!("calibrated.toml: {e}"))?;
    let mut runs = Vec::new();
    for ((fitted, run, cmp), n) in r.fits.iter().zip(&r.names) {
        for ext in ["svg", "png"] {
            draw_overlay(&staging.join(format!("fit_{n}.{ext}")), n, fitted, run, cmp)?;
        }
        runs.push(divertsim_report::run::ReportRun {
            label: n.clone(),
            scenario: &fitted.loaded.scenario,
            result: run,
            measured: measured_points(fitted, cmp),
        });
    }
    let page = divertsim_report::run::multi(
        "divertsim calibrate: the runs at the fitted values and the measured tracks (black dots)",
        &runs,
    );
    std::fs::write(staging.join("report.html"), page).map_err(|e| e.to_string())
}

/// `divertsim calibrate`.
pub fn run(args: &CalibrateArgs) -> i32 {
    analysis::run::<Calibrate>(
        &args.scenario,
        None,
        &args.output,
        &args.options,
        View::files(&files),
    )
}
