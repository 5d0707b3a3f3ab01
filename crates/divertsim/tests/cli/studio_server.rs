//! `divertsim studio` over HTTP (issue 29): a run equals `divertsim simulate`, bad input comes
//! back as the CLI's message, files are never read through the page, requests and studies
//! are bounded, a study streams its progress, can be cancelled and equals the CLI's, and 20
//! clients moving sliders at once for 30 s get each their own answer with bounded memory.
//! Hostile clients (round four): half-sent requests are closed after the read timeout,
//! Ctrl-C ends the studio within 5 s whatever is open, and API calls of other sites or with
//! several Hosts or Origins are refused.

use crate::common::{divertsim, json_stdout};
use serde_json::{json, Value};
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

/// A studio server on a free port, stopped when dropped.
pub struct Server {
    child: Child,
    /// host:port
    pub addr: String,
}

impl Server {
    /// `divertsim studio --port 0 ARGS`, once it has printed its address.
    pub fn start(args: &[&str]) -> Server {
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_divertsim"))
            .args(["studio", "--port", "0"])
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut line)
            .unwrap();
        let url = line
            .trim()
            .strip_prefix("divertsim studio: http://")
            .unwrap_or_else(|| panic!("the address line: {line:?}"));
        Server {
            child,
            addr: url.trim_end_matches('/').to_string(),
        }
    }

    /// The page's address.
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }

    /// The server's resident memory [kB] (Linux).
    pub fn rss_kb(&self) -> u64 {
        std::fs::read_to_string(format!("/proc/{}/status", self.child.id()))
            .unwrap_or_default()
            .lines()
            .find(|l| l.starts_with("VmRSS:"))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|v| v.parse().ok())
            .unwrap_or(0)
    }

    /// `method path` with `body`: the status and the body (HTTP/1.1, one request per
    /// connection).
    pub fn request(&self, method: &str, path: &str, body: Option<&[u8]>) -> (u16, Vec<u8>) {
        let headers = format!("Host: {}\r\nContent-Type: application/json\r\n", self.addr);
        self.request_with(method, path, &headers, body)
    }

    /// [`Server::request`] with these header lines (each ending in CRLF).
    pub fn request_with(
        &self,
        method: &str,
        path: &str,
        headers: &str,
        body: Option<&[u8]>,
    ) -> (u16, Vec<u8>) {
        let mut s = TcpStream::connect(&self.addr).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(120))).unwrap();
        let body = body.unwrap_or(b"");
        write!(
            s,
            "{method} {path} HTTP/1.1\r\n{headers}Connection: close\r\nContent-Length: {}\r\n\r\n",
            body.len()
        )
        .unwrap();
        s.write_all(body).unwrap();
        let mut raw = Vec::new();
        s.read_to_end(&mut raw).unwrap();
        parse_response(&raw)
    }

    /// A JSON request: the status and the JSON body.
    pub fn json(&self, method: &str, path: &str, body: Option<&Value>) -> (u16, Value) {
        let bytes = body.map(|b| b.to_string().into_bytes());
        let (code, out) = self.request(method, path, bytes.as_deref());
        let v = serde_json::from_slice(&out).unwrap_or_else(|_| {
            panic!(
                "{method} {path}: not JSON ({code}): {}",
                String::from_utf8_lossy(&out)
            )
        });
        (code, v)
    }

    /// Start a study; its id.
    pub fn start_study(&self, analysis: &str, sets: &[&str], options: Value) -> u64 {
        let (code, v) = self.json(
            "POST",
            "/api/studies",
            Some(&json!({"analysis": analysis, "sets": sets, "options": options})),
        );
        assert_eq!(code, 202, "{v}");
        v["id"].as_u64().unwrap()
    }

    /// The server-sent events of a study until its `end` event: (event, data) pairs.
    pub fn events(&self, id: u64) -> Vec<(String, Value)> {
        let (code, raw) = self.request("GET", &format!("/api/studies/{id}/events"), None);
        assert_eq!(code, 200);
        let text = String::from_utf8(raw).unwrap();
        let mut out = Vec::new();
        for block in text.split("\n\n") {
            let mut event = None;
            let mut data = String::new();
            for line in block.lines() {
                if let Some(e) = line.strip_prefix("event: ") {
                    event = Some(e.to_string());
                } else if let Some(d) = line.strip_prefix("data: ") {
                    data += d;
                }
            }
            if let Some(e) = event {
                out.push((e, serde_json::from_str(&data).unwrap()));
            }
        }
        out
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The status and body of a raw HTTP/1.1 response (chunked or not).
fn parse_response(raw: &[u8]) -> (u16, Vec<u8>) {
    let end = raw
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .expect("a response head");
    let head = String::from_utf8_lossy(&raw[..end]).to_ascii_lowercase();
    let code: u16 = head.split_whitespace().nth(1).unwrap().parse().unwrap();
    let mut body = &raw[end + 4..];
    if !head.contains("transfer-encoding: chunked") {
        return (code, body.to_vec());
    }
    let mut out = Vec::new();
    while let Some(eol) = body.windows(2).position(|w| w == b"\r\n") {
        let size =
            usize::from_str_radix(String::from_utf8_lossy(&body[..eol]).trim(), 16).unwrap_or(0);
        if size == 0 || body.len() < eol + 2 + size {
            break;
        }
        out.extend_from_slice(&body[eol + 2..eol + 2 + size]);
        body = &body[(eol + 4 + size).min(body.len())..];
    }
    (code, out)
}

/// `divertsim simulate --json` with these overrides.
fn simulate_json(sets: &[&str]) -> Value {
    let mut cmd = divertsim();
    cmd.arg("simulate").arg("--json");
    for s in sets {
        cmd.args(["--set", s]);
    }
    json_stdout(&mut cmd)
}

#[test]
fn studio_run_equals_simulate_and_bad_input_gets_the_cli_message() {
    let server = Server::start(&[]);
    // The page and its assets come from the binary.
    let (code, page) = server.request("GET", "/", None);
    assert_eq!(code, 200);
    let page = String::from_utf8(page).unwrap();
    for asset in ["studio.js", "report.js", "uPlot.iife.min.js", "studio.css"] {
        assert!(page.contains(&format!("/assets/{asset}")), "{asset}");
        let (code, body) = server.request("GET", &format!("/assets/{asset}"), None);
        assert_eq!(code, 200, "{asset}");
        assert!(body.len() > 500, "{asset}");
    }
    assert!(
        !page.contains("http://") && !page.contains("https://"),
        "nothing from the network"
    );
    assert_eq!(server.request("GET", "/assets/../Cargo.toml", None).0, 404);

    // The schema and the resolved values the editor is made of.
    let (code, info) = server.json("GET", "/api/scenario", None);
    assert_eq!(code, 200);
    assert_eq!(info["values"]["machine"]["belt_speed"], 2.0);
    assert!(
        info["schema"]["$defs"]["MachineConfig"]["properties"]["belt_speed"]["description"]
            .as_str()
            .unwrap()
            .contains("[m/s]")
    );

    // A run is `simulate`'s, bit for bit (its summary, with the resolved scenario).
    let sets = ["machine.belt_speed=1.5", "parcel.angle_deg=10"];
    let (code, run) = server.json("POST", "/api/run", Some(&json!({"id": 7, "sets": sets})));
    assert_eq!(code, 200, "{run}");
    assert_eq!(run["id"], 7, "each response names its request");
    assert_eq!(run["summary"], simulate_json(&sets));
    let t = run["data"]["runs"][0]["t"].as_array().unwrap();
    assert!(t.len() > 50);

    // Out of range: the CLI's problems and its very text.
    let bad = ["machine.belt_speed=99", "parcel.mass=-1"];
    let (code, v) = server.json("POST", "/api/run", Some(&json!({"id": 8, "sets": bad})));
    assert_eq!(code, 422);
    assert_eq!(v["id"], 8);
    let keys: Vec<&str> = v["problems"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["key"].as_str().unwrap())
        .collect();
    assert_eq!(keys, ["machine.belt_speed", "parcel.mass"]);
    let cli = divertsim()
        .args(["simulate", "--set", bad[0], "--set", bad[1]])
        .output()
        .unwrap();
    assert_eq!(cli.status.code(), Some(2));
    assert_eq!(
        format!("error: {}", v["error"].as_str().unwrap()),
        String::from_utf8_lossy(&cli.stderr)
    );
    // The same text for a download of that scenario.
    let (code, _) = server.request("GET", "/api/scenario.toml?machine.belt_speed=99", None);
    assert_eq!(code, 422);
}

#[test]
fn studio_reads_no_file_and_bounds_every_request() {
    let server = Server::start(&[]);
    // Review of the studio: a table at a parent key named a file too.
    for set in [
        "base=\"/etc/passwd\"",
        "mix.records=\"/etc/passwd\"",
        "line.arrivals=\"../x.csv\"",
        "machine.drive.table=\"/etc/hosts\"",
        "machine.drive={kind=\"table\", table=\"tab.csv\"}",
        "machine={drive={table=\"tab.csv\"}}",
        "mix={records=\"records.csv\"}",
        "line={arrivals=\"arrivals.csv\"}",
    ] {
        let (code, v) = server.json("POST", "/api/run", Some(&json!({"sets": [set]})));
        assert_eq!(code, 422, "{set}: {v}");
        assert!(
            v["problems"][0]["message"]
                .as_str()
                .unwrap()
                .contains("names a file"),
            "{v}"
        );
    }
    // Not JSON, a body over the limit, too many overrides, an unknown key, an unknown study.
    let (code, v) = server.json("POST", "/api/run", None);
    assert_eq!(
        (code, v["problems"][0]["key"].as_str()),
        (422, Some("request"))
    );
    let huge = vec![b' '; 200 * 1024];
    assert_eq!(server.request("POST", "/api/run", Some(&huge)).0, 413);
    let many: Vec<String> = (0..300).map(|i| format!("parcel.mass={}", 1 + i)).collect();
    let (code, v) = server.json("POST", "/api/run", Some(&json!({"sets": many})));
    assert_eq!(
        (code, v["problems"][0]["key"].as_str()),
        (422, Some("sets"))
    );
    let (code, v) = server.json(
        "POST",
        "/api/run",
        Some(&json!({"sets": ["machine.belt_sped=1"]})),
    );
    assert_eq!(code, 422);
    assert!(
        v["error"].as_str().unwrap().contains("machine.belt_sped"),
        "{v}"
    );
    let (code, v) = server.json(
        "POST",
        "/api/studies",
        Some(&json!({"analysis": "nothing"})),
    );
    assert_eq!(code, 422);
    assert!(
        v["error"].as_str().unwrap().contains("allowed: trigger"),
        "{v}"
    );
    assert_eq!(server.json("GET", "/api/studies/99", None).0, 404);
    // Analyses that read files named in their options are not served; the work limit is
    // the studio's.
    let (code, v) = server.json(
        "POST",
        "/api/studies",
        Some(&json!({"analysis": "compare", "options": {"tracks": ["/etc/hosts"]}})),
    );
    assert_eq!(code, 422);
    assert!(!v["error"].as_str().unwrap().contains("compare,"), "{v}");
    let (code, v) = server.json(
        "POST",
        "/api/studies",
        Some(&json!({"analysis": "reliability", "options": {"max_sims": 100_000_000_000u64}})),
    );
    assert_eq!(
        (code, v["problems"][0]["key"].as_str()),
        (422, Some("max_sims"))
    );
    // Only the studio's own page: another Host (DNS rebinding), another Origin, a body that
    // is not JSON (a cross-site form) are refused.
    let body = br#"{"sets": []}"#;
    let (code, _) = server.request_with(
        "POST",
        "/api/run",
        "Host: attacker.example\r\nContent-Type: application/json\r\n",
        Some(body),
    );
    assert_eq!(code, 403);
    let (code, _) = server.request_with(
        "POST",
        "/api/run",
        &format!(
            "Host: {}\r\nOrigin: http://attacker.example\r\nContent-Type: application/json\r\n",
            server.addr
        ),
        Some(body),
    );
    assert_eq!(code, 403);
    let (code, _) = server.request_with(
        "POST",
        "/api/run",
        &format!("Host: {}\r\nContent-Type: text/plain\r\n", server.addr),
        Some(body),
    );
    assert_eq!(code, 415);
    let (code, _) = server.request_with(
        "POST",
        "/api/run",
        &format!(
            "Host: {}\r\nOrigin: http://{}\r\nContent-Type: application/json\r\n",
            server.addr, server.addr
        ),
        Some(body),
    );
    assert_eq!(code, 200, "the page's own origin");

    // Studies at once are bounded; a cancelled one frees its place.
    let server = Server::start(&["--max-studies", "1", "--study-threads", "1"]);
    let long = json!({"samples": 5_000_000, "shard": 1000});
    let id = server.start_study("reliability", &[], long.clone());
    let (code, v) = server.json(
        "POST",
        "/api/studies",
        Some(&json!({"analysis": "reliability", "options": long})),
    );
    assert_eq!(code, 429, "{v}");
    // A live run is answered while the study runs.
    let (code, _) = server.json("POST", "/api/run", Some(&json!({"sets": []})));
    assert_eq!(code, 200);
    let (code, v) = server.json("DELETE", &format!("/api/studies/{id}"), None);
    assert_eq!(code, 200, "{v}");
    let end = server.events(id).pop().unwrap();
    assert_eq!(end.0, "end");
    assert_eq!(end.1["state"], "cancelled", "{}", end.1);
    // The cancel takes effect at the study's next piece of work, possibly before its
    // first sample is done.
    let done = end.1["done"].as_u64().unwrap();
    assert!(done < 5_000_000, "{done}");
}

#[test]
fn studio_hosts_only_loopback_unless_asked() {
    let out = divertsim()
        .args(["studio", "--host", "0.0.0.0"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--host") && err.contains("--allow-remote"),
        "{err}"
    );
    let out = divertsim()
        .args(["studio", "no/such/file.toml"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn studio_studies_stream_progress_and_equal_the_cli() {
    let hub = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/mix/hub.toml");
    let server = Server::start(&[hub]);
    let id = server.start_study("reliability", &[], json!({"samples": 3000, "shard": 500}));
    let events = server.events(id);
    let progress: Vec<&Value> = events
        .iter()
        .filter(|e| e.0 == "progress")
        .map(|e| &e.1)
        .collect();
    assert!(!progress.is_empty());
    // The rates so far come with the progress: whole shards, never more than the end's.
    for p in progress.iter().filter(|p| !p["partial"].is_null()) {
        let n = p["partial"]["samples"].as_u64().unwrap();
        assert!(n % 500 == 0 && n <= 3000, "{p}");
    }
    let last = &events.last().unwrap().1;
    assert_eq!(last["state"], "done", "{last}");
    assert_eq!(last["done"], last["total"]);
    // The numbers are the CLI's.
    let cli = json_stdout(divertsim().args([
        "reliability",
        hub,
        "--samples",
        "3000",
        "--shard",
        "500",
        "--json",
        "--quiet",
    ]));
    let (a, b) = (&last["summary"]["points"][0], &cli["points"][0]);
    for k in [
        "samples",
        "divert_rate",
        "overload_rate",
        "tipping_rate",
        "failures_by_reason",
        "first_failures",
        "load_spectrum",
    ] {
        assert_eq!(a[k], b[k], "{k}");
    }
    // A failed sample's scenario runs that sample again.
    let first = &a["first_failures"][0];
    assert!(first["sample"].is_u64(), "{a}");
    // The outputs as a zip.
    let (code, zip) = server.request("GET", &format!("/api/studies/{id}/outputs.zip"), None);
    assert_eq!(code, 200);
    assert_eq!(&zip[..2], b"PK");
    let text = String::from_utf8_lossy(&zip);
    for name in [
        "summary.json",
        "failure_rates.csv",
        "report.txt",
        "scenario.toml",
    ] {
        assert!(text.contains(name), "{name}");
    }

    // A capacity map, its cells the CLI's.
    let opts = json!({"cycle_times": "1.2:1.4/3", "light_barriers": "0:0.4/3", "speeds": "1.5:2.1/4", "worst": "paper"});
    let server = Server::start(&[]);
    let id = server.start_study("capacity", &[], opts);
    let end = server.events(id).pop().unwrap().1;
    assert_eq!(end["state"], "done", "{end}");
    let cli = json_stdout(divertsim().args([
        "capacity",
        "--cycle-times",
        "1.2:1.4/3",
        "--light-barriers",
        "0:0.4/3",
        "--speeds",
        "1.5:2.1/4",
        "--worst",
        "paper",
        "--json",
        "--quiet",
    ]));
    assert_eq!(end["summary"]["cells"], cli["cells"]);
}

/// Issue 50, item 1: "feasible" means one thing. The studio's capacity map holds its cells
/// against the searched worst case by default, as the CLI's `capacity` does, and says so.
#[test]
fn the_studio_capacity_map_defaults_to_the_searched_worst_case_as_the_cli() {
    let server = Server::start(&[]);
    let (code, page) = server.request("GET", "/", None);
    assert_eq!(code, 200);
    let page = String::from_utf8(page).unwrap();
    let select = &page[page
        .find("id=\"cap-worst\"")
        .expect("the worst-case choice")..];
    let select = &select[..select.find("</select>").unwrap()];
    assert!(
        select.contains("<option value=\"search\" selected>"),
        "{select}"
    );
    assert!(!select.contains("\"paper\" selected"), "{select}");
    let (_, js) = server.request("GET", "/assets/studio.js", None);
    let js = String::from_utf8(js).unwrap();
    assert!(
        js.contains("no setting feasible against "),
        "the legend names its worst case"
    );
    // The CLI's default is the same search.
    let cli = json_stdout(divertsim().args([
        "capacity",
        "--cycle-times",
        "1.3",
        "--light-barriers",
        "0.2",
        "--speeds",
        "1.5",
        "--json",
        "--quiet",
    ]));
    assert_eq!(cli["worst"], "search", "{cli}");
}

/// 20 clients, each moving its own slider as fast as the server answers, for 30 s: no
/// error, every response for its own request, the server's memory bounded.
#[test]
fn studio_under_load_answers_every_client_its_own() {
    let server = Server::start(&[]);
    // Warm up, then the memory the work may grow to.
    for _ in 0..20 {
        assert_eq!(
            server
                .json("POST", "/api/run", Some(&json!({"sets": []})))
                .0,
            200
        );
    }
    let before = server.rss_kb();
    assert!(before > 0, "the server's memory is read from /proc");
    let deadline = Instant::now() + Duration::from_secs(30);
    let answered = std::sync::atomic::AtomicU64::new(0);
    let peak = std::sync::atomic::AtomicU64::new(0);
    std::thread::scope(|s| {
        for client in 0..20u64 {
            let (server, answered, peak) = (&server, &answered, &peak);
            s.spawn(move || {
                // Bounded: at most 100,000 requests per client.
                for k in 0..100_000u64 {
                    if Instant::now() >= deadline {
                        break;
                    }
                    let id = client * 1_000_000 + k;
                    let speed = 1.0 + 0.05 * ((client + k) % 20) as f64;
                    let set = format!("machine.belt_speed={speed}");
                    let (code, v) =
                        server.json("POST", "/api/run", Some(&json!({"id": id, "sets": [set]})));
                    assert_eq!(code, 200, "{v}");
                    assert_eq!(v["id"], id);
                    assert_eq!(v["summary"]["scenario"]["machine"]["belt_speed"], speed);
                    answered.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    if k % 16 == 0 {
                        peak.fetch_max(server.rss_kb(), std::sync::atomic::Ordering::Relaxed);
                    }
                }
            });
        }
    });
    let n = answered.load(std::sync::atomic::Ordering::Relaxed);
    let peak = peak.load(std::sync::atomic::Ordering::Relaxed);
    eprintln!("{n} runs answered to 20 clients in 30 s; server memory {before} kB before, {peak} kB at most");
    assert!(n > 20, "{n}");
    // A run's response is about 1 MB of JSON; 20 in flight and the allocator's slack stay
    // far below 256 MB of growth.
    assert!(peak < before + 256 * 1024, "{before} kB -> {peak} kB");
}

/// Review of the studio: the scenario's files are read once, at start. A base chain and a
/// drive table deleted while the studio runs change nothing, and a run still equals
/// `simulate` on the files as they were.
#[test]
fn studio_reads_the_scenario_files_once_at_start() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    std::fs::write(
        dir.join("a.csv"),
        "t,alpha_deg\n0,0\n0.3,25\n0.68,45\n1.0,25\n1.36,0\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("machine.toml"),
        "[machine.drive]\nkind = \"table\"\ntable = \"a.csv\"\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("s.toml"),
        "base = \"machine.toml\"\n[machine]\nbelt_speed = 1.8\n",
    )
    .unwrap();
    let scenario = dir.join("s.toml");
    let want = json_stdout(divertsim().arg("simulate").arg(&scenario).args([
        "--json",
        "--set",
        "parcel.mass=4",
    ]));
    let server = Server::start(&[scenario.to_str().unwrap()]);
    std::fs::remove_file(dir.join("a.csv")).unwrap();
    std::fs::remove_file(dir.join("machine.toml")).unwrap();
    let (code, run) = server.json(
        "POST",
        "/api/run",
        Some(&json!({"sets": ["parcel.mass=4"]})),
    );
    assert_eq!(code, 200, "{run}");
    // The same run; the summary's scenario is the resolved one (the table inline).
    for k in ["outcome", "events", "final", "impacts", "max_lateral"] {
        assert!(!want[k].is_null(), "{k}");
        assert_eq!(run["summary"][k], want[k], "{k}");
    }
}

/// Review of issue 50, item 10: the studio's zip of a study kept the records path absolute,
/// as the output folders once did. It now carries a copy beside its scenario, as they do.
#[test]
fn a_studio_zip_carries_the_records_its_scenario_names_not_their_path() {
    let tmp = tempfile::tempdir().unwrap();
    let log = "id,length,width,height,mass\n1,0.3,0.2,0.1,2.0\n2,0.25,0.5,0.2,4.0\n";
    std::fs::write(tmp.path().join("log.csv"), log).unwrap();
    let scenario = tmp.path().join("s.toml");
    std::fs::write(&scenario, "[mix]\nrecords = \"log.csv\"\n").unwrap();
    let server = Server::start(&[scenario.to_str().unwrap()]);
    let id = server.start_study("reliability", &[], json!({"samples": 20}));
    let end = server.events(id).pop().unwrap().1;
    assert_eq!(end["state"], "done", "{end}");
    let (code, bytes) = server.request("GET", &format!("/api/studies/{id}/outputs.zip"), None);
    assert_eq!(code, 200);
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes)).unwrap();
    let mut read = |name: &str| {
        let mut text = String::new();
        std::io::Read::read_to_string(&mut zip.by_name(name).unwrap(), &mut text).unwrap();
        text
    };
    let written = read("scenario.toml");
    assert!(
        written.contains("records = \"input_mix_records.csv\""),
        "{written}"
    );
    let dir = tmp.path().to_string_lossy().into_owned();
    assert!(!written.contains(&dir), "{written}");
    assert_eq!(read("input_mix_records.csv"), log);
}

/// The read timeout of the studio (`studio::READ_TIMEOUT`) and the margin a loaded machine
/// gets on top of it before a connection still open counts as never closed.
const READ_TIMEOUT: Duration = Duration::from_secs(10);
const MARGIN: Duration = Duration::from_secs(20);

/// A connection to `server` that has written `bytes` and sends nothing more.
fn half_sent(server: &Server, bytes: &[u8]) -> TcpStream {
    let mut s = TcpStream::connect(&server.addr).unwrap();
    s.write_all(bytes).unwrap();
    s
}

/// What the server sends on `s` until it closes it (EOF or a reset), if before `deadline`;
/// `None` if it is still open then.
fn until_closed(s: &mut TcpStream, deadline: Instant) -> Option<Vec<u8>> {
    let mut out = Vec::new();
    let mut buf = [0u8; 4096];
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return None;
        }
        s.set_read_timeout(Some(left)).unwrap();
        match s.read(&mut buf) {
            Ok(0) => return Some(out),
            Ok(n) => out.extend_from_slice(&buf[..n]),
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                return None
            }
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(_) => return Some(out), // reset: closed
        }
    }
}

impl Server {
    /// Send SIGINT (Ctrl-C) to the server.
    fn interrupt(&self) {
        let status = std::process::Command::new("kill")
            .args(["-INT", &self.child.id().to_string()])
            .status()
            .unwrap();
        assert!(status.success());
    }

    /// The server's exit status, if it exits before `deadline`.
    fn exit_by(&mut self, deadline: Instant) -> Option<std::process::ExitStatus> {
        // Bounded: at most one look each 20 ms until the deadline.
        while Instant::now() < deadline {
            if let Some(status) = self.child.try_wait().unwrap() {
                return Some(status);
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        self.child.try_wait().unwrap()
    }
}

/// Hostile input, round four: 200 clients that each send half a request's head are all
/// disconnected after the read timeout, and the studio answers others meanwhile.
#[test]
fn half_sent_requests_are_closed_after_the_timeout() {
    let server = Server::start(&[]);
    let head = format!(
        "GET /api/scenario HTTP/1.1\r\nHost: {}\r\nX-Slow: ",
        server.addr
    );
    let mut slow: Vec<TcpStream> = (0..200)
        .map(|_| half_sent(&server, head.as_bytes()))
        .collect();
    let sent = Instant::now();
    let (code, _) = server.json("GET", "/api/scenario", None);
    assert_eq!(
        code, 200,
        "answered while 200 clients hold a half-sent request"
    );
    let deadline = sent + READ_TIMEOUT + MARGIN;
    for (i, s) in slow.iter_mut().enumerate() {
        assert!(
            until_closed(s, deadline).is_some(),
            "client {i} still connected {:?} after its half request",
            sent.elapsed()
        );
    }
    let (code, _) = server.json("GET", "/api/scenario", None);
    assert_eq!(code, 200);
}

/// A body announced far larger than the limit, of which 2 bytes come, is refused at once and
/// its connection closed; one within the limit that never arrives is a 408 after the read
/// timeout, its connection closed too.
#[test]
fn huge_content_length_with_two_bytes_is_closed() {
    let server = Server::start(&[]);
    let post = |length: u64| {
        format!(
            "POST /api/run HTTP/1.1\r\nHost: {}\r\nContent-Type: application/json\r\nContent-Length: {length}\r\n\r\n{{}}",
            server.addr
        )
    };
    let mut huge = half_sent(&server, post(10_000_000_000).as_bytes());
    let mut short = half_sent(&server, post(1000).as_bytes());
    let deadline = Instant::now() + READ_TIMEOUT + MARGIN;
    for (s, want) in [(&mut huge, "413"), (&mut short, "408")] {
        let out = until_closed(s, deadline).expect("the connection is closed");
        let text = String::from_utf8_lossy(&out);
        assert!(text.starts_with(&format!("HTTP/1.1 {want}")), "{text}");
    }
    let (code, _) = server.json("POST", "/api/run", Some(&json!({"sets": []})));
    assert_eq!(code, 200);
}

/// Ctrl-C with a long study's progress stream open: the studio ends within 5 s (its grace
/// for open requests, then the stream and the study are dropped), by its own handler.
#[test]
fn ctrl_c_ends_the_studio_with_a_progress_stream_open() {
    let mut server = Server::start(&["--study-threads", "1"]);
    let id = server.start_study(
        "reliability",
        &[],
        json!({"samples": 5_000_000, "shard": 1000}),
    );
    let mut stream = half_sent(
        &server,
        format!(
            "GET /api/studies/{id}/events HTTP/1.1\r\nHost: {}\r\n\r\n",
            server.addr
        )
        .as_bytes(),
    );
    // The stream is open once its first event came.
    stream
        .set_read_timeout(Some(Duration::from_secs(120)))
        .unwrap();
    let mut seen = Vec::new();
    let mut buf = [0u8; 4096];
    for _ in 0..10_000 {
        if String::from_utf8_lossy(&seen).contains("event: progress") {
            break;
        }
        let n = stream.read(&mut buf).unwrap();
        assert!(n > 0, "the stream ended early");
        seen.extend_from_slice(&buf[..n]);
    }
    assert!(String::from_utf8_lossy(&seen).contains("event: progress"));
    let sent = Instant::now();
    server.interrupt();
    let status = server.exit_by(sent + Duration::from_secs(5));
    assert_eq!(
        status.map(|s| s.code()),
        Some(Some(0)),
        "the studio still ran {:?} after Ctrl-C",
        sent.elapsed()
    );
    // And the stream is closed with it.
    assert!(until_closed(&mut stream, Instant::now() + MARGIN).is_some());
}

/// Ctrl-C while clients hold half-sent requests (a head, a body): the studio ends within
/// 5 s, the read timeout notwithstanding; a second Ctrl-C ends it too.
#[test]
fn ctrl_c_ends_the_studio_with_a_half_sent_request() {
    for twice in [false, true] {
        let mut server = Server::start(&[]);
        let _head = half_sent(
            &server,
            format!("GET / HTTP/1.1\r\nHost: {}\r\n", server.addr).as_bytes(),
        );
        let _body = half_sent(
            &server,
            format!(
                "POST /api/run HTTP/1.1\r\nHost: {}\r\nContent-Type: application/json\r\nContent-Length: 100\r\n\r\n{{",
                server.addr
            )
            .as_bytes(),
        );
        // The server has both by the time it answers a third client.
        assert_eq!(server.json("GET", "/api/scenario", None).0, 200);
        let sent = Instant::now();
        server.interrupt();
        if twice {
            std::thread::sleep(Duration::from_millis(200));
            server.interrupt();
        }
        let status = server.exit_by(sent + Duration::from_secs(5));
        assert_eq!(
            status.map(|s| s.code()),
            Some(Some(0)),
            "twice: {twice}; the studio still ran {:?} after Ctrl-C",
            sent.elapsed()
        );
    }
}

/// A GET of another site (a link, an image) makes the studio run nothing: every API route
/// is refused for `Sec-Fetch-Site: cross-site` and `same-site`; the page itself opens, and
/// the studio's own page, a typed address and curl (no header) are served.
#[test]
fn cross_site_get_runs_no_simulation() {
    let server = Server::start(&[]);
    let headers = |site: &str| {
        format!(
            "Host: {}\r\nContent-Type: application/json\r\nSec-Fetch-Site: {site}\r\n",
            server.addr
        )
    };
    let study = json!({"analysis": "capture"}).to_string();
    let run = json!({"sets": []}).to_string();
    let routes: [(&str, &str, Option<&[u8]>); 9] = [
        ("GET", "/api/report.html?machine.belt_speed=1.5", None),
        ("GET", "/api/scenario.toml", None),
        ("GET", "/api/scenario", None),
        ("POST", "/api/run", Some(run.as_bytes())),
        ("POST", "/api/studies", Some(study.as_bytes())),
        ("GET", "/api/studies/1", None),
        ("DELETE", "/api/studies/1", None),
        ("GET", "/api/studies/1/events", None),
        ("GET", "/api/studies/1/outputs.zip", None),
    ];
    for site in ["cross-site", "same-site"] {
        for (method, path, body) in routes {
            let (code, out) = server.request_with(method, path, &headers(site), body);
            assert_eq!(
                code,
                403,
                "{site} {method} {path}: {}",
                String::from_utf8_lossy(&out)
            );
        }
        assert_eq!(server.request_with("GET", "/", &headers(site), None).0, 200);
    }
    // No study was started by the refused POST.
    assert_eq!(server.json("GET", "/api/studies/1", None).0, 404);
    for site in ["same-origin", "none"] {
        let (code, out) = server.request_with("GET", "/api/scenario.toml", &headers(site), None);
        assert_eq!(code, 200, "{site}: {}", String::from_utf8_lossy(&out));
    }
    assert_eq!(server.request("GET", "/api/scenario.toml", None).0, 200);
}

/// Two Host headers (RFC 9112: 400) or two Origins, even both the studio's own, are a 400.
#[test]
fn duplicate_host_or_origin_is_400() {
    let server = Server::start(&[]);
    let addr = &server.addr;
    let body = br#"{"sets": []}"#;
    for headers in [
        format!("Host: {addr}\r\nHost: {addr}\r\n"),
        format!("Host: {addr}\r\nHost: attacker.example\r\n"),
        format!("Host: {addr}\r\nOrigin: http://{addr}\r\nOrigin: http://{addr}\r\n"),
        format!("Host: {addr}\r\nOrigin: http://{addr}\r\nOrigin: http://attacker.example\r\n"),
    ] {
        let headers = format!("{headers}Content-Type: application/json\r\n");
        let (code, out) = server.request_with("POST", "/api/run", &headers, Some(body));
        assert_eq!(code, 400, "{headers}: {}", String::from_utf8_lossy(&out));
    }
    let (code, _) = server.request_with(
        "POST",
        "/api/run",
        &format!("Host: {addr}\r\nOrigin: http://{addr}\r\nContent-Type: application/json\r\n"),
        Some(body),
    );
    assert_eq!(code, 200);
}

/// Hostile input round four: the studio passed a study's `sweep` straight to the analysis,
/// each value applied as a `--set`, so a swept section could name a file under the server's
/// working directory (and, through a diverter's machine, anywhere). The loader's rule
/// refuses it before the study starts.
#[test]
fn swept_file_key_in_the_studio_is_refused_with_422() {
    let line = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/paper/line.toml");
    let server = Server::start(&[line]);
    for (analysis, sweep) in [
        ("line", json!({"line": ["{arrivals=\"notes.csv\"}"]})),
        ("reliability", json!({"mix": ["{records=\"x.csv\"}"]})),
        (
            "reliability",
            json!({"machine.drive": ["{kind=\"table\",table=\"x.csv\"}"]}),
        ),
        (
            "line",
            json!({"line.diverters": ["[{position=6.0, share=0.5, machine={drive={kind=\"table\", table=\"/etc/passwd\"}}}]"]}),
        ),
    ] {
        let options = match analysis {
            "line" => json!({"sweep": sweep, "parcels": 20, "segment": 10}),
            _ => json!({"sweep": sweep, "samples": 20}),
        };
        let (code, v) = server.json(
            "POST",
            "/api/studies",
            Some(&json!({"analysis": analysis, "options": options})),
        );
        assert_eq!(code, 422, "{analysis} {sweep}: {v}");
        let text = v.to_string();
        assert!(text.contains("names a file"), "{text}");
        assert!(!text.contains("expected two numbers"), "{text}");
    }
}

/// Hostile input round four: a cancel returned 200 but the work ran on, holding one of the
/// two study places (199 of 200 starts got 429); and a line study of 10⁶ parcels as one
/// segment grew the server until it aborted. A cancel 5 s after the start ends the study
/// within 2 s and frees its place (every analysis's cancel: the api's `tests/cancel.rs`),
/// and the server stays up.
#[test]
fn studio_cancel_ends_a_study_within_two_seconds() {
    let line = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/paper/line.toml");
    let server = Server::start(&[line, "--max-studies", "1"]);
    for (analysis, options) in [
        ("line", json!({"parcels": 1_000_000, "segment": 1_000_000})),
        ("worst_case", json!({"search_budget": 2_000_000})),
    ] {
        let id = server.start_study(analysis, &[], options);
        std::thread::sleep(Duration::from_secs(5));
        let (_, v) = server.json("GET", &format!("/api/studies/{id}"), None);
        assert_eq!(v["state"], "running", "{analysis}: {v}");
        let asked = Instant::now();
        let (code, _) = server.json("DELETE", &format!("/api/studies/{id}"), None);
        assert!(code < 300, "{code}");
        let mut state = Value::Null;
        while asked.elapsed() < Duration::from_secs(10) {
            state = server.json("GET", &format!("/api/studies/{id}"), None).1["state"].clone();
            if state != "running" {
                break;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        let took = asked.elapsed();
        assert_eq!(state, "cancelled", "{analysis}");
        assert!(took < Duration::from_secs(2), "{analysis}: {took:?}");
    }
    // The place is free: a new study starts at once.
    server.start_study("overload", &[], json!({"speeds": [1.0]}));
}
