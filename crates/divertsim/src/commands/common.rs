//! What every analysis command shares: the scenario arguments (file + `--set`), the output
//! arguments (`--out`, `--json`, `--threads`, `--quiet`), the work limit, the checkpoint's
//! opening and the all-or-nothing output directory.

use crate::checkpoint::{self, Journal};
use crate::outdir;
use divertsim_api::config::{self, Loaded};
use divertsim_core::run::memo::{Memo, NoMemo};
use std::path::{Path, PathBuf};

/// The scenario a command starts from.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are --help text: [m] is a unit
#[derive(Debug, Clone, clap::Args)]
pub struct ScenarioArgs {
    /// Scenario file (TOML), or `-` for standard input: machine, materials, limits (and a
    /// parcel where the command uses one). Without it, the built-in default (`divertsim example` prints it). The paper's
    /// machine preset is configs/paper/machine.toml.
    pub scenario: Option<PathBuf>,
    /// Override a scenario key by dotted path with a TOML value, e.g.
    /// machine.cycle_time=1.3 (a bare word such as adaptive is a string). Repeatable;
    /// validated like the file. A file path given here (machine.drive.table, mix.records,
    /// line.arrivals), quoted or bare (mix.records=dims.csv), is relative to the working
    /// directory.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Let the scenario read files outside its own directory: an absolute path, one with a
    /// `..` component or a symbolic link leading out, in base, machine.drive.table,
    /// mix.records or line.arrivals (in a --set, outside the working directory). Without it
    /// they are refused, so that a scenario file from elsewhere reads only the files beside it
    /// or below it. Files divertsim writes need it only for mix.records and line.arrivals,
    /// which they keep as absolute paths.
    #[arg(long)]
    pub allow_outside_paths: bool,
}

impl ScenarioArgs {
    /// How to load the scenario.
    pub fn load_options(&self) -> config::LoadOptions {
        config::LoadOptions {
            allow_outside_paths: self.allow_outside_paths,
            ..Default::default()
        }
    }

    /// These arguments with `defaults` (`KEY=VALUE` texts) applied first when no scenario
    /// file is given: a command's own default case, which the user's `--set` still overrides.
    pub fn with_default_sets(&self, defaults: &[&str]) -> ScenarioArgs {
        let mut args = self.clone();
        if args.scenario.is_none() {
            args.sets = defaults
                .iter()
                .map(|s| s.to_string())
                .chain(self.sets.iter().cloned())
                .collect();
        }
        args
    }
}

/// Where and how a command writes its results.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are --help text: [m] is a unit
#[derive(Debug, Clone, clap::Args)]
pub struct OutputArgs {
    /// Write the table (CSV), the plots (SVG, PNG), summary.json (the --json object with the
    /// version, units and resolved scenario) and scenario.toml (`paths`: one
    /// scenario_CASE.toml per case) into DIR, all or nothing: DIR
    /// appears whole when the command succeeds and not at all otherwise. DIR must not exist
    /// yet (an empty directory is fine) unless --force; a mount point is refused (give a folder
    /// inside it).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Replace an existing --out DIR whole (nothing of the old one is kept).
    #[arg(long, requires = "out")]
    pub force: bool,
    /// Print the result as JSON on stdout instead of the readable table.
    #[arg(long)]
    pub json: bool,
    /// Worker threads (default: every core). Results do not depend on it.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u16).range(1..=divertsim_api::threads::MAX_THREADS as i64))]
    pub threads: Option<u16>,
    /// No progress (a bar in a terminal; a plain line every 10 s into a log or a pipe).
    #[arg(long, short)]
    pub quiet: bool,
    /// The work limit: refuse a run that needs more simulations than N whatever its
    /// verdicts, and stop one whose count passes N (the count or its range is printed when
    /// a run starts; a simulation takes about 1-10 ms of one core).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_SIMS)]
    pub max_sims: u64,
}

use divertsim_api::analyses::DEFAULT_MAX_SIMS;

/// Check a run's certain work (`at_least` simulations) against `--max-sims` before it
/// starts: above it, the problem is reported (exit code 2); else the work is printed unless
/// `--quiet` (with its upper bound `at_most` where known). A run that may need more than the
/// limit starts, and is stopped when it passes it. `smaller` says how to ask for less work.
pub fn within_budget(
    what: &str,
    at_least: u64,
    at_most: Option<u64>,
    output: &OutputArgs,
    smaller: &str,
) -> Result<(), i32> {
    if let Some(p) =
        divertsim_api::analyses::over_budget(what, at_least, output.max_sims, "--max-sims", smaller)
    {
        return check(vec![p]);
    }
    if !output.quiet {
        eprintln!(
            "{}",
            divertsim_api::analyses::work_text(what, at_least, at_most)
        );
    }
    Ok(())
}

/// `--resume` of the long commands (`capacity`, `trigger`, `optimize`, `replicate`, `line`,
/// `reliability`).
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are --help text: [m] is a unit
#[derive(Debug, Clone, clap::Args)]
pub struct ResumeArgs {
    /// Continue an interrupted run from its checkpoint (.DIR.checkpoint beside --out DIR,
    /// kept while a run with --out works): finished work is not redone, and the results are
    /// byte-identical to an uninterrupted run. Needs the same command line and scenario.
    #[arg(long, requires = "out")]
    pub resume: bool,
}

/// Open the checkpoint of a run with `--out` (none without): `inputs` is everything that
/// shapes the result. A problem with it is reported like an input problem (exit code 2);
/// what is resumed is said, even with `--quiet` (it is not progress: it says what the
/// results are made of).
pub fn open_journal(
    out: Option<&Path>,
    resume: bool,
    command: &str,
    inputs: &impl std::fmt::Debug,
) -> Result<Option<Journal>, i32> {
    let Some(out) = out else { return Ok(None) };
    let fp = checkpoint::fingerprint(command, inputs);
    let dir = checkpoint::dir_of(out);
    if resume && !dir.exists() {
        eprintln!(
            "note: no checkpoint at {}: starting from the beginning",
            dir.display()
        );
    }
    match checkpoint::open(out, &fp, resume) {
        Ok(j) => {
            // Gone with the publication, under its lock.
            outdir::retire_on_publish(out, dir.clone());
            if j.recalled() > 0 {
                eprintln!(
                    "resuming: {} finished pieces recalled from {}",
                    j.recalled(),
                    dir.display()
                );
            }
            Ok(Some(j))
        }
        Err(message) => check(vec![config::Problem::new("--resume", message)]).map(|()| None),
    }
}

/// The memo of an optional checkpoint.
pub fn memo_of(journal: &Option<Journal>) -> &dyn Memo {
    match journal {
        Some(j) => j,
        None => &NoMemo,
    }
}

/// After a successful run, its checkpoint goes.
pub fn close_journal(journal: Option<Journal>, code: i32) -> i32 {
    if code == 0 {
        if let Some(j) = journal {
            j.remove();
        }
    }
    code
}

/// Load and validate the scenario; on bad input print every problem and return exit code 2.
/// A command that chooses or fixes R_s itself (`uses_trigger` false: all but the line and
/// reliability, [`divertsim_api::contract::Analysis::USES_TRIGGER`]) refuses the per-parcel
/// trigger, as the contract's `execute` does.
pub fn load_scenario(args: &ScenarioArgs, uses_trigger: bool) -> Result<Loaded, i32> {
    let loaded = config::load_with(args.scenario.as_deref(), &args.sets, args.load_options())
        .and_then(|l| match uses_trigger {
            true => Ok(l),
            false => divertsim_api::analyses::fixed_trigger_only(l),
        });
    loaded.map_err(|problems| {
        eprint!("error: {problems}");
        2
    })
}

/// The loaded scenario, once the command's own option problems are reported too: every
/// problem is printed (the scenario's first), exit code 2 if there is any.
pub fn checked(loaded: Result<Loaded, i32>, problems: Vec<config::Problem>) -> Result<Loaded, i32> {
    match loaded {
        Ok(l) => check(problems).map(|()| l),
        Err(code) => {
            let _ = check(problems);
            Err(code)
        }
    }
}

/// Report command-line problems like scenario problems (exit code 2) when there are any.
pub fn check(problems: Vec<config::Problem>) -> Result<(), i32> {
    if problems.is_empty() {
        Ok(())
    } else {
        eprint!("error: {}", config::Problems(problems));
        Err(2)
    }
}

/// Write `files` and whatever `render` draws into the staging directory, then move it to
/// `dir` (all or nothing). Returns the exit code: 0, or 1 with the error printed.
pub fn write_outputs(
    dir: &Path,
    files: Vec<(String, Vec<u8>)>,
    mut render: impl FnMut(&Path) -> Result<(), String>,
) -> i32 {
    match outdir::publish(dir, &files, &mut render) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}

/// Claim `--out DIR` before any simulation runs ([`outdir::claim`]): it must not exist
/// unless `--force`, no other run may be writing it, and its location must be writable.
pub fn out_problems(out: &OutputArgs) -> Vec<config::Problem> {
    match &out.out {
        Some(d) => claim_problems(d, out.force),
        None => Vec::new(),
    }
}

/// [`outdir::claim`] as a problem with the `--out` option.
pub fn claim_problems(dir: &Path, force: bool) -> Vec<config::Problem> {
    match outdir::claim(dir, force) {
        Ok(()) => Vec::new(),
        Err(message) => vec![config::Problem::new("--out", message)],
    }
}

/// Print to stdout; a closed pipe is not an error.
pub fn emit(text: &str) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    let _ = out.write_all(text.as_bytes()).and_then(|_| out.flush());
}

/// Print a JSON value on stdout: pretty, with a final newline.
pub fn emit_json(value: &serde_json::Value) {
    emit(&String::from_utf8_lossy(&json_bytes(value)));
}

/// A JSON file's bytes: pretty, with a final newline.
pub fn json_bytes(value: &serde_json::Value) -> Vec<u8> {
    let mut b = serde_json::to_vec_pretty(value).unwrap_or_default();
    b.push(b'\n');
    b
}
