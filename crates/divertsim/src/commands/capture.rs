//! `divertsim capture` (paper Fig. 5): does the arm catch a parcel riding with the belt? The
//! arm angle α(t) against the polar angle γ_p(t) of the parcel's front corner, the reach angle
//! α_z, the kinematic capture time, and the full simulation's first arm strike, per belt
//! speed. The analysis is `divertsim_api::analyses::capture`; this file parses the options, prints
//! the table and writes capture.csv and capture.svg.

use super::analysis::{self, OptionArgs, View};
use super::common::{OutputArgs, ScenarioArgs};
use divertsim_api::analyses::capture::{deg, Capture, CaptureResult};
use divertsim_core::analysis::paper::capture::CaptureCase;
use divertsim_figures::charts::{line_chart, short, Chart, HLine, Series, Style};
use std::path::Path;

/// Options of `divertsim capture`: the scenario, the analysis's options (from
/// [`divertsim_api::analyses::capture::CaptureOptions`]) and the outputs.
#[derive(Debug, Clone, clap::Args)]
pub struct CaptureArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub options: OptionArgs<Capture>,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// capture.svg (or .png): α(t) and γ_p(t) per speed [deg], α_z as horizontal lines, the
/// capture points marked.
pub fn draw(result: &CaptureResult, path: &Path) -> Result<(), String> {
    let cases: Vec<&CaptureCase> = result.rows.iter().filter_map(|r| r.case.as_ref()).collect();
    let mut series = Vec::new();
    if let Some(c) = cases.first() {
        // Every speed shares t_c, hence α(t).
        series.push(Series {
            color: Some(7),
            ..Series::new(
                "α(t) arm",
                c.curve.iter().map(|p| (p.t, deg(p.alpha))).collect(),
                Style::Line,
            )
        });
    }
    let mut captures = Vec::new();
    for (i, c) in cases.iter().enumerate() {
        series.push(Series {
            color: Some(i % 7),
            ..Series::new(
                format!("γ_p(t) v = {} m/s, R_s = {:.3} m", short(c.speed), c.start),
                c.curve.iter().map(|p| (p.t, deg(p.gamma))).collect(),
                Style::Dashed,
            )
        });
        if let Some(x) = c.kinematic.crossing.filter(|_| c.kinematic.captured) {
            captures.push((x.t, deg(x.alpha)));
        }
    }
    if !captures.is_empty() {
        series.push(Series {
            color: Some(3),
            ..Series::new("capture", captures, Style::Points)
        });
    }
    let mut hlines: Vec<HLine> = Vec::new();
    for c in &cases {
        if let Some(az) = c.kinematic.reach_angle.map(deg) {
            if !hlines.iter().any(|h| (h.y - az).abs() < 1e-9) {
                hlines.push(HLine {
                    y: az,
                    label: format!("α_z = {az:.2}°"),
                });
            }
        }
    }
    let ymax = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1))
        .chain(hlines.iter().map(|h| h.y))
        .filter(|y| y.is_finite())
        .fold(0.0f64, f64::max);
    let chart = Chart {
        title: "Arm angle α and front-corner angle γ_p (capture above α_z)".into(),
        x_label: "t [s]".into(),
        y_label: "angle [deg]".into(),
        series,
        hlines,
        // Far-upstream corners start near 180°; the arm never passes its swing.
        y_range: Some((0.0, ymax.min(100.0) * 1.05 + 1.0)),
        ..Chart::default()
    };
    line_chart(path, &chart).map_err(|e| e.to_string())
}

/// `divertsim capture`: returns the exit code.
pub fn run(args: &CaptureArgs) -> i32 {
    analysis::run::<Capture>(
        &args.scenario,
        None,
        &args.output,
        &args.options,
        View::new(&draw),
    )
}
