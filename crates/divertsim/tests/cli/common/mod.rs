//! Helpers shared by the end-to-end tests of the `divertsim` binary.

#![allow(dead_code)] // each test binary uses part of it

use assert_cmd::Command;
use serde_json::Value;

/// The `divertsim` binary built for the tests.
pub fn divertsim() -> Command {
    Command::cargo_bin("divertsim").unwrap()
}

/// Run `cmd`, which must exit 0 (its stderr is shown otherwise), and parse its stdout as one
/// JSON object.
pub fn json_stdout(cmd: &mut Command) -> Value {
    let out = cmd.output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("stdout is one JSON object")
}
