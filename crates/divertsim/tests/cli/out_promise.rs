//! Issue 27 (B7): `--out DIR` writes summary.json and the resolved scenario in every command
//! that takes it, as `--help` promises (`paths`: one scenario_K_CASE.toml per case).

use crate::common::divertsim;

const PAPER: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/paper");

#[test]
fn every_out_writes_summary_json_and_the_scenario() {
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    let track = t.join("fig13a.csv");
    divertsim()
        .args([
            "track",
            &format!("{PAPER}/fig13a.toml"),
            "-q",
            "--synthesize",
        ])
        .arg(&track)
        .assert()
        .success();
    let machine = format!("{PAPER}/machine.toml");
    let line = format!("{PAPER}/line.toml");
    let mix = format!("{PAPER}/mix.toml");
    let track = track.to_str().unwrap().to_string();
    let commands: Vec<(&str, Vec<String>)> = vec![
        ("simulate", vec![]),
        (
            "trigger",
            vec![
                format!("{PAPER}/fig06.toml"),
                "--speeds".into(),
                "0.65".into(),
            ],
        ),
        (
            "capture",
            vec![
                format!("{PAPER}/fig05.toml"),
                "--speeds".into(),
                "0.65".into(),
            ],
        ),
        (
            "overload",
            vec![machine.clone(), "--speeds".into(), "0.5,1".into()],
        ),
        (
            "worst-case",
            vec![
                machine.clone(),
                "--search-budget".into(),
                "200".into(),
                "--search-starts".into(),
                "1".into(),
            ],
        ),
        (
            "check",
            vec![
                format!("{PAPER}/robust_optimum.toml"),
                "--search-budget".into(),
                "200".into(),
                "--search-starts".into(),
                "1".into(),
            ],
        ),
        (
            "capacity",
            vec![
                machine.clone(),
                "--worst".into(),
                "paper".into(),
                "--cycle-times".into(),
                "1.2,1.4".into(),
                "--light-barriers".into(),
                "0,0.2".into(),
            ],
        ),
        (
            "optimize",
            vec![
                machine.clone(),
                "--worst".into(),
                "paper".into(),
                "--method".into(),
                "ga".into(),
                "--population".into(),
                "6".into(),
                "--generations".into(),
                "1".into(),
            ],
        ),
        (
            "reliability",
            vec![mix.clone(), "--samples".into(), "100".into()],
        ),
        (
            "line",
            vec![
                line.clone(),
                "--parcels".into(),
                "50".into(),
                "--segment".into(),
                "10".into(),
            ],
        ),
        (
            "track",
            vec![machine.clone(), "--track".into(), track.clone()],
        ),
        (
            "compare",
            vec![machine.clone(), "--track".into(), track.clone()],
        ),
        (
            "calibrate",
            vec![
                machine.clone(),
                "--track".into(),
                track.clone(),
                "--budget".into(),
                "20".into(),
                "--no-profiles".into(),
                "--fit".into(),
                "materials.belt_friction".into(),
            ],
        ),
    ];
    for (k, (cmd, args)) in commands.iter().enumerate() {
        let dir = t.join(format!("out{k}"));
        let out = divertsim()
            .arg(cmd)
            .args(args)
            .arg("-q")
            .arg("--out")
            .arg(&dir)
            .output()
            .unwrap();
        assert_eq!(
            out.status.code(),
            Some(0),
            "{cmd}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        for name in ["summary.json", "scenario.toml"] {
            assert!(
                dir.join(name).is_file(),
                "{cmd}: no {name} in {:?}",
                std::fs::read_dir(&dir)
                    .unwrap()
                    .map(|e| e.unwrap().file_name())
                    .collect::<Vec<_>>()
            );
        }
    }
    let dir = t.join("paths");
    divertsim()
        .args([
            "paths",
            &format!("{PAPER}/fig06.toml"),
            &format!("{PAPER}/fig07.toml"),
            "-q",
            "--out",
        ])
        .arg(&dir)
        .assert()
        .success();
    for name in [
        "summary.json",
        "scenario_1_fig06.toml",
        "scenario_2_fig07.toml",
    ] {
        assert!(dir.join(name).is_file(), "paths: no {name}");
    }
    let v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap();
    assert!(v["scenarios"]["fig07"].is_object(), "{v}");
}
