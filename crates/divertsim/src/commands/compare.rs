//! `divertsim compare`: simulate each track's experiment and compare the simulated marker
//! path with the measured one (`divertsim_core::analysis::measurement::track::compare`): time alignment,
//! RMS and largest errors along and across the belt, the discrete Fréchet distance, the
//! verdicts and the belt speed seen on the track; a track that does not match its scenario
//! (another parcel, another speed) is flagged. Overlays like the paper's Figs 13–15.

use std::path::Path;

use divertsim_core::analysis::measurement::track::{Comparison, MarkerPath};
use divertsim_core::sim::SimResult;
use serde_json::json;

use super::common::{self, OutputArgs, ScenarioArgs};
use super::track::{load_tracks, TrackArgs};
use divertsim_api::analyses::calibration::{
    compare_track, comparison_json, measured_points, mismatches, track_name, LoadedTrack,
};
use divertsim_api::config::Problem;
use divertsim_figures::charts::{self, Chart, HLine, Series, Style};

#[allow(rustdoc::broken_intra_doc_links)] // doc comments are --help text: [m] is a unit
#[derive(Debug, clap::Args)]
pub struct CompareArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub tracks: TrackArgs,
    /// A track matches its scenario when the RMS distance between the measured and
    /// simulated marker is at most this [m], the verdicts agree, and the belt speed on the
    /// track is within 5 % of the scenario's.
    #[arg(long, value_name = "M", default_value_t = 0.02)]
    pub tolerance: f64,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// The overlay of a measured and a simulated marker path (SVG or PNG by extension).
pub fn draw_overlay(
    path: &Path,
    name: &str,
    t: &LoadedTrack,
    result: &SimResult,
    c: &Comparison,
) -> Result<(), String> {
    let s = &t.loaded.scenario;
    // The simulated marker every 5 ms over the track's time span.
    let marker = MarkerPath::new(s, result, t.marker_offset);
    let (t_first, t_last) = (t.track.times[0], t.track.times[t.track.times.len() - 1]);
    let steps = (((t_last - t_first) / 0.005).ceil() as usize).clamp(1, 20_000);
    let dense: Vec<(f64, f64)> = (0..=steps)
        .map(|k| {
            let tv = t_first + (t_last - t_first) * k as f64 / steps as f64;
            let q = marker.at(tv - c.offset);
            (q.x, q.y)
        })
        .collect();
    let p = &s.parcel;
    let chart = Chart {
        title: format!(
            "{name}: {:.2} × {:.2} m at ΔP = {} m; v = {} m/s, t_c = {} s, R_s = {} m",
            p.length,
            p.width,
            p.offset,
            s.machine.belt_speed,
            s.machine.cycle_time,
            s.machine.start_position
        ),
        x_label: "x [m] (along the belt)".into(),
        y_label: "y [m] (across the belt)".into(),
        series: vec![
            Series::new("simulated marker", dense, Style::Line),
            Series::new(
                format!("measured ({} points)", t.track.points.len()),
                t.track.points.iter().map(|q| (q.x, q.y)).collect(),
                Style::Points,
            ),
        ],
        hlines: vec![HLine {
            y: s.machine.belt_width,
            label: "far belt edge".into(),
        }],
        ..Chart::default()
    };
    charts::line_chart(path, &chart).map_err(|e| e.to_string())
}

/// `divertsim compare`.
pub fn run(args: &CompareArgs) -> i32 {
    let mut problems = common::out_problems(&args.output);
    if !(args.tolerance > 0.0 && args.tolerance.is_finite()) {
        problems.push(Problem {
            key: "--tolerance".into(),
            message: format!("{} is out of range; allowed: > 0 m", args.tolerance),
        });
    }
    let tracks = load_tracks(&args.scenario, &args.tracks, &mut problems);
    if let Err(code) = common::check(problems) {
        return code;
    }
    let runs: Vec<(String, SimResult, Comparison, Vec<String>)> =
        divertsim_api::threads::with_threads(args.output.threads.map(usize::from), || {
            use rayon::prelude::*;
            tracks
                .par_iter()
                .map(|t| {
                    let (r, c) = compare_track(t);
                    let f = mismatches(&c, &t.loaded.scenario, args.tolerance);
                    (track_name(&t.path), r, c, f)
                })
                .collect()
        });
    let scenarios: Vec<(&str, &divertsim_api::config::ScenarioFile)> = runs
        .iter()
        .zip(&tracks)
        .map(|((n, ..), t)| (n.as_str(), &t.loaded.file))
        .collect();
    let report = divertsim_api::output::describe_runs(
        json!({
            "tolerance_m": args.tolerance,
            "tracks": runs.iter().map(|(n, _, c, f)| comparison_json(n, c, f)).collect::<Vec<_>>(),
        }),
        "compare",
        &scenarios,
    );
    if let Some(dir) = &args.output.out {
        let rows: Vec<Vec<String>> = runs
            .iter()
            .map(|(n, _, c, f)| {
                vec![
                    n.clone(),
                    c.offset.to_string(),
                    c.points.to_string(),
                    c.rms.to_string(),
                    c.rms_x.to_string(),
                    c.max_x.to_string(),
                    c.rms_y.to_string(),
                    c.max_y.to_string(),
                    c.frechet.to_string(),
                    c.measured_diverted.to_string(),
                    c.simulated_diverted.to_string(),
                    c.measured_speed.map(|v| v.to_string()).unwrap_or_default(),
                    f.is_empty().to_string(),
                ]
            })
            .collect();
        let csv = divertsim_api::output::csv_bytes(
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
                "measured_diverted",
                "simulated_diverted",
                "measured_belt_speed_m_s",
                "matches",
            ],
            &rows,
        )
        .unwrap_or_default();
        let report_runs: Vec<crate::report::ReportRun<'_>> = tracks
            .iter()
            .zip(&runs)
            .map(|(t, (n, r, c, _))| crate::report::ReportRun {
                label: n.clone(),
                scenario: &t.loaded.scenario,
                result: r,
                measured: measured_points(t, c),
            })
            .collect();
        let page = crate::report::multi(
            "divertsim compare: simulated runs and measured tracks (black dots)",
            &report_runs,
        );
        let files = vec![
            ("report.html".to_string(), page.into_bytes()),
            ("comparison.csv".to_string(), csv),
            ("comparison.json".to_string(), common::json_bytes(&report)),
        ];
        let code = common::write_outputs(dir, files, |staging| {
            for (t, (n, r, c, _)) in tracks.iter().zip(&runs) {
                for ext in ["svg", "png"] {
                    draw_overlay(&staging.join(format!("compare_{n}.{ext}")), n, t, r, c)?;
                }
            }
            Ok(())
        });
        if code != 0 {
            return code;
        }
    }
    if args.output.json {
        common::emit_json(&report);
    } else {
        let mut s = format!(
            "{:<16} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}  verdict (measured/simulated)\n",
            "track", "t0 [s]", "RMS [m]", "RMS x", "RMS y", "max [m]", "Fréchet"
        );
        for (n, _, c, f) in &runs {
            s += &format!(
                "{:<16} {:>9.4} {:>9.4} {:>9.4} {:>9.4} {:>9.4} {:>9.4}  {}/{}\n",
                n,
                c.offset,
                c.rms,
                c.rms_x,
                c.rms_y,
                c.max_x.max(c.max_y),
                c.frechet,
                if c.measured_diverted {
                    "diverted"
                } else {
                    "not"
                },
                if c.simulated_diverted {
                    "diverted"
                } else {
                    "not"
                },
            );
            for flag in f {
                s += &format!("  ! {flag}\n");
            }
        }
        let bad = runs.iter().filter(|r| !r.3.is_empty()).count();
        s += &if bad == 0 {
            format!(
                "every track matches its scenario (tolerance {} m)\n",
                args.tolerance
            )
        } else {
            format!(
                "{bad} of {} tracks do not match their scenario\n",
                runs.len()
            )
        };
        common::emit(&s);
    }
    0
}
