//! One contract per analysis: what every edge (the CLI, Python, a server) calls.
//!
//! An analysis declares one public options type ([`Analysis::Options`]: serde, `Default`, its
//! JSON Schema, doc comments that are its help text), checks it once ([`Analysis::validate`]:
//! checked inputs, or problems keyed by option name), binds them to the scenario
//! ([`Analysis::bind`]: the bound inputs, the only thing a run takes), states its work before it starts
//! ([`Analysis::work`]), and runs on a loaded scenario with one [`Hooks`] type for progress,
//! cancellation, the checkpoint memo and the thread count ([`Analysis::run`]). Its typed output
//! becomes a serializable summary and named tables ([`Analysis::summary`],
//! [`Analysis::tables`]). [`execute`] is that lifecycle for JSON options; the registry
//! ([`crate::analyses::registry`]) lists the analyses on the contract by name. An edge adds only its own form: flags and
//! files (the CLI), keyword arguments and exceptions (Python).

use crate::config::{Loaded, Problem, Problems, ScenarioFile};
use divertsim_core::run::memo::{Memo, NoMemo};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

/// Why an analysis did not give its result. Every edge maps these kinds in one place (the
/// CLI to exit codes, Python to exception classes).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// The scenario or the options are invalid: every problem, keyed by scenario key or
    /// option name.
    #[error("{}", Problems(.0.clone()))]
    Invalid(Vec<Problem>),
    /// It ran and could not give a result (e.g. the trigger's reference run is diverted).
    #[error("{0}")]
    Failed(String),
    /// A table or file could not be written or read.
    #[error("{0}")]
    Io(String),
    /// The caller's [`Hooks::stop`] asked it to stop; nothing is returned.
    #[error("interrupted")]
    Cancelled,
}

impl Error {
    /// A run that could not give its result, for the reason `e`.
    pub fn failed(e: impl std::fmt::Display) -> Error {
        Error::Failed(e.to_string())
    }

    /// A table or file that could not be formatted, written or read, for the reason `e`.
    pub fn io(e: impl std::fmt::Display) -> Error {
        Error::Io(e.to_string())
    }
}

impl From<Problems> for Error {
    fn from(p: Problems) -> Error {
        Error::Invalid(p.0)
    }
}

impl From<Vec<Problem>> for Error {
    fn from(p: Vec<Problem>) -> Error {
        Error::Invalid(p)
    }
}

/// What a run may call while it works, one type for every analysis.
pub struct Hooks<'a> {
    /// One tick per unit of [`Work::units`].
    pub progress: &'a (dyn Fn() + Sync),
    /// More units than [`Work::units`] announced while running (a robust map's next round).
    pub more: &'a (dyn Fn(u64) + Sync),
    /// Asked between pieces of work: `true` ends the run with [`Error::Cancelled`].
    pub stop: &'a (dyn Fn() -> bool + Sync),
    /// Finished pieces kept by the caller (a checkpoint), recalled bit for bit.
    pub memo: &'a dyn Memo,
    /// Worker threads (`None`: every core). Results do not depend on it.
    pub threads: Option<usize>,
    /// Opens a named live log beside the caller's checkpoint (the optimiser's
    /// `evaluations-N.csv`, written as the run goes); `None`: nothing is logged live.
    /// Results do not depend on it.
    pub live: Option<&'a LiveLog>,
}

/// Opens the live log of a given file name, or `None` if it cannot be made (Send: a run may
/// write it from the thread that tallies).
pub type LiveLog = dyn Fn(&str) -> Option<Box<dyn std::io::Write + Send>> + Sync;

fn no_tick() {}
fn no_more(_: u64) {}
fn never() -> bool {
    false
}

impl Hooks<'_> {
    /// A place where the run may stop without ticking: a piece of work that is not a unit
    /// of progress (a calibration before the sweep, a step between ticks). Under
    /// [`run_stoppable`] (every [`execute`]) a stop unwinds from here like a tick's; a
    /// caller whose `stop` never says so pays one call.
    pub fn stop_point(&self) {
        if (self.stop)() {
            std::panic::resume_unwind(Box::new(Stopped));
        }
    }
}

impl Hooks<'static> {
    /// No progress, never stopped, nothing kept, every core.
    pub fn none() -> Hooks<'static> {
        Hooks {
            progress: &no_tick,
            more: &no_more,
            stop: &never,
            memo: &NoMemo,
            threads: None,
            live: None,
        }
    }
}

/// The work a checked run will do, known before it starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Work {
    /// The most simulations the run can do, where a bound is known before it (a robust
    /// map's later rounds are not: they are announced as they start).
    pub at_most: Option<u64>,
    /// The simulations the run does whatever its verdicts (a lower bound): a run is
    /// refused before it starts only when this is above the work limit `max_sims`, and
    /// stopped while it runs when its count passes the limit.
    pub at_least: u64,
    /// Units of progress ([`Hooks::progress`] ticks this many times).
    pub units: u64,
    /// What a unit is ("speeds", "runs").
    pub unit: &'static str,
    /// How to ask for less work, option names in backticks (`` use fewer `speeds` ``).
    pub smaller: &'static str,
}

/// One analysis's contract (module notes).
pub trait Analysis {
    /// Its name: the registry's key, the CLI's command (with `-` for `_`), Python's
    /// `analysis(name)`, the summary's `divertsim.command`.
    const NAME: &'static str;
    /// What it computes, in one sentence without a final period: the CLI command's about
    /// line, the first line of Python's docstring.
    const ABOUT: &'static str;
    /// Scenario overrides (`KEY=VALUE`) applied to the built-in default scenario when none
    /// is given: the analysis's own default case (the paper's figure parcel).
    const DEFAULT_SETS: &'static [&'static str] = &[];
    /// Whether the analysis runs the scenario's own trigger (fixed or adaptive); the others
    /// set R_s themselves and refuse `machine.trigger = "adaptive"`.
    const USES_TRIGGER: bool = false;
    /// Whether it reads files named in its options (track files): an edge that must read no
    /// file beyond the scenario's own (the studio) does not offer it.
    const READS_FILES: bool = false;
    /// The options as a user writes them.
    type Options: Serialize + DeserializeOwned + Default + schemars::JsonSchema + Clone;
    /// The options once checked, before any scenario.
    type Checked: std::fmt::Debug + Sync;
    /// The checked options bound to a scenario ([`Analysis::bind`]): with what they derive
    /// from it (a search box, sweep points, tracks), everything that shapes the result (a
    /// checkpoint's fingerprint). Work and run take it, so nothing is derived twice; an
    /// analysis that derives nothing binds to its checked type itself (after its checks
    /// against the scenario, if any).
    type Bound: std::fmt::Debug + Sync;
    /// The typed result.
    type Output: Send;

    /// The checked options, or every problem keyed by option name.
    fn validate(options: &Self::Options) -> Result<Self::Checked, Vec<Problem>>;
    /// The checked options bound to this scenario, before any work (what they derive from
    /// it read or derived once, here), or the problems (keyed by option name or scenario
    /// key). An analysis that derives nothing binds to its checked options as they are.
    fn bind(checked: Self::Checked, scenario: &Loaded) -> Result<Self::Bound, Vec<Problem>>;
    /// Warnings on its options besides the list grammar's on `ValueList` options (a
    /// sweep's values read as a step), each keyed by its option; the run goes on.
    fn warnings(_options: &Self::Options) -> Vec<Problem> {
        Vec::new()
    }
    /// The work of a bound run on `scenario` (its design set may size it).
    fn work(bound: &Self::Bound, scenario: &Loaded) -> Work;
    /// Run on a loaded scenario (already refused if it uses the per-parcel trigger).
    fn run(scenario: &Loaded, bound: &Self::Bound, hooks: &Hooks) -> Result<Self::Output, Error>;
    /// The JSON summary (before [`crate::output::describe`] adds version and scenario).
    fn summary(output: &Self::Output, bound: &Self::Bound, scenario: &Loaded) -> Value;
    /// The tidy tables by file name (CSV with unit-suffixed columns).
    fn tables(output: &Self::Output) -> Result<Vec<(String, Vec<u8>)>, Error>;
    /// The readable report: what the CLI prints without `--json`, Python's `text`.
    fn text(output: &Self::Output, bound: &Self::Bound, scenario: &Loaded) -> String;
    /// The scenario file the summary describes: the scenario's (a sweep's analysis: its
    /// first point's).
    fn described_file<'a>(_output: &'a Self::Output, scenario: &'a Loaded) -> &'a ScenarioFile {
        &scenario.file
    }
    /// The scenarios the summary describes when there are several (a comparison's tracks,
    /// each with its experiment's scenario), by name; `None`: [`Analysis::described_file`].
    fn described_runs(_output: &Self::Output) -> Option<Vec<(&str, &ScenarioFile)>> {
        None
    }
    /// The simulations the run did, where it counts them (an edge may report them).
    fn simulations(_output: &Self::Output) -> Option<u64> {
        None
    }
}

/// What [`execute`] gives: the described summary and the tables.
#[derive(Debug, Clone)]
pub struct Report {
    /// The summary, self-describing (version, command, units, scenario).
    pub summary: Value,
    /// The tidy tables, e.g. `("trigger.csv", bytes)`.
    pub tables: Vec<(String, Vec<u8>)>,
    /// The readable report ([`Analysis::text`]).
    pub text: String,
}

/// The scenario for `extra` overrides; `&[]` for the scenario itself.
pub type Loader<'a> = &'a dyn Fn(&[String]) -> Result<Loaded, Problems>;

/// The options of an analysis from a JSON object: unknown names, wrong types and a
/// non-object are problems keyed by the option's name; `null` is the default.
pub fn options_from_json<T: DeserializeOwned + Serialize + Default>(v: &Value) -> Result<T, Error> {
    let mut v = if v.is_null() { json!({}) } else { v.clone() };
    if !v.is_object() {
        return Err(Error::Invalid(vec![Problem::new(
            "options",
            "expected a mapping of option names to values",
        )]));
    }
    if let Some(m) = v.as_object_mut() {
        m.retain(|_, x| !x.is_null());
    }
    // The names the options have (`deny_unknown_fields` does not work with flattened
    // groups): those of the defaults.
    let known = serde_json::to_value(T::default()).unwrap_or_default();
    if let (Some(given), Some(known)) = (v.as_object(), known.as_object()) {
        let unknown: Vec<Problem> = given
            .keys()
            .filter(|k| !known.contains_key(*k))
            .map(|k| {
                let mut names: Vec<&str> = known.keys().map(String::as_str).collect();
                names.sort_unstable();
                Problem::new(
                    k.clone(),
                    format!("unknown option; allowed: {}", names.join(", ")),
                )
            })
            .collect();
        if !unknown.is_empty() {
            return Err(Error::Invalid(unknown));
        }
    }
    serde_path_to_error::deserialize::<_, T>(v.clone()).map_err(|e| {
        let mut key = e.path().to_string();
        if key == "." {
            // Inside a flattened group the path is lost: the option that fails alone.
            key = v
                .as_object()
                .and_then(|m| {
                    m.iter()
                        .find(|(k, x)| {
                            serde_json::from_value::<T>(json!({ k.as_str(): x })).is_err()
                        })
                        .map(|(k, _)| k.clone())
                })
                .unwrap_or_else(|| "options".into());
        }
        Error::Invalid(vec![Problem::new(key, e.inner().to_string())])
    })
}

/// Refuse a run whose certain work (`work.at_least`) is above the work limit `max_sims`
/// (the option `max_sims`), before anything is allocated for it, or one the caller has
/// stopped. A run that may need more is stopped when it does ([`run_stoppable`]).
pub fn admit(
    what: &str,
    work: &Work,
    max_sims: u64,
    stop: &(dyn Fn() -> bool + Sync),
) -> Result<(), Error> {
    if let Some(p) =
        crate::analyses::over_budget(what, work.at_least, max_sims, "max_sims", work.smaller)
    {
        return Err(Error::Invalid(vec![p]));
    }
    if stop() {
        return Err(Error::Cancelled);
    }
    Ok(())
}

/// A tidy table by file name, or the error of formatting it.
pub fn csv_table(
    name: &str,
    bytes: Result<Vec<u8>, csv::Error>,
) -> Result<(String, Vec<u8>), Error> {
    bytes
        .map(|b| (name.to_string(), b))
        .map_err(|e| Error::Io(e.to_string()))
}

/// The whole lifecycle for JSON options: validate (option problems and scenario problems
/// together), load, check the work against `max_sims`, announce its units through
/// [`Hooks::more`] (a caller's progress total: nothing was announced before), run on
/// `hooks.threads` threads, and describe the result.
pub fn execute<A: Analysis>(
    load: Loader<'_>,
    options: &Value,
    max_sims: u64,
    hooks: &Hooks,
) -> Result<Report, Error> {
    let (loaded, bound, work) = prepare::<A>(load, options, max_sims, hooks.stop)?;
    (hooks.more)(work.units);
    let limit = Limit {
        max_sims,
        key: "max_sims",
        at_most: work.at_most,
        smaller: work.smaller,
    };
    let output = run_stoppable::<A>(&loaded, &bound, hooks, &limit)?;
    report::<A>(&output, &bound, &loaded)
}

/// Everything [`execute`] does before the work, without it: the options and the scenario
/// checked (every file a sweep names under the loader's rule), bound, and the work admitted
/// under `max_sims`. A server calls it before it starts a study in the background, so that
/// bad input comes back with the request.
pub fn check<A: Analysis>(load: Loader<'_>, options: &Value, max_sims: u64) -> Result<(), Error> {
    prepare::<A>(load, options, max_sims, &never).map(|_| ())
}

/// The list grammar's warnings on the options of `A` given as text, each keyed by its
/// option and naming it in backticks: a whole-number STEP read as a step (`1:2:1`), a range
/// that gives a single value; then the analysis's own ([`Analysis::warnings`]: a sweep's).
/// The run goes on with those values; an edge shows the warnings before it (the CLI on
/// stderr, with the option's flag; Python as a warning).
pub fn option_warnings<A: Analysis>(options: &Value) -> Vec<Problem> {
    let schema = options_schema::<A>();
    let (Some(props), Some(given)) = (
        schema.get("properties").and_then(Value::as_object),
        options.as_object(),
    ) else {
        return Vec::new();
    };
    given
        .iter()
        .filter_map(|(name, value)| {
            let text = value.as_str()?;
            // An option of the list grammar ([`ValueList`], optional or not).
            let list = props.get(name)?.to_string().contains("/ValueList\"");
            // Wide bounds: a value out of its own range is the check's problem, not a warning.
            let key = format!("`{name}`");
            let (_, warning) = list
                .then(|| crate::config::values::parse_values(&key, text, -1e12, 1e12, "", 1 << 20))?
                .ok()?;
            warning.map(|w| Problem::new(name.clone(), w))
        })
        .chain(
            options_from_json::<A::Options>(options)
                .map(|o| A::warnings(&o))
                .unwrap_or_default(),
        )
        .collect()
}

/// The loaded scenario, the checked and bound options and the admitted work of a run.
fn prepare<A: Analysis>(
    load: Loader<'_>,
    options: &Value,
    max_sims: u64,
    stop: &(dyn Fn() -> bool + Sync),
) -> Result<(Loaded, A::Bound, Work), Error> {
    let options: A::Options = options_from_json(options)?;
    let checked = A::validate(&options).map_err(Error::Invalid)?;
    let loaded = load(&[])?;
    let loaded = match A::USES_TRIGGER {
        true => loaded,
        false => crate::analyses::fixed_trigger_only(loaded)?,
    };
    let bound = A::bind(checked, &loaded).map_err(Error::Invalid)?;
    let work = A::work(&bound, &loaded);
    admit(&A::NAME.replace('_', " "), &work, max_sims, stop)?;
    Ok((loaded, bound, work))
}

/// What a stop unwinds with: private, so that no other unwinding is taken for a stop.
struct Stopped;

/// The work limit of a run: at most `max_sims` simulations. The problem of a run stopped
/// at it is keyed `key` (`max_sims`, `--max-sims`), gives the run's upper bound `at_most`
/// where known, and says how to ask for less (`smaller`).
#[derive(Debug, Clone, Copy)]
pub struct Limit<'a> {
    pub max_sims: u64,
    pub key: &'a str,
    pub at_most: Option<u64>,
    pub smaller: &'a str,
}

/// [`Analysis::run`] on `hooks.threads` threads, ended with [`Error::Cancelled`] at its next
/// piece of work once `hooks.stop` says so, and with the problem of `limit.key` once the
/// simulations it has run pass `limit.max_sims`.
///
/// Every analysis ticks [`Hooks::progress`] once per natural piece (a cell, a setting, an
/// evaluation, a speed, a segment, a run), so the stop and the count are asked at each tick:
/// a stopped run unwinds from there, out of its loops and its parallel maps (each worker
/// ends at its own next tick), to here, where the unwinding is caught and becomes
/// `Cancelled` or the limit's problem. Nothing of the run survives it (its output is dropped
/// whole; its memo keeps only finished pieces, so that a resumed run with a larger limit
/// goes on from them), and any other unwinding goes on as it was. The count is that of the
/// run's own worker pool ([`crate::threads::with_counted_threads`]); it changes no result.
pub fn run_stoppable<A: Analysis>(
    loaded: &Loaded,
    bound: &A::Bound,
    hooks: &Hooks,
    limit: &Limit,
) -> Result<A::Output, Error> {
    if (hooks.stop)() {
        return Err(Error::Cancelled);
    }
    let count = std::sync::Arc::new(std::sync::atomic::AtomicU64::new(0));
    let done = || count.load(std::sync::atomic::Ordering::Relaxed);
    let past = || done() > limit.max_sims;
    let stop = || past() || (hooks.stop)();
    let tick = || {
        if stop() {
            std::panic::resume_unwind(Box::new(Stopped));
        }
        (hooks.progress)();
    };
    let stoppable = Hooks {
        progress: &tick,
        more: hooks.more,
        stop: &stop,
        memo: hooks.memo,
        threads: hooks.threads,
        live: hooks.live,
    };
    let out = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        crate::threads::with_counted_threads(hooks.threads, &count, || {
            A::run(loaded, bound, &stoppable)
        })
    }));
    let stopped = |result: Result<A::Output, Error>| match past() {
        // Passed the limit: whatever the run gave since (a cancellation), the limit speaks.
        true => Err(Error::Invalid(vec![crate::analyses::past_limit(
            &A::NAME.replace('_', " "),
            done(),
            limit.at_most,
            limit.max_sims,
            limit.key,
            limit.smaller,
        )])),
        false => result,
    };
    match out {
        Ok(Ok(output)) => Ok(output),
        Ok(Err(e)) => stopped(Err(e)),
        Err(payload) if payload.is::<Stopped>() => stopped(Err(Error::Cancelled)),
        Err(payload) => std::panic::resume_unwind(payload),
    }
}

/// The report of an output: the summary described (version, command, units, scenario),
/// the tables and the text. What [`execute`] gives; an edge that ran the work its own way
/// (a cluster's merged shards) gets the same.
pub fn report<A: Analysis>(
    output: &A::Output,
    bound: &A::Bound,
    scenario: &Loaded,
) -> Result<Report, Error> {
    Ok(Report {
        summary: describe::<A>(A::summary(output, bound, scenario), output, scenario),
        tables: A::tables(output)?,
        text: A::text(output, bound, scenario),
    })
}

/// A summary made self-describing (version, command, units, and the scenario or the
/// scenarios of [`Analysis::described_runs`]).
pub fn describe<A: Analysis>(summary: Value, output: &A::Output, scenario: &Loaded) -> Value {
    let name = A::NAME.replace('_', "-");
    match A::described_runs(output) {
        Some(runs) => crate::output::describe_runs(summary, &name, &runs),
        None => crate::output::describe(summary, &name, A::described_file(output, scenario)),
    }
}

/// The JSON Schema of an analysis's options.
pub fn options_schema<A: Analysis>() -> Value {
    serde_json::to_value(schemars::schema_for!(A::Options)).unwrap_or_default()
}

/// One analysis in the registry ([`crate::analyses::registry::REGISTRY`]).
pub struct Entry {
    /// [`Analysis::NAME`].
    pub name: &'static str,
    /// [`Analysis::ABOUT`].
    pub about: &'static str,
    /// [`Analysis::DEFAULT_SETS`].
    pub default_sets: &'static [&'static str],
    /// [`options_schema`].
    pub schema: fn() -> Value,
    /// [`execute`].
    pub execute: fn(Loader<'_>, &Value, u64, &Hooks) -> Result<Report, Error>,
    /// [`check`].
    pub check: fn(Loader<'_>, &Value, u64) -> Result<(), Error>,
    /// [`option_warnings`].
    pub warnings: fn(&Value) -> Vec<Problem>,
    /// [`Analysis::READS_FILES`].
    pub reads_files: bool,
}

/// The registry entry of analysis `A`.
pub const fn entry<A: Analysis>() -> Entry {
    Entry {
        name: A::NAME,
        about: A::ABOUT,
        default_sets: A::DEFAULT_SETS,
        schema: options_schema::<A>,
        execute: execute::<A>,
        check: check::<A>,
        warnings: option_warnings::<A>,
        reads_files: A::READS_FILES,
    }
}

/// A list of numbers, given as numbers or as a text in the list grammar
/// ([`crate::config::values::parse_values`]: `A,B,C`, `LO:HI/COUNT`, `LO:HI:STEP` with HI
/// included).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum ValueList {
    /// The values.
    List(Vec<f64>),
    /// A text in the list grammar.
    Spec(String),
}

impl ValueList {
    /// A text in the list grammar.
    pub fn spec(text: &str) -> ValueList {
        ValueList::Spec(text.to_string())
    }

    /// The values, each in `[lo, hi]` `unit`, at most `max` of them; a problem names `key`.
    pub fn resolve(
        &self,
        key: &str,
        (lo, hi, unit, max): (f64, f64, &str, usize),
    ) -> Result<Vec<f64>, Problem> {
        match self {
            ValueList::List(v) => Ok(v.clone()),
            ValueList::Spec(text) => {
                crate::config::values::parse_values(key, text, lo, hi, unit, max).map(|(v, _)| v)
            }
        }
    }
}

/// A closed interval, given as `[lo, hi]` or as the text `LO:HI`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Interval(pub f64, pub f64);

impl<'de> Deserialize<'de> for Interval {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Interval, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Form {
            Pair([f64; 2]),
            Text(String),
        }
        match Form::deserialize(d)? {
            Form::Pair([a, b]) => Ok(Interval(a, b)),
            Form::Text(t) => {
                let parts: Vec<&str> = t.split(':').collect();
                match parts.as_slice() {
                    [a, b] => match (a.trim().parse::<f64>(), b.trim().parse::<f64>()) {
                        (Ok(a), Ok(b)) => Ok(Interval(a, b)),
                        _ => Err(serde::de::Error::custom(format!(
                            "{t:?}: expected MIN:MAX (two numbers)"
                        ))),
                    },
                    _ => Err(serde::de::Error::custom(format!(
                        "{t:?}: expected MIN:MAX (two numbers)"
                    ))),
                }
            }
        }
    }
}

impl schemars::JsonSchema for Interval {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "Interval".into()
    }

    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "description": "[MIN, MAX], or the text \"MIN:MAX\"",
            "anyOf": [
                {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2},
                {"type": "string", "pattern": "^[^:]+:[^:]+$"}
            ]
        })
    }
}

impl std::fmt::Display for Interval {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}", self.0, self.1)
    }
}

/// Named numbers, given as a mapping (`{"overload": 0.1}`) or as the text
/// `NAME=VALUE,...` (`"overload=0.1,divert=0.02"`); the analysis checks the names.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum Pairs {
    /// Numbers by name.
    Map(std::collections::BTreeMap<String, f64>),
    /// The text `NAME=VALUE,...`.
    Text(String),
}

impl Pairs {
    /// As the text `NAME=VALUE,...` its parser reads (numbers written exactly).
    pub fn text(&self) -> String {
        match self {
            Pairs::Text(t) => t.clone(),
            Pairs::Map(m) => m
                .iter()
                .map(|(k, v)| format!("{k}={v}"))
                .collect::<Vec<_>>()
                .join(","),
        }
    }
}
