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
