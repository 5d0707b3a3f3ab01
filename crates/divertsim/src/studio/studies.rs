//! The studio's studies: any analysis of the registry ([`registry::REGISTRY`]) run on the
//! page's scenario in the background, on its own thread and worker pool so that the live
//! runs are never queued behind it, with its progress streamed as server-sent events and a
//! cancel that stops it between pieces of work (the contract's [`Hooks`]).
//!
//! Bounds: at most `max_running` studies at once (a further one is refused with 429), and
//! the [`KEEP`] latest kept for their results, the finished ones' outputs within
//! [`KEPT_BYTES`]; a line study of at most [`MAX_LINE_PARCELS`] parcels (its memory grows
//! with them: docs/studio.md, "Memory").

use super::{json_response, parse_body, problems_json, Studio};
use axum::body::Bytes;
use axum::extract::{Path as UrlPath, State};
use axum::http::StatusCode;
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{IntoResponse, Response};
use divertsim_api::analyses::{registry, DEFAULT_MAX_SIMS};
use divertsim_api::config::{Loaded, Problem, Problems};
use divertsim_api::contract::{Error, Hooks, Report};
use divertsim_core::run::memo::NoMemo;
use serde::Deserialize;
use serde_json::{json, Value};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Studies kept (running or finished); the oldest finished one makes room for a new one.
pub const KEEP: usize = 16;

/// Bytes of outputs (tables, text, summary) the finished studies keep together: when a
/// study finishes beyond it, the oldest finished ones are dropped (the newest is kept).
pub const KEPT_BYTES: u64 = 512 << 20;

/// Parcels a line study runs at most, over all its sweep points (422 beyond). A line run
/// holds about 0.6 KB per parcel of the segments in flight and 24 bytes per parcel of its
/// log, and its parcel log's Parquet is about 100 bytes per parcel: within this, a line
/// study stays under a gigabyte whatever its `segment` (10⁶ parcels as one segment peak at
/// about 600 MB).
pub const MAX_LINE_PARCELS: u64 = 1_000_000;

/// Progress streams open at once.
pub const MAX_STREAMS: usize = 64;

/// The analyses the studio runs: every one of the registry but those that read files named
/// in their options ([`divertsim_api::contract::Entry::reads_files`]: `compare` and
/// `calibrate` read track files).
pub fn analyses() -> Vec<&'static str> {
    registry::REGISTRY
        .iter()
        .filter(|e| !e.reads_files)
        .map(|e| e.name)
        .collect()
}

/// Every study of the server.
pub struct Studies {
    list: Mutex<(u64, Vec<Arc<Study>>)>,
    max_running: usize,
    threads: usize,
}

/// How a study stands.
enum Phase {
    Running,
    Done(Box<Report>),
    Failed(Value),
    Cancelled,
}

/// One study.
pub struct Study {
    id: u64,
    analysis: &'static str,
    /// Units of progress done and announced ([`Hooks::progress`], [`Hooks::more`]).
    done: AtomicU64,
    total: AtomicU64,
    cancel: AtomicBool,
    started: Instant,
    /// The scenario it ran on (for its scenario.toml).
    loaded: Loaded,
    state: Mutex<Phase>,
    /// Seconds it took, once finished.
    seconds: Mutex<Option<f64>>,
    /// The latest partial results the analysis wrote to its live log (reliability: the
    /// rates so far after each shard).
    partial: Mutex<Option<Value>>,
    /// Bytes of its outputs once done ([`KEPT_BYTES`]).
    bytes: AtomicU64,
}

/// A live log that keeps its latest complete JSON line as the study's partial result.
struct PartialSink {
    study: Arc<Study>,
    line: Vec<u8>,
}

impl std::io::Write for PartialSink {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        for &b in buf {
            if b == b'\n' {
                if let Ok(v) = serde_json::from_slice::<Value>(&self.line) {
                    *self.study.partial.lock().unwrap_or_else(|e| e.into_inner()) = Some(v);
                }
                self.line.clear();
            } else if self.line.len() < 1 << 20 {
                self.line.push(b);
            }
        }
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Studies {
    /// No studies yet; `max_running` at once, each on `threads` workers.
    pub fn new(max_running: usize, threads: usize) -> Studies {
        Studies {
            list: Mutex::new((0, Vec::new())),
            max_running: max_running.max(1),
            threads: threads.max(1),
        }
    }

    fn find(&self, id: u64) -> Option<Arc<Study>> {
        let list = self.list.lock().unwrap_or_else(|e| e.into_inner());
        list.1.iter().find(|s| s.id == id).cloned()
    }

    /// Drop the oldest finished studies but `newest` while the finished studies' outputs
    /// exceed [`KEPT_BYTES`].
    fn trim(&self, newest: u64) {
        let mut list = self.list.lock().unwrap_or_else(|e| e.into_inner());
        let kept = |l: &[Arc<Study>]| -> u64 {
            l.iter()
                .filter(|x| !x.running())
                .map(|x| x.bytes.load(Ordering::Relaxed))
                .sum()
        };
        while kept(&list.1) > KEPT_BYTES {
            match list.1.iter().position(|x| !x.running() && x.id != newest) {
                Some(i) => {
                    list.1.remove(i);
                }
                None => break,
            }
        }
    }
}

/// The bytes a finished study keeps: its tables, text and summary.
fn outputs_bytes(r: &Report) -> u64 {
    let tables: usize = r.tables.iter().map(|t| t.0.len() + t.1.len()).sum();
    (tables + r.text.len() + r.summary.to_string().len()) as u64
}

/// A line study's parcels over its sweep points, refused beyond [`MAX_LINE_PARCELS`]
/// (options that do not parse are left to the analysis's own check).
fn line_parcels_problem(options: &Value) -> Option<Problem> {
    use divertsim_api::analyses::line::{LineAnalysis, Options};
    use divertsim_api::contract::{options_from_json, Analysis};
    let o: Options = options_from_json(options).ok()?;
    let points = LineAnalysis::validate(&o)
        .ok()?
        .sweep
        .map_or(1, |(_, values)| values.len() as u64);
    let parcels = o.parcels.saturating_mul(points);
    (parcels > MAX_LINE_PARCELS).then(|| {
        Problem::new(
            "parcels",
            format!(
                "{parcels} parcels ({} per point × {points} points) are above the studio's \
                 line limit; allowed: at most {MAX_LINE_PARCELS} over all points (the command \
                 line takes more)",
                o.parcels
            ),
        )
    })
}

impl Study {
    fn partial(&self) -> Value {
        self.partial
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clone()
            .unwrap_or(Value::Null)
    }

    fn running(&self) -> bool {
        matches!(
            *self.state.lock().unwrap_or_else(|e| e.into_inner()),
            Phase::Running
        )
    }

    /// The study as JSON: its state, progress and, once done, its summary and text.
    pub fn json(&self) -> Value {
        let state = self.state.lock().unwrap_or_else(|e| e.into_inner());
        let mut v = json!({
            "id": self.id,
            "analysis": self.analysis,
            "done": self.done.load(Ordering::Relaxed),
            "total": self.total.load(Ordering::Relaxed),
            "elapsed_s": self.seconds.lock().unwrap_or_else(|e| e.into_inner())
                .unwrap_or_else(|| self.started.elapsed().as_secs_f64()),
        });
        match &*state {
            Phase::Running => {
                v["state"] = json!("running");
                v["partial"] = self.partial();
            }
            Phase::Done(r) => {
                v["state"] = json!("done");
                v["summary"] = r.summary.clone();
                v["text"] = json!(r.text);
                v["tables"] = json!(r.tables.iter().map(|t| &t.0).collect::<Vec<_>>());
            }
            Phase::Failed(e) => {
                v["state"] = json!("failed");
                if let (Some(o), Some(e)) = (v.as_object_mut(), e.as_object()) {
                    o.extend(e.clone());
                }
            }
            Phase::Cancelled => v["state"] = json!("cancelled"),
        }
        v
    }
}

/// A study request: the analysis by name, the page's overrides and the analysis's options
/// (JSON, as Python's `analysis(name)` takes them; `max_sims` the work limit).
#[derive(Debug, Deserialize)]
pub struct StudyRequest {
    pub analysis: String,
    #[serde(default)]
    pub sets: Vec<String>,
    #[serde(default)]
    pub options: Value,
}

/// `POST /api/studies`: start a study; its id, or the problems.
pub async fn start(State(s): State<Arc<Studio>>, body: Bytes) -> Response {
    let req: StudyRequest = match parse_body(&body) {
        Ok(r) => r,
        Err(resp) => return *resp,
    };
    let Some(entry) = registry::find(&req.analysis).filter(|e| !e.reads_files) else {
        let names = analyses();
        return json_response(
            StatusCode::UNPROCESSABLE_ENTITY,
            &problems_json(&[Problem::new(
                "analysis",
                format!(
                    "no analysis '{}'; allowed: {}",
                    req.analysis,
                    names.join(", ")
                ),
            )]),
        );
    };
    let (max_sims, options) = match registry::max_sims_option(&req.options) {
        Ok(o) => o,
        Err(e) => return error_response(&e),
    };
    if let Some(p) = (entry.name == "line")
        .then(|| line_parcels_problem(&options))
        .flatten()
    {
        return json_response(StatusCode::UNPROCESSABLE_ENTITY, &problems_json(&[p]));
    }
    if max_sims > DEFAULT_MAX_SIMS {
        return json_response(
            StatusCode::UNPROCESSABLE_ENTITY,
            &problems_json(&[Problem::new(
                "max_sims",
                format!("{max_sims} is above the studio's work limit; allowed: 1 to {DEFAULT_MAX_SIMS} (the command line takes more)"),
            )]),
        );
    }
    // The scenario is checked here, so that its problems come back with the request.
    let sets = req.sets.clone();
    let loaded = match super::blocking(&s, false, move |studio| studio.scenario(&sets)).await {
        Ok(Ok(l)) => l,
        Ok(Err(p)) => return json_response(StatusCode::UNPROCESSABLE_ENTITY, &problems_json(&p)),
        Err(resp) => return resp,
    };
    // So are the options, with every scenario a sweep makes (a swept key that names a file
    // is refused by the loader's rule here), before anything runs in the background.
    let checked = {
        let (loaded, options) = (loaded.clone(), options.clone());
        super::blocking(&s, false, move |_| {
            let load = move |_: &[String]| -> Result<Loaded, Problems> { Ok(loaded.clone()) };
            (entry.check)(&load, &options, max_sims)
        })
        .await
    };
    match checked {
        Ok(Ok(())) => {}
        Ok(Err(e)) => return error_response(&e),
        Err(resp) => return resp,
    }
    let study = {
        let mut list = s.studies.list.lock().unwrap_or_else(|e| e.into_inner());
        let running = list.1.iter().filter(|x| x.running()).count();
        if running >= s.studies.max_running {
            return json_response(
                StatusCode::TOO_MANY_REQUESTS,
                &json!({"error": format!(
                    "{running} studies are running, the most this studio runs at once; cancel one or wait for it"
                )}),
            );
        }
        while list.1.len() >= KEEP {
            match list.1.iter().position(|x| !x.running()) {
                Some(i) => {
                    list.1.remove(i);
                }
                None => break,
            }
        }
        list.0 += 1;
        let study = Arc::new(Study {
            id: list.0,
            analysis: entry.name,
            done: AtomicU64::new(0),
            total: AtomicU64::new(0),
            cancel: AtomicBool::new(false),
            started: Instant::now(),
            loaded,
            state: Mutex::new(Phase::Running),
            seconds: Mutex::new(None),
            partial: Mutex::new(None),
            bytes: AtomicU64::new(0),
        });
        list.1.push(study.clone());
        study
    };
    let threads = s.studies.threads;
    let worker = study.clone();
    let studio = s.clone();
    let spawned = std::thread::Builder::new()
        .name(format!("study-{}", study.id))
        .spawn(move || {
            let loaded = worker.loaded.clone();
            let load = move |_: &[String]| -> Result<Loaded, Problems> { Ok(loaded.clone()) };
            let progress = || {
                worker.done.fetch_add(1, Ordering::Relaxed);
            };
            let more = |n: u64| {
                worker.total.fetch_add(n, Ordering::Relaxed);
            };
            let stop = || worker.cancel.load(Ordering::Relaxed);
            let partial_of = worker.clone();
            let live = move |_: &str| -> Option<Box<dyn std::io::Write + Send>> {
                Some(Box::new(PartialSink {
                    study: partial_of.clone(),
                    line: Vec::new(),
                }))
            };
            let hooks = Hooks {
                progress: &progress,
                more: &more,
                stop: &stop,
                memo: &NoMemo,
                threads: Some(threads),
                live: Some(&live),
            };
            let out = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                (entry.execute)(&load, &options, max_sims, &hooks)
            }));
            let state = match out {
                Ok(Ok(report)) => Phase::Done(Box::new(report)),
                Ok(Err(Error::Cancelled)) => Phase::Cancelled,
                Ok(Err(e)) => Phase::Failed(error_json(&e)),
                Err(_) => Phase::Failed(json!({"error": "the study stopped unexpectedly"})),
            };
            *worker.seconds.lock().unwrap_or_else(|e| e.into_inner()) =
                Some(worker.started.elapsed().as_secs_f64());
            if let Phase::Done(r) = &state {
                worker.bytes.store(outputs_bytes(r), Ordering::Relaxed);
            }
            *worker.state.lock().unwrap_or_else(|e| e.into_inner()) = state;
            studio.studies.trim(worker.id);
        });
    if let Err(e) = spawned {
        *study.state.lock().unwrap_or_else(|e| e.into_inner()) =
            Phase::Failed(json!({"error": format!("cannot start the study: {e}")}));
    }
    json_response(StatusCode::ACCEPTED, &study.json())
}

fn error_json(e: &Error) -> Value {
    match e {
        Error::Invalid(p) => problems_json(p),
        other => json!({"error": other.to_string()}),
    }
}

fn error_response(e: &Error) -> Response {
    json_response(StatusCode::UNPROCESSABLE_ENTITY, &error_json(e))
}

fn not_found(id: u64) -> Response {
    json_response(
        StatusCode::NOT_FOUND,
        &json!({"error": format!(
            "no study {id} (only the latest {KEEP} are kept, their outputs within {} MiB)",
            KEPT_BYTES >> 20
        )}),
    )
}

/// `GET /api/studies/{id}`: the study's state.
pub async fn status(State(s): State<Arc<Studio>>, UrlPath(id): UrlPath<u64>) -> Response {
    match s.studies.find(id) {
        Some(study) => json_response(StatusCode::OK, &study.json()),
        None => not_found(id),
    }
}

/// `DELETE /api/studies/{id}`: ask the study to stop (between pieces of work).
pub async fn cancel(State(s): State<Arc<Studio>>, UrlPath(id): UrlPath<u64>) -> Response {
    match s.studies.find(id) {
        Some(study) => {
            study.cancel.store(true, Ordering::Relaxed);
            json_response(StatusCode::OK, &study.json())
        }
        None => not_found(id),
    }
}

/// `GET /api/studies/{id}/events`: `progress` events ({done, total, partial}: the results so
/// far where the analysis writes them) while it runs, then one `end` event with the study's
/// final JSON.
pub async fn events(State(s): State<Arc<Studio>>, UrlPath(id): UrlPath<u64>) -> Response {
    let Some(study) = s.studies.find(id) else {
        return not_found(id);
    };
    let open = s.streams.fetch_add(1, Ordering::SeqCst);
    let guard = StreamGuard(s.streams.clone());
    if open >= MAX_STREAMS {
        return json_response(
            StatusCode::TOO_MANY_REQUESTS,
            &json!({"error": format!("{MAX_STREAMS} progress streams are open; close one")}),
        );
    }
    let stream = futures_util::stream::unfold(
        (study, None::<(u64, u64)>, false, guard),
        |(study, last, ended, guard)| async move {
            if ended {
                return None;
            }
            loop {
                if !study.running() {
                    let event = Event::default().event("end").data(study.json().to_string());
                    return Some((
                        Ok::<_, std::convert::Infallible>(event),
                        (study, last, true, guard),
                    ));
                }
                let now = (
                    study.done.load(Ordering::Relaxed),
                    study.total.load(Ordering::Relaxed),
                );
                if last != Some(now) {
                    let event = Event::default().event("progress").data(
                        json!({"done": now.0, "total": now.1, "partial": study.partial()})
                            .to_string(),
                    );
                    return Some((Ok(event), (study, Some(now), false, guard)));
                }
                tokio::time::sleep(Duration::from_millis(100)).await;
            }
        },
    );
    Sse::new(stream)
        .keep_alive(KeepAlive::default())
        .into_response()
}

/// One open progress stream, counted until it is dropped (the client left or it ended).
struct StreamGuard(Arc<std::sync::atomic::AtomicUsize>);

impl Drop for StreamGuard {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::SeqCst);
    }
}

/// `GET /api/studies/{id}/outputs.zip`: the summary, the tables, the text and the scenario,
/// with a copy of each file the scenario names.
pub async fn outputs_zip(State(s): State<Arc<Studio>>, UrlPath(id): UrlPath<u64>) -> Response {
    let Some(study) = s.studies.find(id) else {
        return not_found(id);
    };
    let mut files = {
        let state = study.state.lock().unwrap_or_else(|e| e.into_inner());
        let Phase::Done(r) = &*state else {
            return json_response(
                StatusCode::CONFLICT,
                &json!({"error": format!("study {id} has no outputs (it is not done)")}),
            );
        };
        let mut files = vec![
            (
                "summary.json".to_string(),
                serde_json::to_vec_pretty(&r.summary).unwrap_or_default(),
            ),
            ("report.txt".to_string(), r.text.clone().into_bytes()),
        ];
        files.extend(r.tables.iter().cloned());
        files.push(divertsim_api::output::scenario_toml(
            &study.analysis.replace('_', "-"),
            &study.loaded.file,
        ));
        files
    };
    // As an output folder does: a file the scenario names (its parcel records) goes into the
    // archive beside it, so that it reruns there and shows nothing of the user's layout.
    divertsim_api::output::bundle_inputs(&mut files);
    match zip_bytes(&files) {
        Ok(bytes) => super::attachment(
            bytes,
            "application/zip",
            &format!("{}-{id}.zip", study.analysis),
        ),
        Err(e) => super::server_error(format!("cannot write the zip: {e}")),
    }
}

/// A zip archive of named files (stored: CSV and JSON compress well, but a study's outputs
/// are small).
pub fn zip_bytes(files: &[(String, Vec<u8>)]) -> Result<Vec<u8>, zip::result::ZipError> {
    use std::io::Write;
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options =
        zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
    for (name, bytes) in files {
        zip.start_file(name.as_str(), options)?;
        zip.write_all(bytes)?;
    }
    Ok(zip.finish()?.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A line study is bounded by its parcels over all its points, whatever its segment.
    #[test]
    fn a_line_study_beyond_the_studios_parcels_is_refused() {
        let at_limit = json!({"parcels": MAX_LINE_PARCELS, "segment": 1_000_000});
        assert!(line_parcels_problem(&at_limit).is_none());
        let swept = json!({"parcels": 600_000, "sweep": "line.gap_target=1,2"});
        let p = line_parcels_problem(&swept).expect("1.2e6 parcels over two points");
        assert_eq!(p.key, "parcels");
        assert!(p.message.contains("2 points"), "{}", p.message);
        // Options that do not parse are the analysis's to refuse, with its own words.
        assert!(line_parcels_problem(&json!({"parcels": "many"})).is_none());
    }
}
