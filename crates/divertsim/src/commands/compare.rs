//! `divertsim compare`: simulate each track's experiment and compare the simulated marker
//! path with the measured one (`divertsim_core::analysis::track::compare`): time alignment,
//! RMS and largest errors along and across the belt, the discrete Fréchet distance, the
//! verdicts and the belt speed seen on the track; a track that does not match its scenario
//! (another parcel, another speed) is flagged. Overlays like the paper's Figs 13–15.

use std::path::Path;

use divertsim_core::analysis::track::{compare, Comparison, MarkerPath};
use divertsim_core::model::params::Scenario;
use divertsim_core::sim::{simulate, SimResult};
use serde_json::{json, Value};

use super::common::{self, OutputArgs, ScenarioArgs};
use super::track::{load_tracks, track_name, LoadedTrack, TrackArgs};
use divertsim_api::config::Problem;
use divertsim_figures::charts::{self, Chart, HLine, Series, Style};

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

/// Relative belt-speed difference that flags a track.
pub const SPEED_TOLERANCE: f64 = 0.05;

/// Why a track does not match its scenario (empty: it matches).
pub fn flags(c: &Comparison, scenario: &Scenario, tolerance: f64) -> Vec<String> {
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
        common::with_threads(args.output.threads, || {
            use rayon::prelude::*;
            tracks
                .par_iter()
                .map(|t| {
                    let (r, c) = compare_track(t);
                    let f = flags(&c, &t.loaded.scenario, args.tolerance);
                    (track_name(&t.path), r, c, f)
                })
                .collect()
        });
    let scenarios: Vec<(&str, &divertsim_api::config::ScenarioFile)> = runs
        .iter()
        .zip(&tracks)
        .map(|((n, ..), t)| (n.as_str(), &t.loaded.file))
        .collect();
    let report = common::describe_runs(
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
