//! `divertsim track`: read a filmed marker track (CSV, pixels or metres) through the
//! scenario's `[camera]` into the machine frame, check it, and report it; or, with
//! `--synthesize`, write the track a camera would record of a simulated run. Also the
//! loading of tracks with their scenarios that `compare` and `calibrate` share.

use std::path::{Path, PathBuf};

use serde_json::json;

use super::common::{self, OutputArgs, ScenarioArgs};
use divertsim_api::analyses::calibration::{self, track_name, LoadedTrack};
use divertsim_api::config::Problem;
use divertsim_api::tracks;

/// How tracks are read.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are --help text: [m] is a unit
#[derive(Debug, Clone, clap::Args)]
pub struct TrackArgs {
    /// A tracked marker path (CSV: t or frame, then u, v [px] or x, y [m]; `# set KEY=VALUE`
    /// comment lines give the experiment's own settings, applied after --set: what was
    /// filmed wins over the command line). Repeatable.
    #[arg(long = "track", value_name = "FILE")]
    pub tracks: Vec<PathBuf>,
    /// Largest gap between consecutive points, in frame intervals, before the track is
    /// refused as broken.
    #[arg(long, value_name = "FRAMES", default_value_t = 3.0)]
    pub max_gap: f64,
}

/// Read every track with its scenario ([`calibration::load_tracks`]), problems keyed by
/// their flags.
pub fn load_tracks(
    scenario: &ScenarioArgs,
    args: &TrackArgs,
    problems: &mut Vec<Problem>,
) -> Vec<LoadedTrack> {
    let mut found = Vec::new();
    let tracks = calibration::load_tracks(
        scenario.scenario.as_deref(),
        &scenario.sets,
        scenario.load_options(),
        &args.tracks,
        args.max_gap,
        &mut found,
    );
    problems.extend(crate::flags::flags(found));
    tracks
}

#[allow(rustdoc::broken_intra_doc_links)] // doc comments are --help text: [m] is a unit
#[derive(Debug, clap::Args)]
pub struct TrackCmdArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub tracks: TrackArgs,
    /// Instead of reading a track, write FILE: the pixel track the scenario's camera would
    /// record of the simulated run (25 fps by default, whole pixels), starting --lead s
    /// before the arm and ending --tail s after the run.
    #[arg(long, value_name = "FILE", conflicts_with = "tracks")]
    pub synthesize: Option<PathBuf>,
    /// With --synthesize: seconds of video before the arm starts.
    #[arg(long, default_value_t = 0.2, value_name = "S")]
    pub lead: f64,
    /// With --synthesize: seconds of video after the run's end.
    #[arg(long, default_value_t = 0.1, value_name = "S")]
    pub tail: f64,
    /// With --synthesize: keep sub-pixel positions (no rounding).
    #[arg(long)]
    pub exact: bool,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// `divertsim track`.
pub fn run(args: &TrackCmdArgs) -> i32 {
    if let Some(file) = &args.synthesize {
        return synthesize_cmd(args, file);
    }
    let mut problems = common::out_problems(&args.output);
    let loaded = load_tracks(&args.scenario, &args.tracks, &mut problems);
    if let Err(code) = common::check(problems) {
        return code;
    }
    let reports: Vec<serde_json::Value> = loaded.iter().map(calibration::track_summary).collect();
    if let Some(dir) = &args.output.out {
        let mut files: Vec<(String, Vec<u8>)> = loaded
            .iter()
            .map(|t| {
                (
                    format!("{}_m.csv", track_name(&t.path)),
                    calibration::track_csv(t).unwrap_or_default(),
                )
            })
            .collect();
        // The --json object with every track's scenario (its `# set` lines applied), and the
        // scenario the tracks were read with.
        let names: Vec<String> = loaded.iter().map(|t| track_name(&t.path)).collect();
        let runs: Vec<(&str, &divertsim_api::config::ScenarioFile)> = names
            .iter()
            .zip(&loaded)
            .map(|(n, t)| (n.as_str(), &t.loaded.file))
            .collect();
        let summary =
            divertsim_api::output::describe_runs(json!({"tracks": reports}), "track", &runs);
        files.push(("summary.json".into(), common::json_bytes(&summary)));
        let s = &args.scenario;
        match divertsim_api::config::load_with(s.scenario.as_deref(), &s.sets, s.load_options()) {
            Ok(base) => files.push(divertsim_api::output::scenario_toml("track", &base.file)),
            Err(p) => return common::check(crate::flags::flags(p.0)).err().unwrap_or(2),
        }
        let code = common::write_outputs(dir, files, |_| Ok(()));
        if code != 0 {
            return code;
        }
    }
    if args.output.json {
        common::emit_json(&json!({"tracks": reports}));
    } else {
        let mut s = String::new();
        for r in &reports {
            s += &format!(
                "{}: {} points ({}), {:.3} s; x {:.3}…{:.3} m, y {:.3}…{:.3} m; ±{:.2} mm per axis from the pixel\n",
                r["track"].as_str().unwrap_or(""),
                r["points"],
                r["units"].as_str().unwrap_or(""),
                r["duration_s"].as_f64().unwrap_or(f64::NAN),
                r["x_range_m"][0].as_f64().unwrap_or(f64::NAN),
                r["x_range_m"][1].as_f64().unwrap_or(f64::NAN),
                r["y_range_m"][0].as_f64().unwrap_or(f64::NAN),
                r["y_range_m"][1].as_f64().unwrap_or(f64::NAN),
                1e3 * r["quantisation_sigma_m"][0].as_f64().unwrap_or(f64::NAN),
            );
        }
        common::emit(&s);
    }
    0
}

fn synthesize_cmd(args: &TrackCmdArgs, file: &Path) -> i32 {
    let mut problems = Vec::new();
    for (key, v) in [("--lead", args.lead), ("--tail", args.tail)] {
        if !(v.is_finite() && (0.0..=60.0).contains(&v)) {
            problems.push(Problem::new(
                key,
                format!("{v} is out of range; allowed: [0, 60] s"),
            ));
        }
    }
    let loaded = common::load_scenario(&args.scenario, false);
    let loaded = match common::checked(loaded, problems) {
        Ok(l) => l,
        Err(code) => return code,
    };
    let camera = match loaded.file.camera.map() {
        Ok(c) => c,
        Err(p) => return common::check(vec![p]).err().unwrap_or(2),
    };
    let (r, frames, sets) =
        match calibration::synthesize_track(&loaded, &camera, args.lead, args.tail, !args.exact) {
            Ok(x) => x,
            Err(e) => {
                eprintln!("error: {e}");
                return 2;
            }
        };
    let frames = &frames;
    let text = tracks::pixel_csv(&sets, frames);
    let written = crate::outdir::write_file(file, &mut |tmp| {
        std::fs::write(tmp, &text).map_err(|e| e.to_string())
    });
    if let Err(e) = written {
        eprintln!("error: cannot write {}: {e}", file.display());
        return 1;
    }
    if !args.output.quiet {
        eprintln!(
            "wrote {} frames of the simulated run ({}) to {}",
            frames.len(),
            r.outcome.label(),
            file.display()
        );
    }
    0
}
