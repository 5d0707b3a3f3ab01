//! End-to-end tests of `divertsim optimize` (issue 5 item 4): tiny runs of every method, the
//! evaluation log (header, one row per evaluation), history, front and report files, `--json`,
//! bad options (exit 2, nothing written), identical results for any thread count, and tiny
//! versions of the paper experiment and the comparison.

use std::path::Path;

use serde_json::Value;

use crate::common;
use common::{divertsim, json_stdout};

const PRESET: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../configs/paper/machine.toml"
);

/// A run of the method machinery on the paper's closed-form worst case (`--worst paper`
/// unless the arguments choose): the robust rounds of `--worst search` are tested in
/// worst_case_cli.rs.
fn run_ok(args: &[&str]) -> std::process::Output {
    let worst: &[&str] = if args.contains(&"--worst") {
        &[]
    } else {
        &["--worst", "paper"]
    };
    let out = divertsim()
        .arg("optimize")
        .arg(PRESET)
        .args(worst)
        .args(args)
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn read(dir: &Path, name: &str) -> String {
    std::fs::read_to_string(dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn json_of(dir: &Path) -> Value {
    serde_json::from_str(&read(dir, "summary.json")).unwrap()
}

const HEADER: &str =
    "index,iteration,belt_speed_m_s,cycle_time_s,start_position_m,light_barrier_m,capacity_per_h,\
g:divert:smallest,g:divert:slender,g:divert:compact,g:overload,g:barrier,violation,feasible";

/// Check the files of a single run and return (report, evaluations.csv).
fn check_single(dir: &Path, method: &str) -> (Value, String) {
    let report = json_of(dir);
    assert_eq!(report["method"], method);
    let evals = read(dir, "evaluations.csv");
    let mut lines = evals.lines();
    let header = lines.next().unwrap();
    if method == "nsga2" {
        assert!(
            header.contains("capacity_per_h,overload_ratio,divert_overshoot_m,g:divert:smallest")
        );
    } else {
        assert_eq!(header, HEADER);
    }
    let n = report["evaluations"].as_u64().unwrap() as usize;
    assert!(n > 0);
    assert_eq!(lines.clone().count(), n, "one row per evaluation");
    // Indices are consecutive and the feasible count matches the log.
    let feasible = lines
        .enumerate()
        .filter(|(i, l)| {
            assert!(l.starts_with(&format!("{i},")));
            l.ends_with(",true")
        })
        .count();
    assert_eq!(
        report["feasible_count"].as_u64().unwrap() as usize,
        feasible
    );
    // The best point is inside the default box, with S_d fixed at the preset's 0.
    let p = &report["best"]["point"];
    let v = p["belt_speed"].as_f64().unwrap();
    let tc = p["cycle_time"].as_f64().unwrap();
    let rs = p["start_position"].as_f64().unwrap();
    assert!((1.0..=2.3).contains(&v) && (1.0..=1.5).contains(&tc) && (0.0..=0.9).contains(&rs));
    assert_eq!(p["light_barrier"].as_f64().unwrap(), 0.0);
    // W is the paper's formula at the best point.
    let w = report["best"]["capacity"].as_f64().unwrap();
    assert!((w - 3600.0 / (rs / v + tc)).abs() < 1e-9 * w);
    assert_eq!(report["best"]["constraints"].as_array().unwrap().len(), 5);
    assert!(report["best"]["worst_parcel"]["name"].is_string());
    let history = read(dir, "history.csv");
    assert!(history.starts_with("iteration,evaluations,best_capacity_per_h,best_feasible"));
    assert!(history.lines().count() >= 2);
    assert!(read(dir, "history.svg").contains("<svg"));
    (report, evals)
}

#[test]
fn de_tiny_run_files_json_and_thread_independence() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    let args = [
        "--method",
        "de",
        "--population",
        "6",
        "--generations",
        "2",
        "--no-polish",
        "-q",
    ];
    let out = run_ok(
        &[
            &args[..],
            &["--threads", "1", "--json", "--out", a.to_str().unwrap()],
        ]
        .concat(),
    );
    let stdout: Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    run_ok(&[&args[..], &["--threads", "2", "--out", b.to_str().unwrap()]].concat());
    let (ra, ea) = check_single(&a, "de");
    let (rb, eb) = check_single(&b, "de");
    assert_eq!(ra, rb);
    assert_eq!(ra["evaluations"].as_u64(), Some(18));
    assert_eq!(ea, eb);
    assert_eq!(read(&a, "history.csv"), read(&b, "history.csv"));
    // summary.json carries no timing: the same run gives the same bytes on any thread count.
    assert_eq!(read(&a, "summary.json"), read(&b, "summary.json"));
    // --json prints the report (same content as summary.json).
    assert_eq!(stdout, ra);
    for key in [
        "first_feasible",
        "feasible_count",
        "bounds",
        "constraint_names",
    ] {
        assert!(stdout.get(key).is_some(), "{key}");
    }
}

#[test]
fn every_method_tiny() {
    let tmp = tempfile::tempdir().unwrap();
    let cases: [(&str, &[&str]); 4] = [
        ("ga", &["--population", "6", "--generations", "2"]),
        ("gradient", &["--start", "1.8,1.5,0.5", "--budget", "12"]),
        (
            "cmaes",
            &["--population", "4", "--generations", "2", "--no-polish"],
        ),
        ("nsga2", &["--population", "6", "--generations", "2"]),
    ];
    for (method, extra) in cases {
        let dir = tmp.path().join(method);
        let out = run_ok(
            &[
                &["--method", method, "-q", "--out", dir.to_str().unwrap()],
                extra,
            ]
            .concat(),
        );
        let (report, _) = check_single(&dir, method);
        let text = String::from_utf8_lossy(&out.stdout);
        for needle in [
            "best point:",
            "capacity W =",
            "active constraints",
            "worst parcel:",
            "evaluations:",
        ] {
            assert!(
                text.contains(needle),
                "{method}: {needle} missing in\n{text}"
            );
        }
        match method {
            "ga" => assert_eq!(report["evaluations"].as_u64(), Some(6 + 2 * 4)),
            "gradient" => assert!(report["evaluations"].as_u64().unwrap() <= 12),
            "cmaes" => assert_eq!(report["evaluations"].as_u64(), Some(8)),
            _ => {
                let front = read(&dir, "front.csv");
                assert!(front.starts_with("capacity_per_h,overload_ratio,divert_overshoot_m"));
                assert_eq!(
                    front.lines().count() - 1,
                    report["front"].as_array().unwrap().len()
                );
                assert!(read(&dir, "front.svg").contains("<svg"));
            }
        }
    }
}

#[test]
fn bad_options_exit_2_and_write_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("out");
    let d = dir.to_str().unwrap();
    let cases: [(&[&str], &str); 8] = [
        (&["--bound", "v=0:1"], "--bound"),
        (&["--bound", "q=1:2"], "--bound"),
        (&["--fix", "R_s=9"], "--fix"),
        (&["--method", "ga", "--start", "1.8,1.5,0.5"], "--start"),
        (&["--method", "gradient", "--start", "3,1.5,0.5"], "--start"),
        (&["--population", "2"], "--population"),
        (
            &["--method", "ga", "--population", "6", "--budget", "3"],
            "--budget",
        ),
        (
            &["--method", "gradient", "--population", "6"],
            "--population",
        ),
    ];
    for (args, option) in cases {
        let out = divertsim()
            .arg("optimize")
            .arg(PRESET)
            .args(args)
            .args(["--out", d])
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(option), "{args:?}: {err}");
        assert!(!dir.exists(), "{args:?} wrote {d}");
    }
}

#[test]
fn paper_experiment_and_comparison_tiny() {
    let tmp = tempfile::tempdir().unwrap();
    let p = tmp.path().join("paper");
    let out = run_ok(&[
        "--paper-experiment",
        "--population",
        "4",
        "--generations",
        "1",
        "--budget",
        "8",
        "-q",
        "--out",
        p.to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("paper GA optimum") && text.contains("gradient 3"),
        "{text}"
    );
    let csv = read(&p, "paper_experiment.csv");
    assert_eq!(csv.lines().count(), 1 + 6);
    for f in [
        "fig10_ga.svg",
        "fig11_gradient.svg",
        "GA_1_evaluations.csv",
        "gradient_2_history.csv",
    ] {
        assert!(p.join(f).exists(), "{f}");
    }
    let j: Value = serde_json::from_str(&read(&p, "summary.json")).unwrap();
    assert_eq!(j["runs"].as_array().unwrap().len(), 6);
    // 4 + (4 − 2 elites) children.
    assert_eq!(j["runs"][0]["evaluations"].as_u64(), Some(4 + 2));

    let c = tmp.path().join("cmp");
    run_ok(&[
        "--compare",
        "--seeds",
        "2",
        "--population",
        "4",
        "--generations",
        "1",
        "--budget",
        "12",
        "--no-polish",
        "-q",
        "--out",
        c.to_str().unwrap(),
    ]);
    let csv = read(&c, "comparison.csv");
    assert_eq!(csv.lines().count(), 1 + 5 * 2, "one row per run");
    assert!(
        !csv.contains("median") && !csv.to_lowercase().contains("nan"),
        "{csv}"
    );
    let medians = read(&c, "comparison_medians.csv");
    assert_eq!(medians.lines().count(), 1 + 5, "one row per method");
    assert!(!medians.to_lowercase().contains("nan"), "{medians}");
    let j: Value = serde_json::from_str(&read(&c, "summary.json")).unwrap();
    for r in j["runs"].as_array().unwrap() {
        assert!(r["evaluations"].as_u64().unwrap() <= 12);
    }
}

#[test]
fn the_scenario_files_optimize_section_sets_the_box_and_the_command_line_overrides_it() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("opt.toml");
    std::fs::write(
        &file,
        format!("base = {PRESET:?}\n[optimize]\nbelt_speed = [1.8, 2.0]\nstart_position = 0.1\n"),
    )
    .unwrap();
    let tiny = [
        "--method",
        "de",
        "--population",
        "4",
        "--generations",
        "1",
        "--no-polish",
        "-q",
        "--json",
        // The preset (the base) lies outside the temporary directory.
        "--allow-outside-paths",
    ];
    let run = |extra: &[&str]| -> Value {
        json_stdout(
            divertsim()
                .arg("optimize")
                .arg(&file)
                .args(tiny)
                .args(extra),
        )
    };
    let v = run(&[]);
    assert_eq!(v["bounds"]["belt_speed"], serde_json::json!([1.8, 2.0]));
    assert_eq!(v["bounds"]["start_position"], serde_json::json!([0.1, 0.1]));
    assert_eq!(v["bounds"]["cycle_time"], serde_json::json!([1.0, 1.5]));
    // The command line wins, variable by variable.
    let v = run(&["--bound", "R_s=0:0.2", "--fix", "v=1.9"]);
    assert_eq!(v["bounds"]["start_position"], serde_json::json!([0.0, 0.2]));
    assert_eq!(v["bounds"]["belt_speed"], serde_json::json!([1.9, 1.9]));
    // A bad range in the file is named by its key, exit 2.
    std::fs::write(
        &file,
        format!("base = {PRESET:?}\n[optimize]\nbelt_speed = [0.0, 1.0]\n"),
    )
    .unwrap();
    let out = divertsim()
        .arg("optimize")
        .arg(&file)
        .args(tiny)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("optimize.belt_speed"), "{err}");
}

/// SIGKILL once some evaluations are kept, then `--resume`: the files are byte-identical to
/// an uninterrupted run, and the evaluations streamed into the checkpoint as they happened.
#[test]
fn killed_and_resumed_optimize_is_byte_identical() {
    let t = tempfile::tempdir().unwrap();
    let args = [
        "optimize",
        PRESET,
        "--worst",
        "paper",
        "--method",
        "ga",
        "--population",
        "8",
        "--generations",
        "4",
        "-q",
    ];
    // The header and at least two evaluations streamed.
    common::kill_and_resume(t.path(), &args, |d| {
        std::fs::read_to_string(d.join(".cut.checkpoint/evaluations-0.csv"))
            .map_or(0, |s| s.lines().count())
            >= 3
    });
}

/// Hostile input round three: `--population 10000 --generations 10000 --max-sims 1`
/// allocated 9.4 GB (a full dry run of the solver) before the work limit refused it. The
/// dry check stops every method at its first batch, and the limit is the answer.
#[test]
fn huge_population_times_generations_is_refused_by_the_work_limit() {
    for method in ["ga", "de", "nsga2", "cmaes", "gradient"] {
        let out = divertsim()
            .args(["optimize", "--method", method, "--population", "10000"])
            .args(["--generations", "10000", "--max-sims", "1", "-q"])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{method}: {err}");
        assert!(
            err.contains("--max-sims") || err.contains("--population"),
            "{method}: {err}"
        );
    }
}

/// A new user's report: `optimize` showed 72,719/55,836 (a robust run's confirmation
/// searches were not counted). Every progress line's count stays within its total, here
/// on a robust run that converges (7 rounds, then the confirmation search).
#[test]
fn robust_optimize_progress_never_counts_past_its_total() {
    let out = divertsim()
        .env("DIVERTSIM_PROGRESS_SECONDS", "0")
        .args([
            "optimize",
            PRESET,
            "--rounds",
            "30",
            "--threads",
            "2",
            "--json",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let log = String::from_utf8_lossy(&out.stderr);
    let counts: Vec<(u64, u64)> = log
        .split_whitespace()
        .filter_map(|w| w.split_once('/'))
        .filter_map(|(a, b)| {
            let n = |t: &str| t.replace(',', "").parse::<u64>().ok();
            Some((n(a)?, n(b)?))
        })
        .collect();
    assert!(!counts.is_empty(), "no progress line in {log:?}");
    for (done, total) in counts {
        assert!(done <= total, "{done}/{total} in {log}");
    }
}

/// A new user's wish: the optimum as a scenario file that `simulate` runs directly, at the
/// best point's v, t_c, R_s and S_d.
#[test]
fn optimum_toml_runs_the_best_point() {
    let t = tempfile::tempdir().unwrap();
    let dir = t.path().join("opt");
    let report = json_stdout(
        divertsim()
            .args(["optimize", PRESET, "--worst", "paper", "--method", "ga"])
            .args([
                "--population",
                "6",
                "--generations",
                "2",
                "-q",
                "--json",
                "--out",
            ])
            .arg(&dir),
    );
    let point = &report["best"]["point"];
    let text = read(&dir, "optimum.toml");
    assert!(
        text.starts_with("# Written by `divertsim optimize`"),
        "{text}"
    );
    let run = json_stdout(
        divertsim()
            .args(["simulate", "--json"])
            .arg(dir.join("optimum.toml")),
    );
    let m = &run["scenario"]["machine"];
    for key in [
        "belt_speed",
        "cycle_time",
        "start_position",
        "light_barrier",
    ] {
        assert!(point[key].as_f64().is_some(), "{key}");
        assert_eq!(m[key], point[key], "{key}");
    }
}

/// Review of the contract step: the paper experiment and the comparison skipped the size
/// checks, so a 10¹² population reached the solver's dry check (an allocation of that
/// size) before the work limit. Sizes are checked in every experiment.
#[test]
fn batch_optimize_checks_its_sizes_before_any_work() {
    for mode in ["--compare", "--paper-experiment"] {
        for (flag, value) in [("--population", "1000000000000"), ("--generations", "0")] {
            let out = divertsim()
                .args(["optimize", mode, flag, value, "--max-sims", "1", "-q"])
                .output()
                .unwrap();
            let err = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{mode} {flag}: {err}");
            assert!(err.contains(flag) && err.contains("out of range"), "{err}");
        }
    }
}

const LINE_PRESET: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/paper/line.toml");

/// `--objective line` (issue 25, item 8): the line's files and figures, its report, and
/// `divertsim line` on optimum.toml giving the best point's throughput.
#[test]
fn line_objective_tiny_run_files_and_replay() {
    let t = tempfile::tempdir().unwrap();
    let dir = t.path().join("opt");
    let report = json_stdout(
        divertsim()
            .args(["optimize", LINE_PRESET, "--objective", "line"])
            .args([
                "--parcels",
                "100",
                "--stream-seed",
                "5",
                "--max-missort",
                "0.02",
            ])
            .args(["--population", "6", "--generations", "1", "--no-polish"])
            .args(["-q", "--json", "--out"])
            .arg(&dir),
    );
    assert_eq!(report["objective"], "line");
    assert_eq!(report["parcels"], 100);
    for f in [
        "evaluations.csv",
        "history.csv",
        "history.svg",
        "history.png",
        "summary.json",
        "optimum.toml",
    ] {
        assert!(dir.join(f).is_file(), "{f}");
    }
    let evals = read(&dir, "evaluations.csv");
    assert!(evals.starts_with(
        "index,iteration,belt_speed_m_s,cycle_time_s,start_position_m,light_barrier_m,throughput_per_h,missort_rate,overload_rate,g:missort,g:overload,g:barrier,violation,feasible\n"
    ), "{evals}");
    assert_eq!(evals.lines().count(), 1 + 12);
    let line = json_stdout(
        divertsim()
            .args(["line", "--json", "--parcels", "100", "--seed", "5"])
            .arg(dir.join("optimum.toml")),
    );
    assert_eq!(
        line["points"][0]["throughput_per_h"],
        report["best"]["throughput_per_h"]
    );
    // The methods that cannot search the line are refused by name, nothing written.
    let bad = t.path().join("bad");
    let out = divertsim()
        .args([
            "optimize",
            LINE_PRESET,
            "--objective",
            "line",
            "--method",
            "nsga2",
            "--out",
        ])
        .arg(&bad)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--method") && err.contains("de, ga, cmaes"),
        "{err}"
    );
    assert!(!bad.exists());
}
