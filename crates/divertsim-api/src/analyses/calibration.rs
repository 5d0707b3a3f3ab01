//! Calibration from video: filmed marker tracks read through the scenario's `[camera]` into
//! the machine frame ([`load_tracks`]), compared with the simulated marker path
//! ([`compare_track`], `divertsim_core::analysis::track`), and unknown material and machine
//! values fitted to them with profile-likelihood intervals
//! (`divertsim_core::analysis::calibration`), written back as a scenario file that runs
//! directly ([`calibrated_toml`]).

use std::path::{Path, PathBuf};

use crate::config::{self, BeltFrictionConfig, LoadOptions, Loaded, Problem};
use crate::tracks::{self, TrackFile};
use divertsim_core::analysis::calibration::{Calibration, CalibrationSettings, FitParameter};
use divertsim_core::analysis::track::{compare, CameraMap, Comparison, Track};
use divertsim_core::model::params::Scenario;
use divertsim_core::sim::{simulate, SimResult};
use glam::DVec2;
use serde_json::{json, Value};

/// The settings of a fit: the values to fit (scenario keys), their search boxes
/// (key, low, high in the key's unit, degrees for the swing), δ of the Huber loss [m], loss
/// evaluations of the global search, its seed, and whether to run the profiles. Problems
/// are keyed `fit`, `bound` and `huber`.
pub fn settings(
    fit: &[String],
    bounds: &[(String, f64, f64)],
    huber: f64,
    budget: u64,
    seed: u64,
    profiles: bool,
) -> Result<CalibrationSettings, Vec<Problem>> {
    let mut problems = Vec::new();
    let mut params = Vec::new();
    for key in fit.iter().map(|k| k.trim()).filter(|k| !k.is_empty()) {
        match FitParameter::from_key(key) {
            Some(p) if !params.contains(&p) => params.push(p),
            Some(_) => problems.push(Problem::new("fit", format!("{key} is given twice"))),
            None => problems.push(Problem::new(
                "fit",
                format!(
                    "{key} cannot be fitted; allowed: {}",
                    FitParameter::ALL.map(FitParameter::key).join(", ")
                ),
            )),
        }
    }
    if params.is_empty() {
        problems.push(Problem::new("fit", "no value to fit"));
        return Err(problems);
    }
    let mut s = CalibrationSettings::new(params.clone());
    for (key, lo, hi) in bounds {
        let key = key.trim();
        let Some(k) = params.iter().position(|p| p.key() == key) else {
            problems.push(Problem::new(
                "bound",
                format!("{key} is not among the fitted values"),
            ));
            continue;
        };
        let (dlo, dhi) = FitParameter::default_bounds(params[k]);
        let (lo, hi) = (from_shown(params[k], *lo), from_shown(params[k], *hi));
        // The scenario file's own ranges, so that the fitted file loads.
        let (floor, cap) = match params[k] {
            FitParameter::BeltFriction => (1e-3, 2.0),
            FitParameter::ArmFriction => (0.0, 1.3),
            FitParameter::Restitution => (0.0, 1.0),
            FitParameter::ArmLength => (0.01, 10.0),
            FitParameter::CycleTime => (0.1, 60.0),
            FitParameter::MaxSwing => (1f64.to_radians(), 90f64.to_radians()),
        };
        if !(lo.is_finite() && hi.is_finite() && lo < hi && lo >= floor && hi <= cap) {
            problems.push(Problem::new(
                "bound",
                format!(
                    "{key}: [{}, {}] is not allowed; allowed: finite, LO < HI, within [{}, {}] (default {}:{})",
                    shown(params[k], lo),
                    shown(params[k], hi),
                    shown(params[k], floor),
                    shown(params[k], cap),
                    shown(params[k], dlo),
                    shown(params[k], dhi)
                ),
            ));
            continue;
        }
        s.bounds[k] = (lo, hi);
    }
    if !(huber > 0.0 && huber.is_finite()) {
        problems.push(Problem::new(
            "huber",
            format!("{huber} is out of range; allowed: > 0 m"),
        ));
    }
    s.huber = huber;
    s.global_evaluations = budget as usize;
    s.seed = seed;
    s.profiles = profiles;
    if problems.is_empty() {
        Ok(s)
    } else {
        Err(problems)
    }
}

/// One track with the scenario of its experiment.
pub struct LoadedTrack {
    pub path: PathBuf,
    pub file: TrackFile,
    pub track: Track,
    pub loaded: Loaded,
    pub camera: CameraMap,
    pub marker_offset: DVec2,
}

/// A short name for a track: its file stem.
pub fn track_name(p: &Path) -> String {
    p.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| p.display().to_string())
}

/// Read every track and load its scenario (SCENARIO, --set, then the track's `# set`
/// lines); every problem collected, each naming its track.
pub fn load_tracks(
    scenario: Option<&Path>,
    sets: &[String],
    options: LoadOptions,
    track_files: &[PathBuf],
    max_gap: f64,
    problems: &mut Vec<Problem>,
) -> Vec<LoadedTrack> {
    let mut out = Vec::new();
    if track_files.is_empty() {
        problems.push(Problem {
            key: "track".into(),
            message: "give at least one track file".into(),
        });
    }
    if !(max_gap >= 1.0 && max_gap.is_finite()) {
        problems.push(Problem {
            key: "max_gap".into(),
            message: format!("{} is out of range; allowed: ≥ 1 frame interval", max_gap),
        });
        return out;
    }
    // The scenario alone first: its problems once, not once per track.
    if let Err(e) = config::load_with(scenario, sets, options) {
        problems.extend(e.0);
        return out;
    }
    for path in track_files {
        let track_problem = |e: String| Problem {
            key: "track".into(),
            message: format!("{}: {e}", path.display()),
        };
        // The track's own `# set` lines first: its camera reads its data.
        let own = match tracks::read_sets(path) {
            Ok(s) => s,
            Err(e) => {
                problems.push(track_problem(e));
                continue;
            }
        };
        let sets: Vec<String> = sets.iter().chain(&own).cloned().collect();
        let loaded =
            match config::load_with(scenario, &sets, options).and_then(super::fixed_trigger_only) {
                Ok(l) => l,
                Err(e) => {
                    for mut p in e.0 {
                        p.message = format!(
                            "{} (with the `# set` lines of {})",
                            p.message,
                            path.display()
                        );
                        problems.push(p);
                    }
                    continue;
                }
            };
        let cam = &loaded.file.camera;
        let file = match tracks::read(path, cam.frame_rate, cam.image_size, max_gap) {
            Ok(f) => f,
            Err(e) => {
                problems.push(track_problem(e));
                continue;
            }
        };
        let camera = match loaded.file.camera.map() {
            Ok(c) => c,
            Err(p) => {
                problems.push(p);
                continue;
            }
        };
        let track = file.to_track(&camera);
        out.push(LoadedTrack {
            path: path.clone(),
            marker_offset: DVec2::from(loaded.file.camera.marker_offset),
            file,
            track,
            loaded,
            camera,
        });
    }
    out
}

/// Relative belt-speed difference that flags a track.
pub const SPEED_TOLERANCE: f64 = 0.05;

/// Why a track does not match its scenario (empty: it matches).
pub fn mismatches(c: &Comparison, scenario: &Scenario, tolerance: f64) -> Vec<String> {
    let mut f = Vec::new();
    if c.rms > tolerance {
        f.push(format!(
            "the paths differ: RMS {:.4} m > {tolerance} m (x {:.4}, y {:.4})",
            c.rms, c.rms_x, c.rms_y
        ));
    }
    if !c.verdicts_agree() {
        f.push(format!(
            "the verdicts differ: measured {}, simulated {}",
            if c.measured_diverted {
                "diverted"
            } else {
                "not diverted"
            },
            if c.simulated_diverted {
                "diverted"
            } else {
                "not diverted"
            }
        ));
    }
    if let Some(v) = c.measured_speed {
        let want = scenario.machine.belt_speed;
        if (v - want).abs() > SPEED_TOLERANCE * want.abs().max(1e-9) {
            f.push(format!(
                "the belt speed on the track is {v:.3} m/s, the scenario's {want} m/s"
            ));
        }
    }
    f
}

/// JSON of one comparison.
pub fn comparison_json(name: &str, c: &Comparison, flags: &[String]) -> Value {
    json!({
        "track": name,
        "time_offset_s": c.offset,
        "points": c.points,
        "points_after_run_end": c.after_end,
        "rms_m": c.rms,
        "rms_x_m": c.rms_x,
        "max_x_m": c.max_x,
        "rms_y_m": c.rms_y,
        "max_y_m": c.max_y,
        "frechet_m": c.frechet,
        "measured_diverted": c.measured_diverted,
        "simulated_diverted": c.simulated_diverted,
        "measured_belt_speed_m_s": c.measured_speed,
        "matches": flags.is_empty(),
        "flags": flags,
    })
}

/// A track's points on the simulation clock, for a report: (t − t₀, x, y).
pub fn measured_points(t: &LoadedTrack, c: &Comparison) -> Vec<(f64, f64, f64)> {
    t.track
        .times
        .iter()
        .zip(&t.track.points)
        .map(|(tv, p)| (tv - c.offset, p.x, p.y))
        .collect()
}

/// Simulate and compare one track.
pub fn compare_track(t: &LoadedTrack) -> (SimResult, Comparison) {
    let r = simulate(&t.loaded.scenario);
    let c = compare(&t.track, &t.loaded.scenario, &r, t.marker_offset);
    (r, c)
}

/// A value in its key's unit (the swing in degrees).
pub fn shown(p: FitParameter, v: f64) -> f64 {
    if p == FitParameter::MaxSwing {
        v.to_degrees()
    } else {
        v
    }
}

pub fn from_shown(p: FitParameter, v: f64) -> f64 {
    if p == FitParameter::MaxSwing {
        v.to_radians()
    } else {
        v
    }
}

pub fn report_json(c: &Calibration, names: &[String]) -> Value {
    json!({
        "values": c.parameters.iter().enumerate().map(|(k, p)| {
            let prof = c.profiles.get(k);
            json!({
                "key": p.key(),
                "value": shown(*p, c.values[k]),
                "interval_95": prof.map(|pr| [shown(*p, pr.interval.0), shown(*p, pr.interval.1)]),
                "identifiable": prof.map(|pr| pr.identifiable),
                "profile": prof.map(|pr| pr.points.iter().map(|(v, d)| json!([shown(*p, *v), d])).collect::<Vec<_>>()),
            })
        }).collect::<Vec<_>>(),
        "global_search_values": c.parameters.iter().zip(&c.global_values).map(|(p, v)| shown(*p, *v)).collect::<Vec<_>>(),
        "loss": c.loss,
        "noise_m": c.noise,
        "residual_correlation": c.correlation,
        "tracks": c.cases.iter().zip(names).map(|(f, n)| json!({
            "track": n,
            "time_offset_s": f.offset,
            "rms_m": f.rms,
            "max_m": f.max,
            "points": f.points,
        })).collect::<Vec<_>>(),
        "simulations": c.simulations,
    })
}

/// The scenario file with the fitted values, standing alone.
pub fn calibrated_toml(base: &Loaded, c: &Calibration) -> Result<String, String> {
    let mut f = config::standalone(&base.file);
    for (p, v) in c.parameters.iter().zip(&c.values) {
        match p {
            FitParameter::BeltFriction => {
                f.materials.belt_friction = BeltFrictionConfig::Constant(*v)
            }
            FitParameter::ArmFriction => f.materials.arm_friction = *v,
            FitParameter::Restitution => f.materials.restitution = *v,
            FitParameter::ArmLength => f.machine.arm_length = *v,
            FitParameter::CycleTime => f.machine.cycle_time = *v,
            FitParameter::MaxSwing => f.machine.drive.max_swing_deg = Some(v.to_degrees()),
        }
    }
    let fitted: Vec<String> = c
        .parameters
        .iter()
        .zip(&c.values)
        .map(|(p, v)| format!("{} = {}", p.key(), shown(*p, *v)))
        .collect();
    config::to_toml(
        &f,
        &format!(
            "Written by `divertsim calibrate` from {} track(s): {}.\n`divertsim simulate` runs this file directly.",
            c.cases.len(),
            fitted.join(", ")
        ),
    )
}
