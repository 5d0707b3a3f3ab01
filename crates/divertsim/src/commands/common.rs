//! What every analysis command shares: the scenario arguments (file + `--set`), the output
//! arguments (`--out`, `--json`, `--threads`, `--quiet`), the worker pool, the progress bar and
//! the all-or-nothing output directory.

use crate::checkpoint::{self, Journal};
use crate::outdir;
use divertsim_api::config::{self, Loaded};
use divertsim_core::run::memo::{Memo, NoMemo};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
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

pub use divertsim_api::analyses::{count_text, DEFAULT_MAX_SIMS};

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

/// Seconds between the plain progress lines written when stderr is not a terminal.
pub const PLAIN_PROGRESS_EVERY: f64 = 10.0;

/// The plain-line interval: [`PLAIN_PROGRESS_EVERY`], or DIVERTSIM_PROGRESS_SECONDS.
fn plain_interval() -> f64 {
    std::env::var("DIVERTSIM_PROGRESS_SECONDS")
        .ok()
        .and_then(|v| v.parse::<f64>().ok())
        .filter(|v| v.is_finite() && *v >= 0.0)
        .unwrap_or(PLAIN_PROGRESS_EVERY)
}

/// A progress display for a log file or a pipe: the bar's line, printed as a plain line at
/// most every [`PLAIN_PROGRESS_EVERY`] seconds (none for a run shorter than that).
#[derive(Debug)]
struct PlainLines {
    state: std::sync::Mutex<(std::time::Instant, String)>,
}

impl indicatif::TermLike for PlainLines {
    fn width(&self) -> u16 {
        100
    }
    fn move_cursor_up(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn move_cursor_down(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn move_cursor_right(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn move_cursor_left(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn write_line(&self, s: &str) -> std::io::Result<()> {
        self.write_str(s)
    }
    fn write_str(&self, s: &str) -> std::io::Result<()> {
        if !s.trim().is_empty() {
            if let Ok(mut st) = self.state.lock() {
                st.1 = s.trim_end().to_string();
            }
        }
        Ok(())
    }
    fn clear_line(&self) -> std::io::Result<()> {
        Ok(())
    }
    fn flush(&self) -> std::io::Result<()> {
        if let Ok(mut st) = self.state.lock() {
            if st.0.elapsed().as_secs_f64() >= plain_interval() && !st.1.is_empty() {
                eprintln!("{}", st.1.trim());
                st.0 = std::time::Instant::now();
            }
        }
        Ok(())
    }
}

/// A progress bar on stderr counting runs: drawn in a terminal, written as a plain line every
/// [`PLAIN_PROGRESS_EVERY`] s into a log or a pipe, hidden with `--quiet`.
pub fn progress_bar(len: u64, what: &str, quiet: bool) -> ProgressBar {
    progress_bar_of(len, what, "runs", quiet)
}

/// A progress line for work whose total is not known before it runs: the count so far and
/// the time, no bar, no total (never "38934/0 runs").
pub fn progress_counter(what: &str, unit: &str, quiet: bool) -> ProgressBar {
    let bar = progress_bar_of(0, what, unit, quiet);
    if let Ok(style) = ProgressStyle::with_template(&counter_template(unit)) {
        bar.set_style(style);
    }
    bar
}

/// The line of [`progress_counter`]: the count and the time, no total.
fn counter_template(unit: &str) -> String {
    format!("{{msg:>12}} {{pos}} {unit} so far, {{elapsed}} elapsed")
}

/// [`progress_bar`] counting `unit` ("runs", "pieces", "speeds").
pub fn progress_bar_of(len: u64, what: &str, unit: &str, quiet: bool) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let bar = if std::io::stderr().is_terminal() {
        ProgressBar::new(len)
    } else {
        let plain = PlainLines {
            state: std::sync::Mutex::new((std::time::Instant::now(), String::new())),
        };
        ProgressBar::with_draw_target(
            Some(len),
            indicatif::ProgressDrawTarget::term_like_with_hz(Box::new(plain), 1),
        )
    };
    if let Ok(style) = ProgressStyle::with_template(&format!(
        "{{msg:>12}} [{{bar:40}}] {{pos}}/{{len}} {unit}, {{elapsed}} elapsed, eta {{eta}}"
    )) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(what.to_string());
    // Redrawn every second even between ticks (a long piece, a worst-case search), so the
    // elapsed time moves and a log still gets its plain lines.
    bar.enable_steady_tick(std::time::Duration::from_secs(1));
    bar
}

/// The scenario file's sections: keys of problems that stay as they are.
const SECTIONS: [&str; 10] = [
    "base",
    "machine",
    "parcel",
    "materials",
    "run",
    "limits",
    "optimize",
    "design",
    "mix",
    "camera",
];

/// The api's problems keyed by option names (`scan_step`) as the command line's flags
/// (`--scan-step`); scenario keys (`machine.belt_speed`) and flags stay as they are. An
/// option the message names in backticks becomes its flag too.
pub fn flags(problems: Vec<config::Problem>) -> Vec<config::Problem> {
    problems
        .into_iter()
        .map(|p| {
            let message = flags_in(&p.message);
            match p.key.contains(['.', '-', ' ']) || SECTIONS.contains(&p.key.as_str()) {
                true => config::Problem::new(p.key, message),
                false => config::Problem::new(flag_of(&p.key), message),
            }
        })
        .collect()
}

/// Option names in backticks (`` `worst` ``) as flags (`--worst`).
pub fn flags_in(text: &str) -> String {
    let parts: Vec<&str> = text.split('`').collect();
    let mut out = String::new();
    for (i, part) in parts.iter().enumerate() {
        let name = i % 2 == 1 && i + 1 < parts.len();
        match name && !part.is_empty() && part.chars().all(|c| c.is_ascii_lowercase() || c == '_') {
            true => out += &flag_of(part),
            false if name => out += &format!("`{part}`"),
            false => out += part,
        }
    }
    out
}

/// The flag of an option name: `scan_step` → `--scan-step`.
pub fn flag_of(name: &str) -> String {
    format!("--{}", name.replace('_', "-"))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 50, item 6: replicate's progress read "38934/0 runs"; a count without a known
    /// total shows no total and no bar.
    #[test]
    fn a_progress_count_without_a_total_shows_none() {
        let t = counter_template("runs");
        assert!(!t.contains("{len}") && !t.contains("{bar"), "{t}");
        let bar = progress_counter("replicate", "runs", false);
        bar.set_position(38934);
        assert_eq!(bar.length(), Some(0));
        bar.finish_and_clear();
    }

    #[test]
    fn counts_are_grouped() {
        for (n, t) in [
            (0, "0"),
            (999, "999"),
            (1000, "1,000"),
            (10_000_000, "10,000,000"),
            (123_456_789, "123,456,789"),
        ] {
            assert_eq!(count_text(n), t);
        }
    }
}
