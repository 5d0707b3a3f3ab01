//! `divertsim capture` (paper Fig. 5): does the arm catch a parcel riding with the belt? The
//! arm angle α(t) against the polar angle γ_p(t) of the parcel's front corner, the reach angle
//! α_z, the kinematic capture time, and the full simulation's first arm strike, per belt
//! speed. The analysis is `divertsim_api::analyses::capture`; this file parses the options, prints
//! the table and writes capture.csv and capture.svg.

use super::analysis::{self, OptionArgs, View};
use super::common::{OutputArgs, ScenarioArgs};
use divertsim_api::analyses::capture::{deg, fmt_opt, Capture, CaptureResult};
use divertsim_api::analyses::trigger::stage_list;
use divertsim_core::analysis::paper::capture::CaptureCase;
use divertsim_core::model::params::Scenario;
use divertsim_core::sim::Outcome;
use divertsim_figures::charts::{line_chart, Chart, HLine, Series, Style};
use std::fmt::Write as _;
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

fn ranges_text(r: &[(f64, f64)]) -> String {
    if r.is_empty() {
        return "none".into();
    }
    r.iter()
        .map(|(a, b)| format!("{a:.2}..{b:.2}"))
        .collect::<Vec<_>>()
        .join(" ")
}

fn outcome_text(o: &Outcome) -> String {
    match (o, o.reason()) {
        (Outcome::Failed(_), _) | (_, None) => o.label().to_string(),
        (_, Some(r)) => format!("{} ({r})", o.label()),
    }
}

/// The readable table.
pub fn table(result: &CaptureResult, scenario: &Scenario) -> String {
    let mut s = String::new();
    let p = &scenario.parcel;
    let _ = writeln!(
        s,
        "parcel {} × {} m at ΔP = {} m, φ = {}°; t_c = {} s, R_z = {} m; R_s {}",
        p.length,
        p.width,
        p.offset,
        p.angle.to_degrees(),
        scenario.machine.cycle_time,
        scenario.machine.arm_length,
        if result.trigger.is_some() {
            "from the trigger calibration"
        } else {
            "from the scenario"
        }
    );
    let _ = writeln!(
        s,
        "{:>6} {:>8} {:>8} {:>9} {:>8} {:>7} {:>8} {:>9} {:<9} {:<24} {:<18} stages",
        "v[m/s]",
        "R_s[m]",
        "captured",
        "t*[s]",
        "α*[deg]",
        "α_z",
        "margin",
        "strike[s]",
        "by",
        "outcome",
        "capturing R_s [m]",
    );
    for row in &result.rows {
        let Some(c) = &row.case else {
            let _ = writeln!(
                s,
                "{:>6.3} {:>8} (no trigger root for this speed)",
                row.speed, "none"
            );
            continue;
        };
        let k = &c.kinematic;
        let x = k.crossing.filter(|_| k.captured);
        let strike = c.sim.first_strike.as_ref();
        let by = strike.map_or(String::new(), |i| {
            if c.sim.corner_struck_first {
                "corner".to_string()
            } else {
                i.obstacle.label().to_string()
            }
        });
        let _ = writeln!(
            s,
            "{:>6.3} {:>8.4} {:>8} {:>9} {:>8} {:>7} {:>8} {:>9} {:<9} {:<24} {:<18} {}",
            c.speed,
            c.start,
            if k.captured { "yes" } else { "no" },
            fmt_opt(x.map(|x| x.t), 5),
            fmt_opt(x.map(|x| deg(x.alpha)), 3),
            fmt_opt(k.reach_angle.map(deg), 3),
            fmt_opt(c.margin().map(deg), 3),
            fmt_opt(strike.map(|i| i.t), 5),
            by,
            outcome_text(&c.sim.outcome),
            ranges_text(&row.ranges),
            stage_list(&c.sim.stages),
        );
    }
    s
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
                format!("γ_p(t) v = {} m/s, R_s = {:.3} m", c.speed, c.start),
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
        View::new(&|result, _, loaded| table(result, &loaded.scenario), &draw),
    )
}
