//! A further diverter's setting made in SI from the first's (`MachineChanges`) equals, bit
//! for bit, the setting the scenario file gives it (its `[machine]` table merged over the
//! first's through TOML), for each kind of stated value, and after the first machine's
//! v, t_c, R_s and S_d change as the line objective changes them.

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
        for x in settings {
            let diverters = format!("[{{ position = 4.0, share = 0.5, machine = {table} }}]");
            let mut b = ScenarioBuilder::file(LINE_TWO).value("line.diverters", value(&diverters));
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
            let own = &loaded.file.line.diverters[0].machine;
            let changes = machine_changes(own, &merged.machine);
            let given = loaded.file.run.duration.is_some();
            assert_eq!(&changes.setting(first, given), merged, "{table} at {x:?}");
            compared += 1;
        }
    }
    assert_eq!(compared, 33);
}

/// The line objective's line at x, made in SI by the core (`LineProblem::line_at`: the first
/// machine set, every diverter's setting made again, the setting's faults refused), equals
/// the line the scenario file gives at x through TOML (`scenario_at`, then `line_of`), and
/// the core refuses exactly the settings the file's checks refuse. The lines cover each
/// fault a new first machine can make.
#[test]
fn the_line_objectives_line_is_the_files_line_at_every_setting() {
    use divertsim_api::analyses::line::line_of;
    use divertsim_api::analyses::optimize::line::{LineObjective, LineSearch};
    use divertsim_api::analyses::optimize::search_bounds;
    use divertsim_core::analysis::line::LineRefusal;
    use std::collections::HashSet;

    let further = |machine: &str| {
        value(&format!(
            "[{{ position = 1.5, share = 0.4, machine = {machine} }}]"
        ))
    };
    // Each variant of the two-diverter line, by what it can make a fault of.
    let variants: Vec<(&str, Vec<(&str, toml::Value)>)> = vec![
        ("as given", vec![]),
        (
            "own barrier, inherited start; close behind the first",
            vec![("line.diverters", further("{ light_barrier = -0.3 }"))],
        ),
        (
            "own start, inherited barrier; its own drive",
            vec![(
                "line.diverters",
                further("{ start_position = 0.1, drive = { kind = \"crank-rocker\" } }"),
            )],
        ),
        (
            "two stated cycles",
            vec![("run.cycle_starts", value("[0.0, 1.5]"))],
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
    let mut faults = HashSet::new();
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
                                faults.insert(std::mem::discriminant(r));
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
    assert!(accepted > 50, "{accepted} settings accepted");
    let every_fault = [
        LineRefusal::BarrierDownstream { diverter: 0 },
        LineRefusal::CyclesOverlap { diverter: 0 },
        LineRefusal::Crowded { diverter: 0 },
        LineRefusal::ArmAcrossParcel,
    ];
    for r in every_fault {
        assert!(
            faults.contains(&std::mem::discriminant(&r)),
            "no setting made the fault {r:?}"
        );
    }
}
