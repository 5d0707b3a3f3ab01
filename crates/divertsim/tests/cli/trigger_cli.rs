//! End-to-end tests of `divertsim trigger` (paper Fig. 4): table, JSON, CSV and SVG outputs,
//! option checks before any simulation, and thread-count independence.

use serde_json::Value;

use crate::common;
use common::{divertsim, json_stdout};

/// A small, fast calibration: two speeds, a narrow search.
/// The paper's Fig. 6 case on the preset (configs/paper/fig06.toml): on the built-in default machine
/// (R_z 1 m) the slender reference parcel slides over the arm tip and is diverted.
const SMALL: [&str; 7] = [
    "../../configs/paper/fig06.toml",
    "--speeds",
    "0.65,1.1",
    "--search",
    "0.4:0.84",
    "--scan-step",
    "0.04",
];

#[test]
fn json_has_the_reference_root_and_a_stage_set() {
    let v: Value = json_stdout(divertsim().args(["trigger", "--json", "-q"]).args(SMALL));
    assert_eq!(v["reference"]["speed"], 0.65);
    assert_eq!(v["reference"]["outcome"], "not_diverted");
    let target = v["reference"]["max_lateral"].as_f64().unwrap();
    assert!(target > 0.1 && target < 0.7, "{target}");
    let pts = v["points"].as_array().unwrap();
    assert_eq!(pts.len(), 2);
    // Without a file the parcel is the Fig. 3 slender parcel; at the reference speed the
    // reference start is the root.
    let rs = pts[0]["start_position"].as_f64().unwrap();
    assert!((rs - 0.8).abs() <= 1e-4, "{rs}");
    // At 1.1 m/s the arm must start earlier (paper Fig. 4: R_s falls as v rises).
    let rs2 = pts[1]["start_position"].as_f64().unwrap();
    assert!(rs2 < rs, "{rs2}");
    for p in pts {
        assert!(p["stage_set"].as_str().unwrap().contains('F'), "{p}");
        if p["root_kind"] == "crossing" {
            assert!(p["residual"].as_f64().unwrap().abs() <= 1e-3);
        }
    }
}

#[test]
fn out_dir_has_csv_and_svg_and_threads_do_not_matter() {
    let dir = tempfile::tempdir().unwrap();
    let mut csvs = Vec::new();
    for threads in ["1", "2"] {
        let out_dir = dir.path().join(format!("t{threads}"));
        let out = divertsim()
            .args(["trigger", "-q", "--threads", threads, "--out"])
            .arg(&out_dir)
            .args(SMALL)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0));
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            text.contains("reference run: belt speed v = 0.65 m/s"),
            "{text}"
        );
        let csv = std::fs::read_to_string(out_dir.join("trigger.csv")).unwrap();
        let svg = std::fs::read_to_string(out_dir.join("trigger.svg")).unwrap();
        assert!(csv.starts_with(
            "belt_speed_m_s,start_position_m,max_lateral_m,residual_m,root_kind,stage_set"
        ));
        assert_eq!(csv.lines().count(), 3);
        assert!(svg.contains("reference (0.65 m/s, 0.8 m)") && svg.contains("R_s [m]"));
        csvs.push(csv);
    }
    assert_eq!(csvs[0], csvs[1]);
}

#[test]
fn bad_options_exit_2_naming_them_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("o");
    let out = divertsim()
        .args([
            "trigger",
            "--speeds",
            "2:1:0.1",
            "--tolerance",
            "0",
            "--search",
            "1:0",
        ])
        .arg("--out")
        .arg(&out_dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    for key in ["--speeds", "--tolerance", "--search"] {
        assert!(err.contains(key), "{key} missing in {err}");
    }
    assert!(err.contains("allowed"));
    assert!(!out_dir.exists());
}

#[test]
fn diverted_reference_is_exit_2_with_a_clear_message() {
    let out = divertsim()
        .args([
            "trigger",
            "--reference-speed",
            "2.0",
            "--reference-start",
            "0.2",
        ])
        .args(SMALL)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("diverts the parcel"));
}

/// SIGKILL once a speed is finished, then `--resume`: byte-identical files, the finished
/// speeds recalled.
#[test]
fn killed_and_resumed_trigger_is_byte_identical() {
    let t = tempfile::tempdir().unwrap();
    let fig06 = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../configs/paper/fig06.toml"
    );
    let args = [
        "trigger",
        fig06,
        "--speeds",
        "0.65:1.4/6",
        "--search",
        "0.4:0.84",
        "--scan-step",
        "0.02",
        "-q",
    ];
    common::kill_and_resume(t.path(), &args, common::journal_started);
}
