//! End-to-end tests of `divertsim capacity` (issue 4 item 4): a small grid, its CSV, SVG and
//! JSON, bad options, and identical numbers for any thread count.

use serde_json::Value;

use crate::common;
use common::{divertsim, json_stdout};

/// A small grid with one cheap design parcel (the compact one at ΔP = 0), so that the test
/// runs in a few seconds.
const SCENARIO: &str = r#"
[[design.parcels]]
name = "compact"
length = 0.4
width = 0.26
height = 0.15
mass = 3.0
offset = "near"
"#;

const GRID: &[&str] = &[
    "--cycle-times",
    "1.2:1.4/2",
    "--light-barriers",
    "0:0.6/3",
    "--speeds",
    "1.5:2.1/2",
    "--start-range",
    "0:0.6",
    "--start-step",
    "0.2",
    "--start-tolerance",
    "0.02",
    "-q",
];

fn run_json(dir: &std::path::Path, threads: &str) -> Value {
    json_stdout(
        divertsim()
            .current_dir(dir)
            .arg("capacity")
            .arg("s.toml")
            .args(GRID)
            .args(["--json", "--threads", threads]),
    )
}

#[test]
fn small_grid_json_is_consistent_and_thread_independent() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("s.toml"), SCENARIO).unwrap();
    let one = run_json(tmp.path(), "1");
    let two = run_json(tmp.path(), "2");
    assert_eq!(one, two);
    let cells = one["cells"].as_array().unwrap();
    assert_eq!(cells.len(), 2 * 3);
    assert_eq!(one["settings"].as_array().unwrap().len(), 2 * 2);
    assert_eq!(one["design"].as_array().unwrap().len(), 1);
    for c in cells {
        let feasible = c["feasible"].as_bool().unwrap();
        if feasible {
            // W is the paper's formula at the chosen (v, R_s), and R_s ≥ S_d.
            let (tc, sd) = (
                c["cycle_time"].as_f64().unwrap(),
                c["light_barrier"].as_f64().unwrap(),
            );
            let (v, rs) = (
                c["belt_speed"].as_f64().unwrap(),
                c["start_position"].as_f64().unwrap(),
            );
            assert!(rs >= sd);
            let w = 3600.0 / ((rs - sd) / v + tc);
            assert!((c["capacity"].as_f64().unwrap() - w).abs() < 1e-9 * w);
            assert!(c["worst_margin"].as_f64().unwrap() <= 0.0);
        } else {
            assert_eq!(c["capacity"].as_f64().unwrap(), 0.0);
            assert!(c["belt_speed"].is_null());
            assert!(c["worst_margin"].as_f64().unwrap() > 0.0);
        }
    }
    let s = &one["summary"];
    assert_eq!(s["cells"], 6);
    let n = cells.iter().filter(|c| c["feasible"] == true).count();
    assert_eq!(s["feasible_cells"].as_u64().unwrap() as usize, n);
    assert!(one["simulations"].as_u64().unwrap() > 0);
}

#[test]
fn out_dir_has_csv_and_svg_and_table_on_stdout() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("s.toml"), SCENARIO).unwrap();
    let out = divertsim()
        .current_dir(tmp.path())
        .arg("capacity")
        .arg("s.toml")
        .args(GRID)
        .args(["--out", "cap"])
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("capacity W [parcels/h]"), "{text}");
    assert!(text.contains("feasible cells:"), "{text}");
    let csv = std::fs::read_to_string(tmp.path().join("cap/capacity.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "cycle_time_s,light_barrier_m,capacity_per_h,belt_speed_m_s,start_position_m,feasible,worst_margin,overload_ratio"
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 6);
    assert_eq!(rows[0][0], "1.2");
    assert_eq!(rows[0][1], "0");
    for r in &rows {
        assert!(r[5] == "true" || r[5] == "false");
        assert_eq!(r[3].is_empty(), r[5] == "false");
    }
    let svg = std::fs::read_to_string(tmp.path().join("cap/capacity.svg")).unwrap();
    assert!(svg.starts_with("<svg") || svg.contains("<svg"));
    assert!(svg.contains("cycle time t_c [s]"));
    assert!(svg.contains("light barrier S_d [m]"));
}

#[test]
fn bad_options_exit_2_with_no_output() {
    let tmp = tempfile::tempdir().unwrap();
    for (args, expect) in [
        (vec!["--cycle-times", "1.0:1.5"], "--cycle-times"),
        (vec!["--speeds", "0:2/3"], "[0.05, 10] m/s"),
        (vec!["--light-barriers", "0:0.9:0"], "COUNT"),
        (vec!["--start-range", "0.5:0.1"], "--start-range"),
        (vec!["--start-step", "0"], "[0.001, 5] m"),
        (vec!["--start-tolerance", "-1"], "--start-tolerance"),
        (vec!["--set", "machine.cycle_time=-1"], "machine.cycle_time"),
    ] {
        let out = divertsim()
            .current_dir(tmp.path())
            .arg("capacity")
            .args(&args)
            .args(["--out", "o", "-q"])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(expect), "{args:?}: {err}");
        assert!(!err.contains("panicked"));
        assert!(!tmp.path().join("o").exists());
    }
}

#[test]
fn help_has_an_example() {
    let out = divertsim().args(["capacity", "--help"]).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("Examples:") && text.contains("divertsim capacity"));
}

/// SIGKILL part-way, then `--resume` (with another thread count): byte-identical files,
/// the finished pieces recalled, not recomputed; a plain rerun refuses the checkpoint.
#[test]
fn killed_and_resumed_capacity_is_byte_identical() {
    let t = tempfile::tempdir().unwrap();
    let args = [
        "capacity",
        "--cycle-times",
        "1.2:1.4/3",
        "--light-barriers",
        "0:0.6/3",
        "--speeds",
        "1.5:2.3/4",
        "--start-step",
        "0.1",
        "--quiet",
    ];
    common::kill_and_resume(t.path(), &args, common::journal_started);
    // A plain rerun into a folder with a checkpoint refuses it.
    std::fs::create_dir(t.path().join(".again.checkpoint")).unwrap();
    let plain = divertsim()
        .current_dir(t.path())
        .args(args)
        .args(["--out", "again"])
        .output()
        .unwrap();
    assert_eq!(plain.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&plain.stderr).contains("--resume"));
}

/// Hostile input round three: `--start-step 0.004 --start-range -5:5` (2,501 R_s points)
/// exited 3 with the core's message; it is a usage error naming the flag and the limit.
#[test]
fn start_step_too_fine_for_the_range_is_exit_2() {
    let out = divertsim()
        .args([
            "capacity",
            "--start-step",
            "0.004",
            "--start-range",
            "-5:5",
            "-q",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--start-step") && err.contains("at most 2001"),
        "{err}"
    );
}

/// Issue 50, item 6: a robust map's `simulations` (JSON and text) is the run's own count,
/// every round's map and searches, not the last round's map alone.
#[test]
fn a_robust_maps_json_counts_every_rounds_simulations() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("s.toml"), SCENARIO).unwrap();
    let v = run_json(tmp.path(), "2");
    assert_eq!(v["worst"], "search", "the default");
    let rounds: u64 = v["robust"]["rounds"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["simulations"].as_u64().unwrap())
        .sum();
    assert_eq!(v["simulations"].as_u64().unwrap(), rounds, "{v}");
    assert!(rounds > v["last_map_simulations"].as_u64().unwrap());
    let out = divertsim()
        .current_dir(tmp.path())
        .arg("capacity")
        .arg("s.toml")
        .args(GRID)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let digits = rounds.to_string();
    let grouped: String = digits
        .chars()
        .enumerate()
        .flat_map(|(i, c)| {
            let comma = i > 0 && (digits.len() - i).is_multiple_of(3);
            comma.then_some(',').into_iter().chain([c])
        })
        .collect();
    let counted = format!("simulations: {grouped}");
    assert!(text.contains(&counted), "{counted} in {text}");
}

/// Issue 50, item 3: a best cell on the grid's edge is named in the text and the JSON, with
/// the option to widen.
#[test]
fn a_best_cell_on_the_grids_edge_is_said() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("s.toml"), SCENARIO).unwrap();
    let cmd = |json: bool| {
        let mut c = divertsim();
        c.current_dir(tmp.path())
            .arg("capacity")
            .arg("s.toml")
            .args(GRID)
            .args(["--worst", "paper"]);
        if json {
            c.arg("--json");
        }
        c
    };
    let v = json_stdout(&mut cmd(true));
    let edges = v["summary"]["best_on_edges"].as_array().unwrap();
    assert!(!edges.is_empty(), "{v}");
    let out = cmd(false).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let option = edges[0]["option"].as_str().unwrap();
    assert!(
        text.contains("the best cell is on the grid's edge")
            && text.contains(&format!("`{option}`")),
        "{text}"
    );
}
