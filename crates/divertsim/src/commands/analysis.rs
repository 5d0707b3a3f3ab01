//! The one runner of the analysis commands on the api's contract
//! ([`divertsim_api::contract`]): their flags come from the analysis's options type (its JSON
//! Schema: names, help texts, defaults), the run is the contract's lifecycle, and a command
//! keeps only its readable table and its plot. Error kinds become exit codes here, once.

use super::common::{self, OutputArgs, ResumeArgs, ScenarioArgs};
use clap::{Arg, ArgAction, ArgMatches, Command};
use divertsim_api::config::{Loaded, Problem};
use divertsim_api::contract::{self, Analysis, Error, Hooks};
use divertsim_core::run::memo::Memo;
use serde_json::{Map, Value};
use std::marker::PhantomData;
use std::path::Path;

/// How an option is written on the command line.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    /// `--name` alone sets it.
    Flag,
    /// A number.
    Number,
    /// Numbers separated by commas.
    Numbers,
    /// A text, given to the options as it is (a list or interval grammar).
    Text,
    /// Texts, one per use of the flag.
    Texts,
}

/// One option of an analysis: its name, kind, help text, default as text and, for a
/// choice, the values allowed.
#[derive(Debug, Clone)]
struct OptionSpec {
    name: String,
    /// The flag's long name: the option's, or the schema's `x-flag`; `no-NAME` for a
    /// switch that is on by default.
    flag: String,
    kind: Kind,
    help: String,
    default: Option<String>,
    choices: Vec<String>,
    /// The value's name in the help (the schema's `x-value`, else the option's name).
    value_name: String,
}

/// The values of a choice (a string enum, possibly behind a `$ref` or an optional one's
/// `anyOf`), else none.
fn choices_of(p: &Value, schema: &Value) -> Vec<String> {
    if let Some(Value::Array(variants)) = p.get("anyOf") {
        return variants
            .iter()
            .find(|v| v.get("type").and_then(Value::as_str) != Some("null"))
            .filter(|_| variants.len() == 2)
            .map_or_else(Vec::new, |v| choices_of(v, schema));
    }
    let target = p
        .get("$ref")
        .and_then(Value::as_str)
        .and_then(|r| r.strip_prefix("#/"))
        .and_then(|r| r.split('/').try_fold(schema, |v, k| v.get(k)))
        .unwrap_or(p);
    let strings = |v: &Value| -> Vec<String> {
        v.as_array()
            .map(|a| {
                a.iter()
                    .filter_map(|x| x.as_str().map(String::from))
                    .collect()
            })
            .unwrap_or_default()
    };
    match (target.get("enum"), target.get("oneOf")) {
        (Some(e), _) => strings(e),
        (None, Some(Value::Array(variants))) => variants
            .iter()
            .flat_map(|v| match v.get("const") {
                Some(c) => c.as_str().map(String::from).into_iter().collect(),
                None => v.get("enum").map(strings).unwrap_or_default(),
            })
            .collect(),
        _ => Vec::new(),
    }
}

/// A doc comment as help: lines of a paragraph joined, option names in backticks as flags,
/// and one paragraph without its final period (as clap does with doc comments).
fn help_of(doc: &str) -> String {
    let text = doc
        .split("\n\n")
        .map(|para| para.lines().map(str::trim).collect::<Vec<_>>().join(" "))
        .collect::<Vec<_>>()
        .join("\n\n");
    let text = common::flags_in(&text);
    match text.contains("\n\n") {
        true => text,
        false => text.strip_suffix('.').unwrap_or(&text).to_string(),
    }
}

/// The options of `A` from its JSON Schema, by name.
fn option_specs<A: Analysis>() -> Vec<OptionSpec> {
    let schema = serde_json::to_value(schemars::schema_for!(A::Options)).unwrap_or_default();
    let Some(props) = schema.get("properties").and_then(Value::as_object) else {
        return Vec::new();
    };
    let mut specs: Vec<OptionSpec> = props
        .iter()
        .map(|(name, p)| {
            // The type, a nullable one (`["integer", "null"]`) as its other type.
            let ty = match p.get("type") {
                Some(Value::Array(types)) => types
                    .iter()
                    .filter_map(Value::as_str)
                    .find(|t| *t != "null"),
                t => t.and_then(Value::as_str),
            };
            let texts = p.get("x-repeat") == Some(&Value::Bool(true))
                || p.pointer("/items/type").and_then(Value::as_str) == Some("string");
            let kind = match ty {
                _ if texts => Kind::Texts,
                Some("boolean") => Kind::Flag,
                Some("number" | "integer") => Kind::Number,
                Some("array") => Kind::Numbers,
                _ => Kind::Text,
            };
            let on = kind == Kind::Flag && p.get("default") == Some(&Value::Bool(true));
            let flag = match (p.get("x-flag").and_then(Value::as_str), on) {
                (Some(f), _) => f.to_string(),
                (None, true) => format!("no-{}", name.replace('_', "-")),
                (None, false) => name.replace('_', "-"),
            };
            let default = p.get("default").and_then(|d| match d {
                Value::Bool(_) | Value::Null => None,
                Value::String(s) => Some(s.clone()),
                Value::Array(v) if v.is_empty() => None,
                // An interval [lo, hi] is written LO:HI, a list of numbers A,B.
                Value::Array(v) if kind == Kind::Text => {
                    Some(v.iter().map(Value::to_string).collect::<Vec<_>>().join(":"))
                }
                Value::Array(v) => {
                    Some(v.iter().map(Value::to_string).collect::<Vec<_>>().join(","))
                }
                other => Some(other.to_string()),
            });
            OptionSpec {
                name: name.clone(),
                flag,
                kind,
                help: p
                    .get("description")
                    .and_then(Value::as_str)
                    .unwrap_or("")
                    .to_string(),
                default,
                choices: choices_of(p, &schema),
                value_name: p
                    .get("x-value")
                    .and_then(Value::as_str)
                    .map_or_else(|| name.to_uppercase(), String::from),
            }
        })
        .collect();
    // The help texts, option names in backticks as their flags; a switch that is on by
    // default is turned off by its flag.
    let named = specs.clone();
    for spec in &mut specs {
        spec.help = help_of(&flags_of_names(&named, &spec.help));
        if spec.kind == Kind::Flag && spec.flag.starts_with("no-") {
            let mut chars = spec.help.chars();
            let first = chars.next().map(|c| c.to_lowercase().to_string());
            spec.help = format!("Turn off {}{}", first.unwrap_or_default(), chars.as_str());
        }
    }
    specs
}

/// The options of analysis `A` given on the command line, as the JSON object its options
/// type reads (options not given keep the type's defaults).
pub struct OptionArgs<A> {
    /// The options given, by option name.
    pub given: Map<String, Value>,
    analysis: PhantomData<fn() -> A>,
}

impl<A> Clone for OptionArgs<A> {
    fn clone(&self) -> Self {
        OptionArgs {
            given: self.given.clone(),
            analysis: PhantomData,
        }
    }
}

impl<A> std::fmt::Debug for OptionArgs<A> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OptionArgs")
            .field("given", &self.given)
            .finish()
    }
}

impl<A: Analysis> clap::FromArgMatches for OptionArgs<A> {
    fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
        let mut given = Map::new();
        for spec in option_specs::<A>() {
            let from_user =
                m.value_source(&spec.name) == Some(clap::parser::ValueSource::CommandLine);
            if !from_user {
                continue;
            }
            let value = match spec.kind {
                // A switch on by default: its flag turns it off.
                Kind::Flag => Value::Bool(m.get_flag(&spec.name) != spec.flag.starts_with("no-")),
                Kind::Texts => Value::Array(
                    m.get_many::<String>(&spec.name)
                        .into_iter()
                        .flatten()
                        .map(|t| Value::String(t.clone()))
                        .collect(),
                ),
                _ => {
                    let text = m.get_one::<String>(&spec.name).cloned().unwrap_or_default();
                    json_of(spec.kind, &text)
                }
            };
            given.insert(spec.name, value);
        }
        Ok(OptionArgs {
            given,
            analysis: PhantomData,
        })
    }

    fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

/// A flag's text as the JSON the options type reads; a text that is not what the kind
/// needs stays a text, so that the options type names the option in its problem.
fn json_of(kind: Kind, text: &str) -> Value {
    let number = |t: &str| -> Option<Value> {
        let t = t.trim();
        t.parse::<u64>()
            .ok()
            .map(Value::from)
            .or_else(|| t.parse::<i64>().ok().map(Value::from))
            .or_else(|| {
                t.parse::<f64>()
                    .ok()
                    .and_then(serde_json::Number::from_f64)
                    .map(Value::Number)
            })
    };
    let fallback = || Value::String(text.to_string());
    match kind {
        Kind::Number => number(text).unwrap_or_else(fallback),
        Kind::Numbers => text
            .split(',')
            .map(number)
            .collect::<Option<Vec<Value>>>()
            .map(Value::Array)
            .unwrap_or_else(fallback),
        Kind::Flag | Kind::Text | Kind::Texts => fallback(),
    }
}

impl<A: Analysis> clap::Args for OptionArgs<A> {
    fn augment_args(mut cmd: Command) -> Command {
        for spec in option_specs::<A>() {
            let mut arg = Arg::new(spec.name.clone())
                .long(spec.flag.clone())
                .help(spec.help.clone());
            arg = match spec.kind {
                Kind::Flag => arg.action(ArgAction::SetTrue),
                Kind::Texts => arg
                    .action(ArgAction::Append)
                    .value_name(spec.value_name.clone())
                    .allow_hyphen_values(true),
                _ => arg
                    .action(ArgAction::Set)
                    .value_name(spec.value_name.clone())
                    .allow_hyphen_values(true),
            };
            if let Some(d) = spec.default {
                arg = arg.default_value(d);
            }
            if !spec.choices.is_empty() {
                arg = arg.value_parser(clap::builder::PossibleValuesParser::new(spec.choices));
            }
            cmd = cmd.arg(arg);
        }
        cmd
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}

/// Print an error of the api and give its exit code: invalid input 2 (its problems keyed
/// by flags), a failed run 3, I/O 1, interrupted 130. The one place the CLI maps kinds.
pub fn exit_code(e: Error) -> i32 {
    match e {
        Error::Invalid(p) => common::check(common::flags(p)).err().unwrap_or(2),
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

/// Problems keyed by option names as problems keyed by the flags of analysis `A` (an
/// option's own flag name, `--no-NAME` for a switch on by default), option names in
/// backticks in the messages too; other keys as [`common::flags`] gives them.
pub fn flags_for<A: Analysis>(problems: Vec<Problem>) -> Vec<Problem> {
    let specs = option_specs::<A>();
    let problems = problems.into_iter().map(|p| {
        let message = flags_of_names(&specs, &p.message);
        match specs.iter().find(|s| s.name == p.key) {
            Some(spec) => Problem::new(format!("--{}", spec.flag), message),
            None => Problem::new(p.key, message),
        }
    });
    common::flags(problems.collect())
}

/// Option names in backticks in an api text (`` `speeds` ``) as their flags (`--speeds`).
fn flags_of_names(specs: &[OptionSpec], text: &str) -> String {
    specs.iter().fold(text.to_string(), |t, spec| {
        t.replace(&format!("`{}`", spec.name), &format!("--{}", spec.flag))
    })
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
        let specs = option_specs::<A>();
        for w in contract::option_warnings::<A>(&given) {
            eprintln!("{}", flags_of_names(&specs, &w.message));
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
    let smaller = flags_of_names(&option_specs::<A>(), work.smaller);
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
    let bar = common::progress_bar_of(
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
