//! The command line's edges: the output directory under faults (crate::outdir: a kill
//! during the move, a stale staging directory, two concurrent writers, an existing `--out`,
//! signals, an unwritable target found before computing; the cross-device fallback is
//! unit-tested in `outdir`, injected and, where /dev/shm is a tmpfs, real), the work limit
//! (`--max-sims`), and the built-in presets.

use crate::common;

use common::{divertsim, json_stdout};
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

/// `divertsim simulate --out OUT` (plus `extra`) held with everything staged, just before
/// the move; returns once it says so.
fn held(dir: &Path, out: &str, extra: &[&str]) -> Child {
    held_at(dir, out, extra, "DIVERTSIM_TEST_HOLD_BEFORE_MOVE")
}

/// [`held`] at the test hook `hook` of crate::outdir.
fn held_at(dir: &Path, out: &str, extra: &[&str], hook: &str) -> Child {
    let mut child = Command::new(assert_cmd::cargo::cargo_bin("divertsim"))
        .current_dir(dir)
        .args(["simulate", "--out", out])
        .args(extra)
        .env(hook, "120")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
    loop {
        let line = lines.next().expect("the run ends before the hold").unwrap();
        if line.contains("holding") {
            break;
        }
    }
    child
}

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

const OUTPUTS: [&str; 7] = [
    "plot.png",
    "plot.svg",
    "report.html",
    "scenario.toml",
    "summary.json",
    "trajectory.csv",
    "",
];

fn complete(out: &Path) -> bool {
    names(out) == OUTPUTS[..6]
}

fn signal(child: &Child, sig: &str) {
    let ok = Command::new("kill")
        .args([format!("-{sig}"), child.id().to_string()])
        .status()
        .unwrap()
        .success();
    assert!(ok);
}

#[test]
fn kill_during_the_move_leaves_no_half_output() {
    let t = tempfile::tempdir().unwrap();
    let mut child = held(t.path(), "o", &[]);
    child.kill().unwrap(); // SIGKILL: no handler runs
    child.wait().unwrap();
    assert!(!t.path().join("o").exists(), "no half-filled output");
    assert!(
        names(t.path()).iter().any(|n| n.starts_with(".o.staging-")),
        "{:?}",
        names(t.path())
    );
    // The next run removes what the killed one left and writes the whole output.
    divertsim()
        .current_dir(t.path())
        .args(["simulate", "--out", "o"])
        .assert()
        .success();
    assert!(complete(&t.path().join("o")));
    assert_eq!(names(t.path()), ["o"], "nothing hidden is left");

    // Killed while replacing: the old output stays whole.
    std::fs::write(t.path().join("o/summary.json"), b"old").unwrap();
    let mut child = held(t.path(), "o", &["--force"]);
    child.kill().unwrap();
    child.wait().unwrap();
    assert_eq!(
        std::fs::read(t.path().join("o/summary.json")).unwrap(),
        b"old"
    );
    assert!(complete(&t.path().join("o")));

    // Killed between the two renames of --force (the old output aside, the new one not
    // in yet): the next run puts the old output back whole, and refuses to replace it.
    let mut child = held_at(
        t.path(),
        "o",
        &["--force"],
        "DIVERTSIM_TEST_HOLD_MID_REPLACE",
    );
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!t.path().join("o").exists(), "{:?}", names(t.path()));
    let again = divertsim()
        .current_dir(t.path())
        .args(["simulate", "--out", "o"])
        .output()
        .unwrap();
    assert_eq!(again.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&again.stderr).contains("restored"));
    assert_eq!(
        std::fs::read(t.path().join("o/summary.json")).unwrap(),
        b"old"
    );
    assert!(complete(&t.path().join("o")));
    assert_eq!(names(t.path()), ["o"], "nothing hidden is left");
}

#[test]
fn a_stale_staging_directory_is_not_merged() {
    let t = tempfile::tempdir().unwrap();
    for stale in [
        ".o.staging-abc123",
        ".o.partial-1",
        ".o.copy-Q1w2E3",
        ".o.checkpoint-new-a1B2c3",
        ".o.copy-my notes",
    ] {
        std::fs::create_dir_all(t.path().join(stale)).unwrap();
        std::fs::write(t.path().join(stale).join("junk.csv"), b"stale").unwrap();
    }
    divertsim()
        .current_dir(t.path())
        .args(["simulate", "--out", "o"])
        .assert()
        .success();
    assert!(
        complete(&t.path().join("o")),
        "{:?}",
        names(&t.path().join("o"))
    );
    // A user's folder that only looks similar is kept.
    assert_eq!(names(t.path()), [".o.copy-my notes", "o"]);
    // Published with the usual permissions (as a plain mkdir here), not tempfile's 0700.
    use std::os::unix::fs::PermissionsExt;
    std::fs::create_dir(t.path().join("plain")).unwrap();
    let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode(&t.path().join("o")), mode(&t.path().join("plain")));
    // An old output left aside beside a whole one is removed (a missing one is restored:
    // kill_during_the_move_leaves_no_half_output).
    std::fs::create_dir(t.path().join(".o.replaced-xyz789")).unwrap();
    divertsim()
        .current_dir(t.path())
        .args(["simulate", "--force", "--out", "o"])
        .assert()
        .success();
    assert_eq!(names(t.path()), [".o.copy-my notes", "o", "plain"]);
}

#[test]
fn a_second_writer_is_refused_and_signals_remove_the_staging() {
    let t = tempfile::tempdir().unwrap();
    for (sig, code) in [("TERM", 143), ("INT", 130)] {
        let mut first = held(t.path(), "o", &[]);
        let second = divertsim()
            .current_dir(t.path())
            .args(["simulate", "--out", "o"])
            .output()
            .unwrap();
        assert_eq!(second.status.code(), Some(2));
        let err = String::from_utf8_lossy(&second.stderr);
        assert!(
            err.contains("--out: another divertsim run is writing o"),
            "{err}"
        );
        signal(&first, sig);
        assert_eq!(first.wait().unwrap().code(), Some(code), "SIG{sig}");
        assert_eq!(names(t.path()), Vec::<String>::new(), "SIG{sig}");
    }
}

#[test]
fn an_existing_out_is_refused_unless_force() {
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("o");
    // An empty directory is fine.
    std::fs::create_dir(&out).unwrap();
    divertsim()
        .args(["simulate", "--out"])
        .arg(&out)
        .assert()
        .success();
    std::fs::write(out.join("mine.txt"), b"keep me").unwrap();
    let again = divertsim()
        .args(["simulate", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(again.status.code(), Some(2));
    let err = String::from_utf8_lossy(&again.stderr);
    assert!(
        err.contains("already exists") && err.contains("--force"),
        "{err}"
    );
    assert!(out.join("mine.txt").exists(), "nothing touched");
    // --force replaces it whole.
    divertsim()
        .args(["simulate", "--force", "--out"])
        .arg(&out)
        .assert()
        .success();
    assert!(complete(&out));
    // An analysis command refuses too, before computing.
    let cap = divertsim()
        .args(["capacity", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(cap.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&cap.stderr).contains("--out: "));
    assert!(String::from_utf8_lossy(&cap.stderr).contains("already exists"));
}

#[test]
fn an_unwritable_out_is_found_before_computing() {
    // Root may write anywhere it has permission bits for; /proc refuses everyone.
    let unwritable: [PathBuf; 2] = [
        PathBuf::from("/proc/self/divertsim-out"),
        PathBuf::from("/proc/divertsim/out"),
    ];
    for out in unwritable {
        // A capacity map of 2000 settings and 10⁶ cells: hours of work if it started.
        let r = divertsim()
            .args([
                "capacity",
                "--cycle-times",
                "1:1.5/1000",
                "--light-barriers",
                "0:0.9/1000",
                "--out",
            ])
            .arg(&out)
            .output()
            .unwrap();
        assert_eq!(r.status.code(), Some(2), "{}", out.display());
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(err.contains("--out: cannot"), "{err}");
    }
    // A file where the directory would go.
    let t = tempfile::tempdir().unwrap();
    std::fs::write(t.path().join("f"), b"").unwrap();
    let r = divertsim()
        .args(["trigger", "--out"])
        .arg(t.path().join("f"))
        .output()
        .unwrap();
    assert_eq!(r.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&r.stderr).contains("is not a directory"));
}

/// Every sweep counts the simulations it needs whatever its verdicts and refuses beyond
/// --max-sims before computing,
/// naming how to ask for less; nothing is written.
#[test]
fn work_beyond_max_sims_is_refused() {
    let t = tempfile::tempdir().unwrap();
    let hub = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/mix/hub.toml");
    let cases: [(&[&str], &str); 8] = [
        (&["capacity"], "capacity would run at least"),
        (&["trigger"], "trigger would run at least"),
        (&["capture", "--trigger"], "capture would run at least"),
        (&["overload"], "overload would run at least"),
        (&["worst-case"], "worst case would run at least"),
        (&["optimize"], "optimize would run at least"),
        (&["reliability", hub], "reliability would run at least"),
        (
            &[
                "capacity",
                "--cycle-times",
                "1:1.5/1000",
                "--light-barriers",
                "0:0.9/1000",
                "--speeds",
                "1:2.3/1000",
            ],
            "capacity would run at least",
        ),
    ];
    for (i, (args, expect)) in cases.iter().enumerate() {
        let out = t.path().join(format!("o{i}"));
        let mut cmd = divertsim();
        cmd.args(*args).arg("--out").arg(&out);
        if i < 7 {
            cmd.args(["--max-sims", "10"]);
        }
        let r = cmd.output().unwrap();
        assert_eq!(r.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(
            err.contains(&format!("--max-sims: {expect}")),
            "{args:?}: {err}"
        );
        assert!(err.contains("or raise --max-sims"), "{err}");
        assert!(!out.exists(), "{args:?} wrote its output");
        let left: Vec<String> = names(t.path())
            .into_iter()
            .filter(|n| n.starts_with(&format!(".o{i}.")))
            .collect();
        assert!(left.is_empty(), "{args:?} left {left:?}");
    }
    // Within the limit the work is printed as the run starts.
    let fig06 = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../configs/paper/fig06.toml"
    );
    let r = divertsim()
        .args(["trigger", fig06, "--speeds", "1,2", "--scan-step", "0.1"])
        .output()
        .unwrap();
    assert_eq!(
        r.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&r.stderr)
    );
    // The count depends on the roots found: the least and the most it can be.
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("trigger: ")
            && err.contains(" simulations (the count depends on the verdicts)"),
        "{err}"
    );
}

/// An installed binary has the presets: written out, a figure's scenario runs exactly as
/// the repository's file; `replicate` outside the repository falls back to them.
#[test]
fn presets_are_built_in() {
    let t = tempfile::tempdir().unwrap();
    divertsim()
        .current_dir(t.path())
        .args(["preset", "--write", "cfg"])
        .assert()
        .success();
    let repo = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../configs/paper/fig13a.toml"
    );
    let run = |file: &std::path::Path| {
        let v: serde_json::Value = json_stdout(divertsim().args(["simulate", "--json"]).arg(file));
        v["final"].clone()
    };
    assert_eq!(
        run(&t.path().join("cfg/paper/fig13a.toml")),
        run(std::path::Path::new(repo))
    );
    let printed = divertsim()
        .args(["preset", "paper/machine"])
        .output()
        .unwrap();
    assert_eq!(
        String::from_utf8_lossy(&printed.stdout),
        std::fs::read_to_string(t.path().join("cfg/paper/machine.toml")).unwrap()
    );
    let unknown = divertsim()
        .args(["preset", "paper/fig99"])
        .output()
        .unwrap();
    assert_eq!(unknown.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&unknown.stderr).contains("allowed: default, mix/hub"));
    // No configs/paper here: replicate uses the built-in presets.
    divertsim()
        .current_dir(t.path())
        .args(["replicate", "--quick", "-q", "--out", "figs"])
        .assert()
        .success();
    assert!(t.path().join("figs/findings.json").exists());
}

/// A small tmpfs mounted at `at` for a test, unmounted when dropped; `None` (with a message)
/// where this machine cannot mount one (not root, no mount, a container without the right).
struct Tmpfs(PathBuf);

impl Tmpfs {
    fn mount(at: &Path, size: &str) -> Option<Tmpfs> {
        std::fs::create_dir_all(at).ok()?;
        let ok = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(at)
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            eprintln!("SKIPPED: cannot mount a tmpfs here (needs root and mount); the mount-point fault test did not run");
            return None;
        }
        Some(Tmpfs(at.to_path_buf()))
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
    }
}

/// Everything below `dir` (relative paths, sorted) with the bytes of each file.
fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    common::dir_files(dir)
}

/// Hostile input round three: `--out` at a mount point was not all or nothing (a full disk
/// left it half-written; with --force the old output was emptied first). A mount point is
/// refused as DIR (exit 2, saying to use a folder inside it) and keeps its contents; a
/// folder inside the full mount ends in an error with nothing half-written and no staging
/// folder left behind.
#[test]
#[cfg_attr(
    divertsim_no_mount,
    ignore = "needs root and mount, to mount a small tmpfs"
)]
fn out_at_a_mount_point_under_a_full_disk() {
    let tmp = tempfile::tempdir().unwrap();
    let mnt = tmp.path().join("mnt");
    let Some(_fs) = Tmpfs::mount(&mnt, "256k") else {
        return;
    };
    std::fs::write(mnt.join("old.csv"), b"the old output\n").unwrap();
    // Fill the disk.
    let filler = (0..).find_map(|i| {
        std::fs::write(mnt.join(format!("fill{i}")), vec![7u8; 16 << 10])
            .err()
            .map(|_| ())
    });
    assert!(filler.is_some());
    let before = snapshot(&mnt);
    for extra in [&["--force"][..], &[][..]] {
        let out = divertsim()
            .args(["simulate", "--out"])
            .arg(&mnt)
            .args(extra)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{extra:?}: {err}");
        assert!(
            err.contains("is a mount point") && err.contains("run1"),
            "{err}"
        );
        assert_eq!(
            snapshot(&mnt),
            before,
            "{extra:?}: the mount point is untouched"
        );
    }
    // A folder inside the full mount: an error, nothing of it left.
    let out = divertsim()
        .args(["simulate", "--out"])
        .arg(mnt.join("run1"))
        .output()
        .unwrap();
    assert_ne!(out.status.code(), Some(0));
    assert!(!mnt.join("run1").exists());
    assert_eq!(snapshot(&mnt), before, "no staging folder or lock is left");
    assert!(
        names(&mnt).iter().all(|n| !n.starts_with('.')),
        "{:?}",
        names(&mnt)
    );
}

/// Hostile input round three: bad input with `--out a/b/D` left `a/b` behind.
#[test]
fn bad_input_with_a_deep_out_leaves_no_parent_behind() {
    let tmp = tempfile::tempdir().unwrap();
    let out = divertsim()
        .current_dir(tmp.path())
        .args([
            "simulate",
            "--out",
            "a/b/D",
            "--set",
            "machine.belt_speed=-1",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(names(tmp.path()).is_empty(), "{:?}", names(tmp.path()));
}

/// Hostile input round three: a kill during `--force` left `.DIR.retired-PID` orphans; the
/// next run beside DIR removes them, as it removes stale staging folders.
#[test]
fn retired_checkpoint_orphans_are_removed_by_the_next_run() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(tmp.path().join(".out.retired-4242/sub")).unwrap();
    std::fs::write(tmp.path().join(".out.retired-4242/sub/x"), b"x").unwrap();
    std::fs::create_dir_all(tmp.path().join(".out.retired-keep")).unwrap();
    let out = divertsim()
        .current_dir(tmp.path())
        .args(["simulate", "--out", "out"])
        .output()
        .unwrap();
    assert!(out.status.success());
    assert_eq!(names(tmp.path()), [".out.retired-keep", "out"]);
}
