//! End-to-end tests of `divertsim overload` (issue 4 item 5): table, CSV, SVG, JSON, bad
//! options, thread independence, and the numbers against docs/model.md §2 and §5.

use serde_json::Value;

use crate::common;
use common::{divertsim, json_stdout};

fn json(args: &[&str]) -> Value {
    json_stdout(divertsim().arg("overload").args(args).arg("--json"))
}

#[test]
fn json_has_the_references_and_the_curve() {
    let v = json(&["--speeds", "0.5:2.5/5", "--drop-heights", "0.2,0.3"]);
    assert_eq!(v["cycle_time"], 1.36);
    assert_eq!(v["mass"], 15.0);
    // docs/model.md §2: largest α̇ 1.78249 rad/s at α = 21.70°.
    assert!((v["arm_peak"]["rate"].as_f64().unwrap() - 1.78249).abs() < 5e-6);
    assert!((v["arm_peak"]["angle_deg"].as_f64().unwrap() - 21.70).abs() < 5e-3);
    // docs/model.md §5: S_fall = 47.309 N·s for 15 kg, e* = 0.3, 0.3 m; ∝ √H₀.
    let refs = v["references"].as_array().unwrap();
    let f02 = refs[0]["fall_impulse"].as_f64().unwrap();
    let f03 = refs[1]["fall_impulse"].as_f64().unwrap();
    assert!((f03 - 47.309).abs() < 5e-4);
    assert!((f02 / f03 - (0.2f64 / 0.3).sqrt()).abs() < 1e-12);
    let pts = v["points"].as_array().unwrap();
    assert_eq!(pts.len(), 5);
    let s: Vec<f64> = pts.iter().map(|p| p["impulse"].as_f64().unwrap()).collect();
    assert!(
        s.windows(2).all(|w| w[1] > w[0]),
        "impulse rises with v: {s:?}"
    );
    for p in pts {
        let r = p["ratios"].as_array().unwrap();
        assert!((r[1].as_f64().unwrap() - p["impulse"].as_f64().unwrap() / f03).abs() < 1e-12);
        // u_n0 = v sin α + R_z α̇ at the peak.
        let want = p["belt_speed"].as_f64().unwrap() * 21.70f64.to_radians().sin() + 1.78249;
        assert!((p["approach_speed"].as_f64().unwrap() - want).abs() < 1e-4);
    }
    let max = v["max_impulse"].as_f64().unwrap();
    assert_eq!(max, s[4]);
    assert_eq!(
        refs[1]["below_at_every_speed"].as_bool().unwrap(),
        max < f03
    );
}

#[test]
fn outputs_and_threads() {
    let tmp = tempfile::tempdir().unwrap();
    let run = |threads: &str, out: &str| {
        let o = divertsim()
            .current_dir(tmp.path())
            .args([
                "overload",
                "--speeds",
                "0.5:2.5/9",
                "--threads",
                threads,
                "--out",
                out,
            ])
            .output()
            .unwrap();
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8(o.stdout).unwrap()
    };
    let a = run("1", "a");
    let b = run("2", "b");
    assert_eq!(a, b);
    assert!(a.contains("free fall from H₀ = 0.3 m"));
    let csv_a = std::fs::read(tmp.path().join("a/overload.csv")).unwrap();
    assert_eq!(
        csv_a,
        std::fs::read(tmp.path().join("b/overload.csv")).unwrap()
    );
    let csv = String::from_utf8(csv_a).unwrap();
    // The paper's case, then (the default search) the searched worst case at each speed.
    assert!(csv.starts_with("belt_speed_m_s,drop_height_m,overload_ratio,impulse_n_s,normal_impulse_n_s,tangential_impulse_n_s,approach_speed_m_s,arm_angle_deg,arm_rate_rad_s,equivalent_drop_height_m,searched_ratio,"), "{csv}");
    // Tidy: one row per (speed, drop height): 9 speeds × 2 heights.
    assert_eq!(csv.lines().count(), 1 + 9 * 2);
    let svg = std::fs::read_to_string(tmp.path().join("a/overload.svg")).unwrap();
    assert!(svg.contains("free fall H₀ = 0.3 m"));
    assert!(svg.contains("belt speed v [m/s]"));
}

#[test]
fn design_overload_parcel_is_used() {
    // Doubling the mass of a constant-slip strike doubles S and S_fall alike (ratio kept).
    let a = json(&["--speeds", "1:1:1"]);
    let b = json(&["--speeds", "1:1:1", "--set", "design.overload.mass=30.0"]);
    let (sa, sb) = (
        a["points"][0]["impulse"].as_f64().unwrap(),
        b["points"][0]["impulse"].as_f64().unwrap(),
    );
    assert!((sb / sa - 2.0).abs() < 1e-12, "{sa} {sb}");
    assert_eq!(b["mass"], 30.0);
}

#[test]
fn bad_options_exit_2_with_no_output() {
    let tmp = tempfile::tempdir().unwrap();
    for (args, expect) in [
        (vec!["--speeds", "0.5:30:3"], "[0, 20] m/s"),
        (vec!["--speeds", "fast"], "--speeds"),
        (vec!["--drop-heights", "0.2,-1"], "(0, 10] m"),
        (
            vec!["--set", "design.overload.mass=0"],
            "design.overload.mass",
        ),
    ] {
        let out = divertsim()
            .current_dir(tmp.path())
            .arg("overload")
            .args(&args)
            .args(["--out", "o"])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(expect), "{args:?}: {err}");
        assert!(!tmp.path().join("o").exists());
    }
    let out = divertsim().args(["overload", "--help"]).output().unwrap();
    assert!(String::from_utf8_lossy(&out.stdout).contains("Examples:"));
}

/// Issue 50, item 6: work that runs no simulation says so ("closed form"), never "about 0
/// simulations"; the searched default says its runs.
#[test]
fn a_closed_form_run_says_it_simulates_nothing() {
    let run = |args: &[&str]| {
        let o = divertsim()
            .args(["overload", "--speeds", "1.5"])
            .args(args)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(0));
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let paper = run(&["--worst", "paper"]);
    assert!(
        paper.contains("overload: closed form, no simulation"),
        "{paper}"
    );
    assert!(!paper.contains("about 0"), "{paper}");
    // A search's budget is spent whole: its count is known, not a range.
    let searched = run(&[]);
    assert!(
        searched.contains("overload: ") && searched.contains("00 simulations\n"),
        "{searched}"
    );
    assert!(!searched.contains("about"), "{searched}");
}
