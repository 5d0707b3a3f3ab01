//! `divertsim compare`: each filmed track against the simulation of its experiment, on the
//! api's contract ([`divertsim_api::analyses::measurement::Compare`]: time alignment, RMS and
//! largest errors along and across the belt, the discrete Fréchet distance, the verdicts, the
//! belt speed seen on the track, a track that does not match its scenario flagged). This
//! edge draws the overlays (paper Figs 13–15 style) and the animated report.

use std::path::Path;

use super::analysis::{self, View};
use super::common::{OutputArgs, ScenarioArgs};
use crate::flags::OptionArgs;
use divertsim_api::analyses::calibration::{measured_points, LoadedTrack};
use divertsim_api::analyses::measurement::{Compare, Compared};
use divertsim_api::config::Loaded;
use divertsim_core::analysis::measurement::track::Comparison;
use divertsim_core::run::memo::Memo;
use divertsim_core::sim::SimResult;

/// Compare filmed tracks with simulations of their experiments.
#[derive(Debug, Clone, clap::Args)]
pub struct CompareArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub options: OptionArgs<Compare>,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// The overlay of a track's measured and simulated marker paths (the figures crate's).
pub fn draw_overlay(
    path: &Path,
    name: &str,
    t: &LoadedTrack,
    result: &SimResult,
    c: &Comparison,
) -> Result<(), String> {
    divertsim_figures::tracks::marker_overlay(
        path,
        name,
        &t.loaded.scenario,
        result,
        t.marker_offset,
        &t.track,
        c,
    )
    .map_err(|e| e.to_string())
}

/// The animated report of the runs with their tracks, and an overlay per track.
fn files(r: &Compared, _: &Loaded, staging: &Path, _: &dyn Memo) -> Result<(), String> {
    let runs: Vec<divertsim_report::run::ReportRun<'_>> = r
        .tracks
        .iter()
        .zip(&r.runs)
        .map(|(t, (n, run, c, _))| divertsim_report::run::ReportRun {
            label: n.clone(),
            scenario: &t.loaded.scenario,
            result: run,
            measured: measured_points(t, c),
        })
        .collect();
    let page = divertsim_report::run::multi(
        "divertsim compare: simulated runs and measured tracks (black dots)",
        &runs,
    );
    std::fs::write(staging.join("report.html"), page).map_err(|e| e.to_string())?;
    for (t, (n, run, c, _)) in r.tracks.iter().zip(&r.runs) {
        for ext in ["svg", "png"] {
            draw_overlay(&staging.join(format!("compare_{n}.{ext}")), n, t, run, c)?;
        }
    }
    Ok(())
}

/// `divertsim compare`.
pub fn run(args: &CompareArgs) -> i32 {
    analysis::run::<Compare>(
        &args.scenario,
        None,
        &args.output,
        &args.options,
        View::files(&files),
    )
}
