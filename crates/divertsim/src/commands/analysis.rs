//! The one runner of the analysis commands on the api's contract
//! ([`divertsim_api::contract`]): their flags come from the analysis's options type ([`crate::flags`]: its JSON
//! Schema: names, help texts, defaults), the run is the contract's lifecycle, and a command
//! keeps only its readable table and its plot. Error kinds become exit codes here, once.

use super::common::{self, OutputArgs, ResumeArgs, ScenarioArgs};
use crate::flags::{flags_for, flags_named, OptionArgs};
use divertsim_api::config::Loaded;
use divertsim_api::contract::{self, Analysis, Error, Hooks};
use divertsim_core::run::memo::Memo;
use serde_json::Value;
use std::path::Path;

/// Print an error of the api and give its exit code: invalid input 2 (its problems keyed
/// by flags), a failed run 3, I/O 1, interrupted 130. The one place the CLI maps kinds.
pub fn exit_code(e: Error) -> i32 {
    match e {
        Error::Invalid(p) => common::check(crate::flags::flags(p)).err().unwrap_or(2),
        Error::Failed(m) => {
            eprintln!("error: {m}");
            3
        }
        Error::Io(m) => {
            eprintln!("error: {m}");
            1
        }
        Error::Cancelled => {
            eprintln!("error: interrupted");
            130
        }
    }
}

/// [`exit_code`] with the problems keyed by the flags of analysis `A`.
pub fn exit_code_of<A: Analysis>(e: Error) -> i32 {
    match e {
        Error::Invalid(p) => exit_code(Error::Invalid(flags_for::<A>(p))),
        e => exit_code(e),
    }
}

/// The plot of an analysis's output into a path (.svg or .png).
pub type DrawOf<'a, A> = &'a dyn Fn(&<A as Analysis>::Output, &Path) -> Result<(), String>;
/// Files a command writes besides the tables, the summary and the scenario, into the
/// staging directory of `--out`: from the output, the scenario and the pieces the run kept
/// (its checkpoint's memo: a reliability run's shards).
pub type FilesOf<'a, A> =
    &'a dyn Fn(&<A as Analysis>::Output, &Loaded, &Path, &dyn Memo) -> Result<(), String>;

/// What a command draws and writes of its analysis's output (the readable report is the
/// api's [`Analysis::text`]).
pub struct View<'a, A: Analysis> {
    /// The plot, drawn as `<command>.svg` and `<command>.png`.
    pub draw: Option<DrawOf<'a, A>>,
    /// Other files.
    pub files: Option<FilesOf<'a, A>>,
    /// The exit code of a finished run (`None`: 0, whatever the result), e.g. a verdict
    /// that gates a review.
    pub exit: Option<ExitOf<'a, A>>,
}

/// The exit code of a finished run's output.
pub type ExitOf<'a, A> = &'a dyn Fn(&<A as Analysis>::Output) -> i32;

impl<'a, A: Analysis> View<'a, A> {
    /// A plot.
    pub fn new(draw: DrawOf<'a, A>) -> View<'a, A> {
        View {
            draw: Some(draw),
            files: None,
            exit: None,
        }
    }

    /// Files of the command's own (no plot of the standard name).
    pub fn files(files: FilesOf<'a, A>) -> View<'a, A> {
        View {
            draw: None,
            files: Some(files),
            exit: None,
        }
    }
}

/// Run analysis `A` from the command line: scenario and option problems reported together
/// (exit 2), `--out` claimed before the work, the work limit, the checkpoint with
/// `--resume`, progress, the run, then the files, JSON or table. Returns the exit code.
pub fn run<A: Analysis>(
    scenario: &ScenarioArgs,
    resume: Option<&ResumeArgs>,
    output: &OutputArgs,
    options: &OptionArgs<A>,
    view: View<'_, A>,
) -> i32 {
    let scenario_args = scenario.with_default_sets(A::DEFAULT_SETS);
    let loaded = common::load_scenario(&scenario_args, A::USES_TRIGGER);
    let given = Value::Object(options.given.clone());
    let checked = contract::options_from_json::<A::Options>(&given)
        .and_then(|o| A::validate(&o).map_err(Error::Invalid));
    if checked.is_ok() {
        for w in contract::option_warnings::<A>(&given) {
            eprintln!("{}", flags_named::<A>(&w.message));
        }
    }
    let mut problems = common::out_problems(output);
    let checked = match checked {
        Ok(c) => Some(c),
        Err(Error::Invalid(p)) => {
            problems.extend(flags_for::<A>(p));
            None
        }
        Err(e) => return exit_code_of::<A>(e),
    };
    let loaded = match common::checked(loaded, problems) {
        Ok(l) => l,
        Err(code) => return code,
    };
    let Some(checked) = checked else { return 2 };
    let checked = match A::bind(checked, &loaded) {
        Ok(c) => c,
        Err(p) => return common::check(flags_for::<A>(p)).err().unwrap_or(2),
    };
    let work = A::work(&checked, &loaded);
    let what = A::NAME.replace('_', " ");
    // How to ask for less work, in flags: for the refusal and for a run stopped at the limit.
    let smaller = flags_named::<A>(work.smaller);
    if let Err(code) = common::within_budget(&what, work.at_least, work.at_most, output, &smaller) {
        return code;
    }
    // A checkpoint only for a command that can resume from it (one left by an interrupted
    // compare or calibrate would refuse the next run with advice it cannot follow).
    let journal = match common::open_journal(
        resume.and(output.out.as_deref()),
        resume.is_some_and(|r| r.resume),
        A::NAME,
        &(&loaded.scenario, &loaded.design, &checked),
    ) {
        Ok(j) => j,
        Err(code) => return code,
    };
    let bar = crate::progress::progress_bar_of(
        work.units,
        &what,
        work.unit,
        output.quiet || work.units == 0,
    );
    // A count never runs past its total: work found beyond the estimate (another round of
    // a robust run) lengthens the bar.
    let tick = || {
        bar.inc(1);
        if bar.length().is_some_and(|n| bar.position() > n) {
            bar.set_length(bar.position());
        }
    };
    let more = |n: u64| bar.inc_length(n);
    // Live logs beside the checkpoint.
    let live_dir = journal.as_ref().map(|j| j.dir().to_path_buf());
    let live = move |name: &str| -> Option<Box<dyn std::io::Write + Send>> {
        let file = std::fs::File::create(live_dir.as_ref()?.join(name)).ok()?;
        Some(Box::new(file))
    };
    let hooks = Hooks {
        progress: &tick,
        more: &more,
        memo: common::memo_of(&journal),
        threads: output.threads.map(usize::from),
        live: Some(&live),
        ..Hooks::none()
    };
    let started = std::time::Instant::now();
    let limit = contract::Limit {
        max_sims: output.max_sims,
        key: "--max-sims",
        at_most: work.at_most,
        smaller: &smaller,
    };
    let result = contract::run_stoppable::<A>(&loaded, &checked, &hooks, &limit);
    // Stopped at the limit with a checkpoint: its finished pieces are not lost.
    let result = result.map_err(|e| match (e, &journal) {
        (Error::Invalid(mut p), Some(_)) if p.iter().any(|p| p.key == "--max-sims") => {
            for p in p.iter_mut().filter(|p| p.key == "--max-sims") {
                p.message.push_str(
                    "; the finished pieces are kept: the same command with --resume and a larger --max-sims goes on from them",
                );
            }
            Error::Invalid(p)
        }
        (e, _) => e,
    });
    bar.finish_and_clear();
    let result = match result.and_then(|r| A::tables(&r).map(|t| (r, t))) {
        Ok(r) => r,
        Err(e) => return common::close_journal(journal, exit_code_of::<A>(e)),
    };
    let (out, tables) = result;
    if let (Some(n), false) = (A::simulations(&out), output.quiet) {
        eprintln!(
            "{what}: {n} simulations in {:.1} s",
            started.elapsed().as_secs_f64()
        );
    }
    let name = A::NAME.replace('_', "-");
    let json = (output.json || output.out.is_some())
        .then(|| contract::describe::<A>(A::summary(&out, &checked, &loaded), &out, &loaded));
    if let Some(dir) = &output.out {
        let mut files = tables;
        files.push((
            "summary.json".to_string(),
            common::json_bytes(json.as_ref().unwrap_or(&Value::Null)),
        ));
        files.push(divertsim_api::output::scenario_toml(
            &name,
            A::described_file(&out, &loaded),
        ));
        let code = common::write_outputs(dir, files, |staging| {
            if let Some(draw) = view.draw {
                draw(&out, &staging.join(format!("{name}.svg")))?;
                draw(&out, &staging.join(format!("{name}.png")))?;
            }
            let kept = common::memo_of(&journal);
            view.files
                .map_or(Ok(()), |f| f(&out, &loaded, staging, kept))
        });
        if code != 0 {
            return common::close_journal(journal, code);
        }
    }
    match json {
        Some(j) if output.json => common::emit_json(&j),
        _ => common::emit(&A::text(&out, &checked, &loaded)),
    }
    // The run is finished whatever its verdict: its checkpoint goes.
    let code = common::close_journal(journal, 0);
    view.exit.map_or(code, |f| f(&out))
}
