//! The analyses for Python: `analysis` runs any of `divertsim_api::analyses::request` (the
//! same entry the CLI's numbers come from), and `StudyJob` splits a study that runs in
//! pieces (reliability's shards, the line's segments: [`divertsim_api::pieces`]) for a
//! cluster (`divertsim.dask`) and merges them back into the run one machine would give, bit
//! for bit. Conversion only: arguments in, JSON text and CSV or Parquet bytes out.

use std::collections::HashMap;
use std::sync::OnceLock;

use divertsim_api::analyses::line;
use divertsim_api::analyses::registry as by_name;
use divertsim_api::analyses::reliability::Reliability;
use divertsim_api::config::{self, LoadOptions, Loaded, Problems, ScenarioBuilder};
use divertsim_api::contract::{self, Analysis, Error, Report as Output};
use divertsim_api::pieces::{run_from_pieces, Piece, Pieces};
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

/// A study run as pieces, for any analysis that has them ([`Pieces`]): what a cluster's
/// client and workers both hold.
trait Job: Send + Sync {
    fn pieces(&self) -> Vec<(usize, u64)>;
    fn scenario_toml(&self) -> &str;
    fn run_piece(&self, point: usize, k: u64) -> Result<(u64, Vec<u8>), Error>;
    fn merge(&self, pieces: Vec<(u64, Vec<u8>)>, threads: Option<usize>) -> Result<Output, Error>;
}

/// The job of study `A`: its scenario, the options bound to it, what its pieces need
/// (made once, on first use) and the scenario as the workers load it.
struct JobOf<A: Pieces> {
    base: Loaded,
    bound: A::Bound,
    /// Its pieces in order, worked out once, and their keys by (point, k).
    pieces: Vec<Piece>,
    keys: HashMap<(usize, u64), u64>,
    prepared: OnceLock<Result<A::Prepared, Error>>,
    /// The resolved scenario as TOML text (standalone): what workers load.
    scenario_toml: String,
}

impl<A: Pieces> JobOf<A> {
    fn prepared(&self) -> Result<&A::Prepared, Error> {
        self.prepared
            .get_or_init(|| A::prepare(&self.bound))
            .as_ref()
            .map_err(Clone::clone)
    }
}

impl<A: Pieces> Job for JobOf<A>
where
    A::Bound: Send + Sync,
{
    fn pieces(&self) -> Vec<(usize, u64)> {
        self.pieces.iter().map(|p| (p.point, p.k)).collect()
    }
    fn scenario_toml(&self) -> &str {
        &self.scenario_toml
    }
    fn run_piece(&self, point: usize, k: u64) -> Result<(u64, Vec<u8>), Error> {
        let bytes = A::run_piece(&self.bound, self.prepared()?, point, k)?;
        // run_piece has checked that the piece is one of this run's.
        Ok((self.keys.get(&(point, k)).copied().unwrap_or(0), bytes))
    }
    fn merge(&self, pieces: Vec<(u64, Vec<u8>)>, threads: Option<usize>) -> Result<Output, Error> {
        // The study prepares its own points as it runs: the client's job prepares nothing.
        run_from_pieces::<A>(&self.base, &self.bound, pieces, threads)
    }
}

/// A study split into pieces for a cluster (`divertsim.dask`): a reliability run's shards
/// or a line run's segments, each seeded by (point, k), run by the workers and handed back
/// to the run one machine would make of them, bit for bit.
#[pyclass(frozen, module = "divertsim._native", name = "StudyJob")]
pub struct StudyJob(Box<dyn Job>);

#[pymethods]
impl StudyJob {
    /// Every piece as (point, k), in the order one machine runs them.
    fn pieces(&self) -> Vec<(usize, u64)> {
        self.0.pieces()
    }

    /// The resolved scenario (standalone TOML text, the overrides applied): a worker loads
    /// it to rebuild this job.
    fn scenario_toml(&self) -> String {
        self.0.scenario_toml().to_string()
    }

    /// Run piece `k` of point `point` (GIL released); returns its key and its bytes (a
    /// reliability shard's are those of a Parquet file of its samples).
    #[pyo3(signature = (point, k, threads=None))]
    fn run_piece<'py>(
        &self,
        py: Python<'py>,
        point: usize,
        k: u64,
        threads: Option<usize>,
    ) -> PyResult<(u64, Bound<'py, PyBytes>)> {
        check_threads(threads)?;
        let (key, bytes) = py
            .detach(|| divertsim_api::threads::with_threads(threads, || self.0.run_piece(point, k)))
            .map_err(error)?;
        Ok((key, PyBytes::new(py, &bytes)))
    }

    /// The run from its pieces (key, bytes), tallied in order with the early stop of one
    /// machine; a piece not given is run here, one of another run (or given twice) is
    /// refused. Returns the summary (JSON text), the tables and the text, as
    /// `analysis(name, ...)`.
    #[pyo3(signature = (pieces, threads=None))]
    fn merge<'py>(
        &self,
        py: Python<'py>,
        pieces: Vec<(u64, Vec<u8>)>,
        threads: Option<usize>,
    ) -> PyResult<Given<'py>> {
        check_threads(threads)?;
        let out = py.detach(|| self.0.merge(pieces, threads)).map_err(error)?;
        Ok(output(py, out))
    }
}

/// The job of a study (`reliability` or `line`), validated here: a bad scenario or option
/// raises ScenarioError before any piece runs.
#[pyfunction]
#[pyo3(signature = (name, scenario, overrides, options_json, allow_outside_paths=false))]
pub fn study_job(
    py: Python<'_>,
    name: &str,
    scenario: &Bound<'_, PyAny>,
    overrides: Vec<(String, Bound<'_, PyAny>)>,
    options_json: &str,
    allow_outside_paths: bool,
) -> PyResult<StudyJob> {
    let args = (
        scenario,
        overrides.as_slice(),
        options_json,
        allow_outside_paths,
    );
    fn job<A: Pieces + 'static>(py: Python<'_>, args: JobArgs<'_, '_>) -> PyResult<StudyJob>
    where
        A::Bound: Send + Sync,
    {
        let (base, bound, scenario_toml) = job_inputs::<A>(py, args)?;
        let pieces = A::pieces(&bound);
        Ok(StudyJob(Box::new(JobOf::<A> {
            base,
            keys: pieces.iter().map(|p| ((p.point, p.k), p.key)).collect(),
            pieces,
            bound,
            prepared: OnceLock::new(),
            scenario_toml,
        })))
    }
    match name {
        "reliability" => job::<Reliability>(py, args),
        "line" => job::<line::LineAnalysis>(py, args),
        _ => Err(PyValueError::new_err(format!(
            "no study named {name:?}; allowed: reliability, line (the analyses run in pieces)"
        ))),
    }
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
