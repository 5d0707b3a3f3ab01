//! `divertsim reliability`: divert and overload rates over a parcel mix (issue 11), on the
//! api's contract ([`api::Reliability`]) like every analysis command: exact 95 % intervals,
//! failure breakdowns, the failure rate binned against every input, optional sweeps over
//! one scenario key, a fixed or per-parcel (adaptive) trigger.
//!
//! With `--out DIR` every finished shard is kept in the run's checkpoint beside DIR
//! (`.DIR.checkpoint`, its samples as Parquet bytes), so a killed run continues with
//! `--resume` from its last complete shard. This edge adds only the files: the sample table
//! written from those shards (`samples.parquet`, `--csv`), the largest strokes' scenarios,
//! the plots and the study pages. A checkpoint of an older divertsim
//! (`.DIR.reliability-checkpoint`, a folder of Parquet shards) is refused with what to do.

use std::path::Path;

use divertsim_api::analyses::reliability::{self as api, setting_line, Reliability};
use divertsim_api::config::Loaded;
use divertsim_api::contract;
use divertsim_core::analysis::population::reliability::Tally;
use divertsim_core::run::memo::Memo;
use divertsim_figures::reliability as figures;

use super::analysis::{self, View};
use super::common::{OutputArgs, ResumeArgs, ScenarioArgs};
use crate::flags::OptionArgs;

/// Divert and overload rates over a parcel mix.
#[derive(Debug, clap::Args)]
pub struct ReliabilityArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub options: OptionArgs<Reliability>,
    /// Also write samples.csv (the same table as samples.parquet).
    #[arg(long, requires = "out")]
    pub csv: bool,
    #[command(flatten)]
    pub resume: ResumeArgs,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Failed samples kept for the report (each gets its own run page).
const REPORTED_FAILURES: usize = 20;

/// The checkpoint folder an older divertsim's `reliability --out DIR` kept its shards in.
fn old_checkpoint(out: &Path) -> std::path::PathBuf {
    crate::outdir::beside(out, "reliability-checkpoint")
}

/// `divertsim reliability`.
pub fn run(args: &ReliabilityArgs) -> i32 {
    if let Some(old) = args.output.out.as_deref().map(old_checkpoint) {
        if old.exists() {
            eprintln!(
                "error: {} is the checkpoint of an older divertsim's run, which this version cannot resume (its shards are now kept in the run's .checkpoint); remove that folder to start the run over",
                old.display()
            );
            return 2;
        }
    }
    let files = |study: &api::Study, loaded: &Loaded, staging: &Path, kept: &dyn Memo| {
        study_files(study, loaded, staging, kept, args.csv)
    };
    analysis::run::<Reliability>(
        &args.scenario,
        Some(&args.resume),
        &args.output,
        &args.options,
        View::files(&files),
    )
}

/// The files beside the summary and the tables: the sample table from the shards the run
/// kept, the largest strokes' scenarios, the plots, the study pages and `runs/`.
fn study_files(
    study: &api::Study,
    loaded: &Loaded,
    staging: &Path,
    kept: &dyn Memo,
    csv: bool,
) -> Result<(), String> {
    crate::outdir::write_into(
        staging,
        &api::largest_stroke_files(&study.points, &study.results),
    )?;
    let failed = api::write_samples(study, kept, staging, csv, REPORTED_FAILURES)
        .map_err(|e| e.to_string())?;
    draw(staging, study)?;
    let plots: Vec<(&str, String)> = divertsim_report::study::PLOTS
        .into_iter()
        .filter_map(|name| Some((name, std::fs::read_to_string(staging.join(name)).ok()?)))
        .collect();
    let summary = contract::describe::<Reliability>(
        api::summary_json(
            study.sweep.as_ref(),
            &study.plan,
            &study.points,
            &study.results,
        ),
        study,
        loaded,
    );
    let pages =
        divertsim_report::study::pages(&study.points, &study.results, &failed, &summary, &plots);
    // runs/ is there even when no sample failed (the folder's layout is fixed).
    std::fs::create_dir_all(staging.join("runs")).map_err(|e| e.to_string())?;
    crate::outdir::write_into(staging, &pages)
}

/// The study's plots (the figures crate's [`figures::draw_study`]).
fn draw(staging: &Path, study: &api::Study) -> Result<(), String> {
    let values: Vec<String> = study.points.iter().map(|p| p.value.clone()).collect();
    let tallies: Vec<&Tally> = study.results.iter().map(|(r, _)| &r.tally).collect();
    let setting = match (study.points.first(), study.results.first()) {
        (Some(p), Some((_, t))) => setting_line(p, t),
        _ => return Ok(()),
    };
    let figure = figures::Study {
        seed: study.plan.seed,
        setting: &setting,
        values: &values,
        tallies: &tallies,
        sweep_key: study.sweep.as_ref().map(|(k, _)| k.as_str()),
    };
    figures::draw_study(staging, &figure)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_older_checkpoint_is_looked_for_beside_the_output() {
        assert_eq!(
            old_checkpoint(Path::new("runs/mix1")),
            Path::new("runs/.mix1.reliability-checkpoint")
        );
    }
}
