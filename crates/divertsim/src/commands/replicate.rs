//! `divertsim replicate`: rerun the paper's analyses on the paper preset and check its
//! findings (a)–(g) (issue "The paper's analyses", docs/validation.md). Writes every figure as
//! SVG with its CSV, plus `findings.json` and `findings.md` (one row per finding: the paper's
//! statement, divertsim's figure, and whether it holds), all or nothing.
//!
//! The scenarios are the files of the configs directory (default `configs/paper`):
//! `machine.toml` (the preset), `fig05.toml` (capture), `fig06`–`fig08` (findings a–c, and
//! the trigger reference parcel), `fig03`, `fig13a/b`, `fig14a/b`, `fig15a/b` (paths). The
//! verdict of each finding is computed from the numbers, never asserted.

use crate::commands::common::{self, emit};
use crate::commands::{capture, overload, paths, trigger};
use divertsim_api::analyses::replicate::{
    compute, findings_json, findings_markdown, findings_text, load_inputs, Replication,
};
use divertsim_api::config::Problem;
use std::path::{Path, PathBuf};

/// Arguments of `divertsim replicate`.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are --help text: [m] is a unit
#[derive(Debug, Clone, clap::Args)]
pub struct ReplicateArgs {
    /// Directory of the paper scenarios (machine.toml and fig*.toml). Default: configs/paper
    /// where it exists (in the repository), else the presets built into divertsim.
    #[arg(long, value_name = "DIR")]
    pub configs: Option<PathBuf>,
    /// Where the figures, CSVs and findings go (all or nothing). An existing DIR is
    /// refused unless --force (as docs/figures is: regenerate it with --force).
    #[arg(long, value_name = "DIR", default_value = "docs/figures")]
    pub out: PathBuf,
    /// Replace an existing --out DIR whole.
    #[arg(long)]
    pub force: bool,
    /// Continue an interrupted run from its checkpoint (.DIR.checkpoint beside --out DIR):
    /// the finished trigger speeds and capacity-map pieces are not redone, and the results
    /// are byte-identical to an uninterrupted run.
    #[arg(long)]
    pub resume: bool,
    /// Coarse grids (3 speeds, a 4 × 4 capacity map): a smoke run in seconds, not the report.
    #[arg(long)]
    pub quick: bool,
    /// Print the findings as JSON on stdout instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Worker threads (default: every core). Results do not depend on it.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u16).range(1..=divertsim_api::threads::MAX_THREADS as i64))]
    pub threads: Option<u16>,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Draw every figure into `dir`, as SVG and PNG.
pub fn draw_all(r: &Replication, dir: &Path) -> Result<(), String> {
    for ext in ["svg", "png"] {
        for (name, cases) in &r.paths_figures {
            paths::draw(cases, &dir.join(format!("{name}.{ext}"))).map_err(|e| e.to_string())?;
        }
        trigger::draw(&r.trigger, &dir.join(format!("trigger.{ext}")))?;
        capture::draw(&r.capture, &dir.join(format!("capture.{ext}")))?;
        overload::draw(&r.overload, &dir.join(format!("overload.{ext}")))
            .map_err(|e| e.to_string())?;
        divertsim_figures::capacity::draw(
            &r.capacity,
            divertsim_api::analyses::capacity::against(r.capacity_worst),
            &dir.join(format!("capacity.{ext}")),
        )
        .map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// index.html from the figures drawn into `dir`: [`divertsim_report::paper::replicate_index`].
pub fn index_html(r: &Replication, dir: &Path) -> Result<String, String> {
    let mut svgs = Vec::new();
    for f in &r.findings {
        if svgs.iter().any(|(name, _)| name == f.figure) {
            continue;
        }
        let svg = std::fs::read_to_string(dir.join(f.figure))
            .map_err(|e| format!("{}: {e}", f.figure))?;
        svgs.push((f.figure.to_string(), svg));
    }
    Ok(divertsim_report::paper::replicate_index(r, &svgs))
}

/// Run `divertsim replicate`; returns the exit code.
pub fn run(args: &ReplicateArgs) -> i32 {
    let mut problems = common::claim_problems(&args.out, args.force);
    // An installed binary run outside the repository: the built-in paper presets.
    let repository = Path::new("configs/paper");
    let builtin = (args.configs.is_none() && !repository.is_dir())
        .then(|| {
            let dir = tempfile::tempdir().ok()?;
            divertsim_api::presets::write_all(dir.path()).ok()?;
            Some(dir)
        })
        .flatten();
    let configs = match (&args.configs, &builtin) {
        (Some(c), _) => c.clone(),
        (None, Some(d)) => d.path().join("paper"),
        (None, None) => repository.to_path_buf(),
    };
    if !configs.is_dir() {
        problems.push(Problem::new("--configs", format!(
                "{} is not a directory; it must hold machine.toml and the fig*.toml files (run from the repository root, or pass --configs)",
                configs.display()
            )));
    }
    if let Err(code) = common::check(problems) {
        return code;
    }
    let inputs = match load_inputs(&configs) {
        Ok(i) => i,
        Err(p) => {
            let _ = common::check(p);
            return 2;
        }
    };
    let journal = match common::open_journal(
        Some(&args.out),
        args.resume,
        "replicate",
        &(&inputs, args.quick),
    ) {
        Ok(j) => j,
        Err(code) => return code,
    };
    // Its parts count their runs as they go; no total is known beforehand.
    let bar = crate::progress::progress_counter("replicate", "runs", args.quiet);
    let tick = || bar.inc(1);
    let result = divertsim_api::threads::with_threads(args.threads.map(usize::from), || {
        compute(&inputs, args.quick, &tick, common::memo_of(&journal))
    });
    bar.finish_and_clear();
    let r = match result {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return 3;
        }
    };
    let mut files = r.files.clone();
    files.push((
        "findings.json".into(),
        serde_json::to_vec_pretty(&findings_json(&r)).unwrap_or_default(),
    ));
    files.push(("findings.md".into(), findings_markdown(&r).into_bytes()));
    let code = common::write_outputs(&args.out, files, |dir| {
        draw_all(&r, dir)?;
        let index = index_html(&r, dir)?;
        std::fs::write(dir.join("index.html"), index).map_err(|e| format!("index.html: {e}"))
    });
    if code != 0 {
        return code;
    }
    common::close_journal(journal, 0);
    if args.json {
        common::emit_json(&findings_json(&r));
    } else {
        emit(&findings_text(&r));
    }
    0
}
