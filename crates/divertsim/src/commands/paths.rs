//! `divertsim paths`: several scenario files simulated and their centre paths overlaid in one
//! top view (the paper's Figs 3, 6–8 and 13–15: where the slender and the compact parcel go
//! at the documented and at the optimised setting).
//!
//! Each file brings its own parcel and setting; `--set` applies to every file. The cases run in
//! parallel (`run::sweep::par_map`, order kept), so the output does not depend on
//! `--threads`. Outputs: `paths.svg`/`.png` (plot::overlay_view), `report.html` (the runs
//! animated together), `paths.csv` (the samples of every
//! case: case, t, x, y, phi_deg, stage), `--json` (per case: file, label, outcome, reason,
//! max_lateral, stages), and a readable table by default.

use super::common::{self, OutputArgs};
use divertsim_api::analyses::paths::{compute, csv, default_name, json, text, PathCase};
use divertsim_api::config::{self, Problem};
use divertsim_core::model::params::Scenario;
use divertsim_core::sim::Outcome;
use divertsim_figures::plot::{self, OverlayCase, PlotError, PlotOptions};
use std::path::{Path, PathBuf};

/// Arguments of `divertsim paths`.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are --help text: [m] is a unit
#[derive(Debug, Clone, clap::Args)]
pub struct PathsArgs {
    /// Scenario files (TOML), one case each, drawn in this order (the first case's arm is
    /// drawn).
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
    /// Override a key in every file by dotted path with a TOML value, e.g.
    /// machine.belt_speed=2.0. Repeatable; validated like the files.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Let the files read files outside their own directories (as for `simulate`).
    #[arg(long)]
    pub allow_outside_paths: bool,
    /// The legend name of the case in the same position (repeat once per file, in order;
    /// cases without one are named by their file stem). The outcome is appended.
    #[arg(long = "label", value_name = "TEXT")]
    pub labels: Vec<String>,
    /// Draw the overlay into FILE (.svg or .png) as well as or instead of `--out`.
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Draw the overlay of `cases` to `path` (.svg or .png).
pub fn draw(cases: &[PathCase], path: &Path) -> Result<(), PlotError> {
    let legends: Vec<String> = cases.iter().map(PathCase::legend).collect();
    let overlay: Vec<OverlayCase<'_>> = cases
        .iter()
        .zip(&legends)
        .map(|(c, label)| OverlayCase {
            label,
            scenario: &c.scenario,
            result: &c.result,
        })
        .collect();
    plot::overlay_view(&overlay, path, &PlotOptions::default())
}

/// Load every file with the `--set`s; every problem of every file (its key prefixed with the
/// file), of `--label` and of the outputs, at once.
/// Each file's (path, case name, scenario), and its resolved file for the outputs.
type Inputs = (Vec<(PathBuf, String, Scenario)>, Vec<config::ScenarioFile>);

fn load_all(args: &PathsArgs) -> Result<Inputs, Vec<Problem>> {
    let mut problems = Vec::new();
    let mut inputs = Vec::new();
    let mut files = Vec::new();
    for (i, file) in args.files.iter().enumerate() {
        let options = config::LoadOptions {
            allow_outside_paths: args.allow_outside_paths,
            ..Default::default()
        };
        match config::load_with(Some(file), &args.sets, options)
            .and_then(divertsim_api::analyses::fixed_trigger_only)
        {
            Ok(loaded) => {
                let name = args
                    .labels
                    .get(i)
                    .cloned()
                    .unwrap_or_else(|| default_name(file));
                inputs.push((file.clone(), name, loaded.scenario));
                files.push(loaded.file);
            }
            Err(ps) => problems.extend(
                ps.0.into_iter()
                    .map(|p| Problem::new(format!("{}: {}", file.display(), p.key), p.message)),
            ),
        }
    }
    if args.labels.len() > args.files.len() {
        problems.push(Problem::new(
            "--label",
            format!(
                "given {} times for {} files: at most one label per file",
                args.labels.len(),
                args.files.len()
            ),
        ));
    }
    if let Some(p) = &args.plot {
        if plot::format_of(p).is_err() {
            problems.push(Problem::new(
                "--plot",
                format!("{}: the extension must be .svg or .png", p.display()),
            ));
        }
    }
    problems.extend(common::out_problems(&args.output));
    if problems.is_empty() {
        Ok((inputs, files))
    } else {
        Err(problems)
    }
}

/// Write the plot to `path` through a temporary file beside it (nothing left on failure).
fn write_plot(cases: &[PathCase], path: &Path) -> Result<(), String> {
    crate::outdir::write_file(path, &mut |tmp| draw(cases, tmp).map_err(|e| e.to_string()))
}

/// Run `divertsim paths`; returns the exit code (0, 1 output not written, 2 bad input,
/// 3 a case failed numerically: outputs are still written).
pub fn run(args: &PathsArgs) -> i32 {
    let (inputs, scenario_files) = match load_all(args) {
        Ok(i) => i,
        Err(problems) => {
            return match common::check(problems) {
                Err(code) => code,
                Ok(()) => 2,
            }
        }
    };
    let bar = crate::progress::progress_bar(inputs.len() as u64, "paths", args.output.quiet);
    let tick = || bar.inc(1);
    let cases = divertsim_api::threads::with_threads(args.output.threads.map(usize::from), || {
        compute(inputs, &tick)
    });
    bar.finish_and_clear();

    if let Some(dir) = &args.output.out {
        let bytes = match csv(&cases) {
            Ok(b) => b,
            Err(e) => {
                eprintln!("error: cannot format paths.csv: {e}");
                return 1;
            }
        };
        let runs: Vec<divertsim_report::run::ReportRun<'_>> = cases
            .iter()
            .map(|c| divertsim_report::run::ReportRun {
                label: c.name.clone(),
                scenario: &c.scenario,
                result: &c.result,
                measured: Vec::new(),
            })
            .collect();
        let report = divertsim_report::run::multi("divertsim paths", &runs);
        let runs: Vec<(&str, &config::ScenarioFile)> = cases
            .iter()
            .zip(&scenario_files)
            .map(|(c, f)| (c.name.as_str(), f))
            .collect();
        let summary = divertsim_api::output::describe_runs(json(&cases), "paths", &runs);
        let mut files = vec![
            ("paths.csv".into(), bytes),
            ("report.html".into(), report.into_bytes()),
            ("summary.json".into(), common::json_bytes(&summary)),
        ];
        // Each case's resolved scenario, standing alone (two cases may share a label).
        for (k, (c, f)) in cases.iter().zip(&scenario_files).enumerate() {
            let (_, text) = divertsim_api::output::scenario_toml("paths", f);
            let name: String = c
                .name
                .chars()
                .map(|ch| {
                    if ch.is_ascii_alphanumeric() || ch == '-' {
                        ch
                    } else {
                        '_'
                    }
                })
                .collect();
            files.push((format!("scenario_{}_{name}.toml", k + 1), text));
        }
        let code = common::write_outputs(dir, files, |staging| {
            for name in ["paths.svg", "paths.png"] {
                draw(&cases, &staging.join(name)).map_err(|e| e.to_string())?;
            }
            Ok(())
        });
        if code != 0 {
            return code;
        }
    }
    if let Some(path) = &args.plot {
        if let Err(e) = write_plot(&cases, path) {
            eprintln!("error: cannot write the plot {}: {e}", path.display());
            return 1;
        }
    }
    if args.output.json {
        common::emit_json(&json(&cases));
    } else {
        common::emit(&text(&cases));
    }
    if cases
        .iter()
        .any(|c| matches!(c.result.outcome, Outcome::Failed(_)))
    {
        3
    } else {
        0
    }
}
