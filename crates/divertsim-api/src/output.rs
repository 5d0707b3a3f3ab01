//! Output formats: the JSON summary, the trajectory CSV and the readable summary (the
//! output directory itself is the CLI's `outdir`).

use crate::config::ScenarioFile;
use divertsim_core::model::params::Scenario;
use divertsim_core::sim::{SimResult, State};
use serde_json::{json, Value};
use std::fmt::Write as _;

/// The summary object of `--json` and `summary.json`.
pub fn summary_json(scenario: &Scenario, result: &SimResult) -> Value {
    json!({
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
