//! `divertsim line`: a sorter line (issue 25): a stream of parcels through the scenario's
//! diverters (`[line]`), by `divertsim_api::analyses::line`; the outcome table, the
//! throughput per diverter, line.csv, line_diverters.csv, the parcel log
//! line_parcels.parquet, load_spectrum.csv and largest_stroke.toml (the arms' loads), scenario
//! files of failures (the first 10 of each kind) that `simulate` runs, with a sweep the
//! throughput curve, and report.html (the animated line, the failures' own runs).

use divertsim_api::analyses::line::{
    failures, largest_stroke_files, parcel_file, LineAnalysis, LineStudy,
};
use divertsim_api::config::{to_toml, Loaded};
use divertsim_figures::line::draw_throughput;
use std::path::Path;

use super::analysis::{self, View};
use super::common::{self, OutputArgs, ScenarioArgs};
use crate::flags::OptionArgs;
use divertsim_core::run::memo::Memo;

/// Failures written as scenario files, per point and kind of outcome.
const FAILURE_FILES: usize = 10;

/// Run a stream of parcels through the scenario's line.
#[derive(Debug, Clone, clap::Args)]
pub struct LineArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub resume: common::ResumeArgs,
    #[command(flatten)]
    pub options: OptionArgs<LineAnalysis>,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// largest_stroke.toml: the run behind the largest stroke peak; failures/: the first
/// failures of each kind at each point as scenario files `simulate` runs; with a sweep, the throughput curve (throughput.svg, .png); report.html with the
/// animated line and the failures' own runs.
fn line_files(r: &LineStudy, _: &Loaded, staging: &Path, _: &dyn Memo) -> Result<(), String> {
    for (name, bytes) in largest_stroke_files(r) {
        std::fs::write(staging.join(&name), bytes).map_err(|e| format!("{name}: {e}"))?;
    }
    if let (Some((key, _)), true) = (&r.sweep, r.results.len() > 1) {
        let points: Vec<_> = r
            .results
            .iter()
            .map(|p| (p.point.point.value.as_str(), &p.point.line, &p.tally))
            .collect();
        for ext in ["svg", "png"] {
            draw_throughput(
                &staging.join(format!("throughput.{ext}")),
                &format!("sweep of {key}"),
                &points,
            )
            .map_err(|e| e.to_string())?;
        }
    }
    for (i, res) in r.results.iter().enumerate() {
        let dir = staging.join("failures");
        let mut written = std::collections::BTreeMap::<&str, usize>::new();
        for p in failures(res) {
            let n = written.entry(p.outcome.label()).or_default();
            let file = match parcel_file(res, p) {
                Some(f) if *n < FAILURE_FILES => f,
                _ => continue,
            };
            *n += 1;
            std::fs::create_dir_all(&dir).map_err(|e| format!("failures/: {e}"))?;
            let name = match r.results.len() {
                1 => format!("parcel_{}_{}.toml", p.index, p.outcome.label()),
                _ => format!(
                    "point{}_parcel_{}_{}.toml",
                    i + 1,
                    p.index,
                    p.outcome.label()
                ),
            };
            let heading = format!(
                "Parcel {} of a `divertsim line` run: {} at diverter {}; its run at that \
                 diverter, with every stroke of the arm near it (run.cycle_starts).",
                p.index,
                p.outcome.label(),
                p.decided_at.map_or(0, |d| d + 1)
            );
            let text = to_toml(&file, &heading).map_err(|e| format!("{name}: {e}"))?;
            std::fs::write(dir.join(&name), text).map_err(|e| format!("{name}: {e}"))?;
        }
    }
    let throughput = std::fs::read_to_string(staging.join("throughput.svg")).ok();
    let pages = divertsim_report::line::pages(r, throughput.as_deref())?;
    crate::outdir::write_into(staging, &pages)
}

/// `divertsim line`.
pub fn run(args: &LineArgs) -> i32 {
    analysis::run::<LineAnalysis>(
        &args.scenario,
        Some(&args.resume),
        &args.output,
        &args.options,
        View::files(&line_files),
    )
}
