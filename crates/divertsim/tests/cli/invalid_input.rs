//! Bad input: every case must exit with code 2, name the offending key and its allowed
//! range, and leave no output directory behind (issue "The core", point 8).

use assert_cmd::Command;
use std::path::Path;

struct Case {
    name: &'static str,
    /// Scenario file contents (None: no file argument).
    toml: Option<&'static str>,
    /// Extra files beside the scenario (name, contents).
    extra: &'static [(&'static str, &'static str)],
    sets: &'static [&'static str],
    args: &'static [&'static str],
    /// Fragments that must all appear in stderr.
    expect: &'static [&'static str],
}

const CASES: &[Case] = &[
    Case { name: "malformed toml", toml: Some("[machine\nbelt_speed = 1"), extra: &[], sets: &[], args: &[], expect: &["not valid TOML", "line 1"] },
    Case { name: "unknown key", toml: Some("[machine]\nbelt_sped = 1.0"), extra: &[], sets: &[], args: &[], expect: &["machine.belt_sped", "unknown key"] },
    Case { name: "unknown section", toml: Some("[machina]\nbelt_speed = 1.0"), extra: &[], sets: &[], args: &[], expect: &["machina", "unknown key"] },
    Case { name: "wrong type", toml: Some("[machine]\nbelt_speed = \"fast\""), extra: &[], sets: &[], args: &[], expect: &["machine.belt_speed", "invalid type"] },
    Case { name: "wrong type by --set", toml: None, extra: &[], sets: &["run.arm=maybe"], args: &[], expect: &["run.arm", "invalid type"] },
    Case { name: "mass zero", toml: Some("[parcel]\nmass = 0.0"), extra: &[], sets: &[], args: &[], expect: &["parcel.mass", "[0.001, 1000] kg"] },
    Case { name: "negative length", toml: None, extra: &[], sets: &["parcel.length=-0.1"], args: &[], expect: &["parcel.length", "[0.001, 5] m"] },
    Case { name: "zero width", toml: None, extra: &[], sets: &["parcel.width=0.0"], args: &[], expect: &["parcel.width", "[0.001, 5] m"] },
    Case { name: "negative belt friction", toml: Some("[materials]\nbelt_friction = -0.1"), extra: &[], sets: &[], args: &[], expect: &["materials.belt_friction", "[0, 2]"] },
    Case { name: "negative arm friction", toml: None, extra: &[], sets: &["materials.arm_friction=-0.2"], args: &[], expect: &["materials.arm_friction", "[0, 1.3]"] },
    Case { name: "restitution above one", toml: None, extra: &[], sets: &["materials.restitution=1.2"], args: &[], expect: &["materials.restitution", "[0, 1]"] },
    Case { name: "parcel wider than belt", toml: None, extra: &[], sets: &["parcel.width=0.8"], args: &[], expect: &["parcel.width", "wider than machine.belt_width"] },
    Case { name: "parcel off the far edge", toml: None, extra: &[], sets: &["parcel.offset=0.6"], args: &[], expect: &["parcel.offset", "allowed: [0, 0.44"] },
    Case { name: "parcel off the near edge", toml: None, extra: &[], sets: &["parcel.offset=-0.05"], args: &[], expect: &["parcel.offset", "off the belt"] },
    Case { name: "light barrier downstream", toml: Some("[machine]\nstart_position = 0.2\nlight_barrier = 0.5"), extra: &[], sets: &[], args: &[], expect: &["machine.light_barrier", "light_barrier ≤ start_position"] },
    Case { name: "swing out of range", toml: None, extra: &[], sets: &["machine.drive.max_swing_deg=120"], args: &[], expect: &["machine.drive.max_swing_deg", "(0, 90] deg"] },
    Case { name: "links not a crank-rocker", toml: Some("[machine.drive]\ncrank = 0.2\ncoupler = 0.3\nrocker = 0.15\nground = 0.33"), extra: &[], sets: &[], args: &[], expect: &["machine.drive", "crank-rocker"] },
    Case { name: "links miss the asked swing", toml: Some("[machine.drive]\nmax_swing_deg = 30.0\ncrank = 0.057402515\ncoupler = 0.3\nrocker = 0.15\nground = 0.330461724"), extra: &[], sets: &[], args: &[], expect: &["machine.drive.max_swing_deg", "not the 30° asked"] },
    Case { name: "crank without ground", toml: None, extra: &[], sets: &["machine.drive.crank=0.05"], args: &[], expect: &["machine.drive.ground", "together"] },
    Case { name: "table for a cam law", toml: Some("[machine.drive]\nkind = \"cycloidal\"\ntable = \"a.csv\""), extra: &[], sets: &[], args: &[], expect: &["machine.drive.table", "only to kind = \"table\""] },
    Case { name: "table missing", toml: Some("[machine.drive]\nkind = \"table\"\ntable = \"nope.csv\""), extra: &[], sets: &[], args: &[], expect: &["machine.drive.table", "cannot read"] },
    Case { name: "table not monotone", toml: Some("[machine.drive]\nkind = \"table\"\ntable = \"a.csv\""), extra: &[("a.csv", "t,alpha_deg\n0,0\n0.3,20\n0.2,40\n0.6,20\n0.9,0\n")], sets: &[], args: &[], expect: &["machine.drive.table", "increas"] },
    Case { name: "table too short", toml: Some("[machine.drive]\nkind = \"table\"\ntable = \"a.csv\""), extra: &[("a.csv", "0,0\n1,0\n")], sets: &[], args: &[], expect: &["machine.drive.table", "at least"] },
    Case { name: "table garbage", toml: Some("[machine.drive]\nkind = \"table\"\ntable = \"a.csv\""), extra: &[("a.csv", "0,0\n0.5,abc\n")], sets: &[], args: &[], expect: &["machine.drive.table", "line 2"] },
    Case { name: "empty scenario file", toml: Some(""), extra: &[], sets: &[], args: &[], expect: &["is empty", "built-in default"] },
    Case { name: "non-finite tolerance", toml: Some("[run]\ntolerance = nan"), extra: &[], sets: &[], args: &[], expect: &["run.tolerance", "not a finite number"] },
    Case { name: "infinite velocity", toml: Some("[parcel]\nvelocity = [inf, 0.0]"), extra: &[], sets: &[], args: &[], expect: &["parcel.velocity[0]", "not a finite number"] },
    Case { name: "zero cycle time", toml: None, extra: &[], sets: &["machine.cycle_time=0.0"], args: &[], expect: &["machine.cycle_time", "[0.1, 60] s"] },
    Case { name: "negative duration", toml: None, extra: &[], sets: &["run.duration=-1.0"], args: &[], expect: &["run.duration", "[0.001, 3600] s"] },
    Case { name: "empty friction table", toml: Some("[materials]\nbelt_friction = []"), extra: &[], sets: &[], args: &[], expect: &["materials.belt_friction", "empty"] },
    Case { name: "unknown friction model", toml: None, extra: &[], sets: &["materials.friction_model=fancy"], args: &[], expect: &["materials.friction_model", "exact", "seed"] },
    Case { name: "angle out of range", toml: None, extra: &[], sets: &["parcel.angle_deg=400"], args: &[], expect: &["parcel.angle_deg", "[-180, 180] deg"] },
    Case { name: "set without value", toml: None, extra: &[], sets: &["machine.belt_speed"], args: &[], expect: &["--set", "KEY=VALUE"] },
    Case { name: "design parcel mass zero", toml: Some("[[design.parcels]]\nname = \"a\"\nlength = 0.2\nwidth = 0.1\nmass = 0.0\noffset = \"far\""), extra: &[], sets: &[], args: &[], expect: &["design.parcels[0].mass", "[0.001, 1000] kg"] },
    Case { name: "design parcel off the belt", toml: Some("[[design.parcels]]\nname = \"a\"\nlength = 0.2\nwidth = 0.1\nmass = 1.0\noffset = 0.65"), extra: &[], sets: &[], args: &[], expect: &["design.parcels[0].offset", "allowed: [0, 0.6"] },
    Case { name: "design parcel wider than belt", toml: Some("[[design.parcels]]\nname = \"a\"\nlength = 0.2\nwidth = 0.9\nmass = 1.0\noffset = \"near\""), extra: &[], sets: &[], args: &[], expect: &["design.parcels[0].width", "wider than machine.belt_width"] },
    Case { name: "design parcel bad edge", toml: Some("[[design.parcels]]\nname = \"a\"\nlength = 0.2\nwidth = 0.1\nmass = 1.0\noffset = \"middle\""), extra: &[], sets: &[], args: &[], expect: &["design.parcels[0].offset", "\"near\" or \"far\""] },
    Case { name: "design parcel missing mass", toml: Some("[[design.parcels]]\nname = \"a\"\nlength = 0.2\nwidth = 0.1\noffset = 0.0"), extra: &[], sets: &[], args: &[], expect: &["design.parcels[0]", "missing field `mass`"] },
    Case { name: "design parcel unknown key", toml: Some("[[design.parcels]]\nname = \"a\"\nlength = 0.2\nwidth = 0.1\nmass = 1.0\noffset = 0.0\ncolour = 1"), extra: &[], sets: &[], args: &[], expect: &["design.parcels[0].colour", "unknown key"] },
    Case { name: "design parcel names twice", toml: Some("[[design.parcels]]\nname = \"a\"\nlength = 0.2\nwidth = 0.1\nmass = 1.0\noffset = 0.0\n[[design.parcels]]\nname = \"a\"\nlength = 0.3\nwidth = 0.1\nmass = 1.0\noffset = 0.0"), extra: &[], sets: &[], args: &[], expect: &["design.parcels[1].name", "unique"] },
    Case { name: "design parcel angle", toml: Some("[[design.parcels]]\nname = \"a\"\nlength = 0.2\nwidth = 0.1\nmass = 1.0\noffset = 0.0\nangle_deg = 200.0"), extra: &[], sets: &[], args: &[], expect: &["design.parcels[0].angle_deg", "[-180, 180] deg"] },
    Case { name: "design parcels empty", toml: Some("[design]\nparcels = []"), extra: &[], sets: &[], args: &[], expect: &["design.parcels", "allowed: 1 to 16"] },
    Case { name: "search band reversed", toml: Some("[design.search]\nlength = [0.7, 0.2]"), extra: &[], sets: &[], args: &[], expect: &["design.search.length", "lo ≤ hi"] },
    Case { name: "search phase too wide", toml: None, extra: &[], sets: &["design.search.phase=[-100.0, 0.0]"], args: &[], expect: &["design.search.phase", "[-60, 60] s"] },
    Case { name: "search class wider than belt", toml: Some("[design.search]\nlength = [0.75, 0.8]\nwidth = [0.72, 0.75]"), extra: &[], sets: &[], args: &[], expect: &["design.search.width", "wider than machine.belt_width"] },
    Case { name: "design overload mass", toml: None, extra: &[], sets: &["design.overload.mass=-15"], args: &[], expect: &["design.overload.mass", "[0.001, 1000] kg"] },
    Case { name: "design overload unknown key", toml: Some("[design.overload]\nweight = 15.0"), extra: &[], sets: &[], args: &[], expect: &["design.overload.weight", "unknown key"] },
    Case { name: "arm face misses the parcel", toml: None, extra: &[], sets: &["machine.arm_face_bottom=0.2"], args: &[], expect: &["machine.arm_face_bottom", "misses the parcel", "allowed: below 0.15 m"] },
    Case { name: "arm face misses every parcel of the mix", toml: Some("[mix]\nheight = { kind = \"uniform\", min = 0.1, max = 0.3 }"), extra: &[], sets: &["machine.arm_face_bottom=0.3"], args: &[], expect: &["machine.arm_face_bottom", "misses every parcel", "allowed: below 0.3 m"] },
    Case { name: "arm face top below its bottom", toml: None, extra: &[], sets: &["machine.arm_face_bottom=0.1", "machine.arm_face_top=0.05"], args: &[], expect: &["machine.arm_face_top", "allowed: above 0.1 m"] },
    Case { name: "arm face bottom negative", toml: None, extra: &[], sets: &["machine.arm_face_bottom=-0.1"], args: &[], expect: &["machine.arm_face_bottom", "[0, 2] m"] },
    Case { name: "arm mass negative", toml: None, extra: &[], sets: &["machine.arm_mass=-3"], args: &[], expect: &["machine.arm_mass", "[0, 1000] kg"] },
    Case { name: "arm inertia negative", toml: None, extra: &[], sets: &["machine.arm_inertia=-1"], args: &[], expect: &["machine.arm_inertia", "[0, 10000] kg·m²"] },
    Case { name: "centre of mass above the top", toml: None, extra: &[], sets: &["parcel.com_height=0.2"], args: &[], expect: &["parcel.com_height", "above the parcel's top", "(0, 0.15] m"] },
    Case { name: "tipping rule unknown", toml: None, extra: &[], sets: &["limits.tipping=\"maybe\""], args: &[], expect: &["limits.tipping", "verdict"] },
    Case { name: "plot extension", toml: None, extra: &[], sets: &[], args: &["--plot", "top.jpg"], expect: &["--plot", ".svg or .png"] },
];

fn run_case(case: &Case, dir: &Path) -> (i32, String) {
    let mut cmd = Command::cargo_bin("divertsim").unwrap();
    cmd.current_dir(dir).arg("simulate");
    for (name, text) in case.extra {
        std::fs::write(dir.join(name), text).unwrap();
    }
    if let Some(text) = case.toml {
        std::fs::write(dir.join("scenario.toml"), text).unwrap();
        cmd.arg("scenario.toml");
    }
    for s in case.sets {
        cmd.arg("--set").arg(s);
    }
    cmd.args(case.args).arg("--out").arg("out");
    let output = cmd.output().unwrap();
    (
        output.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

#[test]
fn every_invalid_input_is_reported_with_key_and_range() {
    assert!(CASES.len() >= 20);
    let mut failures = Vec::new();
    for case in CASES {
        let tmp = tempfile::tempdir().unwrap();
        let (code, stderr) = run_case(case, tmp.path());
        let missing: Vec<_> = case
            .expect
            .iter()
            .filter(|e| !stderr.contains(**e))
            .collect();
        let leftovers: Vec<_> = std::fs::read_dir(tmp.path())
            .unwrap()
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains("out"))
            .collect();
        if code != 2 || !missing.is_empty() || !leftovers.is_empty() || stderr.contains("panicked")
        {
            failures.push(format!(
                "{}: exit {code}, missing {missing:?}, leftovers {leftovers:?}\n{stderr}",
                case.name
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn missing_scenario_file_is_exit_2() {
    let tmp = tempfile::tempdir().unwrap();
    let out = Command::cargo_bin("divertsim")
        .unwrap()
        .current_dir(tmp.path())
        .args(["simulate", "absent.toml", "--out", "out"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("absent.toml: cannot read the scenario file")
    );
    assert!(!tmp.path().join("out").exists());
}

#[test]
fn all_problems_are_reported_at_once() {
    let tmp = tempfile::tempdir().unwrap();
    let text = "[machine]\nbelt_speed = -1.0\nfoo = 1\n[parcel]\nmass = -2.0\n[materials]\nrestitution = 2.0\n";
    std::fs::write(tmp.path().join("s.toml"), text).unwrap();
    let out = Command::cargo_bin("divertsim")
        .unwrap()
        .current_dir(tmp.path())
        .args(["simulate", "s.toml"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("4 problems"), "{err}");
    for key in [
        "machine.belt_speed",
        "machine.foo",
        "parcel.mass",
        "materials.restitution",
    ] {
        assert!(err.contains(key), "{key} missing in {err}");
    }
}

/// The message rules (issue 15): numbers with about six significant digits, a range for
/// every rejected value (NaN and infinities included), no serde jargon, "and N more", a
/// one-line --set, a header that does not call option problems a scenario's, and no echo
/// of a file that is not a scenario. Each row: the arguments, what stderr must contain,
/// what it must not.
#[test]
fn message_rules() {
    let tmp = tempfile::tempdir().unwrap();
    let table = tmp.path().join("alpha.csv");
    std::fs::write(&table, "t,alpha_deg\n0,0\nroot:x:0:0:secret\n").unwrap();
    let table_set = format!("machine.drive.table=\"{}\"", table.display());
    let many: Vec<String> = (0..70).map(|i| format!("parcel.k{i}=1")).collect();
    let rows: Vec<(Vec<String>, Vec<&str>, Vec<&str>)> = vec![
        (
            vec!["--set".into(), "machine.belt_speed=1e300".into()],
            vec![
                "1e300 is out of range",
                "allowed: [0, 20] m/s",
                "invalid input",
            ],
            vec!["000000000"],
        ),
        (
            vec!["--set".into(), "machine.belt_speed=nan".into()],
            vec!["NaN is not a finite number; allowed: [0, 20] m/s"],
            vec![],
        ),
        (
            vec!["--set".into(), "parcel.mass=inf".into()],
            vec!["parcel.mass", "allowed: [0.001, 1000] kg"],
            vec![],
        ),
        (
            vec![
                "--set".into(),
                "machine.belt_speed=1.23456789".into(),
                "--set".into(),
                "machine.belt_speed=23.456789123".into(),
            ],
            vec!["23.4568 is out of range"],
            vec!["23.456789123"],
        ),
        (
            vec!["--set".into(), "machine.belt_speed=\"1\n2\"".into()],
            vec!["machine.belt_speed", "one line"],
            vec![],
        ),
        (
            vec![
                "--set".into(),
                "machine.drive.kind=\"table\"".into(),
                "--set".into(),
                table_set,
                "--allow-outside-paths".into(),
            ],
            vec!["machine.drive.table", "line 3", "two numbers"],
            vec!["secret", "root:x"],
        ),
        (
            many.iter()
                .flat_map(|s| ["--set".to_string(), s.clone()])
                .collect(),
            vec!["70 problems", "and 6 more problems"],
            vec![],
        ),
    ];
    for (args, must, must_not) in rows {
        let out = Command::cargo_bin("divertsim")
            .unwrap()
            .arg("simulate")
            .args(&args)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        for m in must {
            assert!(err.contains(m), "{args:?}: missing {m:?} in\n{err}");
        }
        for m in must_not {
            assert!(!err.contains(m), "{args:?}: {m:?} in\n{err}");
        }
    }
    // Serde jargon: an optimiser bound of the wrong shape.
    let out = Command::cargo_bin("divertsim")
        .unwrap()
        .args([
            "optimize",
            "--set",
            "optimize.belt_speed=\"fast\"",
            "--budget",
            "10",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("untagged enum"), "{err}");
}

/// What users meet, round two (11): an empty scenario file or empty standard input ran the
/// built-in default with exit 0; `generate-scenario | divertsim simulate -` did exactly that
/// when `generate-scenario` did not exist. Empty input is an error.
#[test]
fn empty_input_is_an_error() {
    let out = Command::cargo_bin("divertsim")
        .unwrap()
        .args(["simulate", "-"])
        .write_stdin("  \n")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("is empty"), "{err}");
    assert!(out.stdout.is_empty());
}
