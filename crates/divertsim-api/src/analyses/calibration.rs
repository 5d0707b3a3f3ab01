//! Calibration from video: filmed marker tracks read through the scenario's `[camera]` into
//! the machine frame ([`load_tracks`]), compared with the simulated marker path
//! ([`compare_track`], `divertsim_core::analysis::measurement::track`), and unknown material and machine
//! values fitted to them with profile-likelihood intervals
//! (`divertsim_core::analysis::measurement::calibration`), written back as a scenario file that runs
//! directly ([`calibrated_toml`]).

use std::path::{Path, PathBuf};

use crate::config::{self, BeltFrictionConfig, LoadOptions, Loaded, Problem};
use crate::contract::Error;
use crate::tracks::{self, TrackFile};
use divertsim_core::analysis::measurement::calibration::{
    Calibration, CalibrationCase, CalibrationSettings, FitParameter,
};
use divertsim_core::analysis::measurement::track::{
    compare_pinned, CameraMap, Comparison, MeasuredVerdict, Track,
};
use divertsim_core::model::params::Scenario;
use divertsim_core::sim::{simulate, SimResult};
use glam::DVec2;
use serde_json::{json, Value};

/// Problems of a fit with its tracks (key `fit`): the swing cannot be fitted where a
/// crank-rocker's links fix it.
pub fn check_fit(tracks: &[LoadedTrack], settings: &CalibrationSettings) -> Vec<Problem> {
    let links = tracks.iter().any(|t| {
        let d = &t.loaded.file.machine.drive;
        d.crank.is_some() || d.ground.is_some()
    });
    if links && settings.parameters.contains(&FitParameter::MaxSwing) {
        vec![Problem::new(
            "fit",
            "machine.drive.max_swing_deg cannot be fitted for a crank-rocker with given crank and ground links (the swing follows from them)",
        )]
    } else {
        Vec::new()
    }
}

/// The tracks' names and the fit's cases (scenario, track, marker offset).
pub fn cases(tracks: &[LoadedTrack]) -> (Vec<String>, Vec<CalibrationCase>) {
    let names: Vec<String> = tracks.iter().map(|t| track_name(&t.path)).collect();
    let cases = tracks
        .iter()
        .zip(&names)
        .map(|(t, n)| CalibrationCase {
            name: n.clone(),
            scenario: t.loaded.scenario.clone(),
            track: t.track.clone(),
            marker_offset: t.marker_offset,
            arm_start: t.file.arm_start,
        })
        .collect();
    (names, cases)
}

/// Simulations a fit runs at most: each loss evaluation runs every track; the global
/// search, the compass search (up to half as many more), a local fit, and with profiles
/// about 14 local fits per value (a local fit takes some tens of evaluations).
pub fn estimated_evaluations(settings: &CalibrationSettings, tracks: usize) -> u64 {
    let local = 40 * (settings.parameters.len() + 1);
    let evaluations = settings.global_evaluations * 3 / 2
        + local
        + if settings.profiles {
            14 * settings.parameters.len() * local
        } else {
            0
        };
    (evaluations * tracks) as u64
}

/// Simulations a fit runs whatever it finds: the global search's first generation over
/// every track (the search may converge after it).
pub fn least_evaluations(settings: &CalibrationSettings, tracks: usize) -> u64 {
    let population = divertsim_core::analysis::measurement::calibration::global_population(
        settings.parameters.len(),
    );
    (population.min(settings.global_evaluations.max(population)) * tracks) as u64
}

/// What a track holds: its points, units, duration, extent, quantisation σ and `# set`
/// lines (`divertsim track --json`).
pub fn track_summary(t: &LoadedTrack) -> Value {
    let tr = &t.track;
    let n = tr.points.len();
    let (lo, hi) = tr.points.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(a, b), p| (a.min(*p), b.max(*p)),
    );
    let sigma = tr.sigma.iter().fold(DVec2::ZERO, |m, s| m.max(*s));
    json!({
        "track": t.path.display().to_string(),
        "points": n,
        "units": if t.file.pixels { "px" } else { "m" },
        "duration_s": tr.times[n - 1] - tr.times[0],
        "x_range_m": [lo.x, hi.x],
        "y_range_m": [lo.y, hi.y],
        "quantisation_sigma_m": [sigma.x, sigma.y],
        "sets": t.file.sets,
    })
}

/// A track in machine metres with its σ per point (`NAME_m.csv`).
pub fn track_csv(t: &LoadedTrack) -> Result<Vec<u8>, csv::Error> {
    let rows: Vec<Vec<String>> = (0..t.track.times.len())
        .map(|i| {
            let (p, s) = (t.track.points[i], t.track.sigma[i]);
            vec![
                t.track.times[i].to_string(),
                p.x.to_string(),
                p.y.to_string(),
                s.x.to_string(),
                s.y.to_string(),
            ]
        })
        .collect();
    crate::output::csv_bytes(&["t_s", "x_m", "y_m", "sigma_x_m", "sigma_y_m"], &rows)
}

/// Frames of a filmed track: (time \[s], pixel (u, v)).
pub type Frames = Vec<(f64, [f64; 2])>;

/// The track a camera would record of the scenario's run: the run, the frames (time, pixel)
/// of the longest stretch inside the image (`lead`/`tail` seconds around the run,
/// quantised to whole pixels unless `quantise` is false), and the `# set` lines of the
/// experiment so that compare and calibrate replay it from any base scenario.
pub fn synthesize_track(
    loaded: &Loaded,
    camera: &CameraMap,
    lead: f64,
    tail: f64,
    quantise: bool,
) -> Result<(SimResult, Frames, Vec<String>), Error> {
    let cam = &loaded.file.camera;
    let s = &loaded.scenario;
    let r = simulate(s);
    let frames = divertsim_core::analysis::measurement::track::synthesize(
        s,
        &r,
        DVec2::from(cam.marker_offset),
        camera,
        cam.frame_rate,
        lead,
        tail,
        quantise,
    );
    // A camera sees only its image: the longest stretch of frames inside it.
    let inside = |p: &[f64; 2]| {
        (0.0..=cam.image_size[0]).contains(&p[0]) && (0.0..=cam.image_size[1]).contains(&p[1])
    };
    let mut best = (0, 0);
    let mut start = None;
    for (k, f) in frames.iter().enumerate() {
        match (inside(&f.1), start) {
            (true, None) => start = Some(k),
            (false, Some(a)) => {
                if k - a > best.1 - best.0 {
                    best = (a, k);
                }
                start = None;
            }
            _ => {}
        }
    }
    if let Some(a) = start {
        if frames.len() - a > best.1 - best.0 {
            best = (a, frames.len());
        }
    }
    let frames = frames[best.0..best.1].to_vec();
    if frames.len() < tracks::MIN_POINTS {
        return Err(Error::Invalid(vec![Problem::new(
            "camera",
            format!(
                "the marker is inside the {}×{} image in only {} frames; move camera.origin_px or change camera.px_per_m",
                cam.image_size[0],
                cam.image_size[1],
                frames.len()
            ),
        )]));
    }
    let f = &loaded.file;
    let mut sets = vec![
        format!("parcel.length={}", f.parcel.length),
        format!("parcel.width={}", f.parcel.width),
        format!("parcel.height={}", f.parcel.height),
        format!("parcel.mass={}", f.parcel.mass),
        format!("parcel.offset={}", f.parcel.offset),
        format!("parcel.angle_deg={}", f.parcel.angle_deg),
        format!("parcel.spin={}", f.parcel.spin),
        format!("machine.belt_speed={}", f.machine.belt_speed),
        format!("machine.cycle_time={}", f.machine.cycle_time),
        format!("machine.start_position={}", f.machine.start_position),
        format!("machine.light_barrier={}", f.machine.light_barrier),
    ];
    if let Some([vx, vy]) = f.parcel.velocity {
        sets.push(format!("parcel.velocity=[{vx}, {vy}]"));
    }
    Ok((r, frames, sets))
}

/// The settings of a fit: the values to fit (scenario keys), their search boxes
/// (key, low, high in the key's unit, degrees for the swing), δ of the Huber loss \[m], loss
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
#[derive(Debug, Clone)]
pub struct LoadedTrack {
    pub path: PathBuf,
    pub file: TrackFile,
    pub track: Track,
    pub loaded: Loaded,
    pub camera: CameraMap,
    pub marker_offset: DVec2,
}

/// The warnings of the tracks as read: a track without `# set` lines is simulated with the
/// scenario's own parcel and setting, which is rarely the one filmed.
pub fn track_warnings(tracks: &[LoadedTrack]) -> Vec<String> {
    tracks
        .iter()
        .filter(|t| t.file.sets.is_empty())
        .map(|t| {
            format!(
                "track {} has no `# set` lines: it is simulated with the scenario's own parcel and setting (state the filmed ones as `# set parcel.length=0.4` …)",
                track_name(&t.path)
            )
        })
        .collect()
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
    let load = |own: &[String]| {
        let all: Vec<String> = sets.iter().chain(own).cloned().collect();
        config::load_with(scenario, &all, options)
    };
    load_tracks_with(&load, track_files, max_gap, problems)
}

/// [`load_tracks`] over a loaded scenario: each track's `# set` lines applied to its
/// resolved file, as `--set` would to the file.
pub fn load_tracks_on(
    scenario: &Loaded,
    track_files: &[PathBuf],
    max_gap: f64,
    problems: &mut Vec<Problem>,
) -> Vec<LoadedTrack> {
    // The resolved file turned into a table once, a variant per track.
    let base = match config::ScenarioBuilder::resolved(scenario).merged() {
        Ok(b) => b,
        Err(p) => {
            problems.extend(p.0);
            return Vec::new();
        }
    };
    let load = |own: &[String]| base.clone().sets(own).load();
    load_tracks_with(&load, track_files, max_gap, problems)
}

/// Every track with the scenario `load` gives for its `# set` lines (`&[]`: the scenario
/// alone, checked first so that its problems are listed once).
fn load_tracks_with(
    load: &dyn Fn(&[String]) -> Result<Loaded, config::Problems>,
    track_files: &[PathBuf],
    max_gap: f64,
    problems: &mut Vec<Problem>,
) -> Vec<LoadedTrack> {
    let mut out = Vec::new();
    if track_files.is_empty() {
        problems.push(Problem::new("track", "give at least one track file"));
    }
    if !(max_gap >= 1.0 && max_gap.is_finite()) {
        problems.push(Problem::new(
            "max_gap",
            format!("{} is out of range; allowed: ≥ 1 frame interval", max_gap),
        ));
        return out;
    }
    // The scenario alone first: its problems once, not once per track.
    if let Err(e) = load(&[]) {
        problems.extend(e.0);
        return out;
    }
    for path in track_files {
        let track_problem = |e: String| Problem::new("track", format!("{}: {e}", path.display()));
        // The track's own `# set` lines first: its camera reads its data.
        let own = match tracks::read_sets(path) {
            Ok(s) => s,
            Err(e) => {
                problems.push(track_problem(e));
                continue;
            }
        };
        let loaded = match load(&own).and_then(super::fixed_trigger_only) {
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

/// Why a track does not match its scenario (empty: it matches); `verdict`: whether the
/// verdicts must agree (a track that cannot tell never disagrees).
pub fn mismatches(
    c: &Comparison,
    scenario: &Scenario,
    tolerance: f64,
    verdict: bool,
) -> Vec<String> {
    let mut f = Vec::new();
    if c.rms > tolerance {
        f.push(format!(
            "the paths differ: RMS {:.4} m > {tolerance} m (x {:.4}, y {:.4})",
            c.rms, c.rms_x, c.rms_y
        ));
    }
    if verdict && c.verdicts_agree() == Some(false) {
        f.push(format!(
            "the verdicts differ: measured {}, simulated {}",
            c.measured.label().replace('_', " "),
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

/// comparison.csv: a row per track (name, comparison, mismatch flags).
pub fn comparison_csv(rows: &[(&str, &Comparison, &[String])]) -> Result<Vec<u8>, csv::Error> {
    let rows: Vec<Vec<String>> = rows
        .iter()
        .map(|(n, c, f)| {
            vec![
                n.to_string(),
                c.offset.to_string(),
                c.points.to_string(),
                c.rms.to_string(),
                c.rms_x.to_string(),
                c.max_x.to_string(),
                c.rms_y.to_string(),
                c.max_y.to_string(),
                c.frechet.to_string(),
                c.measured.label().to_string(),
                c.simulated_diverted.to_string(),
                c.measured_speed.map(|v| v.to_string()).unwrap_or_default(),
                f.is_empty().to_string(),
            ]
        })
        .collect();
    crate::output::csv_bytes(
        &[
            "track",
            "time_offset_s",
            "points",
            "rms_m",
            "rms_x_m",
            "max_x_m",
            "rms_y_m",
            "max_y_m",
            "frechet_m",
            "measured_verdict",
            "simulated_diverted",
            "measured_belt_speed_m_s",
            "matches",
        ],
        &rows,
    )
}

/// The readable table of a comparison: a line per track, its mismatch flags, and whether
/// every track matches its scenario within `tolerance` \[m].
pub fn comparison_text(rows: &[(&str, &Comparison, &[String])], tolerance: f64) -> String {
    let verdict = |d: bool| if d { "diverted" } else { "not" };
    let measured = |m: MeasuredVerdict| match m {
        MeasuredVerdict::Diverted => "diverted",
        MeasuredVerdict::NotDiverted => "not",
        MeasuredVerdict::Unknown => "unknown",
    };
    let mut s = format!(
        "{:<16} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}  verdict (measured/simulated)\n",
        "track", "t0 [s]", "RMS [m]", "RMS x", "RMS y", "max [m]", "Fréchet"
    );
    for (n, c, f) in rows {
        s += &format!(
            "{:<16} {:>9.4} {:>9.4} {:>9.4} {:>9.4} {:>9.4} {:>9.4}  {}/{}\n",
            n,
            c.offset,
            c.rms,
            c.rms_x,
            c.rms_y,
            c.max_x.max(c.max_y),
            c.frechet,
            measured(c.measured),
            verdict(c.simulated_diverted),
        );
        for flag in f.iter() {
            s += &format!("  ! {flag}\n");
        }
    }
    let bad = rows.iter().filter(|r| !r.2.is_empty()).count();
    s += &match bad {
        0 => format!("every track matches its scenario (tolerance {tolerance} m)\n"),
        _ => format!(
            "{bad} of {} tracks do not match their scenario\n",
            rows.len()
        ),
    };
    s
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
        "measured_diverted": c.measured.diverted(),
        "measured_verdict": c.measured.label(),
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
    let c = compare_pinned(
        &t.track,
        &t.loaded.scenario,
        &r,
        t.marker_offset,
        t.file.arm_start,
    );
    (r, c)
}

/// A value's symbol, for the influence column.
fn symbol(p: FitParameter) -> &'static str {
    match p {
        FitParameter::BeltFriction => "μ_b",
        FitParameter::ArmFriction => "μ_a",
        FitParameter::Restitution => "e*",
        FitParameter::ArmLength => "R_z [m]",
        FitParameter::CycleTime => "t_c [s]",
        FitParameter::MaxSwing => "α_max [°]",
    }
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
                "robust_interval_95": c.robust_intervals.get(k).copied().flatten()
                    .map(|(lo, hi)| [shown(*p, lo), shown(*p, hi)]),
                "identifiable": prof.map(|pr| pr.identifiable),
                "profile": prof.map(|pr| pr.points.iter().map(|(v, d)| json!([shown(*p, *v), d])).collect::<Vec<_>>()),
            })
        }).collect::<Vec<_>>(),
        "global_search_values": c.parameters.iter().zip(&c.global_values).map(|(p, v)| shown(*p, *v)).collect::<Vec<_>>(),
        "loss": c.loss,
        "noise_m": c.noise,
        "pixel_m": c.pixel,
        "warnings": c.warnings,
        "residual_correlation": c.correlation,
        "tracks": c.cases.iter().zip(names).map(|(f, n)| json!({
            "track": n,
            "time_offset_s": f.offset,
            "rms_m": f.rms,
            "max_m": f.max,
            "points": f.points,
            "outlier": f.outlier,
            "excluded": f.excluded,
            // The change of each value without this track, in its key's unit.
            "influence": c.parameters.iter().zip(&f.influence).map(|(p, d)| {
                (p.key().to_string(), json!(shown(*p, *d)))
            }).collect::<serde_json::Map<String, Value>>(),
        })).collect::<Vec<_>>(),
        "simulations": c.simulations,
    })
}

/// profiles.csv: each fitted value's profile, (key, value in its key's unit, Δχ²).
pub fn profiles_csv(c: &Calibration) -> Result<Vec<u8>, csv::Error> {
    let mut rows = Vec::new();
    for (k, p) in c.parameters.iter().enumerate() {
        if let Some(pr) = c.profiles.get(k) {
            for (v, d) in &pr.points {
                rows.push(vec![
                    p.key().to_string(),
                    shown(*p, *v).to_string(),
                    d.to_string(),
                ]);
            }
        }
    }
    crate::output::csv_bytes(&["key", "value", "delta_chi2"], &rows)
}

/// Each track with its scenario at the fitted values, the run and its comparison.
pub fn fitted_runs(
    tracks: &[LoadedTrack],
    c: &Calibration,
) -> Result<Vec<(LoadedTrack, SimResult, Comparison)>, Error> {
    tracks
        .iter()
        .map(|t| {
            let mut s = t.loaded.scenario.clone();
            for (p, v) in c.parameters.iter().zip(&c.values) {
                p.apply(&mut s, *v).map_err(Error::Failed)?;
            }
            let mut fitted = t.clone();
            fitted.loaded.scenario = s;
            let (r, cmp) = compare_track(&fitted);
            Ok((fitted, r, cmp))
        })
        .collect()
}

/// The readable report of a calibration: the fitted values with their 95 % profile
/// intervals and identifiability, and each track's fit.
pub fn text(c: &Calibration, names: &[String]) -> String {
    let mut s = format!(
        "calibration on {} track(s), {} simulations; noise scale {:.2} mm (residual correlation {:.2}; the tracks' pixel {:.2} mm)\n",
        c.cases.iter().filter(|f| !f.excluded).count(),
        c.simulations,
        1e3 * c.noise,
        c.correlation,
        1e3 * c.pixel
    );
    s += "  value                              fitted   95 % profile interval   95 % model-robust interval\n";
    for (k, p) in c.parameters.iter().enumerate() {
        s += &format!("  {:<30} {:>10.5}", p.key(), shown(*p, c.values[k]));
        if let Some(pr) = c.profiles.get(k) {
            s += &format!(
                "   [{:.5}, {:.5}]   ",
                shown(*p, pr.interval.0),
                shown(*p, pr.interval.1)
            );
            if let Some(Some((lo, hi))) = c.robust_intervals.get(k) {
                s += &format!("   [{:.5}, {:.5}]", shown(*p, *lo), shown(*p, *hi));
            }
            if !pr.identifiable {
                s += if pr.one_sided {
                    "   ! bounded on one side only: the tracks pin it down one way"
                } else {
                    "   ! NOT IDENTIFIABLE: flat profile, the tracks say nothing of it"
                };
            }
        }
        s += "\n";
    }
    for (f, n) in c.cases.iter().zip(names) {
        s += &format!(
            "  track {:<16} RMS {:.4} m, max {:.4} m, t0 {:.4} s ({} points)",
            n, f.rms, f.max, f.offset, f.points
        );
        if f.excluded {
            s += "   ! OUTLIER, left out of the fit";
        } else {
            if !f.influence.is_empty() {
                let moves: Vec<String> = c
                    .parameters
                    .iter()
                    .zip(&f.influence)
                    .map(|(p, d)| format!("{} {:+.4}", symbol(*p), shown(*p, *d)))
                    .collect();
                s += &format!("; without it: {}", moves.join(", "));
            }
            if f.outlier {
                s += "   ! OUTLIER (kept: outliers = flag)";
            }
        }
        s += "\n";
    }
    for w in &c.warnings {
        s += &format!("  ! {w}\n");
    }
    s
}

/// The scenario file with the fitted values, standing alone.
pub fn calibrated_toml(base: &Loaded, c: &Calibration) -> Result<String, Error> {
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
