//! End-to-end tests of `divertsim reliability`: kill and resume, thread independence,
//! sweeps, early stop, records files and the errors.

use crate::common;

use common::{divertsim, json_stdout};
use std::path::Path;
use std::time::{Duration, Instant};

const HUB: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/mix/hub.toml");

/// Every file below a directory, by relative path, with its bytes.
fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<(String, Vec<u8>)>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                let rel = p.strip_prefix(root).unwrap().display().to_string();
                out.push((rel, std::fs::read(&p).unwrap()));
            }
        }
    }
    let mut v = Vec::new();
    walk(dir, dir, &mut v);
    v.sort();
    v
}

/// Whole records in the checkpoint's journal (`key u64 | length u32 | bytes | check u64`):
/// the shards kept so far.
fn shards_in(dir: &Path) -> usize {
    let bytes = std::fs::read(dir.join("journal.bin")).unwrap_or_default();
    let (mut at, mut n) = (0usize, 0usize);
    while let Some(head) = bytes.get(at..at + 12) {
        let len = u32::from_le_bytes(head[8..].try_into().unwrap()) as usize;
        if at + 20 + len > bytes.len() {
            break;
        }
        at += 20 + len;
        n += 1;
    }
    n
}

#[test]
fn killed_run_resumes_to_byte_identical_outputs() {
    let tmp = tempfile::tempdir().unwrap();
    let args = |out: &Path| {
        vec![
            "reliability".to_string(),
            HUB.to_string(),
            "--samples".into(),
            "2400".into(),
            "--shard".into(),
            "200".into(),
            "--threads".into(),
            "1".into(),
            "--csv".into(),
            "-q".into(),
            "--out".into(),
            out.display().to_string(),
        ]
    };
    let whole = tmp.path().join("whole");
    divertsim().args(args(&whole)).assert().success();

    let cut = tmp.path().join("cut");
    // The run's checkpoint: its shards as Parquet bytes in the journal (issue 48: the
    // format of every command's checkpoint).
    let checkpoint = tmp.path().join(".cut.checkpoint");
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("divertsim"))
        .args(args(&cut))
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while shards_in(&checkpoint) < 3 {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "no shards written"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    // Killed part-way: no output, a checkpoint with some of the 12 shards.
    assert!(!cut.exists(), "the run finished before it was killed");
    let kept = shards_in(&checkpoint);
    assert!((3..12).contains(&kept), "{kept} shards kept");

    // Without --resume the checkpoint is not overwritten.
    let refused = divertsim().args(args(&cut)).output().unwrap();
    assert_eq!(refused.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("--resume"));
    // With other inputs it is not resumed.
    let mut other = args(&cut);
    other.extend(["--resume".into(), "--seed".into(), "5".into()]);
    let refused = divertsim().args(&other).output().unwrap();
    assert_eq!(refused.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("other inputs"));

    // Resumed with another thread count: the same result.
    let mut resume = args(&cut);
    resume.push("--resume".into());
    let at = resume.iter().position(|a| a == "--threads").unwrap();
    resume[at + 1] = "2".into();
    divertsim().args(&resume).assert().success();
    assert!(!checkpoint.exists(), "the checkpoint is removed at the end");
    let (a, b) = (files(&whole), files(&cut));
    assert_eq!(
        a.iter().map(|f| &f.0).collect::<Vec<_>>(),
        b.iter().map(|f| &f.0).collect::<Vec<_>>()
    );
    for ((name, x), (_, y)) in a.iter().zip(&b) {
        assert!(x == y, "{name} differs after resume");
    }
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(whole.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["points"][0]["samples"], 2400);
    // 2400 samples and a header in the CSV.
    let csv = std::fs::read_to_string(whole.join("samples.csv")).unwrap();
    assert_eq!(csv.lines().count(), 2401);
}

/// Issue 48: an older divertsim kept a reliability run's shards as Parquet files in
/// `.DIR.reliability-checkpoint`; this version keeps them in the run's `.DIR.checkpoint`
/// like every command, and refuses the old folder, saying what to do, before any run.
#[test]
fn an_older_reliability_checkpoint_is_refused_with_what_to_do() {
    let tmp = tempfile::tempdir().unwrap();
    let old = tmp.path().join(".mix.reliability-checkpoint");
    std::fs::create_dir(&old).unwrap();
    for resume in [false, true] {
        let mut cmd = divertsim();
        cmd.args(["reliability", HUB, "--samples", "100", "-q", "--out"])
            .arg(tmp.path().join("mix"));
        if resume {
            cmd.arg("--resume");
        }
        let out = cmd.output().unwrap();
        assert_eq!(out.status.code(), Some(2));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains(".mix.reliability-checkpoint")
                && err.contains("older divertsim")
                && err.contains("remove that folder"),
            "{err}"
        );
    }
    assert!(!tmp.path().join("mix").exists());
    assert!(!tmp.path().join(".mix.checkpoint").exists());
}

#[test]
fn same_result_for_any_thread_count() {
    let run = |threads: &str| {
        json_stdout(divertsim().args([
            "reliability",
            HUB,
            "--samples",
            "300",
            "--shard",
            "100",
            "--json",
            "-q",
            "--threads",
            threads,
        ]))
    };
    assert_eq!(run("1"), run("2"));
}

#[test]
fn sweep_reports_every_point_with_intervals() {
    let v = json_stdout(divertsim().args([
        "reliability",
        "--samples",
        "60",
        "--json",
        "-q",
        "--sweep",
        "machine.trigger=fixed,adaptive",
        "--set",
        "machine.adaptive.length_nodes=2",
        "--set",
        "machine.adaptive.aspect_nodes=1",
        "--set",
        "machine.adaptive.offset_nodes=2",
        "--set",
        "machine.adaptive.angle_nodes=1",
        "--set",
        "machine.adaptive.step=0.1",
        "--set",
        "machine.light_barrier=-0.5",
    ]));
    let points = v["points"].as_array().unwrap();
    assert_eq!(points.len(), 2);
    assert_eq!(points[0]["setting"]["trigger"], "fixed");
    assert_eq!(points[1]["setting"]["trigger"], "adaptive");
    assert_eq!(points[1]["trigger_table"]["nodes"], 4);
    for p in points {
        let d = &p["divert_rate"];
        let (lo, est, hi) = (
            d["lower"].as_f64().unwrap(),
            d["estimate"].as_f64().unwrap(),
            d["upper"].as_f64().unwrap(),
        );
        assert!(lo <= est && est <= hi, "{d}");
        assert_eq!(p["samples"], 60);
        assert!(p["capacity_per_h"].as_f64().unwrap() > 0.0);
    }
    // The same parcels at both points: the fixed point's inputs bins equal the adaptive's
    // (the table changes R_s only).
    assert_eq!(
        points[0]["failure_rate_by_input"][0]["bins"]
            .as_array()
            .unwrap()
            .iter()
            .map(|b| b["samples"].clone())
            .collect::<Vec<_>>(),
        points[1]["failure_rate_by_input"][0]["bins"]
            .as_array()
            .unwrap()
            .iter()
            .map(|b| b["samples"].clone())
            .collect::<Vec<_>>()
    );
    // Sweeping the seed draws other parcels at each point.
    let v = json_stdout(divertsim().args([
        "reliability",
        "--samples",
        "20",
        "--json",
        "-q",
        "--sweep",
        "mix.seed=1,2",
    ]));
    let (a, b) = (&v["points"][0], &v["points"][1]);
    assert_eq!((a["seed"].as_u64(), b["seed"].as_u64()), (Some(1), Some(2)));
    assert_ne!(a["max_overload_ratio"], b["max_overload_ratio"]);
    // A numeric sweep with plots.
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("s");
    divertsim()
        .args([
            "reliability",
            "--samples",
            "30",
            "-q",
            "--sweep",
            "machine.belt_speed=1.8:2.2/3",
            "--out",
        ])
        .arg(&out)
        .assert()
        .success();
    for f in [
        "summary.json",
        "samples.parquet",
        "failure_rates.csv",
        "sweep.svg",
        "sweep.png",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
}

#[test]
fn until_ci_stops_at_a_shard_end() {
    let v = json_stdout(divertsim().args([
        "reliability",
        "--samples",
        "100000",
        "--shard",
        "100",
        "--until-ci",
        "0.2",
        "--json",
        "-q",
    ]));
    let p = &v["points"][0];
    assert_eq!(p["stopped_early"], true);
    let n = p["samples"].as_u64().unwrap();
    assert!(n > 0 && n.is_multiple_of(100) && n < 100000, "{n}");
    for k in ["divert_rate", "overload_rate"] {
        let w = p[k]["upper"].as_f64().unwrap() - p[k]["lower"].as_f64().unwrap();
        assert!(w <= 0.2, "{k} width {w}");
    }
}

#[test]
fn records_file_is_drawn_from() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(
        tmp.path().join("log.csv"),
        "id,length,width,height,mass\n1,0.3,0.2,0.1,2.0\n2,0.25,0.5,0.2,4.0\n",
    )
    .unwrap();
    let scenario = tmp.path().join("s.toml");
    std::fs::write(&scenario, "[mix]\nrecords = \"log.csv\"\n").unwrap();
    let out = tmp.path().join("o");
    divertsim()
        .args(["reliability", "--samples", "40", "-q", "--csv", "--out"])
        .arg(&out)
        .arg(&scenario)
        .assert()
        .success();
    let csv = std::fs::read_to_string(out.join("samples.csv")).unwrap();
    let mut sizes: Vec<String> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').skip(2).take(4).collect::<Vec<_>>().join(","))
        .collect();
    sizes.sort();
    sizes.dedup();
    // Both records, the second with its sides sorted (length ≥ width).
    assert_eq!(sizes, ["0.3,0.2,0.1,2", "0.5,0.25,0.2,4"]);
}

#[test]
fn bad_input_is_named_before_any_run() {
    let fail = |args: &[&str], needles: &[&str]| {
        let out = divertsim().arg("reliability").args(args).output().unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        for n in needles {
            assert!(err.contains(n), "{args:?}: {err}");
        }
    };
    fail(
        &["--sweep", "machine.belt_speed=1:2"],
        &["--sweep", "LO:HI/COUNT"],
    );
    fail(
        &["--sweep", "machine.belt_speed=1,-3"],
        &["machine.belt_speed", "point -3"],
    );
    fail(&["--resume"], &["--resume", "--out"]);
    fail(
        &["--samples", "1000000000", "--shard", "100"],
        &["--shard", "at most 100000 shards"],
    );
    fail(&["--until-ci", "2"], &["--until-ci", "(0, 1)"]);
    fail(
        &[
            "--set",
            "mix.length={kind=\"fixed\",value=3}",
            "--set",
            "mix.width={kind=\"fixed\",value=2}",
        ],
        &["mix", "rejected", "off_belt"],
    );
    fail(
        &["--set", "mix.angle_deg={kind=\"normal\",mean=0}"],
        &["mix.angle_deg", "sd"],
    );
    fail(
        &["--set", "mix.records=\"nope.csv\""],
        &["mix.records", "nope.csv"],
    );
}

#[test]
fn simulate_runs_the_parcels_own_start_and_analyses_refuse_it() {
    let v = json_stdout(divertsim().args([
        "simulate",
        "--json",
        "--set",
        "machine.trigger=adaptive",
        "--set",
        "machine.light_barrier=-0.5",
    ]));
    let t = &v["trigger"];
    assert_eq!(t["kind"], "adaptive");
    let (lo, r, hi) = (
        t["passing_interval"][0].as_f64().unwrap(),
        t["start_position"].as_f64().unwrap(),
        t["passing_interval"][1].as_f64().unwrap(),
    );
    assert!(lo < r && r < hi, "{t}");
    assert!((r - 0.5 * (lo + hi)).abs() < 1e-12);
    assert_eq!(v["outcome"], "diverted");
    let out = divertsim()
        .args(["trigger", "--set", "machine.trigger=adaptive"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("machine.trigger"));
}

/// Outside a terminal the progress is a plain line now and then (here every 0.1 s), and
/// nothing with --quiet.
#[test]
fn progress_is_plain_lines_in_a_log() {
    let run = |quiet: bool| {
        let mut cmd = divertsim();
        cmd.env("DIVERTSIM_PROGRESS_SECONDS", "0.1").args([
            "reliability",
            HUB,
            "--samples",
            "3000",
            "--threads",
            "1",
            "--json",
        ]);
        if quiet {
            cmd.arg("-q");
        }
        let out = cmd.output().unwrap();
        assert!(out.status.success());
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let log = run(false);
    let line = log
        .lines()
        .find(|l| l.contains("runs"))
        .unwrap_or_else(|| panic!("no progress line in {log:?}"));
    assert!(
        line.contains("/3000 runs") && line.contains("eta"),
        "{line}"
    );
    assert!(
        !log.contains('\r') && !log.contains('\u{1b}'),
        "terminal control codes in a log"
    );
    assert!(!run(true).contains("runs"));
}

/// Issue 26: `reliability` on the hub mix reports the tipping rate with its interval and
/// the load spectrum (every stroke counted once, per 10⁶ strokes), and the largest stroke's
/// scenario file gives its peak drive torque again with `simulate`.
#[test]
fn hub_reports_the_load_spectrum_and_its_largest_stroke_reproduces() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("r");
    divertsim()
        .args([
            "reliability",
            HUB,
            "--samples",
            "400",
            "--shard",
            "200",
            "-q",
            "--out",
        ])
        .arg(&out)
        .assert()
        .success();
    let summary = common::summary_in(&out);
    let p = &summary["points"][0];
    let tip = &p["tipping_rate"];
    assert_eq!(tip["of"], 400);
    assert!(tip["lower"].as_f64().unwrap() <= tip["upper"].as_f64().unwrap());
    let spectrum = &p["load_spectrum"];
    assert_eq!(spectrum["strokes"], 400);
    let torque = &spectrum["peak_drive_torque_n_m"];
    assert_eq!(torque["total"], 400);
    let per_million: f64 = torque["bins"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| b["per_million_strokes"].as_f64().unwrap())
        .sum::<f64>()
        + torque["above"]["per_million_strokes"].as_f64().unwrap();
    assert!((per_million - 1e6).abs() < 1e-6, "{per_million}");
    let csv = std::fs::read_to_string(out.join("load_spectrum.csv")).unwrap();
    assert!(csv.starts_with("point,sweep_value,load,bin_lo,bin_hi,count,per_million_strokes"));
    assert!(csv.contains(",strike_angular_impulse_n_m_s,"));
    // The largest stroke, simulated on its own.
    let largest = spectrum["largest_stroke"]["peak_drive_torque_n_m"]
        .as_f64()
        .unwrap();
    assert_eq!(torque["max"].as_f64(), Some(largest));
    common::assert_largest_stroke_reproduces(&out, largest);
    let text = std::fs::read_to_string(out.join("largest_stroke.toml")).unwrap();
    assert!(text.starts_with("# Sample "), "{text}");
}

/// Review of issue 50, item 12: the flags of the other commands in the same grammar
/// (`--speeds`, `--cycle-times`) dropped its warnings. Each command now says, with its
/// flag, that a whole-number STEP was read as a step, and runs with those values.
#[test]
fn a_list_flags_step_that_reads_like_a_count_is_warned_about_on_every_command() {
    let out = divertsim()
        .args([
            "capacity",
            "--speeds",
            "0.5:2.5:2",
            "--cycle-times",
            "1.2",
            "--light-barriers",
            "0",
            "--worst",
            "paper",
            "--json",
            "-q",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("warning: --speeds '0.5:2.5:2' is read as LO:HI:STEP, 2 values (0.5, 2.5)")
            && err.contains("write 0.5:2.5/2"),
        "{err}"
    );
    let out = divertsim()
        .args(["trigger", "--speeds", "1:2:1", "--json", "-q"])
        .output()
        .unwrap();
    assert!(out.status.success());
    assert!(
        out.stderr.is_empty(),
        "a step of 1 reads as no count: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    // A sweep of a command on the contract (the line) is warned about as reliability's is.
    let out = divertsim()
        .args([
            "line",
            concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/paper/line.toml"),
            "--sweep",
            "line.gap_target=1:3:2",
            "--parcels",
            "20",
            "--json",
            "-q",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("warning: sweep '1:3:2' is read as LO:HI:STEP, 2 values (1, 3)"),
        "{err}"
    );
}

/// Issue 50, item 12: `--sweep KEY=0:10:5` read 5 as a step without a word. A whole-number
/// STEP is warned about with the count's spelling, and one that would give a single value
/// (`1.5:2.3:9`) is refused (exit 2) with it.
#[test]
fn a_sweep_step_that_reads_like_a_count_is_warned_about_or_refused() {
    let out = divertsim()
        .args([
            "reliability",
            HUB,
            "--samples",
            "100",
            "--shard",
            "100",
            "-q",
            "--json",
            "--sweep",
            "mix.seed=1:3:2",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("read as LO:HI:STEP"), "{err}");
    assert!(err.contains("write 1:3/2"), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        v["points"].as_array().unwrap().len(),
        2,
        "1 and 3: a step of 2"
    );
    let out = divertsim()
        .args([
            "reliability",
            HUB,
            "--samples",
            "100",
            "-q",
            "--sweep",
            "machine.belt_speed=1.5:2.3:9",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("write 1.5:2.3/9"), "{err}");
}

/// Issue 50, item 10: `--set mix.records=dims.csv` failed with "TOML parse error at line
/// 1, column 5". A key that names a file takes a bare path, as an enum key takes a bare
/// word, and it draws the same parcels as the quoted path.
#[test]
fn a_bare_path_is_taken_for_a_file_key() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(
        tmp.path().join("dims.csv"),
        "length,width,height,mass\n0.3,0.2,0.1,2.0\n0.4,0.25,0.2,4.0\n",
    )
    .unwrap();
    let run = |set: &str| {
        let out = divertsim()
            .current_dir(tmp.path())
            .args([
                "reliability",
                "--samples",
                "30",
                "-q",
                "--json",
                "--set",
                set,
            ])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{set}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        v["points"][0]["divert_rate"].clone()
    };
    assert_eq!(run("mix.records=dims.csv"), run("mix.records=\"dims.csv\""));
    let out = divertsim()
        .current_dir(tmp.path())
        .args(["reliability", "-q", "--set", "mix.records=nope.csv"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("mix.records") && err.contains("nope.csv"),
        "{err}"
    );
    assert!(!err.contains("TOML parse error"), "{err}");
}

/// Issue 50, items 8 and 9: `reliability` on a scenario without `[mix]` drew from a
/// built-in mix that its scenario.toml did not record, and a records mix drew its offset,
/// angle and timing error from unrecorded defaults. The written scenario states every
/// distribution drawn, and running it again gives the same rates.
#[test]
fn the_written_scenario_states_the_mix_it_drew_from() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("o");
    let run = |args: &[&str], out: Option<&Path>| {
        let mut c = divertsim();
        c.current_dir(tmp.path())
            .args(["reliability", "--samples", "200", "-q", "--json"])
            .args(args);
        if let Some(o) = out {
            c.arg("--out").arg(o);
        }
        let o = c.output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        (
            v["points"][0]["divert_rate"].clone(),
            v["points"][0]["tipping_rate"].clone(),
        )
    };
    let first = run(&[], Some(&out));
    let written = std::fs::read_to_string(out.join("scenario.toml")).unwrap();
    let file: toml::Table = toml::from_str(&written).unwrap();
    let mix = file["mix"].as_table().expect("a [mix] section");
    for key in [
        "length",
        "width",
        "height",
        "mass",
        "offset_fraction",
        "angle_deg",
        "speed",
        "spin",
        "phase",
    ] {
        assert!(mix.contains_key(key), "{key} missing from\n{written}");
    }
    assert_eq!(mix["height"]["max"].as_float(), Some(0.3));
    assert_eq!(
        run(&[out.join("scenario.toml").to_str().unwrap()], None),
        first
    );
    // A records mix: the sizes come from the log, every other drawn quantity is stated.
    std::fs::write(
        tmp.path().join("log.csv"),
        "length,width,height,mass\n0.3,0.2,0.1,2.0\n0.4,0.25,0.2,4.0\n",
    )
    .unwrap();
    let rec = tmp.path().join("r");
    run(&["--set", "mix.records=log.csv"], Some(&rec));
    let written = std::fs::read_to_string(rec.join("scenario.toml")).unwrap();
    let file: toml::Table = toml::from_str(&written).unwrap();
    let mix = file["mix"].as_table().unwrap();
    for key in ["offset_fraction", "angle_deg", "phase", "speed", "spin"] {
        assert!(mix.contains_key(key), "{key} missing from\n{written}");
    }
    for key in ["length", "width", "height", "mass"] {
        assert!(
            !mix.contains_key(key),
            "{key}: the records give it\n{written}"
        );
    }
}
