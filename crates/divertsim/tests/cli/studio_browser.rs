//! `divertsim studio` driven in headless Chromium through the DevTools protocol (a small
//! client over its websocket, below): the belt-speed slider dragged redraws the path, and the
//! pose drawn at a scrubbed time equals `divertsim simulate`'s trajectory; an out-of-range
//! value shows the CLI's message; a share URL reproduces the view; a capacity cell clicked
//! runs its setting; a reliability study streams progress, is cancelled, and its numbers
//! equal the CLI's. Screenshots are kept under `target/tmp/studio-screenshots/`; the
//! slider-to-redraw latency is printed (measured, never asserted).

use crate::common::{divertsim, json_stdout};
use crate::report_browser::{chromium_or_skip, pose_at, trajectory, CLOSED};
use crate::studio_server::Server;
use serde_json::{json, Value};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use tungstenite::{stream::MaybeTlsStream, Message, WebSocket};

/// Chromium with its DevTools protocol on a websocket, one page attached (flat session).
struct Browser {
    child: Child,
    ws: WebSocket<MaybeTlsStream<TcpStream>>,
    next: u64,
    session: String,
    shots: PathBuf,
    _profile: tempfile::TempDir,
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Browser {
    fn launch(bin: &Path, name: &str) -> Browser {
        let profile = tempfile::tempdir().unwrap();
        let child = Command::new(bin)
            .args(CLOSED)
            .args(["--remote-debugging-port=0", "--window-size=1400,1700"])
            .arg(format!("--user-data-dir={}", profile.path().display()))
            .arg("about:blank")
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        // Chromium writes its port and the browser's websocket path into the profile.
        let file = profile.path().join("DevToolsActivePort");
        let start = Instant::now();
        let text = loop {
            if let Ok(t) = std::fs::read_to_string(&file) {
                if t.lines().count() >= 2 {
                    break t;
                }
            }
            assert!(
                start.elapsed() < Duration::from_secs(60),
                "chromium did not start"
            );
            std::thread::sleep(Duration::from_millis(50));
        };
        let mut lines = text.lines();
        let (port, path) = (lines.next().unwrap(), lines.next().unwrap());
        let (ws, _) = tungstenite::connect(format!("ws://127.0.0.1:{port}{path}")).unwrap();
        let shots = Path::new(env!("CARGO_TARGET_TMPDIR"))
            .join("studio-screenshots")
            .join(name);
        std::fs::create_dir_all(&shots).unwrap();
        let mut b = Browser {
            child,
            ws,
            next: 0,
            session: String::new(),
            shots,
            _profile: profile,
        };
        let target = b.call("Target.createTarget", json!({"url": "about:blank"}));
        let attached = b.call(
            "Target.attachToTarget",
            json!({"targetId": target["targetId"], "flatten": true}),
        );
        b.session = attached["sessionId"].as_str().unwrap().to_string();
        b.call(
            "Emulation.setDeviceMetricsOverride",
            json!({"width": 1400, "height": 1700, "deviceScaleFactor": 1, "mobile": false}),
        );
        b
    }

    /// A DevTools command on the page (the browser itself before attaching); its result.
    fn call(&mut self, method: &str, params: Value) -> Value {
        self.next += 1;
        let id = self.next;
        let mut msg = json!({"id": id, "method": method, "params": params});
        if !self.session.is_empty() {
            msg["sessionId"] = json!(self.session);
        }
        self.ws.send(Message::text(msg.to_string())).unwrap();
        loop {
            let m = self.ws.read().unwrap();
            let Message::Text(t) = m else { continue };
            let v: Value = serde_json::from_str(t.as_str()).unwrap();
            if v["id"] == id {
                assert!(v.get("error").is_none(), "{method}: {v}");
                return v["result"].clone();
            }
        }
    }

    /// A script's value (promises awaited).
    fn eval(&mut self, expr: &str) -> Value {
        let r = self.call(
            "Runtime.evaluate",
            json!({"expression": expr, "returnByValue": true, "awaitPromise": true}),
        );
        assert!(r.get("exceptionDetails").is_none(), "{expr}: {r}");
        r["result"]["value"].clone()
    }

    /// Wait until a script is true (at most `secs`).
    fn wait(&mut self, expr: &str, secs: u64) {
        let start = Instant::now();
        while self.eval(&format!("!!({expr})")) != json!(true) {
            assert!(
                start.elapsed() < Duration::from_secs(secs),
                "waited {secs} s for {expr}"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    fn open(&mut self, url: &str) {
        self.call("Page.navigate", json!({"url": url}));
        self.wait(
            "document.readyState === 'complete' && window.studio && studio.drawn() > 0 && studio.idle()",
            60,
        );
    }

    fn screenshot(&mut self, name: &str) {
        let r = self.call("Page.captureScreenshot", json!({"format": "png"}));
        let png = base64(r["data"].as_str().unwrap());
        assert_eq!(&png[1..4], b"PNG");
        std::fs::write(self.shots.join(format!("{name}.png")), png).unwrap();
    }

    fn mouse(&mut self, kind: &str, x: f64, y: f64) {
        self.call(
            "Input.dispatchMouseEvent",
            json!({"type": kind, "x": x, "y": y, "button": "left", "clickCount": 1}),
        );
    }

    fn click(&mut self, x: f64, y: f64) {
        self.mouse("mouseMoved", x, y);
        self.mouse("mousePressed", x, y);
        self.mouse("mouseReleased", x, y);
    }
}

/// Standard base64 (DevTools' screenshots).
fn base64(s: &str) -> Vec<u8> {
    let val = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        _ => 63,
    };
    let clean: Vec<u8> = s.bytes().filter(|c| *c != b'=' && *c != b'\n').collect();
    let mut out = Vec::with_capacity(clean.len() * 3 / 4);
    for chunk in clean.chunks(4) {
        let v: Vec<u32> = chunk.iter().map(|c| u32::from(val(*c))).collect();
        let n = v.iter().fold(0u32, |a, x| (a << 6) | x) << (6 * (4 - v.len()));
        let bytes = [(n >> 16) as u8, (n >> 8) as u8, n as u8];
        out.extend_from_slice(&bytes[..v.len() - 1]);
    }
    out
}

/// The slider of a key: its box and range.
fn slider(b: &mut Browser, key: &str) -> Value {
    b.eval(&format!(
        "(() => {{ const s = document.querySelector('[data-key=\"{key}\"] input[type=range]');
            s.scrollIntoView({{block: 'center'}});
            const r = s.getBoundingClientRect();
            return {{left: r.left, width: r.width, y: r.top + r.height / 2, min: +s.min, max: +s.max, value: +s.value}}; }})()"
    ))
}

/// Drag a key's slider to fraction `to` of its track, with the mouse; wait for the redraw.
fn drag(b: &mut Browser, key: &str, to: f64) {
    let s = slider(b, key);
    let f = |k: &str| s[k].as_f64().unwrap();
    let from = (f("value") - f("min")) / (f("max") - f("min"));
    let (x0, x1, y) = (
        f("left") + 8.0 + from * (f("width") - 16.0),
        f("left") + 8.0 + to * (f("width") - 16.0),
        f("y"),
    );
    b.mouse("mouseMoved", x0, y);
    b.mouse("mousePressed", x0, y);
    for k in 1..=5 {
        b.mouse("mouseMoved", x0 + (x1 - x0) * f64::from(k) / 5.0, y);
    }
    b.mouse("mouseReleased", x1, y);
    b.wait("studio.idle()", 60);
}

/// JSON equality with every number compared as f64 (a page's JSON.stringify writes 2.0 as 2).
fn same(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => x.as_f64() == y.as_f64(),
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(p, q)| same(p, q))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| same(v, w)))
        }
        _ => a == b,
    }
}

fn sets(b: &mut Browser) -> Vec<String> {
    serde_json::from_value(b.eval("studio.sets()")).unwrap()
}

fn simulate_json(sets: &[String]) -> Value {
    let mut cmd = divertsim();
    cmd.args(["simulate", "--json"]);
    for s in sets {
        cmd.args(["--set", s]);
    }
    json_stdout(&mut cmd)
}

#[test]
#[cfg_attr(
    divertsim_no_chromium,
    ignore = "no chromium on PATH (apt-get install chromium)"
)]
fn studio_slider_redraws_the_path_and_the_url_reproduces_it() {
    let Some(bin) = chromium_or_skip() else {
        return;
    };
    let server = Server::start(&[]);
    let mut b = Browser::launch(&bin, "slider");
    b.open(&server.url());
    b.screenshot("1_default");
    let path_before = b.eval("JSON.stringify(studio.lastRun().data.runs[0].y)");

    // Drag the belt-speed slider: the page re-runs and redraws.
    drag(&mut b, "machine.belt_speed", 0.2);
    let after = sets(&mut b);
    assert!(
        after.iter().any(|s| s.starts_with("machine.belt_speed=")),
        "{after:?}"
    );
    assert_ne!(
        b.eval("JSON.stringify(studio.lastRun().data.runs[0].y)"),
        path_before,
        "the path is redrawn"
    );
    assert_eq!(
        b.eval("studio.lastRun().sets"),
        json!(after),
        "no stale result drawn"
    );
    b.screenshot("2_slider_moved");

    // The pose drawn at scrubbed times is the CLI's trajectory.
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let mut cmd = divertsim();
    cmd.arg("simulate");
    for s in &after {
        cmd.args(["--set", s]);
    }
    cmd.arg("--out").arg(&out).assert().success();
    let tr = trajectory(&out.join("trajectory.csv"));
    let duration = b.eval("divertsim.duration").as_f64().unwrap();
    for t in [0.2, 0.5, 0.9].map(|f| f * duration) {
        let pose = b.eval(&format!("(divertsim.seek({t}), divertsim.pose())"));
        let want = pose_at(&tr, t);
        for (i, key) in ["x", "y", "phi"].iter().enumerate() {
            let got = pose[key].as_f64().unwrap();
            assert!(
                (got - want[i]).abs() < 1e-6,
                "t = {t}: {key} drawn {got} ({pose}), simulate {} for {after:?}",
                want[i]
            );
        }
    }
    b.screenshot("3_scrubbed");

    // Latency from a slider move to the redrawn path, over 20 moves (reported, not asserted).
    for k in 0..20 {
        drag(&mut b, "machine.belt_speed", 0.1 + 0.02 * f64::from(k));
    }
    let mut lat: Vec<f64> = serde_json::from_value(b.eval("studio.latencies")).unwrap();
    lat.sort_by(f64::total_cmp);
    eprintln!(
        "studio latency, slider change to redrawn path: median {:.1} ms over {} changes (max {:.1} ms)",
        lat[lat.len() / 2],
        lat.len(),
        lat[lat.len() - 1]
    );

    // An out-of-range value is marked in place with the CLI's message.
    b.eval(
        "(() => { const f = document.querySelector('[data-key=\"parcel.mass\"] input[type=text]');
            f.scrollIntoView({block: 'center'}); f.value = '-1'; f.dispatchEvent(new Event('change')); })()",
    );
    b.wait("studio.idle()", 60);
    let shown = b.eval("document.querySelector('[data-key=\"parcel.mass\"] .problem').textContent");
    let cli = divertsim()
        .args(["simulate", "--set", "parcel.mass=-1"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&cli.stderr).to_string();
    let message = shown.as_str().unwrap();
    assert!(
        message.contains("out of range") && stderr.contains(message),
        "{message} / {stderr}"
    );
    let banner = b.eval("document.getElementById('errors').textContent");
    assert!(
        stderr.contains(banner.as_str().unwrap().lines().next().unwrap()),
        "{banner}"
    );
    b.screenshot("4_out_of_range");

    // A valid value again, then the share URL in a fresh page reproduces the run.
    b.eval(
        "(() => { const f = document.querySelector('[data-key=\"parcel.mass\"] input[type=text]');
            f.value = '4.5'; f.dispatchEvent(new Event('change')); })()",
    );
    b.wait("studio.idle() && !document.querySelector('[data-key=\"parcel.mass\"]').classList.contains('bad')", 60);
    let url = b.eval("location.href").as_str().unwrap().to_string();
    let summary = b.eval("studio.lastRun().summary");
    let mut fresh = Browser::launch(&bin, "shared");
    fresh.open(&url);
    assert!(same(&fresh.eval("studio.lastRun().summary"), &summary));
    assert_eq!(fresh.eval("studio.sets()"), b.eval("studio.sets()"));
    assert_eq!(
        fresh.eval("document.querySelector('[data-key=\"parcel.mass\"] input[type=text]').value"),
        json!("4.5")
    );
    assert!(same(&summary, &simulate_json(&sets(&mut b))));
    fresh.screenshot("shared_url");
    assert_eq!(b.eval("studio.errors"), json!([]));
    assert_eq!(fresh.eval("studio.errors"), json!([]));
}

#[test]
#[cfg_attr(
    divertsim_no_chromium,
    ignore = "no chromium on PATH (apt-get install chromium)"
)]
fn studio_capacity_cell_runs_its_setting() {
    let Some(bin) = chromium_or_skip() else {
        return;
    };
    let server = Server::start(&[]);
    let mut b = Browser::launch(&bin, "capacity");
    b.open(&server.url());
    b.eval(
        "(() => { document.getElementById('cap-tc').value = '1.1:1.5/5';
            document.getElementById('cap-sd').value = '0:0.8/5';
            document.getElementById('cap-v').value = '1.0:2.3/14';
            // The default scenario holds nowhere against the searched worst case (the
            // default); the paper's worst case gives cells to click.
            document.getElementById('cap-worst').value = 'paper';
            document.getElementById('capacity').scrollIntoView();
            document.getElementById('cap-run').click(); })()",
    );
    b.wait("studio.capacity()", 120);
    b.wait("studio.idle()", 60);
    // The map's outputs, downloadable.
    let zip = b.eval("document.getElementById('cap-zip').href");
    assert!(zip.as_str().unwrap().ends_with("/outputs.zip"), "{zip}");
    let path = zip
        .as_str()
        .unwrap()
        .split(&server.addr)
        .nth(1)
        .unwrap()
        .to_string();
    let (code, bytes) = server.request("GET", &path, None);
    assert_eq!((code, &bytes[..2]), (200, &b"PK"[..]));
    assert!(String::from_utf8_lossy(&bytes).contains("capacity.csv"));
    b.screenshot("1_map");
    // The first feasible cell, clicked with the mouse.
    let k = b
        .eval("studio.capacity().cells.findIndex(c => c.feasible)")
        .as_i64()
        .unwrap();
    assert!(k >= 0, "a feasible cell");
    let at = b.eval(&format!("studio.cellCentre({k})"));
    let cell = at["cell"].clone();
    b.click(at["x"].as_f64().unwrap(), at["y"].as_f64().unwrap());
    b.wait("studio.idle() && studio.sets().length >= 4", 60);
    let now = sets(&mut b);
    for (key, v) in [
        ("machine.cycle_time", &cell["cycle_time"]),
        ("machine.light_barrier", &cell["light_barrier"]),
        ("machine.belt_speed", &cell["belt_speed"]),
        ("machine.start_position", &cell["start_position"]),
    ] {
        assert!(now.contains(&format!("{key}={v}")), "{key}={v} in {now:?}");
    }
    assert!(same(
        &b.eval("studio.lastRun().summary"),
        &simulate_json(&now)
    ));
    b.eval("window.scrollTo(0, 0)");
    b.screenshot("2_cell_run");
    assert_eq!(b.eval("studio.errors"), json!([]));
}

#[test]
#[cfg_attr(
    divertsim_no_chromium,
    ignore = "no chromium on PATH (apt-get install chromium)"
)]
fn studio_reliability_streams_cancels_and_equals_the_cli() {
    let Some(bin) = chromium_or_skip() else {
        return;
    };
    let hub = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/mix/hub.toml");
    let server = Server::start(&[hub]);
    let mut b = Browser::launch(&bin, "reliability");
    b.open(&server.url());
    // A long study: progress streams in, then it is cancelled.
    b.eval(
        "(() => { document.getElementById('rel-samples').value = '2000000';
            document.getElementById('reliability').scrollIntoView();
            document.getElementById('rel-run').click(); })()",
    );
    b.wait("document.getElementById('rel-progress').value > 0", 60);
    let first = b.eval("document.getElementById('rel-progress').value");
    b.wait(
        &format!("document.getElementById('rel-progress').value > {first}"),
        60,
    );
    // The rates so far appear as the shards finish.
    b.wait(
        "document.getElementById('rel-result').textContent.includes('so far')",
        60,
    );
    let partial = b.eval("document.getElementById('rel-result').textContent");
    assert!(
        partial.as_str().unwrap().contains("divert rate"),
        "{partial}"
    );
    b.screenshot("1_progress");
    b.eval("document.getElementById('rel-cancel').click()");
    b.wait(
        "document.getElementById('rel-status').textContent.startsWith('cancelled')",
        60,
    );
    b.screenshot("2_cancelled");

    // A short one to the end: its numbers are the CLI's.
    b.eval(
        "(() => { document.getElementById('rel-samples').value = '3000';
            document.getElementById('rel-run').click(); })()",
    );
    b.wait("studio.reliability()", 120);
    let page = b.eval("studio.reliability().points[0]");
    let cli = json_stdout(divertsim().args([
        "reliability",
        hub,
        "--samples",
        "3000",
        "--json",
        "--quiet",
    ]));
    for k in [
        "samples",
        "divert_rate",
        "overload_rate",
        "tipping_rate",
        "failures_by_reason",
        "first_failures",
    ] {
        assert!(
            same(&page[k], &cli["points"][0][k]),
            "{k} differs from the CLI's"
        );
    }
    let shown = b.eval("document.getElementById('rel-result').textContent");
    let rate = page["divert_rate"]["estimate"].as_f64().unwrap();
    assert!(
        shown
            .as_str()
            .unwrap()
            .contains(&format!("{:.2} %", 100.0 * rate)),
        "{shown}"
    );
    b.screenshot("3_done");

    // A failed sample, clicked, runs that sample: its verdict is the study's.
    let failure = page["first_failures"][0].clone();
    assert!(failure.is_object(), "the hub mix has failures: {page}");
    b.eval("document.querySelector('.failure').click()");
    b.wait("studio.idle() && studio.sets().length > 0", 60);
    let run = b.eval("studio.lastRun().summary");
    assert_eq!(run["reason"], failure["reason"], "{run}");
    b.screenshot("4_failure_run");
    assert_eq!(b.eval("studio.errors"), json!([]));
}

#[test]
#[cfg_attr(
    divertsim_no_chromium,
    ignore = "no chromium on PATH (apt-get install chromium)"
)]
fn studio_line_run_equals_the_cli() {
    let Some(bin) = chromium_or_skip() else {
        return;
    };
    let line = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/paper/line.toml");
    let server = Server::start(&[line]);
    let mut b = Browser::launch(&bin, "line");
    b.open(&server.url());
    b.eval(
        "(() => { document.getElementById('line-parcels').value = '3000';
            document.getElementById('line').scrollIntoView();
            document.getElementById('line-run').click(); })()",
    );
    b.wait("studio.line()", 120);
    let page = b.eval("studio.line().points[0]");
    let cli =
        json_stdout(divertsim().args(["line", line, "--parcels", "3000", "--json", "--quiet"]));
    for k in [
        "parcels",
        "throughput_per_h",
        "missort_rate",
        "struck_rate",
        "outcomes",
        "tipped_rate",
    ] {
        assert!(
            same(&page[k], &cli["points"][0][k]),
            "{k} differs from the CLI's"
        );
    }
    let shown = b.eval("document.getElementById('line-result').textContent");
    let throughput = page["throughput_per_h"].as_f64().unwrap();
    assert!(
        shown
            .as_str()
            .unwrap()
            .contains(&format!("{throughput:.0}")),
        "{shown}"
    );
    b.screenshot("1_line");
    assert_eq!(b.eval("studio.errors"), json!([]));
}
