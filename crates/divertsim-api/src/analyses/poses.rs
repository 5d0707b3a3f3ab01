//! The views of a parcel's pose that several analyses show: one line of text, JSON with
//! the scenario file's keys, the scenario file of a worst pose; and an overload ratio judged
//! against its limit in words. The searched worst case, `check`, the capacity map, the
//! overload curve, the optimiser and `replicate` all show poses the same way.

use crate::config::{self, Loaded};
use crate::contract::Error;
use divertsim_core::analysis::design::worst_case::{Pose, WorstCase, WorstObjective};
use serde_json::{json, Value};

/// A pose as JSON (the keys of the scenario file where there is one).
pub fn pose_json(p: &Pose) -> Value {
    let mut v = json!({
        "length": p.length,
        "width": p.width,
        "mass": p.mass,
        "angle_deg": p.angle_deg,
        "offset": p.offset,
        "phase": p.phase,
        "belt_speed_scale": p.belt_speed_scale,
        "belt_friction_scale": p.belt_friction_scale,
        "arm_friction": p.arm_friction,
        "restitution": p.restitution,
    });
    if let Some(h) = p.height {
        v["height"] = json!(h);
    }
    v
}

/// An overload ratio S/S_fall judged in words against its limit (1 − the overload margin):
/// "within the limit 1" or "EXCEEDS the limit 1".
pub fn against_limit(ratio: f64, limit: f64) -> String {
    match ratio <= limit {
        true => format!("within the limit {limit}"),
        false => format!("EXCEEDS the limit {limit}"),
    }
}

/// A pose in one line.
pub fn pose_text(p: &Pose) -> String {
    format!("{}, δt = {:+.4} s", pose_text_no_phase(p), p.phase)
}

/// A pose in one line, without the arrival phase (where the R_s it gives is shown instead).
pub fn pose_text_no_phase(p: &Pose) -> String {
    let height = p.height.map(|h| format!(" × {h:.3}")).unwrap_or_default();
    let mut s = format!(
        "{:.3} × {:.3}{height} m, {:.2} kg, φ = {:.1}°, ΔP = {:.3} m",
        p.length, p.width, p.mass, p.angle_deg, p.offset
    );
    if p.belt_speed_scale != 1.0 {
        s += &format!(", v × {:.4}", p.belt_speed_scale);
    }
    if p.belt_friction_scale != 1.0 {
        s += &format!(", μ_b × {:.4}", p.belt_friction_scale);
    }
    s + &format!(", μ_a = {:.3}, e* = {:.3}", p.arm_friction, p.restitution)
}

/// The scenario file of a worst pose, with a heading that says what it is.
pub fn pose_toml(
    loaded: &Loaded,
    setting: &divertsim_core::model::params::Scenario,
    w: &WorstCase,
) -> Result<String, Error> {
    let file = config::pose_file(&loaded.file, setting, &w.pose);
    let what = match w.objective {
        WorstObjective::Impulse => format!("the largest impulse found, S/S_fall = {}", w.value),
        WorstObjective::Reserve => format!("the smallest divert reserve found, d = {} m", w.value),
        WorstObjective::Torque => format!(
            "the largest peak drive torque found, {} N·m at the arm",
            w.value
        ),
    };
    config::to_toml(
        &file,
        &format!(
            "Written by `divertsim worst-case`: {what}.\n`divertsim simulate` on this file reproduces the run exactly."
        ),
    )
}
