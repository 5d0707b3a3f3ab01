//! `divertsim compare`: simulate each track's experiment and compare the simulated marker
//! path with the measured one (`divertsim_core::analysis::measurement::track::compare`): time alignment,
//! RMS and largest errors along and across the belt, the discrete Fréchet distance, the
//! verdicts and the belt speed seen on the track; a track that does not match its scenario
//! (another parcel, another speed) is flagged. Overlays like the paper's Figs 13–15.

use std::path::Path;

use divertsim_core::analysis::measurement::track::Comparison;
use divertsim_core::sim::SimResult;
use serde_json::json;

use super::common::{self, OutputArgs, ScenarioArgs};
use super::track::{load_tracks, TrackArgs};
use divertsim_api::analyses::calibration::{
    compare_track, comparison_csv, comparison_json, comparison_text, measured_points, mismatches,
    track_name, LoadedTrack,
};
use divertsim_api::config::Problem;

#[allow(rustdoc::broken_intra_doc_links)] // doc comments are --help text: [m] is a unit
#[derive(Debug, clap::Args)]
pub struct CompareArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub tracks: TrackArgs,
    /// A track matches its scenario when the RMS distance between the measured and
    /// simulated marker is at most this [m], the verdicts agree, and the belt speed on the
    /// track is within 5 % of the scenario's.
    #[arg(long, value_name = "M", default_value_t = 0.02)]
    pub tolerance: f64,
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

/// `divertsim compare`.
pub fn run(args: &CompareArgs) -> i32 {
    let mut problems = common::out_problems(&args.output);
    if !(args.tolerance > 0.0 && args.tolerance.is_finite()) {
        problems.push(Problem::new(
            "--tolerance",
            format!("{} is out of range; allowed: > 0 m", args.tolerance),
        ));
    }
    let tracks = load_tracks(&args.scenario, &args.tracks, &mut problems);
    if let Err(code) = common::check(problems) {
        return code;
    }
    let runs: Vec<(String, SimResult, Comparison, Vec<String>)> =
        divertsim_api::threads::with_threads(args.output.threads.map(usize::from), || {
            use rayon::prelude::*;
            tracks
                .par_iter()
                .map(|t| {
                    let (r, c) = compare_track(t);
                    let f = mismatches(&c, &t.loaded.scenario, args.tolerance);
                    (track_name(&t.path), r, c, f)
                })
                .collect()
        });
    let scenarios: Vec<(&str, &divertsim_api::config::ScenarioFile)> = runs
        .iter()
        .zip(&tracks)
        .map(|((n, ..), t)| (n.as_str(), &t.loaded.file))
        .collect();
    let report = divertsim_api::output::describe_runs(
        json!({
            "tolerance_m": args.tolerance,
            "tracks": runs.iter().map(|(n, _, c, f)| comparison_json(n, c, f)).collect::<Vec<_>>(),
        }),
        "compare",
        &scenarios,
    );
    if let Some(dir) = &args.output.out {
        let rows: Vec<(&str, &Comparison, &[String])> = runs
            .iter()
            .map(|(n, _, c, f)| (n.as_str(), c, f.as_slice()))
            .collect();
        let csv = comparison_csv(&rows).unwrap_or_default();
        let report_runs: Vec<crate::report::ReportRun<'_>> = tracks
            .iter()
            .zip(&runs)
            .map(|(t, (n, r, c, _))| crate::report::ReportRun {
                label: n.clone(),
                scenario: &t.loaded.scenario,
                result: r,
                measured: measured_points(t, c),
            })
            .collect();
        let page = crate::report::multi(
            "divertsim compare: simulated runs and measured tracks (black dots)",
            &report_runs,
        );
        let files = vec![
            ("report.html".to_string(), page.into_bytes()),
            ("comparison.csv".to_string(), csv),
            ("comparison.json".to_string(), common::json_bytes(&report)),
        ];
        let code = common::write_outputs(dir, files, |staging| {
            for (t, (n, r, c, _)) in tracks.iter().zip(&runs) {
                for ext in ["svg", "png"] {
                    draw_overlay(&staging.join(format!("compare_{n}.{ext}")), n, t, r, c)?;
                }
            }
            Ok(())
        });
        if code != 0 {
            return code;
        }
    }
    if args.output.json {
        common::emit_json(&report);
    } else {
        let rows: Vec<(&str, &Comparison, &[String])> = runs
            .iter()
            .map(|(n, _, c, f)| (n.as_str(), c, f.as_slice()))
            .collect();
        let s = comparison_text(&rows, args.tolerance);
        common::emit(&s);
    }
    0
}
