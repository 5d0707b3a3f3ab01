//! `base = "other.toml"` in a scenario file: the base is read first, the file's own keys
//! override it key by key, chains work, drive tables stay relative to their own file, and a
//! cycle or a missing base is a clear error (exit 2).

use divertsim_api::config;
use std::fs;

#[test]
fn file_keys_override_the_base_key_by_key() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(
        dir.path().join("machine.toml"),
        "[machine]\nbelt_speed = 0.65\ncycle_time = 1.2\n[materials]\narm_friction = 0.2\n",
    )
    .unwrap();
    fs::create_dir(dir.path().join("cases")).unwrap();
    fs::write(
        dir.path().join("cases/a.toml"),
        "base = \"../machine.toml\"\n[machine]\ncycle_time = 1.5\n",
    )
    .unwrap();
    // `..` leaves the file's directory: refused unless allowed (tests/scenario_paths.rs).
    let allow = config::LoadOptions {
        allow_outside_paths: true,
        ..Default::default()
    };
    let l = config::load_with(Some(&dir.path().join("cases/a.toml")), &[], allow).unwrap();
    assert_eq!(l.scenario.machine.belt_speed, 0.65);
    assert_eq!(l.scenario.machine.cycle_time, 1.5);
    assert_eq!(l.scenario.materials.arm_friction, 0.2);
    // --set still wins over both.
    let l = config::load_with(
        Some(&dir.path().join("cases/a.toml")),
        &["machine.belt_speed=1.1".into()],
        allow,
    )
    .unwrap();
    assert_eq!(l.scenario.machine.belt_speed, 1.1);
}

#[test]
fn a_base_drive_table_is_relative_to_the_base_file() {
    let dir = tempfile::tempdir().unwrap();
    fs::create_dir(dir.path().join("m")).unwrap();
    fs::write(
        dir.path().join("m/alpha.csv"),
        "t,alpha_deg\n0,0\n0.25,20\n0.5,45\n0.75,20\n1.0,0\n",
    )
    .unwrap();
    fs::write(
        dir.path().join("m/machine.toml"),
        "[machine.drive]\nkind = \"table\"\ntable = \"alpha.csv\"\n",
    )
    .unwrap();
    fs::write(dir.path().join("case.toml"), "base = \"m/machine.toml\"\n").unwrap();
    let l = config::load(Some(&dir.path().join("case.toml")), &[]);
    assert!(l.is_ok(), "{:?}", l.err());
}

#[test]
fn cycles_missing_bases_and_set_base_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("a.toml"), "base = \"b.toml\"\n").unwrap();
    fs::write(dir.path().join("b.toml"), "base = \"a.toml\"\n").unwrap();
    let e = config::load(Some(&dir.path().join("a.toml")), &[]).unwrap_err();
    assert!(e.to_string().contains("base"), "{e}");
    fs::write(dir.path().join("c.toml"), "base = \"nowhere.toml\"\n").unwrap();
    let e = config::load(Some(&dir.path().join("c.toml")), &[]).unwrap_err();
    assert!(
        e.0[0].key == "base" && e.0[0].message.contains("nowhere.toml"),
        "{e}"
    );
    fs::write(dir.path().join("d.toml"), "base = 3\n").unwrap();
    let e = config::load(Some(&dir.path().join("d.toml")), &[]).unwrap_err();
    assert!(e.0[0].message.contains("must be a string"), "{e}");
    let e = config::load(None, &["base=\"x.toml\"".into()]).unwrap_err();
    assert_eq!(e.0[0].key, "base");
}
