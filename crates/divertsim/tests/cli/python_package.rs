//! The Python package's pytest suite (`crates/divertsim-py/tests`, run by
//! `scripts/python-tests.sh`: a venv, the maturin wheel, pytest) against this test build's
//! binary: the package equals the CLI bit for bit, its errors, threads and the Dask cluster.
//!
//! It builds a release wheel and installs numpy, pandas and Dask from PyPI, minutes of work
//! a plain `cargo test` should not impose: it runs when DIVERTSIM_PYTHON_TESTS=1 (CI sets
//! it, and then a failure to build or install fails the test) and otherwise says how to run
//! it, and the test runner reports it ignored (build.rs).

use std::path::Path;
use std::process::Command;

#[test]
#[cfg_attr(
    divertsim_no_python_tests,
    ignore = "the Python package's suite runs with DIVERTSIM_PYTHON_TESTS=1 (or scripts/python-tests.sh); it needs python3 with venv and pip"
)]
fn python_package_suite_passes() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    // Its own target directory: the wheel's release build must not wait on this test run's.
    let target = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("..")
        .join("python");
    let out = Command::new("bash")
        .arg(root.join("scripts/python-tests.sh"))
        .env("DIVERTSIM_BIN", env!("CARGO_BIN_EXE_divertsim"))
        .env("CARGO_TARGET_DIR", &target)
        .output()
        .expect("bash runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let summary = stdout
        .lines()
        .rev()
        .find(|l| l.contains(" passed") || l.contains(" failed") || l.contains(" error"))
        .unwrap_or("(no pytest summary)");
    eprintln!("python package: {summary}");
    assert!(
        out.status.success(),
        "the Python package's tests failed: {summary}\n--- stdout (end) ---\n{}\n--- stderr (end) ---\n{}",
        tail(&stdout, 80),
        tail(&stderr, 40)
    );
    assert!(summary.contains(" passed"), "{summary}");
}

fn tail(text: &str, lines: usize) -> String {
    let all: Vec<&str> = text.lines().collect();
    all[all.len().saturating_sub(lines)..].join("\n")
}
