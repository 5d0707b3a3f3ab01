//! The scenario contract (`divertsim_api::config`) on its own: loading files and the built-in
//! default, `--set` overrides, base chains, validation keyed by dotted keys, the JSON Schema
//! and the annotated example. The CLI and Python tests reach these through their edges; these
//! pin the library's behaviour where it lives.

use divertsim_api::config::{self, example, MachineConfig, Problems};
use divertsim_core::model::params::Scenario;
use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn keys(p: &Problems) -> Vec<&str> {
    p.0.iter().map(|p| p.key.as_str()).collect()
}

fn sets(s: &[&str]) -> Vec<String> {
    s.iter().map(|s| s.to_string()).collect()
}

#[test]
fn the_built_in_default_is_the_cores_default_scenario() {
    let l = config::load(None, &[]).unwrap();
    let core = Scenario::paper_default();
    assert_eq!(l.scenario.machine.belt_speed, core.machine.belt_speed);
    assert_eq!(l.scenario.machine.cycle_time, core.machine.cycle_time);
    assert_eq!(l.scenario.machine.arm_length, core.machine.arm_length);
    assert_eq!(l.scenario.parcel, core.parcel);
    // configs/default.toml is the same scenario, written out.
    let file = config::load(Some(&repo().join("configs/default.toml")), &[]).unwrap();
    assert_eq!(
        file.scenario.machine.belt_speed,
        l.scenario.machine.belt_speed
    );
    assert_eq!(file.scenario.parcel, l.scenario.parcel);
}

#[test]
fn a_base_chain_merges_the_paper_machine_under_the_figure() {
    let l = config::load(Some(&repo().join("configs/paper/fig06.toml")), &[]).unwrap();
    // From fig06.toml itself.
    assert_eq!(l.scenario.machine.belt_speed, 0.65);
    assert_eq!(l.scenario.machine.start_position, 0.8);
    assert_eq!(l.scenario.parcel.length, 0.7);
    // From its base, machine.toml: the paper preset's machine.
    let preset = Scenario::paper_machine();
    assert_eq!(l.scenario.machine.arm_length, preset.machine.arm_length);
    assert_eq!(
        l.scenario.materials.arm_friction,
        preset.materials.arm_friction
    );
    // The resolved file has no base left: its keys are merged in.
    assert!(config::to_toml(&l.file, "t")
        .unwrap()
        .lines()
        .all(|l| !l.starts_with("base")));
}

#[test]
fn sets_override_in_order_and_keep_exact_values() {
    let l = config::load(
        None,
        &sets(&[
            "machine.belt_speed=1.5",
            "machine.belt_speed=1.75",
            "parcel.angle_deg=30",
        ]),
    )
    .unwrap();
    assert_eq!(l.scenario.machine.belt_speed, 1.75);
    assert_eq!(l.scenario.parcel.angle, 30f64.to_radians());
    let (key, value) = config::parse_set("machine.cycle_time=1.3").unwrap();
    assert_eq!(
        (key.as_str(), value.as_float()),
        ("machine.cycle_time", Some(1.3))
    );
}

#[test]
fn every_problem_is_reported_at_once_keyed_by_its_dotted_key() {
    let p = config::load(
        None,
        &sets(&[
            "machine.belt_speed=-3",
            "machine.cycle_time=0",
            "parcel.mass=-1",
        ]),
    )
    .unwrap_err();
    let k = keys(&p);
    for want in ["machine.belt_speed", "machine.cycle_time", "parcel.mass"] {
        assert!(k.contains(&want), "{k:?}");
    }
    // The message names the allowed range from the one bounds table.
    let speed = p.0.iter().find(|p| p.key == "machine.belt_speed").unwrap();
    assert!(
        speed.message.contains(&MachineConfig::BELT_SPEED.range()),
        "{}",
        speed.message
    );
    assert!(p.to_string().starts_with("invalid input: "));
}

#[test]
fn unknown_keys_and_malformed_sets_are_refused() {
    let p = config::load(None, &sets(&["machine.belt_sped=1"])).unwrap_err();
    assert_eq!(keys(&p), ["machine.belt_sped"]);
    let p = config::load(None, &sets(&["machine.belt_speed"])).unwrap_err();
    assert_eq!(p.0.len(), 1);
    let missing = config::load(Some(Path::new("/nonexistent/s.toml")), &[]).unwrap_err();
    assert_eq!(missing.0.len(), 1);
}

#[test]
fn a_table_loads_as_its_file_would() {
    let text = std::fs::read_to_string(repo().join("configs/paper/fig06.toml")).unwrap();
    let table: toml::Table = text.parse().unwrap();
    let from_table = config::ScenarioBuilder::table(table, "fig06", &repo().join("configs/paper"))
        .value("machine.belt_speed", toml::Value::Float(1.0))
        .load()
        .unwrap();
    let from_file = config::load(
        Some(&repo().join("configs/paper/fig06.toml")),
        &sets(&["machine.belt_speed=1.0"]),
    )
    .unwrap();
    assert_eq!(from_table.scenario.machine, from_file.scenario.machine);
    assert_eq!(from_table.scenario.parcel, from_file.scenario.parcel);
}

#[test]
fn the_schema_carries_the_bounds_and_every_section() {
    let schema = config::json_schema();
    let text = schema.to_string();
    for section in [
        "MachineConfig",
        "ParcelConfig",
        "MaterialsConfig",
        "DesignConfig",
    ] {
        assert!(text.contains(section), "{section}");
    }
    let speed = &schema["$defs"]["MachineConfig"]["properties"]["belt_speed"];
    assert_eq!(speed["minimum"], MachineConfig::BELT_SPEED.lo);
    assert_eq!(speed["maximum"], MachineConfig::BELT_SPEED.hi);
}

#[test]
fn the_example_loads_and_is_the_built_in_default() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("example.toml");
    std::fs::write(&path, example::example_toml()).unwrap();
    let l = config::load(Some(&path), &[]).unwrap();
    let d = config::load(None, &[]).unwrap();
    assert_eq!(l.scenario.machine, d.scenario.machine);
    assert_eq!(l.scenario.parcel, d.scenario.parcel);
}
