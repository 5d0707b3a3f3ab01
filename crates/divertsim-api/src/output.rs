//! Output formats: the JSON summary, the trajectory CSV and the readable summary (the
//! output directory itself is the CLI's `outdir`).

use crate::config::ScenarioFile;
use divertsim_core::model::params::Scenario;
use divertsim_core::sim::{SimResult, State};
use serde_json::{json, Value};
use std::fmt::Write as _;

/// The summary object of `--json` and `summary.json`.
pub fn summary_json(scenario: &Scenario, result: &SimResult) -> Value {
    let mut summary = json!({
        "outcome": result.outcome.label(),
        "reason": result.outcome.reason(),
        "stages": result.stages.iter().map(|s| s.label()).collect::<Vec<_>>(),
        "events": result.events.iter().map(|e| json!({"t": e.t, "kind": e.kind.label()})).collect::<Vec<_>>(),
        "final": state_json(&result.final_state),
        "max_lateral": result.max_lateral,
        "max_impulse": result.overload.max_impulse,
        "fall_impulse": result.overload.fall_impulse,
        "overload_ratio": result.overload.overload_ratio,
        "equivalent_drop_height": result.overload.equivalent_drop_height,
        "energy_ratio": result.overload.energy_ratio,
        "arm_max_impulse": result.overload.arm_max_impulse,
        "arm_total_impulse": result.overload.arm_total_impulse,
        "tipping": tipping_json(result),
        "arm_loads": arm_loads_json(scenario, result),
        "impacts": result.impacts.iter().map(|i| json!({
            "t": i.t,
            "stage": i.stage.label(),
            "obstacle": i.obstacle.label(),
            "point": i.point,
            "normal_impulse": i.normal_impulse,
            "tangential_impulse": i.tangential_impulse,
            "impulse": i.impulse,
            "approach_speed": i.approach_speed,
            "compression_work": i.compression_work,
            "dissipated": i.dissipated,
            "persistent": i.persistent,
            // J_c: the strike's angular impulse on the arm about the pivot (null off the arm).
            "arm_angular_impulse": i.obstacle.is_arm().then(|| {
                result.arm_strikes.iter().find(|s| s.0 == i.t).map(|s| s.1)
            }).flatten(),
        })).collect::<Vec<_>>(),
    });
    // Only a jammed run has the key: every other summary stays as it was.
    if let Some(jam) = &result.jam {
        summary["jam"] = jam_json(jam);
    }
    summary
}

/// Where and when a run jammed: `{"t", "place", "contacts": [{"obstacle", "point"}],
/// "cause"}`.
pub fn jam_json(jam: &divertsim_core::sim::Jam) -> Value {
    json!({
        "t": jam.t,
        "place": jam.place(),
        "cause": jam.cause,
        "contacts": jam.contacts.iter().map(|(o, p)| json!({"obstacle": o.label(), "point": p})).collect::<Vec<_>>(),
    })
}

/// The tipping check's record: the smallest margin (null if nothing loaded the parcel
/// sideways), when, over which edge and from what.
pub fn tipping_json(result: &SimResult) -> Value {
    let t = &result.tipping;
    json!({
        "margin": t.margin.is_finite().then_some(t.margin),
        "t": t.t.is_finite().then_some(t.t),
        "edge": t.edge.map(|e| e.label()),
        "cause": t.cause.map(|c| c.label()),
        "max_tilt_deg": t.max_tilt.to_degrees(),
        "tipped": t.tipped(),
    })
}

/// The loads on the arm's side of the stroke (null without an arm): the drive's peak and
/// RMS torque at the arm, the input shaft's peak torque, the stroke's energy, the parcel's
/// peak torque on the arm and the largest strike's angular impulse about the pivot.
pub fn arm_loads_json(scenario: &Scenario, result: &SimResult) -> Value {
    match result.arm_loads(scenario) {
        None => Value::Null,
        Some(l) => json!({
            "cycle_start": l.cycle_start,
            "arm_inertia": scenario.machine.arm_inertia,
            "peak_torque": l.peak_torque,
            "rms_torque": l.rms_torque,
            "peak_input_torque": l.peak_input_torque,
            "energy": l.energy,
            "peak_contact_torque": l.peak_contact_torque,
            "max_strike_angular_impulse": l.max_strike_angular_impulse,
        }),
    }
}

/// The tipping line of the readable summary.
pub fn tipping_words(result: &SimResult) -> String {
    use divertsim_core::model::tipping::TipCause;
    let t = &result.tipping;
    let (Some(edge), Some(cause)) = (t.edge, t.cause) else {
        return "stands (nothing loaded it sideways)".into();
    };
    let by = match cause {
        TipCause::Forces => "the forces",
        TipCause::Strike => "a strike",
    };
    if t.tipped() {
        format!(
            "TIPPED over {} at t = {:.4} s (its centre of mass passed over the edge; smallest \
             margin {:.3}, by {by})",
            edge.words(),
            t.t,
            t.margin
        )
    } else if t.max_tilt > 0.0 {
        format!(
            "stands: it rocked back, at most {:.2}° (smallest margin {:.3} at t = {:.4} s, by \
             {by}, towards {})",
            t.max_tilt.to_degrees(),
            t.margin,
            t.t,
            edge.words()
        )
    } else {
        format!(
            "stands: smallest margin {:.3} (below 1 an edge lifts) at t = {:.4} s, by {by}, towards {}",
            t.margin,
            t.t,
            edge.words()
        )
    }
}

/// The units of every number in divertsim's outputs (a table's columns carry theirs in
/// their names where they are not these).
pub fn units() -> Value {
    json!({
        "system": "SI",
        "length, position, displacement, reserve": "m",
        "time, cycle_time, duration": "s",
        "speed, velocity": "m/s",
        "angle": "deg where the key ends in _deg (inputs and tables), else rad",
        "angular velocity (omega, spin)": "rad/s",
        "mass": "kg",
        "impulse": "N·s",
        "energy, work": "J",
        "capacity": "parcels/h",
        "ratios, rates, friction, restitution": "dimensionless",
    })
}

/// `value` (a JSON object) with what makes it self-describing: the tool and its version,
/// the command, the units, and the resolved scenario (every key, defaults filled in).
pub fn describe(mut value: Value, command: &str, file: &ScenarioFile) -> Value {
    value = describe_runs(value, command, &[]);
    if let Some(obj) = value.as_object_mut() {
        obj.entry("scenario")
            .or_insert_with(|| serde_json::to_value(file).unwrap_or_default());
    }
    value
}

/// [`describe`] for a command of several scenarios (one per track): each resolved scenario
/// under `scenarios`, by name.
pub fn describe_runs(mut value: Value, command: &str, runs: &[(&str, &ScenarioFile)]) -> Value {
    if let Some(obj) = value.as_object_mut() {
        obj.insert(
            "divertsim".into(),
            json!({"version": env!("CARGO_PKG_VERSION"), "command": command}),
        );
        obj.insert("units".into(), units());
        if !runs.is_empty() {
            let scenarios: serde_json::Map<String, Value> = runs
                .iter()
                .map(|(n, f)| (n.to_string(), serde_json::to_value(f).unwrap_or_default()))
                .collect();
            obj.insert("scenarios".into(), scenarios.into());
        }
    }
    value
}

fn state_json(s: &State) -> Value {
    json!({
        "t": s.t, "x": s.x, "y": s.y, "phi_deg": s.phi.to_degrees(),
        "vx": s.vx, "vy": s.vy, "omega": s.omega,
    })
}

/// The trajectory as CSV, unit-suffixed columns: t_s, x_m, y_m, phi_deg, vx_m_s,
/// vy_m_s, omega_rad_s, alpha_deg, drive_torque_n_m (the drive's torque on the arm, empty
/// without an arm), stage, and the points of up to two active contacts (empty when none).
pub fn trajectory_csv(scenario: &Scenario, result: &SimResult) -> Result<Vec<u8>, csv::Error> {
    let torque = result.drive_torque_series(scenario);
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "t_s",
        "x_m",
        "y_m",
        "phi_deg",
        "vx_m_s",
        "vy_m_s",
        "omega_rad_s",
        "alpha_deg",
        "drive_torque_n_m",
        "stage",
        "contact1_x_m",
        "contact1_y_m",
        "contact2_x_m",
        "contact2_y_m",
    ])?;
    for (k, s) in result.trajectory.iter().enumerate() {
        let st = &s.state;
        w.write_record([
            st.t.to_string(),
            st.x.to_string(),
            st.y.to_string(),
            st.phi.to_degrees().to_string(),
            st.vx.to_string(),
            st.vy.to_string(),
            st.omega.to_string(),
            s.arm_angle.to_degrees().to_string(),
            torque
                .as_ref()
                .map(|m| m[k].to_string())
                .unwrap_or_default(),
            s.stage.label().to_string(),
            coord(s.contacts[0], 0),
            coord(s.contacts[0], 1),
            coord(s.contacts[1], 0),
            coord(s.contacts[1], 1),
        ])?;
    }
    w.into_inner().map_err(|e| csv::Error::from(e.into_error()))
}

/// One coordinate of an optional contact point; empty when there is none.
fn coord(p: Option<[f64; 2]>, i: usize) -> String {
    p.map(|p| p[i].to_string()).unwrap_or_default()
}

/// A readable summary for the terminal.
pub fn summary_text(scenario: &Scenario, result: &SimResult) -> String {
    let mut s = String::new();
    let p = &scenario.parcel;
    let m = &scenario.machine;
    let _ = writeln!(
        s,
        "parcel {:.3} × {:.3} m, {} kg, its gap to the pivot-side belt edge ΔP = {} m, angle φ = {:.1}°; belt speed v = {} m/s, arm cycle t_c = {} s, arm started when the parcel's front is at R_s = {} m",
        p.length,
        p.width,
        p.mass,
        p.offset,
        p.angle.to_degrees(),
        m.belt_speed,
        m.cycle_time,
        m.start_position
    );
    let verdict = result.outcome.verdict();
    let _ = writeln!(s, "outcome:     {verdict}");
    if let Some(jam) = &result.jam {
        let _ = writeln!(
            s,
            "jam:         at t = {:.4} s, {} (the drive stalls there; the loads below stop at the jam)",
            jam.t,
            jam.place()
        );
    }
    let stages: Vec<&str> = result.stages.iter().map(|x| x.label()).collect();
    let _ = writeln!(s, "stages:      {}", stages.join(" → "));
    let _ = writeln!(
        s,
        "             ({})",
        divertsim_core::sim::stage_legend(&result.stages)
    );
    let _ = writeln!(
        s,
        "max lateral: {:.4} m (far edge at {} m)",
        result.max_lateral, m.belt_width
    );
    let _ = writeln!(s, "tipping:     {}", tipping_words(result));
    if let Some(l) = result.arm_loads(scenario) {
        let _ = writeln!(
            s,
            "arm loads:   drive torque at the arm peak {:.1} N·m, RMS {:.1} N·m over the cycle; input shaft peak {:.1} N·m; {:.2} J per stroke; largest strike {:.3} N·m·s about the pivot{}",
            l.peak_torque,
            l.rms_torque,
            l.peak_input_torque,
            l.energy,
            l.max_strike_angular_impulse,
            if scenario.machine.arm_inertia == 0.0 {
                " (massless arm: give machine.arm_mass or arm_inertia)"
            } else {
                ""
            }
        );
    }
    let o = &result.overload;
    if result.impacts.is_empty() {
        let _ = writeln!(s, "strikes:     none");
    } else {
        let _ = writeln!(
            s,
            "strikes:     {}; largest impulse {:.3} N·s = {:.3} × the {} m free fall ({:.3} N·s), equivalent drop height {:.3} m",
            result.impacts.len(),
            o.max_impulse,
            o.overload_ratio,
            scenario.limits.drop_height,
            o.fall_impulse,
            o.equivalent_drop_height
        );
    }
    let f = &result.final_state;
    let _ = writeln!(
        s,
        "final:       t = {:.4} s, centre ({:.4}, {:.4}) m, φ = {:.2}°, v = ({:.4}, {:.4}) m/s, ω = {:.4} rad/s",
        f.t,
        f.x,
        f.y,
        f.phi.to_degrees(),
        f.vx,
        f.vy,
        f.omega
    );
    let _ = writeln!(s, "events:");
    let mut impacts = result.impacts.iter();
    for e in &result.events {
        let _ = write!(s, "  {:>9.6} s  {}", e.t, e.kind.label());
        if e.kind == divertsim_core::sim::EventKind::Impact {
            if let Some(i) = impacts.next() {
                let _ = write!(
                    s,
                    " ({} on the {}: {:.3} m/s approach, impulse {:.3} N·s{})",
                    i.stage.label(),
                    i.obstacle.label().replace('_', " "),
                    i.approach_speed,
                    i.impulse,
                    if i.persistent { ", no rebound" } else { "" }
                );
            }
        }
        let _ = writeln!(s);
    }
    s
}

/// A CSV file from a header and rows of already formatted cells.
pub fn csv_bytes(header: &[&str], rows: &[Vec<String>]) -> Result<Vec<u8>, csv::Error> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(header)?;
    for r in rows {
        w.write_record(r)?;
    }
    w.into_inner().map_err(|e| e.into_error().into())
}

/// `scenario.toml` of an output directory: the resolved scenario, every key with its value.
pub fn scenario_toml(command: &str, file: &crate::config::ScenarioFile) -> (String, Vec<u8>) {
    let heading = format!(
        "The scenario of this `divertsim {command}` run (divertsim {}), every input resolved.",
        env!("CARGO_PKG_VERSION")
    );
    let text = crate::config::to_toml(file, &heading).unwrap_or_default();
    ("scenario.toml".into(), text.into_bytes())
}

/// Make an output's scenario files rerun where they are: every value of a written `.toml`
/// that names a file by absolute path ([`crate::config::files::FILE_KEYS`]: the parcel
/// records, the arrivals log, a drive table) is replaced by a copy of that file beside it,
/// `input_<key>.<ext>`, one copy per file and folder. The files come from the scenario as it
/// was loaded, where the path rule was already applied; a file that can no longer be read
/// keeps its path. So `divertsim … DIR/scenario.toml` (or `largest_stroke.toml`) reruns
/// from anywhere without `--allow-outside-paths`, and the folder shows nothing of the
/// user's own layout. Returns how many copies were added.
pub fn bundle_inputs(files: &mut Vec<(String, Vec<u8>)>) -> usize {
    use std::collections::BTreeMap;
    use std::path::{Path, PathBuf};
    // (folder, source) → the copy's name in that folder.
    let mut copies: BTreeMap<(String, PathBuf), String> = BTreeMap::new();
    let mut added: Vec<(String, Vec<u8>)> = Vec::new();
    let mut taken: std::collections::BTreeSet<String> =
        files.iter().map(|(n, _)| n.clone()).collect();
    for (name, bytes) in files.iter_mut() {
        if !name.ends_with(".toml") {
            continue;
        }
        let Ok(text) = std::str::from_utf8(bytes) else {
            continue;
        };
        let Ok(mut doc) = text.parse::<toml_edit::DocumentMut>() else {
            continue;
        };
        let folder = match name.rfind('/') {
            Some(i) => name[..=i].to_string(),
            None => String::new(),
        };
        let mut changed = false;
        let mut slots = Vec::new();
        file_values(doc.as_table_mut(), "", "", &mut slots);
        for (key, item) in slots {
            let Some(value) = item.as_value_mut() else {
                continue;
            };
            let Some(raw) = value.as_str().map(str::to_string) else {
                continue;
            };
            let source = PathBuf::from(&raw);
            if !source.is_absolute() {
                continue;
            }
            let copy = match copies.get(&(folder.clone(), source.clone())) {
                Some(c) => c.clone(),
                None => {
                    let Ok(content) = std::fs::read(&source) else {
                        continue;
                    };
                    let ext = Path::new(&raw)
                        .extension()
                        .and_then(|e| e.to_str())
                        .filter(|e| e.len() <= 8 && e.chars().all(|c| c.is_ascii_alphanumeric()))
                        .unwrap_or("csv")
                        .to_string();
                    let stem: String = key
                        .chars()
                        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
                        .collect();
                    let stem = format!("input_{}", stem.trim_matches('_'));
                    let mut copy = format!("{stem}.{ext}");
                    let mut k = 2;
                    while taken.contains(&format!("{folder}{copy}")) {
                        copy = format!("{stem}_{k}.{ext}");
                        k += 1;
                    }
                    taken.insert(format!("{folder}{copy}"));
                    added.push((format!("{folder}{copy}"), content));
                    copies.insert((folder.clone(), source), copy.clone());
                    copy
                }
            };
            let decor = value.decor().clone();
            *value = toml_edit::Value::from(copy);
            *value.decor_mut() = decor;
            changed = true;
        }
        if changed {
            *bytes = doc.to_string().into_bytes();
        }
    }
    let n = added.len();
    files.extend(added);
    n
}

/// The values at [`crate::config::files::FILE_KEYS`] in `table`, at any depth (tables and
/// inline tables alike, arrays of either: an array's items under the array's key), with
/// their dotted keys: the rule of `config::files::named_files`, over `toml_edit`'s items.
fn file_values<'a>(
    table: &'a mut dyn toml_edit::TableLike,
    prefix: &str,
    section: &str,
    out: &mut Vec<(String, &'a mut toml_edit::Item)>,
) {
    let top = prefix.is_empty();
    for (k, v) in table.iter_mut() {
        let name = k.get().to_string();
        let key = if top {
            name.clone()
        } else {
            format!("{prefix}.{name}")
        };
        let names_a_file = crate::config::files::FILE_KEYS
            .iter()
            .any(|&(s, n)| n == name && if s.is_empty() { top } else { s == section });
        if names_a_file {
            out.push((key, v));
            continue;
        }
        match v {
            toml_edit::Item::ArrayOfTables(a) => {
                for (i, t) in a.iter_mut().enumerate() {
                    file_values(t, &format!("{key}[{i}]"), &name, out);
                }
            }
            toml_edit::Item::Value(toml_edit::Value::Array(a)) => {
                for (i, x) in a.iter_mut().enumerate() {
                    if let Some(t) = x.as_inline_table_mut() {
                        file_values(t, &format!("{key}[{i}]"), &name, out);
                    }
                }
            }
            other => {
                if let Some(t) = other.as_table_like_mut() {
                    file_values(t, &key, &name, out);
                }
            }
        }
    }
}

#[cfg(test)]
mod bundle_tests {
    use super::bundle_inputs;

    /// Every file key at any depth is copied once per folder and renamed, comments and
    /// layout kept; relative paths, non-file keys and unreadable files are left as they are.
    #[test]
    fn bundle_inputs_copies_each_named_file_once_per_folder() {
        let t = tempfile::tempdir().unwrap();
        let records = t.path().join("dims.csv");
        let table = t.path().join("alpha.csv");
        std::fs::write(&records, "length,width\n0.4,0.2\n").unwrap();
        std::fs::write(&table, "t,alpha_deg\n0,0\n").unwrap();
        let (r, a) = (records.display(), table.display());
        let scenario = format!(
            "# heading kept\n[mix]\nrecords = \"{r}\" # the day's log\nlength = 1\n\n\
             [machine.drive]\ntable = \"{a}\"\n\n[line]\narrivals = \"log.csv\"\n\n\
             [[line.diverters]]\nmachine = {{ drive = {{ table = \"{a}\" }} }}\n\n\
             [[line.diverters]]\n[line.diverters.machine.drive]\ntable = \"/nonexistent/x.csv\"\n"
        );
        let mut files = vec![
            ("scenario.toml".to_string(), scenario.clone().into_bytes()),
            (
                "largest_stroke.toml".to_string(),
                scenario.clone().into_bytes(),
            ),
            ("runs/one.toml".to_string(), scenario.into_bytes()),
            ("input_mix_records.csv".to_string(), b"taken".to_vec()),
        ];
        let added = bundle_inputs(&mut files);
        let text = String::from_utf8(files[0].1.clone()).unwrap();
        assert!(text.starts_with("# heading kept\n"), "{text}");
        assert!(
            text.contains("records = \"input_mix_records_2.csv\" # the day's log"),
            "{text}"
        );
        assert!(
            text.contains("table = \"input_machine_drive_table.csv\""),
            "{text}"
        );
        assert!(text.contains("arrivals = \"log.csv\""), "relative: kept");
        assert!(text.contains("/nonexistent/x.csv"), "unreadable: kept");
        assert!(!text.contains(&a.to_string()), "{text}");
        assert_eq!(files[1].1, files[0].1, "the same copies for a second file");
        // Two copies at the top (records, drive table), two in runs/.
        assert_eq!(
            added,
            4,
            "{:?}",
            files.iter().map(|f| &f.0).collect::<Vec<_>>()
        );
        let named = |n: &str| files.iter().find(|f| f.0 == n).map(|f| f.1.clone());
        assert_eq!(named("input_mix_records.csv").unwrap(), b"taken");
        assert_eq!(
            named("input_mix_records_2.csv").unwrap(),
            b"length,width\n0.4,0.2\n"
        );
        assert!(named("runs/input_mix_records.csv").is_some());
        assert!(named("runs/input_machine_drive_table.csv").is_some());
    }
}
