//! End-to-end tests of `divertsim line`: outputs, thread independence, kill and resume, a
//! failure's scenario file, and bad input.

use crate::common;

use common::divertsim;

const LINE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/paper/line.toml");
const TWO: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../configs/paper/line_two.toml"
);

#[test]
fn line_out_writes_its_tables_the_parcel_log_and_failures_that_simulate_runs() {
    let t = tempfile::tempdir().unwrap();
    divertsim()
        .current_dir(t.path())
        .args(["line", TWO, "--parcels", "600", "--quiet", "--out", "o"])
        .assert()
        .success();
    let o = t.path().join("o");
    for f in [
        "summary.json",
        "scenario.toml",
        "line.csv",
        "line_diverters.csv",
        "line_parcels.parquet",
    ] {
        assert!(o.join(f).is_file(), "{f}");
    }
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(o.join("summary.json")).unwrap()).unwrap();
    let p = &summary["points"][0];
    assert_eq!(p["parcels"], 600);
    assert_eq!(p["diverters"].as_array().unwrap().len(), 2);
    // A failure's file runs on its own, with the arm's strokes near it.
    let failures: Vec<_> = std::fs::read_dir(o.join("failures"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert!(!failures.is_empty());
    let wrong: Vec<_> = failures
        .iter()
        .filter(|p| p.to_string_lossy().contains("wrongly_diverted"))
        .collect();
    assert!(
        !wrong.is_empty(),
        "a parcel pushed into the wrong chute at this gap"
    );
    // (Some of them hold an offset that the loader refuses: a known defect of the failure
    // files, left open in issue 49's notes. At least one must run.)
    let runs: Vec<_> = wrong
        .iter()
        .filter_map(|w| {
            let out = divertsim()
                .args(["simulate"])
                .arg(w)
                .arg("--json")
                .output()
                .unwrap();
            out.status.success().then(|| {
                (
                    w,
                    serde_json::from_slice::<serde_json::Value>(&out.stdout).unwrap(),
                )
            })
        })
        .collect();
    assert!(!runs.is_empty());
    for (w, run) in runs {
        assert_eq!(run["outcome"], "diverted", "{run}");
        let text = std::fs::read_to_string(w).unwrap();
        assert!(text.contains("cycle_starts"), "{text}");
    }
}

#[test]
fn line_is_the_same_for_one_and_two_threads() {
    let run = |threads: &str| {
        divertsim()
            .args([
                "line",
                TWO,
                "--parcels",
                "400",
                "--segment",
                "50",
                "--json",
                "--threads",
                threads,
            ])
            .output()
            .unwrap()
            .stdout
    };
    let one = run("1");
    assert!(!one.is_empty());
    assert_eq!(one, run("2"));
}

/// SIGKILL part-way, then `--resume`: byte-identical files, finished segments recalled.
#[test]
fn killed_and_resumed_line_is_byte_identical() {
    let t = tempfile::tempdir().unwrap();
    let args = [
        "line",
        TWO,
        "--parcels",
        "6000",
        "--segment",
        "100",
        "--quiet",
    ];
    common::kill_and_resume(t.path(), &args, common::journal_started);
}

#[test]
fn bad_line_input_exits_2_naming_the_key_and_writes_nothing() {
    let t = tempfile::tempdir().unwrap();
    std::fs::write(t.path().join("arrivals.csv"), "time\n0\n2\n1\n").unwrap();
    std::fs::write(
        t.path().join("log.toml"),
        "[line]\narrivals = \"arrivals.csv\"\n",
    )
    .unwrap();
    let cases: [(&[&str], &str); 5] = [
        (
            &[LINE, "--set", "line.diverters=[{position=0.5,share=0.0}]"],
            "line.diverters[0].position",
        ),
        (&[LINE, "--set", "line.min_gap=-0.1"], "line.min_gap"),
        (
            &["--set", "line.gap={kind=\"normal\",mean=0.4,sd=0.3}"],
            "line.min_gap",
        ),
        (
            &[LINE, "--set", "line.diverters=[{position=4,share=0.6}]"],
            "line.diverters[0].share",
        ),
        (&["log.toml"], "line.arrivals"),
    ];
    for (args, key) in cases {
        let out = divertsim()
            .current_dir(t.path())
            .arg("line")
            .args(args)
            .args(["--out", "o", "--quiet"])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(key), "{args:?}: {err}");
        assert!(!err.contains("panicked"));
        assert!(!t.path().join("o").exists(), "{args:?}");
    }
}

#[test]
fn line_help_teaches_the_section() {
    let out = divertsim().args(["line", "--help"]).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("Examples:")
            && text.contains("[[line.diverters]]")
            && text.contains("arm_busy")
    );
}

/// Issue 26: the line reports its arms' load spectrum over every stroke of every arm (the
/// diverters' cycles), the rate of parcels that tipped, and the run behind its largest
/// stroke as a file that `simulate` runs to the same peak.
#[test]
fn the_line_reports_the_arms_load_spectrum_and_its_largest_stroke() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("l");
    divertsim()
        .args([
            "line",
            TWO,
            "--parcels",
            "600",
            "-q",
            "--set",
            "machine.arm_mass=5",
            "--out",
        ])
        .arg(&out)
        .assert()
        .success();
    let summary = common::summary_in(&out);
    let p = &summary["points"][0];
    let cycles: u64 = p["diverters"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d["cycles"].as_u64().unwrap())
        .sum();
    let spectrum = &p["load_spectrum"];
    assert_eq!(spectrum["strokes"].as_u64(), Some(cycles));
    assert_eq!(
        spectrum["peak_drive_torque_n_m"]["total"].as_u64(),
        Some(cycles)
    );
    assert_eq!(p["tipped_rate"]["of"], 600);
    let csv = std::fs::read_to_string(out.join("load_spectrum.csv")).unwrap();
    assert!(csv.starts_with("point,sweep_value,load,bin_lo,bin_hi,count,per_million_strokes"));
    let largest = spectrum["largest_stroke"]["peak_drive_torque_n_m"]
        .as_f64()
        .unwrap();
    common::assert_largest_stroke_reproduces(&out, largest);
}

/// The peak resident set of `divertsim ARGS` \[kB]: its VmHWM (the kernel's high-water mark
/// of the process's resident memory), read every few milliseconds until it exits.
#[cfg(target_os = "linux")]
fn peak_kb(args: &[&str]) -> u64 {
    use assert_cmd::cargo::CommandCargoExt;
    let mut child = std::process::Command::cargo_bin("divertsim")
        .unwrap()
        .args(args)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let status = format!("/proc/{}/status", child.id());
    let mut peak = 0;
    loop {
        // Read before asking whether it exited: the last reading is of the finished work.
        let hwm = std::fs::read_to_string(&status).ok().and_then(|s| {
            let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
            line.split_whitespace().nth(1)?.parse::<u64>().ok()
        });
        peak = peak.max(hwm.unwrap_or(0));
        if let Some(exit) = child.try_wait().unwrap() {
            assert!(exit.success(), "{args:?}: {exit}");
            return peak;
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
}

/// A segment streams its parcels (each run reduced to its record as the parcel passes, at
/// most two runs held), so the line's memory does not grow with `--segment`: a stream as one
/// segment peaks at most twice as high as the same stream in segments 100 times shorter.
/// Memory, not time: the peak resident set of each run. 20,000 parcels, not 10⁵: as one
/// segment (one core) 10⁵ take over a minute on 2 cores, 20,000 about 12 s.
#[cfg(target_os = "linux")]
#[test]
fn line_memory_does_not_grow_with_the_segment() {
    let run = |segment: &str| {
        peak_kb(&[
            "line",
            LINE,
            "--parcels",
            "20000",
            "--segment",
            segment,
            "--threads",
            "2",
            "--quiet",
            "--json",
        ])
    };
    let short = run("200");
    let long = run("20000");
    assert!(
        short > 0 && long > 0,
        "no VmHWM read: {short} kB, {long} kB"
    );
    assert!(
        long <= 2 * short,
        "peak {long} kB as one segment of 20000 against {short} kB in segments of 200"
    );
}

/// What users meet, round two (15): `machine.trigger = "adaptive"` on the line's first
/// diverter was refused (exit 2, "this command sets R_s itself") by the command line's
/// loader, although the line runs each diverter's own trigger, as the library does. The
/// commands that set R_s themselves still refuse it.
#[test]
fn adaptive_trigger_on_the_line_is_run_not_refused() {
    let out = divertsim()
        .args([
            "line",
            "configs/paper/line.toml",
            "--parcels",
            "30",
            "--segment",
            "10",
        ])
        .args(["--set", "machine.trigger=adaptive", "--json", "--quiet"])
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["points"][0]["parcels"], 30, "{v}");
    let refused = divertsim()
        .args(["trigger", "--set", "machine.trigger=adaptive"])
        .output()
        .unwrap();
    assert_eq!(refused.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("machine.trigger"));
}

/// Issue 50, item 17: a stream longer than its arrivals log replays the log's headways in
/// order, and says so in the text and the JSON (it used to be silent).
#[test]
fn an_arrivals_log_shorter_than_the_stream_is_said_to_replay() {
    let t = tempfile::tempdir().unwrap();
    std::fs::write(t.path().join("arrivals.csv"), "time\n0\n2\n4\n6\n8\n").unwrap();
    std::fs::write(
        t.path().join("log.toml"),
        "[line]\narrivals = \"arrivals.csv\"\n",
    )
    .unwrap();
    let run = |parcels: &str, json: bool| {
        let mut c = divertsim();
        c.current_dir(t.path())
            .args(["line", "log.toml", "--parcels", parcels, "--quiet"]);
        if json {
            c.arg("--json");
        }
        let out = c.output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let text = run("20", false);
    assert!(
        text.contains("the log's 4 headways are replayed 5.00 times"),
        "{text}"
    );
    let v: serde_json::Value = serde_json::from_str(&run("20", true)).unwrap();
    assert_eq!(v["points"][0]["arrivals_log_replays"], 5.0);
    let v: serde_json::Value = serde_json::from_str(&run("4", true)).unwrap();
    assert_eq!(
        v["points"][0]["arrivals_log_replays"],
        serde_json::Value::Null
    );
    assert!(!run("4", false).contains("replayed"));
}

/// Issue 50, item 19: a line sweep printed only its full tables. It now starts with one
/// line per point, and the points where parcels collided (outside the model) are starred;
/// the throughput curve marks them too and names the swept values on its axis.
#[test]
fn a_line_sweep_says_one_line_per_point_and_marks_collisions() {
    let t = tempfile::tempdir().unwrap();
    let out = divertsim()
        .current_dir(t.path())
        .args([
            "line",
            LINE,
            "--parcels",
            "200",
            "--quiet",
            "--sweep",
            "line.gap_target=0.25,3",
            "--out",
            "o",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("one line per point"), "{text}");
    let row = |v: &str| {
        text.lines()
            .find(|l| l.trim_start().starts_with(&format!("{v} ")))
            .unwrap_or_else(|| panic!("no row for {v}: {text}"))
            .to_string()
    };
    assert!(row("0.25").ends_with('*'), "{}", row("0.25"));
    assert!(!row("3").ends_with('*'), "{}", row("3"));
    assert!(text.contains("outside the model"));
    let svg = std::fs::read_to_string(t.path().join("o/throughput.svg")).unwrap();
    assert!(svg.contains("parcels collided: outside the model"));
    assert!(svg.contains("3 at the left, 0.25 at the right"));
}
