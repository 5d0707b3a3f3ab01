//! End-to-end tests of `divertsim capture` (paper Fig. 5): table, JSON, CSV and SVG outputs,
//! option checks before any simulation, and thread-count independence.

use serde_json::Value;

use crate::common;
use common::{divertsim, json_stdout};

#[test]
fn json_rows_agree_with_the_simulation() {
    let v: Value = json_stdout(
        divertsim()
            .args([
                "capture",
                "--json",
                "-q",
                "--speeds",
                "1.0,2.0",
                "--window-step",
                "0.1",
            ])
            .args(["--set", "machine.start_position=0.0"]),
    );
    // Without a file: the Fig. 5 case, the smallest parcel farthest from the pivot.
    assert_eq!(v["parcel"]["length"], 0.2);
    assert_eq!(v["parcel"]["offset"], 0.6);
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    for r in rows {
        // α_z = asin(0.6 / 1.15) for the corner at y = 0.6 m and the paper machine's
        // R_z = 1.15 m.
        let az = r["alpha_z_deg"].as_f64().unwrap();
        assert!(
            (az - (0.6f64 / 1.15).asin().to_degrees()).abs() < 1e-9,
            "{az}"
        );
        if r["captured"] == true {
            assert!(r["alpha_capture_deg"].as_f64().unwrap() >= az - 1e-9);
            if r["sim"]["corner_struck_first"] == true {
                let t = r["t_capture"].as_f64().unwrap();
                let ts = r["sim"]["first_strike_t"].as_f64().unwrap();
                assert!((t - ts).abs() < 1e-6, "{t} vs {ts}");
            }
        } else {
            assert!(r["t_capture"].is_null());
        }
        assert!(r["capture_ranges"].is_array());
    }
}

#[test]
fn out_dir_has_curves_and_plot_and_threads_do_not_matter() {
    let dir = tempfile::tempdir().unwrap();
    let mut csvs = Vec::new();
    for threads in ["1", "2"] {
        let out_dir = dir.path().join(format!("t{threads}"));
        let out = divertsim()
            .args([
                "capture",
                "-q",
                "--speeds",
                "1.0,1.5",
                "--window-step",
                "0.1",
            ])
            .args(["--threads", threads, "--out"])
            .arg(&out_dir)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0));
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            text.contains("captured") && text.contains("0.2 × 0.1 m"),
            "{text}"
        );
        let csv = std::fs::read_to_string(out_dir.join("capture.csv")).unwrap();
        let svg = std::fs::read_to_string(out_dir.join("capture.svg")).unwrap();
        assert!(
            csv.starts_with("belt_speed_m_s,start_position_m,t_s,alpha_deg,gamma_deg,alpha_z_deg")
        );
        // Two speeds × (272 + 1) curve points + the header.
        assert_eq!(csv.lines().count(), 1 + 2 * 273);
        assert!(svg.contains("α_z = 31.45°") && svg.contains("α(t) arm"));
        csvs.push(csv);
    }
    assert_eq!(csvs[0], csvs[1]);
}

#[test]
fn bad_options_exit_2_naming_them_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("o");
    let out = divertsim()
        .args(["capture", "--speeds", "1.0,abc", "--window-step=0"])
        .arg("--out")
        .arg(&out_dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--speeds") && err.contains("--window-step"),
        "{err}"
    );
    assert!(!out_dir.exists());
}
