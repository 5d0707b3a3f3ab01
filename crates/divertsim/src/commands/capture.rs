//! `divertsim capture` (paper Fig. 5): does the arm catch a parcel riding with the belt? The
//! arm angle α(t) against the polar angle γ_p(t) of the parcel's front corner, the reach angle
//! α_z, the kinematic capture time, and the full simulation's first arm strike, per belt
//! speed. The analysis is `divertsim_api::analyses::capture`; this file parses the options, prints
//! the table and writes capture.csv and capture.svg.

use super::common::{self, OutputArgs, ScenarioArgs};
use super::trigger::{parse_interval, parse_speeds};
use divertsim_api::analyses::capture::{
    self as api, compute, csv, deg, fmt_opt, json, CaptureResult, FIG5_PARCEL_SETS,
};
use divertsim_api::analyses::trigger::stage_list;
use divertsim_api::config::Problem;
use divertsim_core::analysis::paper::capture::CaptureCase;
use divertsim_core::analysis::paper::trigger::TriggerSettings;
use divertsim_core::model::params::Scenario;
use divertsim_core::sim::Outcome;
use divertsim_figures::charts::{line_chart, Chart, HLine, Series, Style};
use std::fmt::Write as _;
use std::path::Path;

/// Options of `divertsim capture`.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are --help text: [m] is a unit
#[derive(Debug, Clone, clap::Args)]
pub struct CaptureArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    /// Belt speeds v [m/s], each in (0, 20]: A,B,C, LO:HI/COUNT or LO:HI:STEP.
    #[arg(long, value_name = "SPEEDS", default_value = "1.0,1.5,2.0")]
    pub speeds: String,
    /// R_s per speed from the trigger calibration (`divertsim trigger`, the paper's Fig. 4:
    /// the slender 0.7 × 0.1 m parcel at ΔP = 0 matching the reference 0.65 m/s, 1.36 s,
    /// 0.8 m on the scenario's machine) instead of the scenario's machine.start_position.
    #[arg(long)]
    pub trigger: bool,
    /// R_s interval scanned (kinematic test only) for the start positions that capture
    /// [m], MIN:MAX within [−10, 10].
    #[arg(
        long,
        value_name = "MIN:MAX",
        default_value = "-0.5:1.5",
        allow_hyphen_values = true
    )]
    pub window: String,
    /// Spacing of that scan [m], (0, 1].
    #[arg(long, value_name = "M", default_value_t = 0.01)]
    pub window_step: f64,
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

/// Every problem with the options, or the parsed speeds, window and window step.
/// Speeds [m/s], R_s window (min, max) [m], window step [m].
type Options = (Vec<f64>, (f64, f64), f64);

fn options_of(args: &CaptureArgs) -> Result<Options, Vec<Problem>> {
    let mut problems = Vec::new();
    let speeds = parse_speeds(&args.speeds, "--speeds")
        .map_err(|p| problems.push(p))
        .ok();
    let window = parse_interval(&args.window, "--window")
        .map_err(|p| problems.push(p))
        .ok();
    if let Some(w) = window {
        problems.extend(common::flags(api::check(w, args.window_step)));
    }
    match (speeds, window) {
        (Some(s), Some(w)) if problems.is_empty() => Ok((s, w, args.window_step)),
        _ => Err(problems),
    }
}

/// `divertsim capture`: returns the exit code.
pub fn run(args: &CaptureArgs) -> i32 {
    let scenario_args = args.scenario.with_default_sets(&FIG5_PARCEL_SETS);
    let loaded = common::load_scenario(&scenario_args);
    let options = options_of(args);
    let mut problems = common::out_problems(&args.output);
    if let Err(p) = &options {
        problems.extend(p.iter().cloned());
    }
    let loaded = match common::checked(loaded, problems) {
        Ok(l) => l,
        Err(code) => return code,
    };
    let Ok((speeds, window, window_step)) = options else {
        return 2;
    };
    let scenario = loaded.scenario.clone();
    let settings = args.trigger.then(TriggerSettings::default);
    let sims =
        divertsim_api::analyses::capture::estimated_simulations(speeds.len(), settings.as_ref());
    if let Err(code) = common::within_budget("capture", sims, &args.output, "use fewer --speeds") {
        return code;
    }
    let bar = common::progress_bar(speeds.len() as u64, "capture", args.output.quiet);
    let tick = || bar.inc(1);
    let result = divertsim_api::threads::with_threads(args.output.threads.map(usize::from), || {
        compute(
            &scenario,
            &speeds,
            settings.as_ref(),
            window,
            window_step,
            &tick,
        )
    });
    bar.finish_and_clear();
    let result = match result {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    common::finish(
        &args.output,
        "capture",
        &loaded,
        || csv(&result),
        |p| draw(&result, p),
        || json(&result, &scenario),
        || table(&result, &scenario),
    )
}
