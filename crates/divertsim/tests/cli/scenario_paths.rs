//! The paths a scenario names (`base`, `machine.drive.table`, `mix.records`): relative to
//! the file that names them (to the working directory for `--set`), inside its directory
//! unless `--allow-outside-paths`, regular files only, never echoed; and the files divertsim
//! writes stand alone, so `simulate DIR/scenario.toml` reproduces a drive-table run bit for
//! bit.

use crate::common;

use common::divertsim;
use divertsim_api::config::{self, LoadOptions};
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

const ALPHA: &str = "t,alpha_deg\n0,0\n0.25,20\n0.5,45\n0.75,20\n1.0,0\n";
const RECORDS: &str = "length,width,height,mass\n0.4,0.2,0.1,2.0\n0.3,0.2,0.15,1.0\n";
const BASE: &str = "[machine]\nbelt_speed = 1.5\n";

/// What a scenario file names and the content a good target of that key holds.
const KEYS: [(&str, &str, &str); 3] = [
    ("base", "base = \"{}\"\n", BASE),
    (
        "machine.drive.table",
        "[machine.drive]\nkind = \"table\"\ntable = \"{}\"\n",
        ALPHA,
    ),
    ("mix.records", "[mix]\nrecords = \"{}\"\n", RECORDS),
];

/// `load_with` on another thread: a FIFO or a device must not make it wait forever.
fn load_in_time(path: &Path, sets: &[String], allow: bool) -> Result<config::Loaded, String> {
    let (tx, rx) = mpsc::channel();
    let (path, sets) = (path.to_path_buf(), sets.to_vec());
    std::thread::spawn(move || {
        let options = LoadOptions {
            allow_outside_paths: allow,
            ..Default::default()
        };
        let _ = tx.send(config::load_with(Some(&path), &sets, options).map_err(|e| e.to_string()));
    });
    rx.recv_timeout(Duration::from_secs(20))
        .expect("loading did not finish within 20 s")
}

/// One layout: the scenario at `dir/case/s.toml`, the named path as written in it, and
/// whether it loads without and with --allow-outside-paths.
struct Case {
    name: &'static str,
    /// The path as the scenario writes it (`{dir}` is the temporary root).
    written: &'static str,
    /// Where the good target is put, relative to the root (None: nothing is made there).
    target: Option<&'static str>,
    ok_without: bool,
    ok_with: bool,
    /// Fragments of the error (besides the key).
    expect: &'static [&'static str],
}

const CASES: &[Case] = &[
    Case {
        name: "beside",
        written: "x.dat",
        target: Some("case/x.dat"),
        ok_without: true,
        ok_with: true,
        expect: &[],
    },
    Case {
        name: "below",
        written: "sub/x.dat",
        target: Some("case/sub/x.dat"),
        ok_without: true,
        ok_with: true,
        expect: &[],
    },
    Case {
        name: "up",
        written: "../x.dat",
        target: Some("x.dat"),
        ok_without: false,
        ok_with: true,
        expect: &["\"../x.dat\"", "`..`", "--allow-outside-paths"],
    },
    Case {
        name: "absolute",
        written: "{dir}/x.dat",
        target: Some("x.dat"),
        ok_without: false,
        ok_with: true,
        expect: &["is an absolute path", "--allow-outside-paths"],
    },
    Case {
        name: "directory",
        written: "d",
        target: None,
        ok_without: false,
        ok_with: false,
        expect: &["is a directory"],
    },
    Case {
        name: "fifo",
        written: "fifo",
        target: None,
        ok_without: false,
        ok_with: false,
        expect: &["not a regular file"],
    },
    Case {
        name: "device",
        written: "/dev/zero",
        target: None,
        ok_without: false,
        ok_with: false,
        expect: &["/dev/zero"],
    },
];

#[test]
fn path_policy_for_every_path_key() {
    let mut failures = Vec::new();
    for (key, template, content) in KEYS {
        for case in CASES {
            let tmp = tempfile::tempdir().unwrap();
            let root = tmp.path();
            fs::create_dir_all(root.join("case/sub")).unwrap();
            fs::create_dir(root.join("case/d")).unwrap();
            let made = std::process::Command::new("mkfifo")
                .arg(root.join("case/fifo"))
                .status()
                .unwrap();
            assert!(made.success());
            if let Some(t) = case.target {
                fs::write(root.join(t), content).unwrap();
            }
            let written = case.written.replace("{dir}", &root.display().to_string());
            let scenario = root.join("case/s.toml");
            fs::write(&scenario, template.replace("{}", &written)).unwrap();
            for (allow, want_ok) in [(false, case.ok_without), (true, case.ok_with)] {
                let got = load_in_time(&scenario, &[], allow);
                let fine = match &got {
                    Ok(_) => want_ok,
                    Err(e) => {
                        !want_ok
                            && e.contains(&format!("{key}:"))
                            && case.expect.iter().all(|f| e.contains(f))
                    }
                };
                if !fine {
                    failures.push(format!(
                        "{key} {} (allow {allow}): want ok {want_ok}, got {:?}",
                        case.name,
                        got.as_ref().map(|_| ()).map_err(|e| e.trim().to_string())
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A `base` (or a table or records file) that is not what it should be is reported without a
/// word of what it holds.
#[test]
fn a_file_that_is_not_a_scenario_is_never_echoed() {
    let tmp = tempfile::tempdir().unwrap();
    let secret = "hunter2-the-password";
    for (name, text) in [
        ("plain.txt", format!("{secret}\n")),
        ("passwd", format!("root:x:0:0:{secret}:/root:/bin/bash\n")),
        ("dup.txt", format!("{secret} = 1\n{secret} = 2\n")),
        ("open.txt", format!("[{secret}\n")),
    ] {
        fs::write(tmp.path().join(name), &text).unwrap();
        for scenario in [
            format!("base = \"{name}\"\n"),
            format!("[machine.drive]\nkind = \"table\"\ntable = \"{name}\"\n"),
            format!("[mix]\nrecords = \"{name}\"\n"),
        ] {
            let s = tmp.path().join("s.toml");
            fs::write(&s, &scenario).unwrap();
            let e = config::load(Some(&s), &[]).unwrap_err().to_string();
            assert!(e.contains(name), "{scenario}: {e}");
            assert!(
                !e.contains("hunter2") && !e.contains("root:x"),
                "{scenario}: {e}"
            );
        }
    }
}

/// A path given with --set is relative to the working directory, not to the scenario file.
#[test]
fn a_set_path_is_relative_to_the_working_directory() {
    let tmp = tempfile::tempdir().unwrap();
    fs::create_dir(tmp.path().join("case")).unwrap();
    fs::write(
        tmp.path().join("case/s.toml"),
        "[machine.drive]\nkind = \"table\"\n",
    )
    .unwrap();
    fs::write(tmp.path().join("alpha.csv"), ALPHA).unwrap();
    let run = |sets: &[&str]| {
        let mut cmd = divertsim();
        cmd.current_dir(tmp.path())
            .args(["simulate", "case/s.toml", "--json"]);
        for s in sets {
            cmd.arg("--set").arg(s);
        }
        cmd.output().unwrap()
    };
    let out = run(&["machine.drive.table=\"alpha.csv\""]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The same name relative to the file's directory does not exist.
    fs::rename(
        tmp.path().join("alpha.csv"),
        tmp.path().join("case/alpha.csv"),
    )
    .unwrap();
    let out = run(&["machine.drive.table=\"alpha.csv\""]);
    assert_eq!(out.status.code(), Some(2));
    // And leaving the working directory needs the flag, as in a file.
    let out = run(&["machine.drive.table=\"../x.csv\""]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        err.contains("machine.drive.table") && err.contains("--allow-outside-paths"),
        "{err}"
    );
}

#[test]
fn outside_paths_are_exit_2_and_the_flag_lets_them_through() {
    let tmp = tempfile::tempdir().unwrap();
    fs::create_dir(tmp.path().join("case")).unwrap();
    fs::write(tmp.path().join("machine.toml"), BASE).unwrap();
    fs::write(
        tmp.path().join("case/s.toml"),
        "base = \"../machine.toml\"\n",
    )
    .unwrap();
    let out = divertsim()
        .current_dir(tmp.path())
        .args(["simulate", "case/s.toml", "--out", "out"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("base: in case/s.toml: \"../machine.toml\" has a `..` component")
            && err.contains("add --allow-outside-paths"),
        "{err}"
    );
    assert!(!tmp.path().join("out").exists());
    let out = divertsim()
        .current_dir(tmp.path())
        .args(["simulate", "case/s.toml", "--allow-outside-paths", "--json"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    // The analysis commands take the flag too (ScenarioArgs).
    let out = divertsim()
        .current_dir(tmp.path())
        .args(["overload", "case/s.toml", "--speeds", "1", "--json"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let out = divertsim()
        .current_dir(tmp.path())
        .args([
            "overload",
            "case/s.toml",
            "--speeds",
            "1",
            "--json",
            "--allow-outside-paths",
        ])
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// `simulate --out` saves scenario.toml with the drive table inline: `simulate` on it, from
/// anywhere, reproduces the run bit for bit, without --allow-outside-paths.
#[test]
fn the_saved_scenario_of_a_table_drive_reproduces_the_run() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    fs::create_dir(root.join("machine")).unwrap();
    // Awkward numbers: a saved file must keep every bit of them.
    fs::write(
        root.join("machine/alpha.csv"),
        "t,alpha_deg\n0,0\n0.1,3.3333333333333335\n0.45,44.99999999999999\n0.8,17.1\n1.0,0\n",
    )
    .unwrap();
    fs::write(
        root.join("machine/machine.toml"),
        "[machine]\ncycle_time = 1.3\n[machine.drive]\nkind = \"table\"\ntable = \"alpha.csv\"\n",
    )
    .unwrap();
    fs::write(
        root.join("case.toml"),
        "base = \"machine/machine.toml\"\n[parcel]\noffset = 0.1\nangle_deg = 7.3\n",
    )
    .unwrap();
    let first = divertsim()
        .current_dir(root)
        .args(["simulate", "case.toml", "--out", "run1", "--json"])
        .output()
        .unwrap();
    assert_eq!(
        first.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let saved = fs::read_to_string(root.join("run1/scenario.toml")).unwrap();
    assert!(saved.contains("points = "), "{saved}");
    assert!(
        !saved.contains("table =") && !saved.contains("base ="),
        "{saved}"
    );
    // Reloaded from elsewhere: no relative path left to break.
    let elsewhere: PathBuf = root.join("elsewhere");
    fs::create_dir(&elsewhere).unwrap();
    let again = divertsim()
        .current_dir(&elsewhere)
        .args([
            "simulate",
            "../run1/scenario.toml",
            "--out",
            "run2",
            "--json",
        ])
        .output()
        .unwrap();
    assert_eq!(
        again.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
    assert_eq!(first.stdout, again.stdout);
    let trajectory = |d: &Path| fs::read(d.join("trajectory.csv")).unwrap();
    assert_eq!(
        trajectory(&root.join("run1")),
        trajectory(&elsewhere.join("run2"))
    );
    // The scenario the core ran is the same, down to the table's last bit.
    let a = config::load(Some(&root.join("case.toml")), &[]).unwrap();
    let b = config::load(Some(&root.join("run1/scenario.toml")), &[]).unwrap();
    assert_eq!(format!("{:?}", a.scenario), format!("{:?}", b.scenario));
}

/// Inline rows are checked like a table file's, at their own key.
#[test]
fn inline_points_are_checked_like_a_table() {
    let bad = [
        (
            vec!["machine.drive.kind=\"table\"", "machine.drive.points=[[0.0, 0.0], [1.0, 0.0]]"],
            "machine.drive.points",
            "at least",
        ),
        (
            vec![
                "machine.drive.kind=\"table\"",
                "machine.drive.points=[[0.0, 0.0], [0.5, 30.0], [0.4, 40.0], [0.8, 20.0], [1.0, 0.0]]",
            ],
            "machine.drive.points",
            "increase",
        ),
        (
            vec![
                "machine.drive.kind=\"table\"",
                "machine.drive.table=\"a.csv\"",
                "machine.drive.points=[[0.0, 0.0]]",
            ],
            "machine.drive.points",
            "cannot be given with machine.drive.table",
        ),
        (
            vec!["machine.drive.points=[[0.0, 0.0]]"],
            "machine.drive.points",
            "only to kind = \"table\"",
        ),
        (
            vec!["machine.drive.kind=\"table\""],
            "machine.drive.table",
            "points = [[t, alpha_deg], ...]",
        ),
    ];
    for (sets, key, fragment) in bad {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        let e = config::load(None, &sets).unwrap_err();
        assert!(
            e.0.iter()
                .any(|p| p.key == key && p.message.contains(fragment)),
            "{sets:?}: {e}"
        );
    }
    let good = [
        "machine.drive.kind=\"table\"".to_string(),
        "machine.drive.points=[[0.0, 0.0], [0.25, 20.0], [0.5, 45.0], [0.75, 20.0], [1.0, 0.0]]"
            .to_string(),
    ];
    assert!(config::load(None, &good).is_ok());
}

/// Hostile input round three: a symbolic link inside the scenario's folder to a file outside
/// it was read, its values copied into `scenario.toml` and echoed in errors. For every path
/// key, the link is refused (exit 2, naming the key) without a trace of the target's text;
/// `--allow-outside-paths` lets it through; a link that stays inside is read.
#[cfg(unix)]
#[test]
fn symlink_out_of_the_folder_is_refused_and_never_echoed() {
    let tmp = tempfile::tempdir().unwrap();
    let (scen, elsewhere) = (tmp.path().join("scen"), tmp.path().join("elsewhere"));
    fs::create_dir_all(&scen).unwrap();
    fs::create_dir_all(&elsewhere).unwrap();
    fs::write(
        elsewhere.join("secret.toml"),
        "[machine]\nbelt_speed = \"hunter2-secret\"\nhunter3 = 1\n",
    )
    .unwrap();
    std::os::unix::fs::symlink("../elsewhere/secret.toml", scen.join("b.toml")).unwrap();
    for (key, template, _) in KEYS {
        fs::write(scen.join("a.toml"), template.replace("{}", "b.toml")).unwrap();
        let out = divertsim()
            .args(["simulate", "--json"])
            .arg(scen.join("a.toml"))
            .arg("--out")
            .arg(tmp.path().join("out"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{key}: {err}");
        assert!(
            err.contains(key) && err.contains("symbolic link"),
            "{key}: {err}"
        );
        assert!(!err.contains("hunter"), "{key}: {err}");
        assert!(
            out.stdout.is_empty() && !tmp.path().join("out").exists(),
            "{key}"
        );
    }
    // Allowed, the base is read; its values are still not echoed in the error.
    fs::write(scen.join("a.toml"), "base = \"b.toml\"\n").unwrap();
    let out = divertsim()
        .args(["simulate", "--allow-outside-paths"])
        .arg(scen.join("a.toml"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("machine.belt_speed") && err.contains("machine.hunter3"),
        "{err}"
    );
    assert!(!err.contains("hunter2-secret"), "{err}");
    // A link inside the folder is an ordinary file.
    fs::write(scen.join("inside.toml"), BASE).unwrap();
    fs::remove_file(scen.join("b.toml")).unwrap();
    std::os::unix::fs::symlink("inside.toml", scen.join("b.toml")).unwrap();
    let out = divertsim()
        .args(["simulate", "--json"])
        .arg(scen.join("a.toml"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A scenario whose further diverter names `table` as its drive table.
fn diverter_table_scenario(table: &str) -> String {
    format!(
        "[line]\nshare = 0.5\n\n[[line.diverters]]\nposition = 6.0\nshare = 0.5\n\
         machine = {{ drive = {{ kind = \"table\", table = \"{table}\" }} }}\n"
    )
}

/// Hostile input round four: `line.diverters[K].machine` is a free table merged over
/// `[machine]`, and its `drive.table` was read with no path rule (`/etc/passwd` read, its
/// numbers echoed in errors, in `line` and `optimize --objective line`).
#[test]
fn further_diverter_table_outside_the_folder_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(
        dir.path().join("evil.toml"),
        diverter_table_scenario("/etc/passwd"),
    )
    .unwrap();
    for args in [
        &["line", "evil.toml", "--parcels", "20", "--segment", "10"][..],
        &["optimize", "evil.toml", "--objective", "line"][..],
    ] {
        let out = divertsim()
            .current_dir(dir.path())
            .args(args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("line.diverters[0].machine.drive.table")
                && err.contains("is an absolute path")
                && err.contains("--allow-outside-paths"),
            "{args:?}: {err}"
        );
        // Nothing of the file is read, so nothing of it is echoed.
        assert!(!err.contains("expected two numbers"), "{err}");
        assert!(!err.contains("line 2"), "{err}");
    }
    // The same rule through --set, relative to the working directory.
    let out = divertsim()
        .current_dir(dir.path())
        .args(["line", "--parcels", "20", "--segment", "10", "--set"])
        .arg("line.diverters=[{position=6.0, share=0.5, machine={drive={kind=\"table\", table=\"../x.csv\"}}}]")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("line.diverters[0].machine.drive.table") && err.contains("`..`"),
        "{err}"
    );
}

/// Hostile input round four: a further diverter's relative `table` was resolved from the
/// working directory, so a table beside the scenario was not found. It is relative to the
/// file that names it, like every other path.
#[test]
fn further_diverter_relative_table_is_found_from_any_working_directory() {
    let root = tempfile::tempdir().unwrap();
    let case = root.path().join("case");
    fs::create_dir_all(&case).unwrap();
    fs::write(case.join("tab.csv"), ALPHA).unwrap();
    fs::write(case.join("line.toml"), diverter_table_scenario("tab.csv")).unwrap();
    for cwd in [root.path(), case.as_path()] {
        let file = case.join("line.toml");
        let out = divertsim()
            .current_dir(cwd)
            .arg("line")
            .arg(&file)
            .args(["--parcels", "20", "--segment", "10", "--json"])
            .output()
            .unwrap();
        assert_eq!(
            out.status.code(),
            Some(0),
            "from {}: {}",
            cwd.display(),
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// Issue 50, item 10: an output folder's scenario files name the records they used by a copy
/// beside them, `input_mix_records.csv`, never by the user's absolute path; the folder reruns
/// from any working directory without `--allow-outside-paths`, to the same rates.
#[test]
fn written_scenarios_carry_their_records_and_rerun_from_anywhere() {
    let t = tempfile::tempdir().unwrap();
    let work = t.path().join("work");
    fs::create_dir(&work).unwrap();
    fs::write(work.join("dims.csv"), RECORDS).unwrap();
    let run = |cwd: &Path, args: &[&str]| {
        let out = divertsim()
            .current_dir(cwd)
            .args(args)
            .args(["--samples", "60", "-q"])
            .output()
            .unwrap();
        assert_eq!(
            out.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    run(
        &work,
        &[
            "reliability",
            "--set",
            "mix.records=dims.csv",
            "--out",
            "first",
        ],
    );
    let first = work.join("first");
    let copy = fs::read_to_string(first.join("input_mix_records.csv")).unwrap();
    assert_eq!(copy, RECORDS);
    let home = t.path().display().to_string();
    for name in ["scenario.toml", "largest_stroke.toml"] {
        let text = fs::read_to_string(first.join(name)).unwrap();
        assert!(
            text.contains("records = \"input_mix_records.csv\""),
            "{name}: {text}"
        );
        assert!(!text.contains(&home), "{name} names the user's folder");
    }
    // From elsewhere, with no flag: the same draws, the same rates.
    let elsewhere = t.path().join("elsewhere");
    fs::create_dir(&elsewhere).unwrap();
    let scenario = first.join("scenario.toml").display().to_string();
    run(&elsewhere, &["reliability", &scenario, "--out", "second"]);
    let rates = |dir: &Path| {
        let v: serde_json::Value =
            serde_json::from_slice(&fs::read(dir.join("summary.json")).unwrap()).unwrap();
        v["points"][0]["divert_rate"].clone()
    };
    assert_eq!(rates(&first), rates(&elsewhere.join("second")));
    assert!(!rates(&first).is_null());
    let again = divertsim()
        .current_dir(&elsewhere)
        .args([
            "simulate",
            &first.join("largest_stroke.toml").display().to_string(),
        ])
        .output()
        .unwrap();
    assert_eq!(again.status.code(), Some(0));
}
