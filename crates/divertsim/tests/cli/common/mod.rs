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

/// Every file of a directory and below it, sorted by relative path, with its bytes.
pub fn dir_files(dir: &std::path::Path) -> Vec<(String, Vec<u8>)> {
    fn walk(root: &std::path::Path, dir: &std::path::Path, out: &mut Vec<(String, Vec<u8>)>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                let rel = p.strip_prefix(root).unwrap().to_string_lossy().into_owned();
                out.push((rel, std::fs::read(&p).unwrap()));
            }
        }
    }
    let mut v = Vec::new();
    walk(dir, dir, &mut v);
    v.sort();
    v
}

/// In `dir`: `divertsim ARGS --out whole`; then `ARGS --out cut --threads 1`, killed by
/// SIGKILL as soon as `ready(dir)` holds (it must not finish first); then `ARGS --out cut
/// --resume`, which must succeed, recall finished pieces, and write byte-identical files.
pub fn kill_and_resume(
    dir: &std::path::Path,
    args: &[&str],
    ready: impl Fn(&std::path::Path) -> bool,
) {
    divertsim()
        .current_dir(dir)
        .args(args)
        .args(["--out", "whole"])
        .assert()
        .success();
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("divertsim"))
        .current_dir(dir)
        .args(args)
        .args(["--out", "cut", "--threads", "1"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let started = std::time::Instant::now();
    while !ready(dir) {
        assert!(started.elapsed().as_secs() < 300, "nothing finished");
        assert!(
            child.try_wait().unwrap().is_none(),
            "finished before the kill"
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!dir.join("cut").exists());
    let resumed = divertsim()
        .current_dir(dir)
        .args(args)
        .args(["--out", "cut", "--resume"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&resumed.stderr);
    assert_eq!(resumed.status.code(), Some(0), "{err}");
    assert!(err.contains("finished pieces recalled"), "{err}");
    assert_eq!(dir_files(&dir.join("cut")), dir_files(&dir.join("whole")));
    assert!(!dir.join(".cut.checkpoint").exists(), "the checkpoint goes");
}

/// Whether the checkpoint journal of `--out cut` holds a finished piece: a whole first
/// record (key u64, length u32, value, check u64). A journal that merely has bytes may hold a
/// record still being written, and a kill then leaves nothing to recall.
pub fn journal_started(dir: &std::path::Path) -> bool {
    let bytes = std::fs::read(dir.join(".cut.checkpoint/journal.bin")).unwrap_or_default();
    whole_first_record(&bytes)
}

fn whole_first_record(bytes: &[u8]) -> bool {
    bytes.get(8..12).is_some_and(|len| {
        let len = u32::from_le_bytes(len.try_into().unwrap()) as usize;
        bytes.len() >= 20 + len
    })
}

/// Regression: the line's kill-and-resume test killed a run whose first record was torn
/// (the journal had bytes, not a piece), and the resume recalled nothing.
#[test]
fn a_torn_first_record_is_not_a_finished_piece() {
    let mut rec = 7u64.to_le_bytes().to_vec();
    rec.extend_from_slice(&3u32.to_le_bytes());
    rec.extend_from_slice(b"abc");
    assert!(!whole_first_record(&rec[..5]));
    assert!(!whole_first_record(&rec), "the check is missing");
    rec.extend_from_slice(&0u64.to_le_bytes());
    assert!(whole_first_record(&rec));
}

/// A study's `--out` directory's summary.json.
pub fn summary_in(dir: &std::path::Path) -> Value {
    serde_json::from_slice(&std::fs::read(dir.join("summary.json")).expect("summary.json"))
        .expect("summary.json is JSON")
}

/// Assert that `simulate` on a study's largest_stroke.toml gives the study's peak drive
/// torque `peak` [N·m] (to 1e-6 relative: φ goes through degrees in the file).
pub fn assert_largest_stroke_reproduces(dir: &std::path::Path, peak: f64) {
    let again = json_stdout(
        divertsim()
            .args(["simulate", "--json", "-q"])
            .arg(dir.join("largest_stroke.toml")),
    );
    let simulated = again["arm_loads"]["peak_torque"]
        .as_f64()
        .expect("arm_loads");
    assert!(
        (simulated - peak).abs() <= 1e-6 * peak,
        "simulate gives {simulated} N·m, the study {peak} N·m"
    );
}
