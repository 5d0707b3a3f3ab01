//! End-to-end tests of `divertsim track`, `compare` and `calibrate` on synthetic tracks of
//! the paper preset's runs (25 fps, 304 px per 0.6 m, whole pixels).

use crate::common;

use common::{divertsim, json_stdout};
use std::path::{Path, PathBuf};

const PAPER: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/paper");

fn preset(name: &str) -> String {
    format!("{PAPER}/{name}.toml")
}

/// A synthetic pixel track of a preset's run.
fn synthesize(dir: &Path, name: &str) -> PathBuf {
    let out = dir.join(format!("{name}.csv"));
    divertsim()
        .args(["track", &preset(name), "-q", "--synthesize"])
        .arg(&out)
        .assert()
        .success();
    out
}

#[test]
fn track_reads_and_refuses_bad_files() {
    let tmp = tempfile::tempdir().unwrap();
    let t = synthesize(tmp.path(), "fig15b");
    let text = std::fs::read_to_string(&t).unwrap();
    assert!(text.contains("# set parcel.length=0.4"));
    let v = json_stdout(
        divertsim()
            .args(["track", &preset("machine"), "--json", "--track"])
            .arg(&t),
    );
    let r = &v["tracks"][0];
    assert_eq!(r["units"], "px");
    assert!(r["points"].as_u64().unwrap() >= 10);
    let sigma = r["quantisation_sigma_m"][0].as_f64().unwrap();
    assert!((sigma - 0.6 / 304.0 / 12f64.sqrt()).abs() < 1e-9);
    // Broken tracks: named with their line.
    let bad = tmp.path().join("bad.csv");
    std::fs::write(
        &bad,
        "t,u,v\n0,10,10\n0.04,11,10\n0.04,12,10\n0.08,13,10\n0.12,14,10\n",
    )
    .unwrap();
    let out = divertsim()
        .args(["track", "--track"])
        .arg(&bad)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("line 4") && err.contains("times must increase"),
        "{err}"
    );
}

/// A track from another parcel, or another belt speed, than its scenario is flagged; the
/// right scenario matches to the pixel.
#[test]
fn compare_flags_a_track_from_another_experiment() {
    let tmp = tempfile::tempdir().unwrap();
    let t = synthesize(tmp.path(), "fig13b");
    // The track without its `# set` lines: the scenario alone says what was filmed.
    let bare = tmp.path().join("bare.csv");
    let text: String = std::fs::read_to_string(&t)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with("# set"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(&bare, text).unwrap();
    let run = |scenario: &str, sets: &[&str]| {
        let mut cmd = divertsim();
        cmd.args(["compare", scenario, "--json", "--track"])
            .arg(&bare);
        for s in sets {
            cmd.args(["--set", s]);
        }
        json_stdout(&mut cmd)["tracks"][0].clone()
    };
    let right = run(&preset("fig13b"), &[]);
    assert_eq!(right["matches"], true, "{right}");
    assert!(right["rms_m"].as_f64().unwrap() < 0.002);
    assert!((right["time_offset_s"].as_f64().unwrap() - 0.2).abs() < 0.002);
    // The compact parcel instead of the slender one.
    let other_parcel = run(&preset("fig15b"), &[]);
    assert_eq!(other_parcel["matches"], false, "{other_parcel}");
    // The same parcel at 1.8 m/s instead of 2.
    let other_speed = run(&preset("fig13b"), &["machine.belt_speed=1.8"]);
    assert_eq!(other_speed["matches"], false, "{other_speed}");
    assert!(!other_speed["flags"].as_array().unwrap().is_empty());
}

/// Calibration from the CLI: the fitted scenario file runs with `simulate`.
#[test]
fn calibrate_writes_a_scenario_that_simulates() {
    let tmp = tempfile::tempdir().unwrap();
    let a = synthesize(tmp.path(), "fig13a");
    let b = synthesize(tmp.path(), "fig15b");
    let out = tmp.path().join("cal");
    let v = json_stdout(
        divertsim()
            .args([
                "calibrate",
                &preset("machine"),
                "--fit",
                "materials.belt_friction,materials.arm_friction",
                "--set",
                "materials.belt_friction=0.3",
                "--budget",
                "150",
                "--json",
                "-q",
                "--out",
            ])
            .arg(&out)
            .arg("--track")
            .arg(&a)
            .arg("--track")
            .arg(&b),
    );
    let values = v["values"].as_array().unwrap();
    assert_eq!(values[0]["key"], "materials.belt_friction");
    // The preset's μ_b 0.5 and μ_a 0.38, from a start at μ_b 0.3 and a small budget.
    assert!(
        (values[0]["value"].as_f64().unwrap() - 0.5).abs() < 0.03,
        "{v}"
    );
    assert!(
        (values[1]["value"].as_f64().unwrap() - 0.38).abs() < 0.03,
        "{v}"
    );
    for f in [
        "summary.json",
        "calibrated.toml",
        "profiles.csv",
        "fit_fig13a.svg",
        "fit_fig15b.png",
        "report.html",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
    let s = json_stdout(
        divertsim()
            .args(["simulate", "--json"])
            .arg(out.join("calibrated.toml")),
    );
    assert!(s["outcome"].is_string());
    // Bad options are named.
    let bad = divertsim()
        .args([
            "calibrate",
            "--fit",
            "parcel.mass",
            "--bound",
            "materials.restitution=2:3",
            "--track",
        ])
        .arg(&a)
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.contains("parcel.mass cannot be fitted"), "{err}");
}

/// Issue 27 (C10): a track cut where the camera's field of view ends, before the parcel
/// reaches the far edge, is no measured "not diverted": its verdict is unknown and the
/// track still matches its scenario; `--ignore-verdict` leaves verdicts out altogether.
#[test]
fn a_track_cut_before_the_far_edge_still_matches() {
    let tmp = tempfile::tempdir().unwrap();
    let t = synthesize(tmp.path(), "fig15b");
    let text = std::fs::read_to_string(&t).unwrap();
    // Keep the comments, the header and the first half of the points.
    let (head, rows): (Vec<&str>, Vec<&str>) = text
        .lines()
        .partition(|l| l.starts_with('#') || l.starts_with(|c: char| c.is_alphabetic()));
    let cut = tmp.path().join("cut.csv");
    let kept = &rows[..rows.len() / 2];
    std::fs::write(&cut, format!("{}\n{}\n", head.join("\n"), kept.join("\n"))).unwrap();
    for extra in [&[][..], &["--ignore-verdict"][..]] {
        let v = json_stdout(
            divertsim()
                .args(["compare", &preset("machine"), "--json", "-q", "--track"])
                .arg(&cut)
                .args(extra),
        );
        let r = &v["tracks"][0];
        assert_eq!(r["measured_verdict"], "unknown", "{r}");
        assert_eq!(r["measured_diverted"], serde_json::Value::Null);
        assert_eq!(r["simulated_diverted"], true);
        assert_eq!(r["matches"], true, "{r}");
        assert_eq!(v["warnings"], serde_json::json!([]));
    }
    // Without its `# set` lines a track runs the scenario's own parcel: said, not silent.
    let bare = tmp.path().join("bare.csv");
    let rows: Vec<&str> = text.lines().filter(|l| !l.starts_with("# set")).collect();
    std::fs::write(&bare, rows.join("\n") + "\n").unwrap();
    let v = json_stdout(
        divertsim()
            .args(["compare", &preset("machine"), "--json", "-q", "--track"])
            .arg(&bare),
    );
    let w = v["warnings"][0].as_str().unwrap_or_default();
    assert!(w.contains("bare") && w.contains("no `# set` lines"), "{v}");
}

/// A fit has no piece of work to stop at, so the work limit is held by refusing it on the
/// most it can run (its budget), before it starts: a limit below that is refused naming
/// --max-sims and --budget, however little its first generation needs.
#[test]
fn calibrate_is_refused_on_its_budget_as_it_cannot_be_stopped_midway() {
    let tmp = tempfile::tempdir().unwrap();
    let t = synthesize(tmp.path(), "fig15b");
    let o = divertsim()
        .args([
            "calibrate",
            &preset("machine"),
            "--max-sims",
            "100",
            "--track",
        ])
        .arg(&t)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--max-sims: calibrate would run at least") && err.contains("--budget"),
        "{err}"
    );
}
