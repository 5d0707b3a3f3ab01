//! `divertsim studio`: a local web page where a setting is tried as fast as a slider moves.
//!
//! A small HTTP server (axum on tokio) serves one page from the binary (HTML, scripts and
//! styles compiled in: nothing from the network at view time) and a JSON API over the same
//! library calls as every other edge:
//! - `GET /api/scenario`: the scenario's JSON Schema ([`config::json_schema`]) and its
//!   resolved values, which the page turns into its editor;
//! - `POST /api/run`: one run of the scenario with the page's overrides, as
//!   `divertsim simulate` runs it ([`runs::run`]), drawn by the report's own viewer
//!   ([`divertsim_report::run::data`]); bad values come back as the CLI's problems;
//! - `GET /api/scenario.toml`, `GET /api/report.html`: the current scenario and its
//!   self-contained report, the overrides in the query (the page's share URL);
//! - `/api/studies`: analyses of the registry ([`divertsim_api::analyses::registry`]) run in
//!   the background with progress as server-sent events, cancellable ([`studies`]).
//!
//! Each connection is served by hyper with read timeouts ([`READ_TIMEOUT`]), so that a client
//! that sends half a request holds nothing for long; Ctrl-C gives open requests
//! [`SHUTDOWN_GRACE`] and then ends the process, progress streams and studies included.
//!
//! The page's overrides are `--set` texts (`machine.belt_speed=1.5`), parsed by the same
//! [`config::parse_set`]; an override or a study's sweep that names a file, wherever the key
//! sits, is refused by the loader's rule ([`config::LoadOptions::overrides_name_no_files`]),
//! so the page reads nothing beyond the scenario the server was started with
//! (docs/studio.md).

pub mod studies;

use axum::body::Bytes;
use axum::extract::{DefaultBodyLimit, Path as UrlPath, Query, State};
use axum::http::{header, StatusCode};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::Router;
use divertsim_api::analyses::runs;
use divertsim_api::config::{self, Loaded, Problem, Problems, ScenarioBuilder};
use divertsim_core::sim::Recording;
use serde::Deserialize;
use serde_json::{json, Value};
use std::net::{IpAddr, SocketAddr};
use std::path::PathBuf;
use std::sync::Arc;

const PAGE: &str = include_str!("../../assets/studio/studio.html");
const STUDIO_JS: &str = include_str!("../../assets/studio/studio.js");
const STUDIO_CSS: &str = include_str!("../../assets/studio/studio.css");
use divertsim_report::assets::{REPORT_CSS, REPORT_JS, UPLOT_CSS, UPLOT_JS};

/// Largest request body \[bytes]: a page's overrides are a few hundred bytes.
pub const MAX_BODY: usize = 64 * 1024;
/// Largest number of overrides in one request.
pub const MAX_SETS: usize = 256;
/// Largest override text (`KEY=VALUE`) \[bytes].
pub const MAX_SET_LEN: usize = 4096;
/// Time a client has to send a request's head, counted from its connecting or from the end
/// of its previous response (so an idle kept-alive connection is closed after it too), and
/// apart, the time it has to send the body. A client that sends half a request is then
/// disconnected instead of holding a connection and its task for ever.
pub const READ_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(10);
/// Time open requests get to end after Ctrl-C; then the process exits, progress streams,
/// half-sent requests and running studies included.
pub const SHUTDOWN_GRACE: std::time::Duration = std::time::Duration::from_secs(3);

/// How the studio is served.
#[derive(Debug, Clone)]
pub struct StudioOptions {
    /// The scenario file the page starts from (`None`: the built-in default).
    pub scenario: Option<PathBuf>,
    /// Whether files outside the scenario's folder may be read (the CLI's flag).
    pub allow_outside_paths: bool,
    /// The address to bind (loopback unless the user asks otherwise).
    pub host: IpAddr,
    /// The port (0: any free port).
    pub port: u16,
    /// Studies that may run at once.
    pub max_studies: usize,
    /// Worker threads of a study (the live runs keep the rest).
    pub study_threads: usize,
}

/// The server's state: the scenario source read once, the schema, the studies.
pub struct Studio {
    /// The resolved scenario: each run adds the page's overrides.
    base: ScenarioBuilder,
    /// The scenario as loaded at start.
    loaded: Loaded,
    /// Its name for the page (the file name, or "built-in default").
    name: String,
    schema: Value,
    /// Live runs at once (each is CPU work on a blocking thread, which holds its permit).
    runs: Arc<tokio::sync::Semaphore>,
    /// Open progress streams.
    pub(crate) streams: Arc<std::sync::atomic::AtomicUsize>,
    /// The Host values of the address served: a request naming another is refused.
    hosts: std::sync::Mutex<Vec<String>>,
    /// Whether any Host is accepted (--allow-remote).
    any_host: bool,
    studies: studies::Studies,
}

impl Studio {
    /// The studio of `options`, or the scenario's problems.
    pub fn new(options: &StudioOptions) -> Result<Studio, Problems> {
        // The page's overrides and a study's sweep may name no file: it reads only what the
        // scenario it was started with names.
        let load = config::LoadOptions {
            allow_outside_paths: options.allow_outside_paths,
            overrides_name_no_files: true,
        };
        let loaded = ScenarioBuilder::path(options.scenario.as_deref())
            .options(load)
            .load()?;
        // Every run starts from the resolved scenario: its base chain merged and its drive
        // table inline, read once here (mix records are read again by each load).
        let base = ScenarioBuilder::resolved(&loaded).merged()?;
        let name = options.scenario.as_ref().map_or_else(
            || "built-in default".to_string(),
            |p| p.display().to_string(),
        );
        let cores = std::thread::available_parallelism().map_or(2, |n| n.get());
        Ok(Studio {
            base,
            loaded,
            name,
            schema: config::json_schema(),
            runs: Arc::new(tokio::sync::Semaphore::new(cores.max(2))),
            streams: Arc::new(std::sync::atomic::AtomicUsize::new(0)),
            hosts: std::sync::Mutex::new(Vec::new()),
            any_host: !options.host.is_loopback(),
            studies: studies::Studies::new(options.max_studies, options.study_threads),
        })
    }

    /// The scenario with the page's overrides (`KEY=VALUE` texts), or every problem, each
    /// with the CLI's message.
    pub fn scenario(&self, sets: &[String]) -> Result<Loaded, Vec<Problem>> {
        let mut problems = Vec::new();
        if sets.len() > MAX_SETS {
            problems.push(Problem::new(
                "sets",
                format!("{} overrides; allowed: at most {MAX_SETS}", sets.len()),
            ));
            return Err(problems);
        }
        let mut builder = self.base.clone();
        for set in sets {
            match set_problem(set) {
                Some(p) => problems.push(p),
                None => builder = builder.set(set),
            }
        }
        if !problems.is_empty() {
            return Err(problems);
        }
        builder.load().map_err(|p| p.0)
    }
}

/// A problem with one override before it is applied: too long. (An override that names a
/// file, in any form, is refused by the loader under the studio's rule,
/// [`config::LoadOptions::overrides_name_no_files`].)
fn set_problem(set: &str) -> Option<Problem> {
    let key = set.split('=').next().unwrap_or("").trim();
    (set.len() > MAX_SET_LEN).then(|| {
        Problem::new(
            key,
            format!(
                "the override is {} bytes; allowed: at most {MAX_SET_LEN}",
                set.len()
            ),
        )
    })
}

/// The JSON of a list of problems: each key with the CLI's message, and the CLI's whole text.
pub fn problems_json(problems: &[Problem]) -> Value {
    json!({
        "error": Problems(problems.to_vec()).to_string(),
        "problems": problems.iter().map(|p| json!({"key": p.key, "message": p.message})).collect::<Vec<_>>(),
    })
}

fn json_response(status: StatusCode, v: &Value) -> Response {
    (
        status,
        [(header::CONTENT_TYPE, "application/json")],
        v.to_string(),
    )
        .into_response()
}

fn invalid(problems: &[Problem]) -> Response {
    json_response(StatusCode::UNPROCESSABLE_ENTITY, &problems_json(problems))
}

fn bad_request(key: &str, message: impl Into<String>) -> Response {
    invalid(&[Problem::new(key, message)])
}

/// Requests only from the studio's own page: exactly one Host, which must be the address
/// served (a page of another site reaching it through a rebound DNS name is refused), at
/// most one `Origin`, which must be that address, no API call that a browser marks as sent
/// by another site (`Sec-Fetch-Site`), and a body must be JSON (a cross-site form cannot
/// send one without asking).
async fn same_site(
    State(s): State<Arc<Studio>>,
    req: axum::extract::Request,
    next: axum::middleware::Next,
) -> Response {
    // Owned values: the request's body is not shared across threads.
    let headers = req.headers().clone();
    // RFC 9112 §3.2: several Host headers are a 400; several Origins are as ambiguous (which
    // one would be checked is up to the reader).
    for name in [header::HOST, header::ORIGIN] {
        let n = headers.get_all(&name).iter().count();
        if n > 1 {
            return json_response(
                StatusCode::BAD_REQUEST,
                &json!({"error": format!("{n} {name} headers; a request has at most one")}),
            );
        }
    }
    let header = |name: header::HeaderName| {
        headers
            .get(name)
            .and_then(|v| v.to_str().ok())
            .map(str::to_string)
    };
    let host = header(header::HOST).unwrap_or_default();
    let known = s
        .hosts
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .contains(&host);
    if !s.any_host && !known {
        return json_response(
            StatusCode::FORBIDDEN,
            &json!({"error": format!("Host '{host}' is not this studio's address")}),
        );
    }
    if let Some(origin) = header(header::ORIGIN) {
        if origin != format!("http://{host}") {
            return json_response(
                StatusCode::FORBIDDEN,
                &json!({"error": format!("requests from {origin} are refused: only the studio's own page may call it")}),
            );
        }
    }
    // A browser names the site a request comes from. A GET sends no Origin, yet an image or a
    // link on another site (or on another port of this host: "same-site") would make the
    // studio run a simulation: the API answers only its own page ("same-origin") and
    // requests a user makes (an address typed: "none"; curl sends no such header). The page
    // itself may be opened from anywhere.
    let site = headers.get("sec-fetch-site").map(|v| v.as_bytes());
    let own = matches!(site, None | Some(b"same-origin") | Some(b"none"));
    if !own && req.uri().path().starts_with("/api/") {
        let site = String::from_utf8_lossy(site.unwrap_or_default());
        return json_response(
            StatusCode::FORBIDDEN,
            &json!({"error": format!("a request from another site (Sec-Fetch-Site: {site}) is refused: only the studio's own page may call the API")}),
        );
    }
    let json_body = header(header::CONTENT_TYPE)
        .is_some_and(|t| t.split(';').next().map(str::trim) == Some("application/json"));
    if req.method() == axum::http::Method::POST && !json_body {
        return json_response(
            StatusCode::UNSUPPORTED_MEDIA_TYPE,
            &json!({"error": "a request body must be JSON (Content-Type: application/json)"}),
        );
    }
    next.run(req).await
}

/// The request's body read whole before any handler runs, bounded in size ([`MAX_BODY`])
/// and in time ([`READ_TIMEOUT`]): a body announced larger than the limit is refused before
/// a byte of it is read (413), one sent too slowly is answered 408. Both close the
/// connection (its unread rest cannot be skipped).
async fn read_body(req: axum::extract::Request, next: axum::middleware::Next) -> Response {
    use futures_util::StreamExt;
    let closing = |status: StatusCode, message: String| {
        let mut resp = json_response(status, &json!({ "error": message }));
        resp.headers_mut().insert(
            header::CONNECTION,
            header::HeaderValue::from_static("close"),
        );
        resp
    };
    let too_large = |n: u64| {
        closing(
            StatusCode::PAYLOAD_TOO_LARGE,
            format!("the request body is {n} bytes or more; allowed: at most {MAX_BODY}"),
        )
    };
    let (parts, body) = req.into_parts();
    let announced = parts
        .headers
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.trim().parse::<u64>().ok());
    if let Some(n) = announced.filter(|&n| n > MAX_BODY as u64) {
        return too_large(n);
    }
    let read = async {
        let mut bytes = Vec::new();
        let mut chunks = body.into_data_stream();
        while let Some(chunk) = chunks.next().await {
            let chunk = chunk
                .map_err(|e| closing(StatusCode::BAD_REQUEST, format!("the request body: {e}")))?;
            if bytes.len() + chunk.len() > MAX_BODY {
                return Err(too_large((bytes.len() + chunk.len()) as u64));
            }
            bytes.extend_from_slice(&chunk);
        }
        Ok(bytes)
    };
    match tokio::time::timeout(READ_TIMEOUT, read).await {
        Ok(Ok(bytes)) => {
            let req = axum::extract::Request::from_parts(parts, axum::body::Body::from(bytes));
            next.run(req).await
        }
        Ok(Err(resp)) => resp,
        Err(_) => closing(
            StatusCode::REQUEST_TIMEOUT,
            format!(
                "the request body did not arrive within {} s",
                READ_TIMEOUT.as_secs()
            ),
        ),
    }
}

/// The Host values of an address: the address itself and, on loopback, `localhost`.
fn host_names(addr: SocketAddr) -> Vec<String> {
    let mut names = vec![addr.to_string()];
    if addr.ip().is_loopback() {
        names.push(format!("localhost:{}", addr.port()));
    }
    names
}

/// The routes of the studio.
pub fn router(studio: Arc<Studio>) -> Router {
    Router::new()
        .route("/", get(page))
        .route("/assets/{name}", get(asset))
        .route("/api/scenario", get(scenario_info))
        .route("/api/run", post(run))
        .route("/api/scenario.toml", get(scenario_toml))
        .route("/api/report.html", get(report_html))
        .route("/api/studies", post(studies::start))
        .route(
            "/api/studies/{id}",
            get(studies::status).delete(studies::cancel),
        )
        .route("/api/studies/{id}/events", get(studies::events))
        .route("/api/studies/{id}/outputs.zip", get(studies::outputs_zip))
        // Layers run last added first: a refused request's body is never read.
        .layer(axum::middleware::from_fn(read_body))
        .layer(axum::middleware::from_fn_with_state(
            studio.clone(),
            same_site,
        ))
        .layer(DefaultBodyLimit::max(MAX_BODY))
        .with_state(studio)
}

async fn page() -> Response {
    let page = divertsim_report::run::fill(PAGE, &[("VIEWER", &divertsim_report::run::viewer(""))]);
    (
        [
            (header::CONTENT_TYPE, "text/html; charset=utf-8"),
            (header::CACHE_CONTROL, "no-store"),
        ],
        page,
    )
        .into_response()
}

async fn asset(UrlPath(name): UrlPath<String>) -> Response {
    let (body, kind) = match name.as_str() {
        "studio.js" => (STUDIO_JS, "text/javascript"),
        "studio.css" => (STUDIO_CSS, "text/css"),
        "report.js" => (REPORT_JS, "text/javascript"),
        "report.css" => (REPORT_CSS, "text/css"),
        "uPlot.iife.min.js" => (UPLOT_JS, "text/javascript"),
        "uPlot.min.css" => (UPLOT_CSS, "text/css"),
        _ => return (StatusCode::NOT_FOUND, "no such asset").into_response(),
    };
    (
        [
            (header::CONTENT_TYPE, format!("{kind}; charset=utf-8")),
            (header::CACHE_CONTROL, "no-store".to_string()),
        ],
        body,
    )
        .into_response()
}

async fn scenario_info(State(s): State<Arc<Studio>>) -> Response {
    let values = serde_json::to_value(&s.loaded.file).unwrap_or(Value::Null);
    json_response(
        StatusCode::OK,
        &json!({
            "name": s.name,
            "version": env!("CARGO_PKG_VERSION"),
            "schema": s.schema,
            "values": values,
            "path_keys": config::files::PATH_KEYS.iter().map(|k| k.join(".")).collect::<Vec<_>>(),
            "analyses": divertsim_api::analyses::registry::REGISTRY.iter().map(|e| json!({
                "name": e.name, "about": e.about, "options": (e.schema)(),
            })).collect::<Vec<_>>(),
        }),
    )
}

/// A run request: the page's request number (echoed, so that the page draws only the
/// latest) and its overrides.
#[derive(Debug, Deserialize)]
pub struct RunRequest {
    #[serde(default)]
    pub id: u64,
    #[serde(default)]
    pub sets: Vec<String>,
}

/// A JSON body, or the response that says why it is not one.
pub fn parse_body<T: serde::de::DeserializeOwned>(body: &Bytes) -> Result<T, Box<Response>> {
    serde_json::from_slice(body)
        .map_err(|e| Box::new(bad_request("request", format!("not a valid request: {e}"))))
}

/// One run of the scenario with `sets`, as the page draws it.
pub fn run_json(s: &Studio, id: u64, sets: &[String]) -> Result<Value, Vec<Problem>> {
    let loaded = s.scenario(sets)?;
    let run = runs::run(&loaded, Recording::Full);
    let shown = [divertsim_report::run::ReportRun {
        label: "parcel".into(),
        scenario: &run.scenario,
        result: &run.result,
        measured: Vec::new(),
    }];
    Ok(json!({
        "id": id,
        "sets": sets,
        "data": divertsim_report::run::data(&shown),
        "summary": runs::summary(&run, &loaded.file),
        "setting": divertsim_report::run::setting_line(&run.scenario),
        "summary_html": divertsim_report::run::summary_html(&shown),
    }))
}

/// `work` on a blocking thread (runs and loads are CPU and file work, kept off the server's
/// threads); `limited`: it waits for a live-run place and holds it until the work ends,
/// even if its client has left. A work that stopped unexpectedly is a 500 with the reason.
pub async fn blocking<T: Send + 'static>(
    s: &Arc<Studio>,
    limited: bool,
    work: impl FnOnce(&Studio) -> T + Send + 'static,
) -> Result<T, Response> {
    let permit = match limited {
        true => match s.runs.clone().acquire_owned().await {
            Ok(p) => Some(p),
            Err(_) => {
                return Err(json_response(
                    StatusCode::SERVICE_UNAVAILABLE,
                    &json!({"error": "the studio is closing"}),
                ))
            }
        },
        false => None,
    };
    let studio = s.clone();
    tokio::task::spawn_blocking(move || {
        let _permit = permit;
        work(&studio)
    })
    .await
    .map_err(|e| server_error(format!("the work stopped: {e}")))
}

/// A 500 with its reason.
pub fn server_error(message: String) -> Response {
    json_response(
        StatusCode::INTERNAL_SERVER_ERROR,
        &json!({ "error": message }),
    )
}

async fn run(State(s): State<Arc<Studio>>, body: Bytes) -> Response {
    let req: RunRequest = match parse_body(&body) {
        Ok(r) => r,
        Err(resp) => return *resp,
    };
    let id = req.id;
    match blocking(&s, true, move |studio| run_json(studio, req.id, &req.sets)).await {
        Ok(Ok(v)) => json_response(StatusCode::OK, &v),
        Ok(Err(problems)) => {
            let mut v = problems_json(&problems);
            v["id"] = json!(id);
            json_response(StatusCode::UNPROCESSABLE_ENTITY, &v)
        }
        Err(resp) => resp,
    }
}

/// The overrides of a query string (`?machine.belt_speed=1.5&…`, the share URL's).
fn query_sets(q: &[(String, String)]) -> Vec<String> {
    q.iter().map(|(k, v)| format!("{k}={v}")).collect()
}

async fn scenario_toml(
    State(s): State<Arc<Studio>>,
    Query(q): Query<Vec<(String, String)>>,
) -> Response {
    let loaded = match blocking(&s, false, move |studio| studio.scenario(&query_sets(&q))).await {
        Ok(Ok(l)) => l,
        Ok(Err(p)) => return invalid(&p),
        Err(resp) => return resp,
    };
    let heading = format!(
        "Saved from divertsim studio {} (from {}), every input resolved: `divertsim simulate scenario.toml` runs it.",
        env!("CARGO_PKG_VERSION"),
        s.name
    );
    match config::to_toml(&config::standalone(&loaded.file), &heading) {
        Ok(text) => attachment(text.into_bytes(), "application/toml", "scenario.toml"),
        Err(e) => server_error(e.to_string()),
    }
}

async fn report_html(
    State(s): State<Arc<Studio>>,
    Query(q): Query<Vec<(String, String)>>,
) -> Response {
    let out = blocking(&s, true, move |studio| {
        let loaded = studio.scenario(&query_sets(&q))?;
        let run = runs::run(&loaded, Recording::Full);
        let resolved = config::to_toml(&loaded.file, "The scenario, every input resolved.")
            .unwrap_or_default();
        Ok::<_, Vec<Problem>>(divertsim_report::run::single(
            &run.scenario,
            &run.result,
            &resolved,
        ))
    })
    .await;
    match out {
        Ok(Ok(html)) => attachment(html.into_bytes(), "text/html; charset=utf-8", "report.html"),
        Ok(Err(p)) => invalid(&p),
        Err(resp) => resp,
    }
}

/// A file to download.
pub fn attachment(bytes: Vec<u8>, kind: &str, name: &str) -> Response {
    (
        [
            (header::CONTENT_TYPE, kind.to_string()),
            (
                header::CONTENT_DISPOSITION,
                format!("attachment; filename=\"{name}\""),
            ),
        ],
        bytes,
    )
        .into_response()
}

/// Why the studio stopped serving.
pub enum ServeError {
    /// The address could not be bound (the studio is given back, to try another port).
    Bind(std::io::Error, Box<Studio>),
    /// The server failed.
    Io(std::io::Error),
}

/// Serve `studio` on `options`' address until Ctrl-C; `ready` gets the bound address.
pub fn serve_on(
    options: &StudioOptions,
    studio: Studio,
    ready: impl FnOnce(SocketAddr),
) -> Result<(), ServeError> {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .map_err(ServeError::Io)?;
    let served = rt.block_on(async move {
        let listener = match tokio::net::TcpListener::bind((options.host, options.port)).await {
            Ok(l) => l,
            Err(e) => return Err(ServeError::Bind(e, Box::new(studio))),
        };
        let addr = listener.local_addr().map_err(ServeError::Io)?;
        *studio.hosts.lock().unwrap_or_else(|e| e.into_inner()) = host_names(addr);
        // Ctrl-C is caught from here on (polled once: its handler is installed now), so that a
        // script that reads the address may stop the studio at once.
        let mut ctrl_c = Box::pin(ctrl_c());
        let _ = futures_util::FutureExt::now_or_never(&mut ctrl_c);
        ready(addr);
        serve(listener, router(Arc::new(studio)), ctrl_c).await;
        Ok(())
    });
    // A live run still working on a blocking thread is not waited for: the process ends now
    // (a study runs on a thread of its own, which ends with the process).
    rt.shutdown_background();
    served
}

/// Ctrl-C; pending for ever where no handler can be installed (Ctrl-C then ends the process
/// as it ends any other).
async fn ctrl_c() {
    if tokio::signal::ctrl_c().await.is_err() {
        std::future::pending::<()>().await;
    }
}

/// Serve `app` on `listener` until `stop`: each connection with the [`READ_TIMEOUT`] of a
/// request's head (hyper's: axum::serve sets none), the body's being [`read_body`]'s. Then
/// no connection is accepted, open requests get [`SHUTDOWN_GRACE`] to end (a second Ctrl-C
/// cuts it short), and whatever is left is dropped: a progress stream never ends by
/// itself, and a client that sent half a request may send nothing more.
async fn serve(
    listener: tokio::net::TcpListener,
    app: Router,
    stop: std::pin::Pin<Box<impl std::future::Future<Output = ()>>>,
) {
    let mut http = hyper::server::conn::http1::Builder::new();
    http.timer(hyper_util::rt::TokioTimer::new())
        .header_read_timeout(READ_TIMEOUT);
    let (closing, closed) = tokio::sync::watch::channel(());
    let mut connections = tokio::task::JoinSet::new();
    let mut stop = stop;
    loop {
        // Finished connections are reaped as new ones come: the set holds open ones only.
        while connections.try_join_next().is_some() {}
        let tcp = tokio::select! {
            () = &mut stop => break,
            accepted = listener.accept() => match accepted {
                Ok((tcp, _)) => tcp,
                // Out of file descriptors, or a connection reset before it was accepted:
                // the listener stays, the next accept may succeed.
                Err(_) => {
                    tokio::time::sleep(std::time::Duration::from_millis(100)).await;
                    continue;
                }
            },
        };
        let service = hyper_util::service::TowerToHyperService::new(app.clone());
        let conn = http.serve_connection(hyper_util::rt::TokioIo::new(tcp), service);
        let mut closed = closed.clone();
        connections.spawn(async move {
            let mut conn = std::pin::pin!(conn);
            tokio::select! {
                _ = conn.as_mut() => return,
                _ = closed.changed() => conn.as_mut().graceful_shutdown(),
            }
            let _ = conn.await;
        });
    }
    drop(listener);
    let _ = closing.send(());
    eprintln!(
        "stopping: open requests get {} s (Ctrl-C again stops at once)",
        SHUTDOWN_GRACE.as_secs()
    );
    tokio::select! {
        () = async { while connections.join_next().await.is_some() {} } => {}
        () = tokio::time::sleep(SHUTDOWN_GRACE) => {}
        () = ctrl_c() => {}
    }
    // Dropping the set aborts the connections left.
}
