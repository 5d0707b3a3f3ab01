//! `divertsim._native`: the Rust side of the Python package, a thin edge over divertsim-api.
//!
//! It converts arguments (Python values → TOML values, exactly: a Python float becomes the
//! same `f64`) and results (→ JSON text, numpy arrays, columns); loading, validation, the
//! runs and the pictures are divertsim-api's and divertsim-figures', as for the CLI. The
//! pure-Python package `divertsim` wraps this module; see its docstrings.

mod analyses;

use divertsim_api::analyses::runs::{self, Run};
use divertsim_api::config::{
    self, files::parse_toml, LoadOptions, Loaded, Problem, Problems, ScenarioBuilder, ScenarioFile,
};
use divertsim_api::presets as builtin;
use divertsim_core::run::sweep::par_map;
use divertsim_core::sim::Recording;
use divertsim_figures::plot::{self, PlotOptions};
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::create_exception;
use pyo3::exceptions::{PyKeyError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::time::Duration;

create_exception!(
    _native,
    ScenarioError,
    PyValueError,
    "Invalid scenario input; args: (message, [(key, message), ...], row or None, rows)."
);

/// What a scenario table is called in messages when it was given as a dict or as TOML text.
const DICT_NAME: &str = "scenario (dict)";
const TEXT_NAME: &str = "scenario (TOML text)";

/// The Python exception for `problems` (of row `row` of a batch, if given).
fn scenario_error(problems: &Problems, row: Option<usize>, more: &[usize]) -> PyErr {
    let mut message = problems.to_string().trim_end().to_string();
    if let Some(r) = row {
        message = format!("scenario {r}: {message}");
        if !more.is_empty() {
            let listed: Vec<String> = more.iter().take(20).map(usize::to_string).collect();
            message.push_str(&format!(
                "\n{} more invalid scenario{}: {}{}",
                more.len(),
                if more.len() == 1 { "" } else { "s" },
                listed.join(", "),
                if more.len() > 20 { ", ..." } else { "" }
            ));
        }
    }
    let list: Vec<(String, String)> = problems
        .0
        .iter()
        .map(|p| (p.key.clone(), p.message.clone()))
        .collect();
    let rows: Vec<usize> = row.into_iter().chain(more.iter().copied()).collect();
    ScenarioError::new_err((message, list, row, rows))
}

fn problems_of(key: &str, message: String) -> Problems {
    Problems(vec![Problem::new(key.to_string(), message)])
}

/// `threads` checked as the CLI checks `--threads` (1 to 1024, or None: one per core).
pub(crate) fn check_threads(threads: Option<usize>) -> PyResult<()> {
    match divertsim_api::threads::check(threads, "threads") {
        Some(p) => Err(scenario_error(&Problems(vec![p]), None, &[])),
        None => Ok(()),
    }
}

/// How often a long call looks at Python's signal handlers.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// Longest wait, after an interrupt, for the work to stop: an analysis stops at its next
/// piece of work (about a second at most), so this bounds only a stuck one.
const STOP_WAIT: Duration = Duration::from_secs(30);

/// Run `f` on a thread of its own with the GIL released, looking at Python's signal
/// handlers every 50 ms: Ctrl-C raises `KeyboardInterrupt` promptly instead of when the
/// call returns. `f` gets a stop flag, set on an interrupt, that work split into pieces
/// (simulate_many's chunks, every analysis's pieces through the contract) checks between
/// pieces; the interrupt is raised once the work has stopped, so that no work runs on
/// behind it and the next call starts at once.
pub(crate) fn interruptible<T: Send + 'static>(
    py: Python<'_>,
    f: impl FnOnce(&AtomicBool) -> T + Send + 'static,
) -> PyResult<T> {
    let stop = Arc::new(AtomicBool::new(false));
    let (tx, rx) = mpsc::channel();
    let flag = Arc::clone(&stop);
    let spawned = std::thread::Builder::new()
        .name("divertsim-call".into())
        .spawn(move || {
            let _ = tx.send(f(&flag));
        });
    if let Err(e) = spawned {
        return Err(pyo3::exceptions::PyRuntimeError::new_err(format!(
            "could not start a worker thread: {e}"
        )));
    }
    let mut rx = rx;
    loop {
        let (got, back) = py.detach(move || (rx.recv_timeout(SIGNAL_POLL), rx));
        rx = back;
        match got {
            Ok(out) => return Ok(out),
            Err(mpsc::RecvTimeoutError::Timeout) => {
                if let Err(e) = py.check_signals() {
                    stop.store(true, Ordering::Relaxed);
                    let _ = py.detach(move || rx.recv_timeout(STOP_WAIT));
                    return Err(e);
                }
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                return Err(pyo3::exceptions::PyRuntimeError::new_err(
                    "the computation ended without a result (an internal error)",
                ))
            }
        }
    }
}

/// Deepest nesting a converted value may have. A scenario is a few levels deep (a drive
/// table is a list of pairs inside `machine.drive`); anything deeper is a mistake, and a
/// list or dict that contains itself would otherwise recurse until the stack overflows.
pub(crate) const MAX_DEPTH: usize = 32;
/// Most values (items of lists and dicts, counted through every level) one argument may
/// hold: a scenario's largest part, a drive table, has a few hundred.
pub(crate) const MAX_VALUES: usize = 1_000_000;

/// A conversion in progress: the problems found and the values it may still take.
struct Conv<'a> {
    problems: &'a mut Vec<Problem>,
    values_left: usize,
    /// The key of the top-level value being converted: what a too-deep value is reported
    /// under (its own path would repeat `[0]` or `.x` 32 times).
    root: String,
}

impl<'a> Conv<'a> {
    fn new(problems: &'a mut Vec<Problem>) -> Self {
        Conv {
            problems,
            values_left: MAX_VALUES,
            root: String::new(),
        }
    }

    fn bad<T>(&mut self, key: &str, why: String) -> Option<T> {
        self.problems.push(Problem::new(key.to_string(), why));
        None
    }

    /// Enter one more level under `key`, or the problem (too deep, too many values).
    fn enter(&mut self, key: &str, depth: usize) -> Option<()> {
        if depth > MAX_DEPTH {
            let root = self.root.clone();
            return self.bad(
                &root,
                format!(
                    "nested more than {MAX_DEPTH} levels deep (a list or dict that contains itself?)"
                ),
            );
        }
        if self.values_left == 0 {
            return self.bad(
                key,
                format!("holds more than {MAX_VALUES} values; a scenario needs far fewer"),
            );
        }
        self.values_left -= 1;
        Some(())
    }

    /// A Python value as a TOML value, exactly (bool, int within i64, float, str,
    /// list/tuple, dict with str keys; numpy scalars and arrays through `.tolist()`); `None`
    /// where the value has no TOML form, with the problem pushed under `key`. The depth and
    /// the count of values are bounded, so no value (a cycle, a 20,000-deep list, an object
    /// whose `tolist()` returns another such object) can exhaust the stack or the memory.
    fn value(&mut self, v: &Bound<'_, PyAny>, key: &str, depth: usize) -> Option<toml::Value> {
        if depth == 0 {
            self.root = key.to_string();
        }
        self.enter(key, depth)?;
        if v.is_instance_of::<PyBool>() {
            return v.extract::<bool>().ok().map(toml::Value::Boolean);
        }
        if v.is_instance_of::<PyFloat>() {
            return v.extract::<f64>().ok().map(toml::Value::Float);
        }
        if v.is_instance_of::<PyInt>() {
            return match v.extract::<i64>() {
                Ok(i) => Some(toml::Value::Integer(i)),
                Err(_) => self.bad(
                    key,
                    "the integer is outside the 64-bit range of TOML".into(),
                ),
            };
        }
        if v.is_instance_of::<PyString>() {
            return match v.extract::<String>() {
                Ok(s) => Some(toml::Value::String(s)),
                Err(_) => self.bad(key, "the string is not valid Unicode".into()),
            };
        }
        if let Ok(d) = v.cast::<PyDict>() {
            return self.table(d, key, depth + 1).map(toml::Value::Table);
        }
        if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
            // A snapshot of the items: nothing converted below can change what is walked.
            let items: Vec<Bound<'_, PyAny>> = match v.try_iter() {
                Ok(it) => it.take(MAX_VALUES + 1).filter_map(Result::ok).collect(),
                Err(_) => return self.bad(key, "the list cannot be read".into()),
            };
            let mut out = Vec::with_capacity(items.len().min(1024));
            for (i, item) in items.iter().enumerate() {
                out.push(self.value(item, &format!("{key}[{i}]"), depth + 1)?);
            }
            return Some(toml::Value::Array(out));
        }
        // numpy scalars and arrays, pandas values: their plain Python form.
        if v.hasattr("tolist").unwrap_or(false) {
            if let Ok(plain) = v.call_method0("tolist") {
                if !plain.is(v) {
                    return self.value(&plain, key, depth + 1);
                }
            }
        }
        let type_name = v
            .get_type()
            .name()
            .map(|n| n.to_string())
            .unwrap_or_else(|_| "?".into());
        self.bad(
            key,
            format!(
                "a value of type {type_name} has no TOML form; allowed: bool, int, float, str, list, dict"
            ),
        )
    }

    /// A dict's entries as (str key, value) pairs, snapshotted; a non-str key is a problem.
    fn entries<'py>(
        &mut self,
        d: &Bound<'py, PyDict>,
        prefix: &str,
    ) -> Option<Vec<(String, Bound<'py, PyAny>)>> {
        let mut out = Vec::new();
        let mut ok = true;
        for item in d.items().iter().take(MAX_VALUES + 1) {
            let Ok((k, v)) = item.extract::<(Bound<'py, PyAny>, Bound<'py, PyAny>)>() else {
                ok = false;
                continue;
            };
            match k.extract::<String>() {
                Ok(k) => out.push((k, v)),
                Err(_) => {
                    self.bad::<()>(prefix, "a dict key is not a string".into());
                    ok = false;
                }
            }
        }
        ok.then_some(out)
    }

    /// A dict (nested like the TOML file; a dotted key stands for nested sections) as a
    /// table.
    fn table(&mut self, d: &Bound<'_, PyDict>, prefix: &str, depth: usize) -> Option<toml::Table> {
        let entries = self.entries(d, prefix);
        let mut table = toml::Table::new();
        let mut ok = entries.is_some();
        for (k, v) in entries.unwrap_or_default() {
            let path = if prefix.is_empty() {
                k.clone()
            } else {
                format!("{prefix}.{k}")
            };
            if v.is_none() {
                continue;
            }
            match self.value(&v, &path, depth) {
                Some(value) => {
                    if let Err(p) = config::set_value(&mut table, &k, value) {
                        self.problems.push(Problem::new(
                            if prefix.is_empty() {
                                p.key
                            } else {
                                format!("{prefix}.{}", p.key)
                            },
                            p.message,
                        ));
                        ok = false;
                    }
                }
                None => {
                    ok = false;
                    if self.values_left == 0 {
                        break;
                    }
                }
            }
        }
        ok.then_some(table)
    }

    /// Flatten a dict into dotted-key overrides (nested dicts become dotted keys; lists and
    /// other values are leaves; `None` is left out).
    fn flatten(
        &mut self,
        d: &Bound<'_, PyDict>,
        prefix: &str,
        depth: usize,
        out: &mut Vec<(String, toml::Value)>,
    ) {
        let Some(entries) = self.entries(d, prefix) else {
            return;
        };
        for (k, v) in entries {
            let path = if prefix.is_empty() {
                k
            } else {
                format!("{prefix}.{k}")
            };
            if v.is_none() {
                continue;
            }
            if depth == 0 {
                self.root = path.clone();
            }
            if let Ok(sub) = v.cast::<PyDict>() {
                if self.enter(&path, depth).is_none() {
                    return;
                }
                self.flatten(sub, &path, depth + 1, out);
            } else if let Some(value) = self.value(&v, &path, depth) {
                out.push((path, value));
            } else if self.values_left == 0 {
                return;
            }
        }
    }
}

/// A Python value as a TOML value (see [`Conv::value`]).
fn to_toml(v: &Bound<'_, PyAny>, key: &str, problems: &mut Vec<Problem>) -> Option<toml::Value> {
    Conv::new(problems).value(v, key, 0)
}

/// A dict as a table (see [`Conv::table`]).
fn dict_table(
    d: &Bound<'_, PyDict>,
    prefix: &str,
    problems: &mut Vec<Problem>,
) -> Option<toml::Table> {
    Conv::new(problems).table(d, prefix, 0)
}

/// A dict as dotted-key overrides (see [`Conv::flatten`]).
fn flatten(
    d: &Bound<'_, PyDict>,
    prefix: &str,
    out: &mut Vec<(String, toml::Value)>,
    problems: &mut Vec<Problem>,
) {
    Conv::new(problems).flatten(d, prefix, 0, out)
}

/// A scenario argument (None, a path, TOML text, a dict) read once, under the path rule
/// `options`: a builder to clone for each set of overrides.
fn scenario_source(
    scenario: &Bound<'_, PyAny>,
    options: LoadOptions,
) -> Result<ScenarioBuilder, Problems> {
    if scenario.is_none() {
        return ScenarioBuilder::new().options(options).merged();
    }
    if let Ok(d) = scenario.cast::<PyDict>() {
        let mut problems = Vec::new();
        return match dict_table(d, "", &mut problems) {
            Some(t) if problems.is_empty() => ScenarioBuilder::table(t, DICT_NAME, Path::new(""))
                .options(options)
                .merged(),
            _ => Err(Problems(problems)),
        };
    }
    match scenario.extract::<String>() {
        Ok(s) if s.contains('\n') => {
            let t = parse_toml(&s).map_err(|e| problems_of(TEXT_NAME, e))?;
            ScenarioBuilder::table(t, TEXT_NAME, Path::new(""))
                .options(options)
                .merged()
        }
        Ok(path) => ScenarioBuilder::file(path).options(options).merged(),
        Err(_) => Err(problems_of(
            "scenario",
            "must be None, a path, TOML text or a dict".into(),
        )),
    }
}

/// Overrides given as (dotted key, value) pairs, converted exactly.
fn overrides_of(
    pairs: &[(String, Bound<'_, PyAny>)],
) -> Result<Vec<(String, toml::Value)>, Problems> {
    let mut problems = Vec::new();
    let mut out = Vec::with_capacity(pairs.len());
    for (k, v) in pairs {
        if let Some(value) = to_toml(v, k, &mut problems) {
            out.push((k.clone(), value));
        }
    }
    if problems.is_empty() {
        Ok(out)
    } else {
        Err(Problems(problems))
    }
}

/// One finished run with its resolved scenario file.
#[pyclass(frozen, module = "divertsim._native", name = "Run")]
struct PyRun {
    run: Run,
    file: ScenarioFile,
}

#[pymethods]
impl PyRun {
    /// The JSON summary, as `divertsim simulate --json` prints it (compact).
    fn summary_json(&self) -> String {
        runs::summary(&self.run, &self.file).to_string()
    }

    /// The resolved scenario as TOML text (what `scenario.toml` of `--out` holds).
    fn scenario_toml(&self) -> PyResult<String> {
        config::to_toml(
            &self.file,
            "The scenario of this run, every input resolved.",
        )
        .map_err(crate::analyses::error)
    }

    /// The animated run report, one self-contained HTML page (`divertsim simulate
    /// --report`'s).
    fn report_html(&self, py: Python<'_>) -> PyResult<String> {
        let toml = self.scenario_toml()?;
        Ok(
            py.detach(|| {
                divertsim_report::run::single(&self.run.scenario, &self.run.result, &toml)
            }),
        )
    }

    /// The top view as SVG text.
    #[pyo3(signature = (width=1000, height=700))]
    fn svg(&self, py: Python<'_>, width: u32, height: u32) -> PyResult<String> {
        let options = PlotOptions {
            width,
            height,
            ..PlotOptions::default()
        };
        py.detach(|| plot::top_view_svg(&self.run.scenario, &self.run.result, &options))
            .map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// The trajectory as columns: float64 arrays t, x, y, phi, vx, vy, omega, alpha [SI,
    /// rad], drive_torque [N·m] (NaN without an arm), contact1_x … contact2_y (NaN without a
    /// contact) and the list `stage`.
    fn trajectory<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let tr = &self.run.result.trajectory;
        let d = PyDict::new(py);
        let col = |f: &dyn Fn(&divertsim_core::sim::Sample) -> f64| -> Vec<f64> {
            tr.iter().map(f).collect()
        };
        let contact = |k: usize, i: usize| col(&|s| s.contacts[k].map_or(f64::NAN, |p| p[i]));
        let torque = self
            .run
            .result
            .drive_torque_series(&self.run.scenario)
            .unwrap_or_else(|| vec![f64::NAN; tr.len()]);
        let columns: [(&str, Vec<f64>); 13] = [
            ("t", col(&|s| s.state.t)),
            ("x", col(&|s| s.state.x)),
            ("y", col(&|s| s.state.y)),
            ("phi", col(&|s| s.state.phi)),
            ("vx", col(&|s| s.state.vx)),
            ("vy", col(&|s| s.state.vy)),
            ("omega", col(&|s| s.state.omega)),
            ("alpha", col(&|s| s.arm_angle)),
            ("drive_torque", torque),
            ("contact1_x", contact(0, 0)),
            ("contact1_y", contact(0, 1)),
            ("contact2_x", contact(1, 0)),
            ("contact2_y", contact(1, 1)),
        ];
        for (name, v) in columns {
            d.set_item(name, PyArray1::from_vec(py, v))?;
        }
        let stages: Vec<&str> = tr.iter().map(|s| s.stage.label()).collect();
        d.set_item("stage", stages)?;
        Ok(d)
    }
}

/// Load and run one scenario with its full trajectory.
#[pyfunction]
#[pyo3(signature = (scenario, overrides, allow_outside_paths=false))]
fn simulate(
    py: Python<'_>,
    scenario: &Bound<'_, PyAny>,
    overrides: Vec<(String, Bound<'_, PyAny>)>,
    allow_outside_paths: bool,
) -> PyResult<PyRun> {
    let options = LoadOptions {
        allow_outside_paths,
        ..Default::default()
    };
    let source = scenario_source(scenario, options).map_err(|p| scenario_error(&p, None, &[]))?;
    let sets = overrides_of(&overrides).map_err(|p| scenario_error(&p, None, &[]))?;
    let out = py.detach(|| {
        source.values(&sets).load().map(|loaded| PyRun {
            run: runs::run(&loaded, Recording::Full),
            file: loaded.file,
        })
    });
    out.map_err(|p| scenario_error(&p, None, &[]))
}

/// One job of a batch: which table it starts from and its overrides.
type Job = (usize, Vec<(String, toml::Value)>);

/// Load and run many scenarios in parallel without trajectories; returns the result table's
/// columns (name → numpy array or list), in input order.
///
/// `scenarios`: a list of None (the base), paths or TOML texts (whole scenarios) or dicts
/// (overrides over the base, nested or dotted); or `columns`: (dotted key, values) pairs of
/// equal length, one scenario per row over the base (NaN or None: key not set).
#[pyfunction]
#[pyo3(signature = (base, scenarios=None, columns=None, rows=0, threads=None, allow_outside_paths=false))]
fn simulate_many<'py>(
    py: Python<'py>,
    base: &Bound<'py, PyAny>,
    scenarios: Option<Vec<Bound<'py, PyAny>>>,
    columns: Option<Vec<(String, Bound<'py, PyAny>)>>,
    rows: usize,
    threads: Option<usize>,
    allow_outside_paths: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let options = LoadOptions {
        allow_outside_paths,
        ..Default::default()
    };
    check_threads(threads)?;
    let base_source = scenario_source(base, options).map_err(|p| scenario_error(&p, None, &[]))?;
    let mut tables = vec![base_source];
    let mut jobs: Vec<Job> = Vec::new();
    let mut early: Vec<(usize, Problems)> = Vec::new();
    if let Some(items) = scenarios {
        for (i, item) in items.iter().enumerate() {
            if item.is_none() {
                jobs.push((0, Vec::new()));
            } else if let Ok(d) = item.cast::<PyDict>() {
                let mut sets = Vec::new();
                let mut problems = Vec::new();
                flatten(d, "", &mut sets, &mut problems);
                if !problems.is_empty() {
                    early.push((i, Problems(problems)));
                }
                jobs.push((0, sets));
            } else {
                match scenario_source(item, options) {
                    Ok(t) => {
                        tables.push(t);
                        jobs.push((tables.len() - 1, Vec::new()));
                    }
                    Err(p) => {
                        early.push((i, p));
                        jobs.push((0, Vec::new()));
                    }
                }
            }
        }
    } else if let Some(columns) = columns {
        jobs = (0..rows).map(|_| (0, Vec::new())).collect();
        let mut problems: Vec<Vec<Problem>> = vec![Vec::new(); rows];
        for (key, values) in &columns {
            if let Ok(a) = values.extract::<PyReadonlyArray1<'_, f64>>() {
                let a = a.as_array();
                if a.len() != rows {
                    return Err(PyValueError::new_err(format!(
                        "column {key} has {} values for {rows} rows",
                        a.len()
                    )));
                }
                for (job, &v) in jobs.iter_mut().zip(a.iter()) {
                    if !v.is_nan() {
                        job.1.push((key.clone(), toml::Value::Float(v)));
                    }
                }
            } else {
                let values: Vec<Bound<'_, PyAny>> = values.extract()?;
                if values.len() != rows {
                    return Err(PyValueError::new_err(format!(
                        "column {key} has {} values for {rows} rows",
                        values.len()
                    )));
                }
                for (r, v) in values.iter().enumerate() {
                    let missing = v.is_none()
                        || (v.is_instance_of::<PyFloat>()
                            && v.extract::<f64>().is_ok_and(f64::is_nan));
                    if missing {
                        continue;
                    }
                    if let Some(value) = to_toml(v, key, &mut problems[r]) {
                        jobs[r].1.push((key.clone(), value));
                    }
                }
            }
        }
        early.extend(
            problems
                .into_iter()
                .enumerate()
                .filter(|(_, p)| !p.is_empty())
                .map(|(r, p)| (r, Problems(p))),
        );
    }
    if let Some((row, p)) = early.first() {
        let more: Vec<usize> = early[1..].iter().map(|(r, _)| *r).collect();
        return Err(scenario_error(p, Some(*row), &more));
    }

    let outcome = interruptible(py, move |stop| {
        divertsim_api::threads::with_threads(threads, || {
            let loaded: Vec<Result<Loaded, Problems>> = par_map(&jobs, &|| {}, |(t, sets)| {
                tables[*t].clone().values(sets).load()
            });
            let bad: Vec<usize> = loaded
                .iter()
                .enumerate()
                .filter(|(_, l)| l.is_err())
                .map(|(i, _)| i)
                .collect();
            if let Some(&first) = bad.first() {
                let p = match &loaded[first] {
                    Err(p) => p.clone(),
                    Ok(_) => Problems(Vec::new()),
                };
                return Err(Some((first, p, bad[1..].to_vec())));
            }
            let loaded: Vec<Loaded> = loaded.into_iter().flatten().collect();
            // In chunks, so that an interrupt stops the work at the next chunk; the
            // results do not depend on the chunking (each run is its own).
            let workers = threads.unwrap_or_else(|| {
                std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
            });
            let chunk = 64 * workers.max(1);
            let mut runs = Vec::with_capacity(loaded.len());
            for part in loaded.chunks(chunk) {
                if stop.load(Ordering::Relaxed) {
                    return Err(None);
                }
                runs.extend(par_map(part, &|| {}, |l| {
                    runs::run(l, Recording::VerdictOnly)
                }));
            }
            Ok(runs)
        })
    })?;
    let outcome = match outcome {
        Ok(r) => Ok(r),
        Err(Some(e)) => Err(e),
        // Only after an interrupt, which has raised already.
        Err(None) => {
            return Err(pyo3::exceptions::PyKeyboardInterrupt::new_err(
                "interrupted",
            ))
        }
    };
    let runs = outcome.map_err(|(row, p, more)| scenario_error(&p, Some(row), &more))?;
    table_columns(py, &runs)
}

/// The result table's columns: unit-suffixed names as in the CLI's CSVs.
fn table_columns<'py>(py: Python<'py>, runs: &[Run]) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let text = |f: &dyn Fn(&Run) -> Option<String>| -> Vec<Option<String>> {
        runs.iter().map(f).collect()
    };
    d.set_item("outcome", text(&|r| Some(r.result.outcome.label().into())))?;
    d.set_item("reason", text(&|r| r.result.outcome.reason()))?;
    d.set_item(
        "stages",
        text(&|r| {
            Some(
                r.result
                    .stages
                    .iter()
                    .map(|s| s.label())
                    .collect::<Vec<_>>()
                    .join(" "),
            )
        }),
    )?;
    let diverted: Vec<bool> = runs
        .iter()
        .map(|r| r.result.outcome == divertsim_core::sim::Outcome::Diverted)
        .collect();
    d.set_item("diverted", PyArray1::from_vec(py, diverted))?;
    let float = |f: &dyn Fn(&Run) -> f64| -> Vec<f64> { runs.iter().map(f).collect() };
    let count = |f: &dyn Fn(&Run) -> usize| -> Vec<i64> {
        runs.iter()
            .map(|r| i64::try_from(f(r)).unwrap_or(i64::MAX))
            .collect()
    };
    let floats: [(&str, Vec<f64>); 17] = [
        (
            "start_position_m",
            float(&|r| r.scenario.machine.start_position),
        ),
        ("max_lateral_m", float(&|r| r.result.max_lateral)),
        ("max_impulse_n_s", float(&|r| r.result.overload.max_impulse)),
        (
            "fall_impulse_n_s",
            float(&|r| r.result.overload.fall_impulse),
        ),
        (
            "overload_ratio",
            float(&|r| r.result.overload.overload_ratio),
        ),
        (
            "equivalent_drop_height_m",
            float(&|r| r.result.overload.equivalent_drop_height),
        ),
        ("energy_ratio", float(&|r| r.result.overload.energy_ratio)),
        (
            "arm_max_impulse_n_s",
            float(&|r| r.result.overload.arm_max_impulse),
        ),
        (
            "arm_total_impulse_n_s",
            float(&|r| r.result.overload.arm_total_impulse),
        ),
        ("end_time_s", float(&|r| r.result.final_state.t)),
        ("final_x_m", float(&|r| r.result.final_state.x)),
        ("final_y_m", float(&|r| r.result.final_state.y)),
        (
            "final_phi_deg",
            float(&|r| r.result.final_state.phi.to_degrees()),
        ),
        ("final_vx_m_s", float(&|r| r.result.final_state.vx)),
        ("final_vy_m_s", float(&|r| r.result.final_state.vy)),
        ("final_omega_rad_s", float(&|r| r.result.final_state.omega)),
        (
            "first_impact_s",
            float(&|r| r.result.impacts.first().map_or(f64::NAN, |i| i.t)),
        ),
    ];
    for (name, v) in floats {
        d.set_item(name, PyArray1::from_vec(py, v))?;
    }
    d.set_item(
        "impacts",
        PyArray1::from_vec(py, count(&|r| r.result.impacts.len())),
    )?;
    d.set_item(
        "events",
        PyArray1::from_vec(py, count(&|r| r.result.events.len())),
    )?;
    Ok(d)
}

/// Every built-in preset: (name without `.toml`, its first comment line).
#[pyfunction]
fn presets() -> Vec<(String, String)> {
    builtin::PRESETS
        .iter()
        .map(|(p, text)| {
            (
                p.trim_end_matches(".toml").to_string(),
                builtin::description(text).to_string(),
            )
        })
        .collect()
}

/// The TOML text of the preset `name` ("default", "paper/fig13a").
#[pyfunction]
fn preset(name: &str) -> PyResult<String> {
    match builtin::find(name) {
        Some((_, text)) => Ok(text.to_string()),
        None => {
            let names: Vec<&str> = builtin::PRESETS
                .iter()
                .map(|(p, _)| p.trim_end_matches(".toml"))
                .collect();
            Err(PyKeyError::new_err(format!(
                "no preset '{name}'; allowed: {}",
                names.join(", ")
            )))
        }
    }
}

/// TOML text as JSON text (numbers exact), for a dict view of a preset.
#[pyfunction]
fn toml_to_json(text: &str) -> PyResult<String> {
    let t = parse_toml(text).map_err(PyValueError::new_err)?;
    serde_json::to_string(&t).map_err(|e| PyValueError::new_err(e.to_string()))
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("ScenarioError", m.py().get_type::<ScenarioError>())?;
    m.add_class::<PyRun>()?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(simulate_many, m)?)?;
    m.add_function(wrap_pyfunction!(presets, m)?)?;
    m.add_function(wrap_pyfunction!(preset, m)?)?;
    m.add_function(wrap_pyfunction!(toml_to_json, m)?)?;
    m.add_function(wrap_pyfunction!(analyses::analysis, m)?)?;
    m.add_function(wrap_pyfunction!(analyses::registry, m)?)?;
    m.add_function(wrap_pyfunction!(analyses::study_job, m)?)?;
    m.add_class::<analyses::StudyJob>()?;
    Ok(())
}
