//! End-to-end tests of `divertsim simulate`, `schema` and `example`: the output contract of
//! the issues "The core" and "Arm contact and impacts".

use serde_json::Value;

use crate::common;
use common::{divertsim, json_stdout};

fn json_of(args: &[&str]) -> Value {
    json_stdout(divertsim().args(args))
}

#[test]
fn default_run_prints_a_readable_summary() {
    let out = divertsim().arg("simulate").output().unwrap();
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "outcome:",
        "stages:",
        "max lateral:",
        "strikes:",
        "events:",
        "arm_start",
    ] {
        assert!(text.contains(needle), "{needle} missing in\n{text}");
    }
}

#[test]
fn json_summary_has_the_contract_fields() {
    let v = json_of(&["simulate", "--json"]);
    assert_eq!(v["outcome"], "diverted");
    let stages: Vec<&str> = v["stages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap())
        .collect();
    assert_eq!(&stages[..2], &["ride", "F1"]);
    for k in ["t", "x", "y", "phi_deg", "vx", "vy", "omega"] {
        assert!(v["final"][k].is_number(), "final.{k}");
    }
    assert!(v["max_lateral"].as_f64().unwrap() >= 0.7 - 1e-9);
    let kinds: Vec<&str> = v["events"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["kind"].as_str().unwrap())
        .collect();
    assert_eq!(kinds.first(), Some(&"arm_start"));
    assert_eq!(kinds.last(), Some(&"exit"));
    for k in [
        "max_impulse",
        "overload_ratio",
        "equivalent_drop_height",
        "energy_ratio",
    ] {
        assert!(v[k].as_f64().unwrap() > 0.0, "{k}");
    }
    let impacts = v["impacts"].as_array().unwrap();
    assert!(!impacts.is_empty());
    for i in impacts {
        for k in [
            "t",
            "normal_impulse",
            "tangential_impulse",
            "impulse",
            "approach_speed",
        ] {
            assert!(i[k].is_number(), "impact.{k}");
        }
    }
    assert_eq!(impacts[0]["stage"], "F1");
}

/// Done-when of "The core": no arm, parcel 1 m/s faster than the 2 m/s belt.
#[test]
fn ride_start_at_one_over_mu_g_from_the_command_line() {
    let v = json_of(&[
        "simulate",
        "--json",
        "--set",
        "run.arm=false",
        "--set",
        "parcel.velocity=[3.0,0.0]",
    ]);
    let ev = v["events"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["kind"] == "ride_start")
        .unwrap();
    let t = ev["t"].as_f64().unwrap();
    assert!((t - 1.0 / (0.4 * 9.81)).abs() < 1e-6, "ride_start at {t}");
    assert_eq!(v["final"]["vx"].as_f64(), Some(2.0));
    assert_eq!(v["final"]["vy"].as_f64(), Some(0.0));
    assert_eq!(v["stages"], serde_json::json!(["F2", "ride"]));
    assert_eq!(v["reason"], "left_on_belt");
}

#[test]
fn out_dir_holds_csv_summary_and_plot() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("run");
    let stdout: Value = json_stdout(divertsim().args(["simulate", "--json", "--out"]).arg(&dir));
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(stdout, summary);
    let csv = std::fs::read_to_string(dir.join("trajectory.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some(
            "t_s,x_m,y_m,phi_deg,vx_m_s,vy_m_s,omega_rad_s,alpha_deg,drive_torque_n_m,stage,contact1_x_m,contact1_y_m,contact2_x_m,contact2_y_m"
        )
    );
    // The drive torque beside α: never above the stroke's peak, and it reaches most of it.
    let torque: Vec<f64> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(8).unwrap().parse::<f64>().unwrap().abs())
        .collect();
    let largest = torque.iter().copied().fold(0.0, f64::max);
    let peak = summary["arm_loads"]["peak_torque"].as_f64().unwrap();
    assert!(
        largest <= peak * (1.0 + 1e-9) && largest > 0.5 * peak,
        "trajectory's largest |M_d| {largest}, the stroke's peak {peak}"
    );
    // Each strike on the arm carries its angular impulse about the pivot; the largest is
    // the stroke's.
    let arm_strikes: Vec<f64> = summary["impacts"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|i| i["obstacle"].as_str().unwrap().starts_with("arm"))
        .map(|i| i["arm_angular_impulse"].as_f64().unwrap().abs())
        .collect();
    assert!(!arm_strikes.is_empty());
    assert_eq!(
        arm_strikes.iter().copied().fold(0.0, f64::max),
        summary["arm_loads"]["max_strike_angular_impulse"]
            .as_f64()
            .unwrap()
    );
    let times: Vec<f64> = lines
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .collect();
    assert!(
        times.windows(2).all(|w| w[1] >= w[0]),
        "times must not decrease"
    );
    for e in summary["events"].as_array().unwrap() {
        let t = e["t"].as_f64().unwrap();
        assert!(
            times.contains(&t),
            "event instant {t} ({}) missing in the CSV",
            e["kind"]
        );
    }
    // Contact stages carry their contact points.
    let with_contact = csv
        .lines()
        .skip(1)
        .filter(|l| l.contains(",F4,") && !l.ends_with(",,,,"))
        .count();
    assert!(with_contact > 0, "no F4 sample with a contact point");
    let svg = std::fs::read_to_string(dir.join("plot.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.contains("strike"));
    // Nothing else left behind (no staging directory).
    let names: Vec<String> = std::fs::read_dir(tmp.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, vec!["run".to_string()]);
}

#[test]
fn png_plot_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    let png = tmp.path().join("top.png");
    let out = divertsim()
        .args(["simulate", "--plot"])
        .arg(&png)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
}

#[test]
fn same_input_gives_the_same_bytes() {
    let a = divertsim()
        .args(["simulate", "--json"])
        .output()
        .unwrap()
        .stdout;
    let b = divertsim()
        .args(["simulate", "--json"])
        .output()
        .unwrap()
        .stdout;
    assert_eq!(a, b);
}

#[test]
fn schema_is_json_with_the_sections() {
    let v = json_of(&["schema"]);
    let props = &v["properties"];
    for section in ["machine", "parcel", "materials", "run", "limits"] {
        assert!(props.get(section).is_some(), "schema lacks {section}");
    }
    let text = v.to_string();
    assert!(
        text.contains("belt_speed") && text.contains("angle_deg") && text.contains("restitution")
    );
}

/// `divertsim example` prints the built-in default, and running that file gives exactly the
/// same result as running without a file.
#[test]
fn example_round_trips_to_the_default() {
    let tmp = tempfile::tempdir().unwrap();
    let text = divertsim().arg("example").output().unwrap().stdout;
    let path = tmp.path().join("default.toml");
    std::fs::write(&path, text).unwrap();
    let from_file = divertsim()
        .args(["simulate", "--json"])
        .arg(&path)
        .output()
        .unwrap();
    assert_eq!(
        from_file.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&from_file.stderr)
    );
    let builtin = divertsim().args(["simulate", "--json"]).output().unwrap();
    assert_eq!(from_file.stdout, builtin.stdout);
}

/// Every paper scenario under configs/ runs to a verdict.
#[test]
fn shipped_configs_run() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs");
    let mut files: Vec<_> = std::fs::read_dir(root.join("paper"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.push(root.join("default.toml"));
    files.push(root.join("wedge.toml"));
    assert!(files.len() >= 12);
    for f in files {
        let v = json_of(&["simulate", "--json", f.to_str().unwrap()]);
        assert_ne!(v["outcome"], "failed", "{}: {}", f.display(), v["reason"]);
    }
}

/// A scenario from standard input (`-`) runs like the same file.
#[test]
fn scenario_from_stdin() {
    let text = "[parcel]\nlength = 0.7\nwidth = 0.1\nmass = 1.5\noffset = 0.45\n";
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("s.toml");
    std::fs::write(&file, text).unwrap();
    let from_file =
        common::json_stdout(common::divertsim().args(["simulate", "--json"]).arg(&file));
    let from_stdin = common::json_stdout(
        common::divertsim()
            .args(["simulate", "-", "--json"])
            .write_stdin(text),
    );
    assert_eq!(from_file, from_stdin);
    let bad = common::divertsim()
        .args(["simulate", "-"])
        .write_stdin("[parcel]\nlength = -1\n")
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("parcel.length"));
}

/// Shell completions and the manual page are generated from the command line itself.
#[test]
fn completions_and_man_page() {
    for shell in ["bash", "zsh", "fish"] {
        let out = common::divertsim()
            .args(["completions", shell])
            .output()
            .unwrap();
        assert!(out.status.success());
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            text.contains("reliability") && text.contains("calibrate"),
            "{shell}"
        );
    }
    let man = common::divertsim().arg("man").output().unwrap();
    let text = String::from_utf8_lossy(&man.stdout);
    assert!(man.status.success() && text.contains(".TH divertsim 1"));
}

/// configs/wedge.toml: the returning arm wedges a parcel against a full-length guide
/// (docs/model.md §6b). The run ends jammed, and both summaries say when and where.
#[test]
fn a_wedged_parcel_jams_and_the_summaries_say_where() {
    let wedge = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/wedge.toml");
    let wedge = wedge.to_str().unwrap();
    let v = json_of(&["simulate", wedge, "--json"]);
    assert_eq!(
        (v["outcome"].as_str(), v["reason"].as_str()),
        (Some("not_diverted"), Some("jammed"))
    );
    let jam = &v["jam"];
    let t = jam["t"].as_f64().unwrap();
    let events = v["events"].as_array().unwrap();
    let last = events.last().unwrap();
    assert_eq!(last["kind"], "jammed");
    assert_eq!(last["t"].as_f64(), Some(t));
    assert_eq!(v["final"]["t"].as_f64(), Some(t));
    let obstacles: Vec<&str> = jam["contacts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["obstacle"].as_str().unwrap())
        .collect();
    assert_eq!(obstacles.first(), Some(&"arm_back"), "{jam}");
    assert_eq!(obstacles.last(), Some(&"guide"), "{jam}");
    let place = jam["place"].as_str().unwrap();
    assert!(
        place.starts_with("between the arm's back face at ("),
        "{place}"
    );

    let out = divertsim().args(["simulate", wedge]).output().unwrap();
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("outcome:     not_diverted (jammed)"),
        "{text}"
    );
    assert!(
        text.contains(&format!("jam:         at t = {t:.4} s, {place}")),
        "{text}"
    );

    // A run that does not jam has no `jam` key (its summary is as it was).
    assert!(json_of(&["simulate", "--json"]).get("jam").is_none());
}
