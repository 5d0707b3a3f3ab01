//! Behaviour pinned across refactors: one small command per analysis, its `--json` stdout
//! (and `replicate`'s findings) compared byte for byte with the files in `tests/golden/`.
//! A change that alters any of them is a change of behaviour, made on purpose: rerun with
//! `DIVERTSIM_BLESS=1` to rewrite the files, and say why in the commit.

use super::common::divertsim;
use std::path::{Path, PathBuf};

/// The small capacity grid both capacity commands share.
const GRID: &[&str] = &[
    "--cycle-times",
    "1.2:1.4/2",
    "--light-barriers",
    "0:0.6/2",
    "--speeds",
    "1.5:2.1/2",
    "--start-range",
    "0:0.6",
    "--start-step",
    "0.2",
    "--start-tolerance",
    "0.02",
];

/// Name and arguments (run from the crate's folder) of each pinned command; the capacity
/// commands add [`GRID`].
const COMMANDS: &[(&str, &[&str])] = &[
    ("simulate", &["simulate"]),
    (
        "trigger",
        &[
            "trigger",
            "../../configs/paper/fig06.toml",
            "--speeds",
            "0.65,1.1",
            "--search",
            "0.4:0.84",
            "--scan-step",
            "0.04",
        ],
    ),
    ("capture", &["capture"]),
    ("overload", &["overload"]),
    (
        "worst_case",
        &[
            "worst-case",
            "--search-budget",
            "300",
            "--search-starts",
            "2",
        ],
    ),
    ("capacity_paper", &["capacity", "--worst", "paper"]),
    (
        "capacity_search",
        &[
            "capacity",
            "--rounds",
            "1",
            "--search-budget",
            "200",
            "--search-starts",
            "1",
        ],
    ),
    (
        "optimize",
        &[
            "optimize",
            "--method",
            "ga",
            "--population",
            "8",
            "--generations",
            "3",
            "--worst",
            "paper",
        ],
    ),
    (
        "reliability",
        &[
            "reliability",
            "../../configs/mix/hub.toml",
            "--samples",
            "200",
            "--shard",
            "100",
        ],
    ),
];

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden")
}

/// `actual` against the golden file `name`, or rewrite it with DIVERTSIM_BLESS=1.
fn compare(name: &str, actual: &[u8]) -> Option<String> {
    let path = golden_dir().join(name);
    if std::env::var_os("DIVERTSIM_BLESS").is_some() {
        std::fs::create_dir_all(golden_dir()).unwrap();
        std::fs::write(&path, actual).unwrap();
        return None;
    }
    let expected = std::fs::read(&path)
        .unwrap_or_else(|e| panic!("{}: {e} (DIVERTSIM_BLESS=1 writes it)", path.display()));
    (expected != actual).then(|| {
        let first = expected
            .iter()
            .zip(actual)
            .position(|(a, b)| a != b)
            .unwrap_or(expected.len().min(actual.len()));
        let from = first.saturating_sub(80);
        format!(
            "{name}: differs at byte {first}:\n  golden: {}\n  now:    {}",
            String::from_utf8_lossy(&expected[from..(first + 80).min(expected.len())]),
            String::from_utf8_lossy(&actual[from..(first + 80).min(actual.len())]),
        )
    })
}

#[test]
fn every_analysis_json_is_byte_identical_to_its_golden_file() {
    let mut differences = Vec::new();
    for (name, args) in COMMANDS {
        let out = divertsim()
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .args(*args)
            .args(if args[0] == "capacity" { GRID } else { &[] })
            .args(["--json"])
            .args((*name != "simulate").then_some("-q"))
            .output()
            .unwrap();
        assert_eq!(
            out.status.code(),
            Some(0),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        differences.extend(compare(&format!("{name}.json"), &out.stdout));
    }
    assert!(differences.is_empty(), "{}", differences.join("\n"));
}

#[test]
fn replicate_findings_are_byte_identical_to_the_golden_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("figs");
    divertsim()
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args([
            "replicate",
            "--quick",
            "-q",
            "--configs",
            "../../configs/paper",
        ])
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    let differences: Vec<String> = ["findings.md", "findings.json"]
        .iter()
        .filter_map(|f| {
            compare(
                &format!("replicate_{f}"),
                &std::fs::read(out.join(f)).unwrap(),
            )
        })
        .collect();
    assert!(differences.is_empty(), "{}", differences.join("\n"));
}
