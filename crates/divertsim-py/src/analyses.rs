//! The analyses for Python: `analysis` runs any of `divertsim_api::analyses::request` (the
//! same entry the CLI's numbers come from), and `ReliabilityJob` splits a reliability run
//! into shards for a cluster (`divertsim.dask`) and merges them back into the run one
//! machine would give, bit for bit; `LineJob` does the same with a line run's segments.
//! Conversion only: arguments in, JSON text and CSV or Parquet bytes out.

use std::sync::OnceLock;

use divertsim_api::analyses::line;
use divertsim_api::analyses::registry as by_name;
use divertsim_api::analyses::reliability::{self, GivenShards, Point, Quiet, Reliability, Sweep};
use divertsim_api::config::{self, LoadOptions, Loaded, Problems, ScenarioBuilder};
use divertsim_api::contract::{self, Analysis, Error, Report as Output};
use divertsim_api::samples;
use divertsim_core::analysis::population::reliability::{RunPlan, StartRule};
use divertsim_core::run::sweep::no_progress;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use crate::{check_threads, interruptible, overrides_of, scenario_error, scenario_source};
use std::sync::atomic::Ordering;

/// A loader of the scenario (table and overrides) with a sweep point's `KEY=VALUE` sets on
/// top, as `request::run` wants it.
fn loader(
    source: ScenarioBuilder,
    sets: Vec<(String, toml::Value)>,
) -> impl Fn(&[String]) -> Result<Loaded, Problems> {
    move |extra: &[String]| source.clone().values(&sets).sets(extra).load()
}

/// The scenario argument and overrides as a table and exact overrides; with no scenario,
/// the analysis's default overrides first (the CLI's figure parcels).
fn inputs(
    name: &str,
    scenario: &Bound<'_, PyAny>,
    overrides: &[(String, Bound<'_, PyAny>)],
    options: LoadOptions,
) -> PyResult<(ScenarioBuilder, Vec<(String, toml::Value)>)> {
    let table = scenario_source(scenario, options).map_err(|p| scenario_error(&p, None, &[]))?;
    let mut sets = Vec::new();
    if scenario.is_none() {
        for s in by_name::default_sets(name) {
            sets.push(
                config::parse_set(s).map_err(|p| scenario_error(&Problems(vec![p]), None, &[]))?,
            );
        }
    }
    sets.extend(overrides_of(overrides).map_err(|p| scenario_error(&p, None, &[]))?);
    Ok((table, sets))
}

/// The one place the api's error kinds become Python exceptions: invalid input ScenarioError
/// (a ValueError), a failed run RuntimeError, I/O OSError, a stop KeyboardInterrupt.
pub(crate) fn error(e: Error) -> PyErr {
    match e {
        Error::Invalid(p) => scenario_error(&Problems(p), None, &[]),
        Error::Failed(m) => PyRuntimeError::new_err(m),
        Error::Io(m) => pyo3::exceptions::PyOSError::new_err(m),
        Error::Cancelled => pyo3::exceptions::PyKeyboardInterrupt::new_err("interrupted"),
    }
}

type Tables<'py> = Vec<(String, Bound<'py, PyBytes>)>;

/// What an analysis gives Python: the summary as JSON text, the tables and the readable
/// report.
type Given<'py> = (String, Tables<'py>, String);

fn output<'py>(py: Python<'py>, out: Output) -> Given<'py> {
    let tables = out
        .tables
        .into_iter()
        .map(|(n, b)| (n, PyBytes::new(py, &b)))
        .collect();
    (out.summary.to_string(), tables, out.text)
}

/// The analyses on the contract: (name, about, the scenario overrides of its default case,
/// the JSON Schema of its options as text), what `divertsim._codegen` writes the Python
/// functions from.
#[pyfunction]
pub fn registry() -> Vec<(String, String, Vec<String>, String)> {
    divertsim_api::analyses::registry::REGISTRY
        .iter()
        .map(|e| {
            (
                e.name.to_string(),
                e.about.to_string(),
                e.default_sets.iter().map(|s| s.to_string()).collect(),
                (e.schema)().to_string(),
            )
        })
        .collect()
}

/// Run analysis `name` with `options_json` (a JSON object of the CLI flags' names in
/// snake case) on `threads` workers; returns the summary as JSON text, the tidy tables as
/// (file name, CSV bytes) and the readable report.
#[pyfunction]
#[pyo3(signature = (name, scenario, overrides, options_json, threads=None, allow_outside_paths=false))]
pub fn analysis<'py>(
    py: Python<'py>,
    name: &str,
    scenario: &Bound<'py, PyAny>,
    overrides: Vec<(String, Bound<'py, PyAny>)>,
    options_json: &str,
    threads: Option<usize>,
    allow_outside_paths: bool,
) -> PyResult<Given<'py>> {
    let load_options = LoadOptions {
        allow_outside_paths,
        ..Default::default()
    };
    let options: serde_json::Value =
        serde_json::from_str(options_json).map_err(|e| PyValueError::new_err(e.to_string()))?;
    check_threads(threads)?;
    let (table, sets) = inputs(name, scenario, &overrides, load_options)?;
    // The list grammar's warnings (`speeds="1:2:1"` read as a step), as the CLI's.
    for w in by_name::warnings(name, &options) {
        let text = w.message.trim_start_matches("warning: ");
        let text = std::ffi::CString::new(text).unwrap_or_default();
        PyErr::warn(
            py,
            &py.get_type::<pyo3::exceptions::PyUserWarning>(),
            &text,
            1,
        )?;
    }
    let load = loader(table, sets);
    let name = name.to_string();
    let out = interruptible(py, move |stop| {
        let stop = || stop.load(Ordering::Relaxed);
        divertsim_api::threads::with_threads(threads, || {
            by_name::run(&name, &load, &options, &stop)
        })
    })?;
    Ok(output(py, out.map_err(error)?))
}

/// A reliability run split into shards: the points (a sweep's), the plan, each point's
/// trigger (an adaptive table is built once, on first use).
#[pyclass(frozen, module = "divertsim._native", name = "ReliabilityJob")]
pub struct ReliabilityJob {
    /// The run's options as checked.
    options: reliability::Options,
    points: Vec<Point>,
    plan: RunPlan,
    sweep: Option<Sweep>,
    triggers: Vec<OnceLock<Result<StartRule, Error>>>,
    /// The resolved scenario as TOML text (standalone): what workers load.
    scenario_toml: String,
}

impl ReliabilityJob {
    fn trigger(&self, i: usize) -> PyResult<&StartRule> {
        let p = self
            .points
            .get(i)
            .ok_or_else(|| PyValueError::new_err(format!("no point {i}")))?;
        self.triggers[i]
            .get_or_init(|| reliability::trigger_for(p, &Quiet))
            .as_ref()
            .map_err(|e| error(e.clone()))
    }
}

#[pymethods]
impl ReliabilityJob {
    /// Every shard as (point, k), in the order one machine runs them.
    fn shards(&self) -> Vec<(usize, u64)> {
        (0..self.points.len())
            .flat_map(|i| (0..self.plan.shards()).map(move |k| (i, k)))
            .collect()
    }

    /// The resolved scenario (standalone TOML text, the overrides applied): a worker loads
    /// it to rebuild this job.
    fn scenario_toml(&self) -> String {
        self.scenario_toml.clone()
    }

    /// Run shard `k` of point `point` (GIL released) and return its samples as the bytes
    /// of a Parquet file.
    #[pyo3(signature = (point, k, threads=None))]
    fn run_shard<'py>(
        &self,
        py: Python<'py>,
        point: usize,
        k: u64,
        threads: Option<usize>,
    ) -> PyResult<Bound<'py, PyBytes>> {
        check_threads(threads)?;
        if k >= self.plan.shards() {
            return Err(PyValueError::new_err(format!(
                "no shard {k}; this run has {}",
                self.plan.shards()
            )));
        }
        let bytes = py.detach(|| {
            divertsim_api::threads::with_threads(threads, || {
                let trigger = self.trigger(point)?;
                let s = reliability::run_shard(
                    &self.points[point],
                    trigger,
                    &self.plan,
                    k,
                    &no_progress,
                )
                .map_err(error)?;
                samples::to_parquet_bytes(point, &s).map_err(error)
            })
        })?;
        Ok(PyBytes::new(py, &bytes))
    }

    /// The run from its shards (point, k, Parquet bytes), tallied in order with the early
    /// stop of one machine; a shard not given is run here. Returns the summary (JSON text)
    /// and the tables, as `analysis("reliability", ...)`.
    #[pyo3(signature = (shards, threads=None))]
    fn merge<'py>(
        &self,
        py: Python<'py>,
        shards: Vec<(usize, u64, Vec<u8>)>,
        threads: Option<usize>,
    ) -> PyResult<Given<'py>> {
        check_threads(threads)?;
        let out = py.detach(|| -> PyResult<Output> {
            let mut given = GivenShards::default();
            for (i, k, bytes) in shards {
                // Every shard once, of a point and a shard this run has, holding that point's
                // samples of that range: a shard of another run cannot slip in.
                if i >= self.points.len() || k >= self.plan.shards() {
                    return Err(PyValueError::new_err(format!(
                        "shard ({i}, {k}) is not one of this run's: {} points of {} shards",
                        self.points.len(),
                        self.plan.shards()
                    )));
                }
                if given.contains(i, k) {
                    return Err(PyValueError::new_err(format!(
                        "shard ({i}, {k}) is given twice"
                    )));
                }
                let s = samples::from_parquet_bytes_of(bytes, Some(i))
                    .map_err(|e| PyValueError::new_err(e.to_string()))?;
                let p = &self.points[i];
                let plan = reliability::point_plan(&self.plan, p);
                let again = reliability::run_shard_first(p, &plan, k);
                let want: Vec<u64> = plan.shard_range(k).collect();
                let fits = s.iter().map(|x| x.draw.index).eq(want.iter().copied())
                    && again
                        .as_ref()
                        .is_none_or(|d| s.first().map(|x| &x.draw) == Some(d));
                if !fits {
                    return Err(PyValueError::new_err(format!(
                        "shard ({i}, {k}) does not hold this run's samples {}..{} of point {i}",
                        want.first().copied().unwrap_or(0),
                        want.last().map_or(0, |l| l + 1)
                    )));
                }
                given.insert(i, k, s);
            }
            // The triggers this job built for its shards (an adaptive table once per job).
            let trigger = |i: usize, _: &Point| {
                self.trigger(i)
                    .cloned()
                    .map_err(|e| Error::Failed(e.to_string()))
            };
            let results = divertsim_api::threads::with_threads(threads, || {
                reliability::run_with(
                    &self.points,
                    &self.plan,
                    &given,
                    &|| false,
                    &Quiet,
                    &trigger,
                )
            })
            .map_err(error)?;
            let study = reliability::Study {
                points: self.points.clone(),
                plan: self.plan,
                sweep: self.sweep.clone(),
                results,
            };
            let inputs = reliability::StudyInputs {
                options: self.options.clone(),
                sweep: self.sweep.clone(),
                points: self.points.clone(),
            };
            let first = &self.points[0].loaded;
            contract::report::<reliability::Reliability>(&study, &inputs, first).map_err(error)
        })?;
        Ok(output(py, out))
    }
}

/// The job of a reliability run (validated here: a bad scenario or option raises
/// ScenarioError before any shard runs).
#[pyfunction]
#[pyo3(signature = (scenario, overrides, options_json, allow_outside_paths=false))]
pub fn reliability_job(
    py: Python<'_>,
    scenario: &Bound<'_, PyAny>,
    overrides: Vec<(String, Bound<'_, PyAny>)>,
    options_json: &str,
    allow_outside_paths: bool,
) -> PyResult<ReliabilityJob> {
    let job = (
        scenario,
        overrides.as_slice(),
        options_json,
        allow_outside_paths,
    );
    let (_, inputs, scenario_toml) = job_inputs::<Reliability>(py, job)?;
    let points = inputs.points;
    let plan = reliability::plan(&inputs.options, &points);
    Ok(ReliabilityJob {
        triggers: points.iter().map(|_| OnceLock::new()).collect(),
        options: inputs.options,
        points,
        plan,
        sweep: inputs.sweep,
        scenario_toml,
    })
}

/// A cluster job's arguments: the scenario, its overrides, the options (JSON text) and the
/// path rule.
type JobArgs<'a, 'py> = (
    &'a Bound<'py, PyAny>,
    &'a [(String, Bound<'py, PyAny>)],
    &'a str,
    bool,
);

/// What a cluster job of analysis `A` starts from, checked as `analysis(A::NAME)` checks it
/// (a bad scenario or option raises ScenarioError, work beyond `max_sims` is refused,
/// before any task runs): the loaded scenario, the options bound to it, and the resolved
/// scenario as standalone TOML text, which the workers load.
fn job_inputs<A: Analysis>(
    py: Python<'_>,
    (scenario, overrides, options_json, allow_outside_paths): JobArgs<'_, '_>,
) -> PyResult<(Loaded, A::Bound, String)>
where
    A::Bound: Send,
{
    let load_options = LoadOptions {
        allow_outside_paths,
        ..Default::default()
    };
    let options: serde_json::Value =
        serde_json::from_str(options_json).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let (table, sets) = inputs(A::NAME, scenario, overrides, load_options)?;
    let load = loader(table, sets);
    py.detach(|| {
        let (max_sims, options) = by_name::max_sims_option(&options).map_err(error)?;
        let base = load(&[]).map_err(|p| error(Error::Invalid(p.0)))?;
        let o: A::Options = contract::options_from_json(&options).map_err(error)?;
        let bound = A::validate(&o)
            .and_then(|c| A::bind(c, &base))
            .map_err(|p| error(Error::Invalid(p)))?;
        let work = A::work(&bound, &base);
        // The workers of a cluster job are not metered: refuse on the most it can run.
        let work = contract::Work {
            at_least: work.at_most.unwrap_or(work.at_least).max(work.at_least),
            ..work
        };
        contract::admit(A::NAME, &work, max_sims, &by_name::never_stop).map_err(error)?;
        let heading = format!("A {} job's scenario, every input resolved.", A::NAME);
        let scenario_toml =
            config::to_toml(&config::standalone(&base.file), &heading).map_err(error)?;
        Ok((base, bound, scenario_toml))
    })
}

/// A line run split into segments for a cluster: the checked options bound to the
/// scenario, and the points with their triggers (built once, on first use).
#[pyclass(frozen, module = "divertsim._native", name = "LineJob")]
pub struct LineJob {
    base: Loaded,
    inputs: line::LineInputs,
    points: OnceLock<Result<Vec<line::LinePoint>, Error>>,
    /// The resolved scenario as TOML text (standalone): what workers load.
    scenario_toml: String,
}

impl LineJob {
    fn points(&self) -> PyResult<&[line::LinePoint]> {
        self.points
            .get_or_init(|| line::prepare(&self.inputs))
            .as_ref()
            .map(Vec::as_slice)
            .map_err(|e| error(e.clone()))
    }
}

/// Segments kept by their memo keys: what the workers sent back, recalled by the run.
struct GivenSegments(std::collections::HashMap<u64, Vec<u8>>);

impl divertsim_core::run::memo::Memo for GivenSegments {
    fn recall(&self, key: u64) -> Option<Vec<u8>> {
        self.0.get(&key).cloned()
    }
    fn keep(&self, _: u64, _: &[u8]) {}
}

#[pymethods]
impl LineJob {
    /// Every segment as (point, k), in the order one machine runs them.
    fn segments(&self) -> PyResult<Vec<(usize, u64)>> {
        let n = line::segments(&self.inputs.options);
        let points = self.inputs.points.len();
        Ok((0..points)
            .flat_map(|i| (0..n).map(move |k| (i, k)))
            .collect())
    }

    /// The resolved scenario (standalone TOML text, the overrides applied): a worker loads
    /// it to rebuild this job.
    fn scenario_toml(&self) -> String {
        self.scenario_toml.clone()
    }

    /// Run segment `k` of point `point` (GIL released); returns its memo key and its bytes.
    #[pyo3(signature = (point, k, threads=None))]
    fn run_segment<'py>(
        &self,
        py: Python<'py>,
        point: usize,
        k: u64,
        threads: Option<usize>,
    ) -> PyResult<(u64, Bound<'py, PyBytes>)> {
        check_threads(threads)?;
        let o = &self.inputs.options;
        if k >= line::segments(o) {
            return Err(PyValueError::new_err(format!(
                "no segment {k}; this run has {}",
                line::segments(o)
            )));
        }
        let (key, bytes) = py.detach(|| -> PyResult<(u64, Vec<u8>)> {
            let points = self.points()?;
            let p = points
                .get(point)
                .ok_or_else(|| PyValueError::new_err(format!("no point {point}")))?;
            let s = divertsim_api::threads::with_threads(threads, || line::segment(p, o, k))
                .map_err(error)?;
            // The memo's own encoding: the run recalls exactly these bytes.
            let bytes = divertsim_core::run::memo::encode(&s)
                .ok_or_else(|| PyRuntimeError::new_err("a segment could not be encoded"))?;
            Ok((line::segment_key(line::line_key(p, o), k), bytes))
        })?;
        Ok((key, PyBytes::new(py, &bytes)))
    }

    /// The run from its segments (memo key, bytes), in order, as one machine tallies them;
    /// a segment not given is run here. Returns the summary (JSON text), the tables and the
    /// text, as `analysis("line", ...)`.
    #[pyo3(signature = (segments, threads=None))]
    fn merge<'py>(
        &self,
        py: Python<'py>,
        segments: Vec<(u64, Vec<u8>)>,
        threads: Option<usize>,
    ) -> PyResult<Given<'py>> {
        check_threads(threads)?;
        let out = py.detach(|| -> PyResult<Output> {
            let given = GivenSegments(segments.into_iter().collect());
            let hooks = contract::Hooks {
                memo: &given,
                threads,
                ..contract::Hooks::none()
            };
            let study = divertsim_api::threads::with_threads(threads, || {
                line::LineAnalysis::run(&self.base, &self.inputs, &hooks)
            })
            .map_err(error)?;
            contract::report::<line::LineAnalysis>(&study, &self.inputs, &self.base).map_err(error)
        })?;
        Ok(output(py, out))
    }
}

/// The job of a line run (validated here: a bad scenario or option raises ScenarioError
/// before any segment runs).
#[pyfunction]
#[pyo3(signature = (scenario, overrides, options_json, allow_outside_paths=false))]
pub fn line_job(
    py: Python<'_>,
    scenario: &Bound<'_, PyAny>,
    overrides: Vec<(String, Bound<'_, PyAny>)>,
    options_json: &str,
    allow_outside_paths: bool,
) -> PyResult<LineJob> {
    let job = (
        scenario,
        overrides.as_slice(),
        options_json,
        allow_outside_paths,
    );
    let (base, inputs, scenario_toml) = job_inputs::<line::LineAnalysis>(py, job)?;
    Ok(LineJob {
        base,
        inputs,
        points: OnceLock::new(),
        scenario_toml,
    })
}
