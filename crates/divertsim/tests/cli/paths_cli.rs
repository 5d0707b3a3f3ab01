//! End-to-end tests of `divertsim paths` (issue 4 item 6): the paper's Figs 6–8 overlaid, the
//! CSV/SVG/JSON contract, bad input, and thread-count independence.

use serde_json::Value;

use crate::common;
use common::{divertsim, json_stdout};

const FIG06: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../configs/paper/fig06.toml"
);
const FIG07: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../configs/paper/fig07.toml"
);
const FIG08: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../configs/paper/fig08.toml"
);

/// Run `paths` on Figs 6–8 with `extra` arguments; returns (exit code, stdout, stderr).
fn paths(extra: &[&str]) -> (Option<i32>, Vec<u8>, String) {
    let out = divertsim()
        .args(["paths", FIG06, FIG07, FIG08])
        .args(extra)
        .output()
        .unwrap();
    (
        out.status.code(),
        out.stdout,
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The summary of `simulate --json FILE`, the single-run reference for each case.
fn simulate(file: &str) -> Value {
    json_stdout(divertsim().args(["simulate", "--json", file]))
}

/// The paper's findings (a)–(c) with the preset: Fig. 6 not diverted, Figs 7 and 8 diverted;
/// each case's outcome, max_lateral and stages are exactly those of `simulate` on its file.
#[test]
fn json_lists_each_case_as_simulate_reports_it() {
    let (code, stdout, stderr) = paths(&["--json", "--quiet"]);
    assert_eq!(code, Some(0), "{stderr}");
    let v: Value = serde_json::from_slice(&stdout).expect("one JSON object");
    let cases = v["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 3);
    let expected = [
        (FIG06, "fig06", "not_diverted"),
        (FIG07, "fig07", "diverted"),
        (FIG08, "fig08", "diverted"),
    ];
    for (case, (file, label, outcome)) in cases.iter().zip(expected) {
        assert_eq!(case["label"], label);
        assert_eq!(case["outcome"], outcome, "{label}");
        assert!(case["file"]
            .as_str()
            .unwrap()
            .ends_with(&format!("{label}.toml")));
        let single = simulate(file);
        assert_eq!(case["outcome"], single["outcome"], "{label}");
        assert_eq!(case["max_lateral"], single["max_lateral"], "{label}");
        assert_eq!(case["stages"], single["stages"], "{label}");
    }
    // (a): the slender parcel's centre stays below the far edge P_max = 0.7 m.
    assert!(cases[0]["max_lateral"].as_f64().unwrap() < 0.7);
}

#[test]
fn out_dir_holds_csv_and_svg() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("figs");
    let (code, stdout, stderr) = paths(&[
        "--quiet",
        "--label",
        "Fig. 6",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    // The readable table names every case.
    let table = String::from_utf8_lossy(&stdout);
    for needle in ["Fig. 6", "fig07", "fig08", "not_diverted", "diverted"] {
        assert!(table.contains(needle), "{needle} missing in\n{table}");
    }

    let csv = std::fs::read_to_string(dir.join("paths.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("case,t_s,x_m,y_m,phi_deg,stage"));
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    // Every case has samples, in file order, each case's times non-decreasing.
    let names: Vec<&str> = rows.iter().map(|r| r[0].as_str()).collect();
    let first = |n: &str| names.iter().position(|x| *x == n).unwrap();
    assert!(first("Fig. 6") < first("fig07") && first("fig07") < first("fig08"));
    for name in ["Fig. 6", "fig07", "fig08"] {
        let t: Vec<f64> = rows
            .iter()
            .filter(|r| r[0] == name)
            .map(|r| r[1].parse().unwrap())
            .collect();
        assert!(t.len() > 10, "{name}: {} samples", t.len());
        assert!(t.windows(2).all(|w| w[1] >= w[0]), "{name}: times decrease");
    }
    // Fig. 7 ends diverted: its centre reaches the far edge; Fig. 6 never does.
    let max_y = |name: &str| {
        rows.iter()
            .filter(|r| r[0] == name)
            .map(|r| r[3].parse::<f64>().unwrap())
            .fold(f64::MIN, f64::max)
    };
    assert!(max_y("Fig. 6") < 0.7);
    assert!(max_y("fig07") >= 0.7 - 1e-9);
    // Stage column holds the paper's stage names.
    assert!(rows.iter().any(|r| r[5] == "F5"));

    let svg = std::fs::read_to_string(dir.join("paths.svg")).unwrap();
    assert!(svg.contains("<svg"));
    for text in [
        "Fig. 6: not_diverted",
        "fig07: diverted",
        "fig08: diverted",
        "stage begins",
        "far edge (P_max)",
        "Paths of the parcel centre G, 3 cases",
    ] {
        assert!(svg.contains(text), "SVG lacks {text:?}");
    }
    // Stage names written on the paths (beside the markers).
    // fig06 starts flush on the arm (F5); fig08 starts with its front corner at the arm's
    // root and its side on the guide, pushed by the arm from t = 0 (F6).
    for label in ["F5", "F6"] {
        assert!(
            svg.lines().any(|l| l.trim() == label),
            "no {label:?} stage label"
        );
    }
    // The three case colours (first three of the palette).
    for color in ["#1F77B4", "#D62728", "#2CA02C"] {
        assert!(svg.contains(color), "SVG lacks case colour {color}");
    }
    assert!(!svg.contains("NaN"));
}

#[test]
fn plot_option_writes_only_that_file() {
    let tmp = tempfile::tempdir().unwrap();
    let png = tmp.path().join("over.png");
    let (code, _, stderr) = paths(&["--quiet", "--plot", png.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{stderr}");
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let names: Vec<String> = std::fs::read_dir(tmp.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, vec!["over.png".to_string()]);
}

#[test]
fn bad_input_exits_2_and_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("figs");
    for extra in [
        vec!["--set", "machine.belt_speed=-1"],
        vec!["--plot", "x.gif"],
        vec![
            "--label", "a", "--label", "b", "--label", "c", "--label", "d",
        ],
    ] {
        let mut args = extra.clone();
        args.extend(["--out", dir.to_str().unwrap()]);
        let (code, stdout, stderr) = paths(&args);
        assert_eq!(code, Some(2), "{extra:?}: {stderr}");
        assert!(stdout.is_empty(), "{extra:?}");
        let key = if extra[0] == "--set" {
            "machine.belt_speed"
        } else {
            extra[0]
        };
        assert!(stderr.contains(key), "{extra:?}: {stderr}");
        assert!(!dir.exists(), "{extra:?} left an output directory");
    }
    // A missing file is named; the others are still checked.
    let out = divertsim()
        .args(["paths", FIG06, "no/such/file.toml", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no/such/file.toml"));
    assert!(!dir.exists());
    // No file at all: clap's usage error, also exit 2.
    let out = divertsim().arg("paths").output().unwrap();
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn thread_count_does_not_change_the_output() {
    let tmp = tempfile::tempdir().unwrap();
    let (d1, d2) = (tmp.path().join("t1"), tmp.path().join("t2"));
    let (c1, j1, _) = paths(&["--json", "--threads", "1", "--out", d1.to_str().unwrap()]);
    let (c2, j2, _) = paths(&["--json", "--threads", "2", "--out", d2.to_str().unwrap()]);
    assert_eq!((c1, c2), (Some(0), Some(0)));
    assert_eq!(j1, j2);
    for f in ["paths.csv", "paths.svg"] {
        assert_eq!(
            std::fs::read(d1.join(f)).unwrap(),
            std::fs::read(d2.join(f)).unwrap(),
            "{f} differs"
        );
    }
}

#[test]
fn set_applies_to_every_file() {
    // Without the arm nothing is diverted, whatever the file.
    let (code, stdout, stderr) = paths(&["--json", "--set", "run.arm=false"]);
    assert_eq!(code, Some(0), "{stderr}");
    let v: Value = serde_json::from_slice(&stdout).unwrap();
    for case in v["cases"].as_array().unwrap() {
        assert_eq!(case["outcome"], "not_diverted");
        assert_eq!(case["stages"], serde_json::json!(["ride"]));
    }
}
