//! A further diverter's setting made in SI from the first's (`MachineChanges`) equals, bit
//! for bit, the setting the scenario file gives it (its `[machine]` table merged over the
//! first's through TOML), for each kind of stated value: its changes read from the file as
//! given, applied to the first machine after its v, t_c, R_s and S_d change as the line
//! objective changes them. And the line objective's whole line at a setting is the file's.

use divertsim_api::config::line::{diverter_scenarios, machine_changes};
use divertsim_api::config::ScenarioBuilder;

const LINE_TWO: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../configs/paper/line_two.toml"
);

fn value(text: &str) -> toml::Value {
    toml::from_str::<toml::Table>(&format!("v = {text}")).unwrap()["v"].clone()
}

#[test]
fn a_diverter_inherits_the_first_machine_as_the_file_does() {
    let tables = [
        "{}",
        "{ cycle_time = 1.2 }",
        "{ start_position = 0.2, light_barrier = 0.1 }",
        "{ light_barrier = -0.3 }",
        "{ arm_length = 1.0 }",
        "{ arm_mass = 2.5 }",
        "{ arm_length = 0.9, arm_mass = 2.0 }",
        "{ arm_inertia = 0.4 }",
        "{ near_side = \"guide\" }",
        "{ drive = { kind = \"crank-rocker\" } }",
        "{ arm_face_bottom = 0.02, arm_face_top = 0.4 }",
    ];
    // The objective's settings of the first machine: (v, t_c, R_s, S_d).
    let settings = [
        None,
        Some((1.7, 1.45, 0.35, 0.1)),
        Some((2.2, 1.05, 0.6, 0.6)),
    ];
    let mut compared = 0;
    for table in tables {
        let diverters = format!("[{{ position = 4.0, share = 0.5, machine = {table} }}]");
        let given = ScenarioBuilder::file(LINE_TWO)
            .value("line.diverters", value(&diverters))
            .load()
            .unwrap_or_else(|p| panic!("{table}: {p}"));
        let own = &given.file.line.diverters[0].machine;
        let changes = machine_changes(own, &diverter_scenarios(&given.file).unwrap()[1].1.machine);
        for x in settings {
            let mut b = ScenarioBuilder::resolved(&given);
            if let Some((v, tc, rs, sd)) = x {
                for (k, val) in [
                    ("machine.belt_speed", v),
                    ("machine.cycle_time", tc),
                    ("machine.start_position", rs),
                    ("machine.light_barrier", sd),
                ] {
                    b = b.value(k, toml::Value::Float(val));
                }
            }
            let loaded = b.load().unwrap_or_else(|p| panic!("{table}: {p}"));
            let by_file = diverter_scenarios(&loaded.file).unwrap();
            let first = &by_file[0].1;
            let merged = &by_file[1].1;
            let stated = loaded.file.run.duration.is_some();
            assert_eq!(&changes.setting(first, stated), merged, "{table} at {x:?}");
            compared += 1;
        }
    }
    assert_eq!(compared, 33);
}

/// The line objective's line at x, made in SI by the core (`LineProblem::line_at`: the first
/// machine set, every diverter's setting made again, the setting's faults refused), equals
/// the line the scenario file gives at x through TOML (`scenario_at`, then `line_of`), the
/// core refusing exactly the settings the file is refused at. The variants reach every fault
/// a setting within the optimiser's limits can make (a drive refuses no t_c > 0: a table's
/// times are scaled to t_c, and the cam and crank laws take any), each at its diverter.
#[test]
fn the_line_objectives_line_is_the_files_line_at_every_setting() {
    use divertsim_api::analyses::line::line_of;
    use divertsim_api::analyses::optimize::line::{LineObjective, LineSearch};
    use divertsim_api::analyses::optimize::search_bounds;
    use std::collections::BTreeSet;

    let further = |entries: &[(f64, &str)]| {
        let list: Vec<String> = entries
            .iter()
            .map(|(at, machine)| format!("{{ position = {at}, share = 0.2, machine = {machine} }}"))
            .collect();
        value(&format!("[{}]", list.join(", ")))
    };
    // Each variant of the line, by what it can make a fault of.
    let variants: Vec<(&str, Vec<(&str, toml::Value)>)> = vec![
        ("as given", vec![]),
        (
            "own barrier, inherited start; close behind the first",
            vec![(
                "line.diverters",
                further(&[(1.5, "{ light_barrier = -0.3 }")]),
            )],
        ),
        (
            "own start, inherited barrier; its own drive",
            vec![(
                "line.diverters",
                further(&[(
                    1.5,
                    "{ start_position = 0.1, drive = { max_swing_deg = 50.0 } }",
                )]),
            )],
        ),
        (
            "three: the second's own longer arm reaches the third",
            vec![(
                "line.diverters",
                further(&[(2.0, "{ arm_length = 1.6 }"), (3.9, "{}")]),
            )],
        ),
        (
            "two stated cycles; a further diverter's own slower cycle",
            vec![
                ("run.cycle_starts", value("[0.0, 1.5]")),
                ("line.diverters", further(&[(4.0, "{ cycle_time = 2.0 }")])),
            ],
        ),
        (
            "a cycle under way at t = 0, a stated length",
            vec![
                ("run.cycle_starts", value("[-0.4]")),
                ("run.duration", value("4.0")),
            ],
        ),
    ];
    let objective = LineObjective {
        parcels: 10,
        seed: Some(1),
        max_missort: 0.001,
        max_overload: 0.01,
    };
    let mut faults = BTreeSet::new();
    let mut accepted = 0;
    for (what, sets) in &variants {
        let mut b = ScenarioBuilder::file(LINE_TWO);
        for (k, v) in sets {
            b = b.value(k, v.clone());
        }
        let loaded = b.load().unwrap_or_else(|p| panic!("{what}: {p}"));
        let search = LineSearch::new(&loaded, search_bounds(&[], 0.0).unwrap(), objective)
            .unwrap_or_else(|p| panic!("{what}: {p:?}"));
        for v in [0.6, 2.0] {
            for tc in [0.5, 1.36, 1.8] {
                for rs in [-0.5, 0.0, 0.4] {
                    for sd in [-0.4, 0.2] {
                        let x = [v, tc, rs, sd];
                        let core = search.problem.line_at(&x);
                        let by_file = search
                            .scenario_at(&x)
                            .and_then(|l| line_of(&l).map(|(_, line)| line));
                        match (&core, &by_file) {
                            (Ok(c), Ok(f)) => {
                                assert_eq!(c, f, "{what} at {x:?}");
                                accepted += 1;
                            }
                            (Err(r), Err(_)) => {
                                faults.insert(format!("{r:?}"));
                            }
                            _ => panic!(
                                "{what} at {x:?}: the core says {:?}, the file {:?}",
                                core.as_ref().err(),
                                by_file.as_ref().err()
                            ),
                        }
                    }
                }
            }
        }
    }
    assert!(accepted > 100, "{accepted} settings accepted");
    let every_fault = [
        "BarrierDownstream { diverter: 1 }",
        "CyclesOverlap",
        "Crowded { diverter: 1 }",
        "Crowded { diverter: 2 }",
        "ArmAcrossParcel",
    ];
    for r in every_fault {
        assert!(
            faults.contains(r),
            "no setting made the fault {r}: {faults:?}"
        );
    }
}

/// An adaptive further diverter's table, built by the core for the line at a setting,
/// is the table the api builds from its file (its nodes and search from the file).
#[test]
fn an_adaptive_diverters_table_is_built_from_its_files_nodes() {
    use divertsim_api::analyses::line::line_of;
    use divertsim_api::analyses::population::{machine_trigger, Quiet};
    use divertsim_core::run::sweep::no_progress;

    let loaded = ScenarioBuilder::file(LINE_TWO)
        .value(
            "line.diverters",
            value(
                "[{ position = 4.0, share = 0.5, machine = { trigger = \"adaptive\", adaptive = \
                 { length_nodes = 2, aspect_nodes = 1, offset_nodes = 1, angle_nodes = 1, step = 0.1 } } }]",
            ),
        )
        .load()
        .unwrap();
    let (files, mut line) = line_of(&loaded).unwrap();
    line.build_triggers(5, &no_progress).unwrap();
    for (k, (d, f)) in line.diverters.iter().zip(&files).enumerate() {
        let by_file = machine_trigger(&f.machine, &line.mix, &d.setting, 5, &Quiet).unwrap();
        assert_eq!(d.trigger, by_file, "diverter {k}");
    }
    assert_eq!(line.diverters[1].trigger.label(), "adaptive");
    assert_eq!(line.diverters[0].trigger.label(), "fixed");
}
