//! End-to-end test of `divertsim replicate --quick`: every figure and table is written, the
//! findings are judged (and (a)–(c) hold with the paper preset), the output does not depend on
//! the thread count, and a bad configs directory is exit 2 with nothing written.

use assert_cmd::Command;
use serde_json::Value;
use std::path::Path;

const CONFIGS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/paper");

fn replicate(out: &Path, threads: &str) -> Value {
    let o = Command::cargo_bin("divertsim")
        .unwrap()
        .args([
            "replicate",
            "--quick",
            "--quiet",
            "--json",
            "--threads",
            threads,
        ])
        .arg("--configs")
        .arg(CONFIGS)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn quick_replication_writes_every_figure_and_judges_the_findings() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("figs");
    let v = replicate(&out, "2");
    for name in [
        "findings_abc",
        "fig03",
        "fig13",
        "fig14",
        "fig15",
        "trigger",
        "capture",
        "overload",
        "capacity",
    ] {
        let svg = std::fs::read_to_string(out.join(format!("{name}.svg"))).unwrap();
        assert!(svg.starts_with("<svg"), "{name}.svg");
        let csv = std::fs::read_to_string(out.join(format!("{name}.csv"))).unwrap();
        assert!(csv.lines().count() > 1, "{name}.csv is empty");
    }
    let findings = v["findings"].as_array().unwrap();
    let ids: Vec<&str> = findings.iter().map(|f| f["id"].as_str().unwrap()).collect();
    assert_eq!(ids, ["a", "b", "c", "d", "e", "f", "g"]);
    for f in &findings[..3] {
        assert_eq!(f["verdict"], "holds", "{f}");
    }
    for f in findings {
        let verdict = f["verdict"].as_str().unwrap();
        assert!(["holds", "holds in part", "does not hold"].contains(&verdict));
        assert!(!f["divertsim"].as_str().unwrap().is_empty());
    }
    let md = std::fs::read_to_string(out.join("findings.md")).unwrap();
    assert_eq!(md.lines().count(), 2 + 7);
    // Same numbers on one thread.
    let out1 = dir.path().join("figs1");
    replicate(&out1, "1");
    for name in [
        "findings.json",
        "capacity.csv",
        "trigger.csv",
        "capture.csv",
    ] {
        assert_eq!(
            std::fs::read(out.join(name)).unwrap(),
            std::fs::read(out1.join(name)).unwrap(),
            "{name} differs between 1 and 2 threads"
        );
    }
}

#[test]
fn a_bad_configs_directory_is_exit_2_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("figs");
    let o = Command::cargo_bin("divertsim")
        .unwrap()
        .args(["replicate", "--quick", "--configs"])
        .arg(dir.path().join("nowhere"))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--configs"));
    assert!(!out.exists());
    // A configs directory without the preset names the missing file.
    std::fs::create_dir(dir.path().join("empty")).unwrap();
    let o = Command::cargo_bin("divertsim")
        .unwrap()
        .args(["replicate", "--quick", "--configs"])
        .arg(dir.path().join("empty"))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("machine.toml"));
    assert!(!out.exists());
}
