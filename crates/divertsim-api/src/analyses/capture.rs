//! Capture (paper Fig. 5, §4.1): for each belt speed, the arm angle α(t) against the polar
//! angle γ_p(t) of the parcel's nearest corner, the reach angle α_z where the arm catches
//! it, the first strike of a simulated run, and the start positions R_s that capture over a
//! window. R_s per speed is the scenario's or the trigger calibration's (Fig. 4). The
//! kinematics are `divertsim_core::analysis::paper::capture`.

use crate::analyses::trigger::stage_list;
use crate::config::{Loaded, Problem};
use crate::contract::{csv_table, Analysis, Error, Hooks, Interval, ValueList, Work};
use divertsim_core::analysis::paper::capture::{self, CaptureCase, CaptureError};
use divertsim_core::analysis::paper::trigger::{self, TriggerCurve, TriggerSettings};
use divertsim_core::model::params::Scenario;
use divertsim_core::run::sweep::Progress;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};
use std::fmt::Write as _;

/// Every problem with the R_s `window` \[m] and its `window_step` \[m]; keys are the option
/// names.
pub fn check(window: (f64, f64), window_step: f64) -> Vec<Problem> {
    let mut problems = Vec::new();
    let (a, b) = window;
    if !(a.is_finite() && b.is_finite() && -10.0 <= a && a < b && b <= 10.0) {
        problems.push(Problem::new(
            "window",
            format!("{a}:{b}: expected MIN:MAX with −10 ≤ MIN < MAX ≤ 10 m"),
        ));
    }
    let h = window_step;
    if !(h.is_finite() && h > 0.0 && h <= 1.0) {
        problems.push(Problem::new(
            "window_step",
            format!("{h} is out of range; allowed: (0, 1] m"),
        ));
    } else if (b - a) / h > 1e5 {
        problems.push(Problem::new(
            "window_step",
            format!(
                "{h} m gives more than 100000 points over the window; allowed: ≥ {} m",
                (b - a) / 1e5
            ),
        ));
    }
    problems
}

/// Scenario keys that make the built-in default scenario the paper's Fig. 5 case (the
/// smallest parcel 0.2 × 0.1 × 0.1 m, 0.5 kg, farthest from the pivot, ΔP = 0.6 m, φ = 0) on
/// the paper's machine (`trigger::PAPER_MACHINE_SETS`), applied before the user's `--set`
/// when no scenario file is given.
pub const FIG5_PARCEL_SETS: [&str; 14] = crate::analyses::trigger::on_paper_machine([
    "parcel.length=0.2",
    "parcel.width=0.1",
    "parcel.height=0.1",
    "parcel.mass=0.5",
    "parcel.offset=0.6",
    "parcel.angle_deg=0.0",
]);

/// Intervals of the α(t), γ_p(t) curves over [0, t_c].
pub const CURVE_POINTS: usize = 272;

/// One speed's answer.
#[derive(Debug, Clone, PartialEq)]
pub struct CaptureRow {
    /// v [m/s]
    pub speed: f64,
    /// The analysis; `None` when --trigger found no R_s for this speed.
    pub case: Option<CaptureCase>,
    /// Runs of R_s \[m] over the window that the kinematic test captures.
    pub ranges: Vec<(f64, f64)>,
}

/// The whole result.
#[derive(Debug, Clone, PartialEq)]
pub struct CaptureResult {
    pub rows: Vec<CaptureRow>,
    /// The trigger calibration used with --trigger.
    pub trigger: Option<TriggerCurve>,
}

pub fn window_grid(window: (f64, f64), step: f64) -> Vec<f64> {
    let n = ((window.1 - window.0) / step).ceil().max(1.0) as usize;
    (0..=n)
        .map(|i| window.0 + (window.1 - window.0) * i as f64 / n as f64)
        .collect()
}

/// The capture analysis for a loaded scenario (reusable by `divertsim replicate`):
/// R_s per speed from `trigger` (calibrated with the paper's Fig. 3 parcel on the scenario's
/// machine) or the scenario's; `window` scanned every `window_step` for the capturing R_s.
/// Simulations of the run: one run per speed (the window is kinematic), and the trigger
/// curve's when it is calibrated.
pub fn estimated_simulations(speeds: usize, trigger: Option<&TriggerSettings>) -> u64 {
    (speeds + trigger.map_or(0, |t| t.estimated_simulations(speeds))) as u64
}

fn compute(
    scenario: &Scenario,
    speeds: &[f64],
    trigger: Option<&TriggerSettings>,
    window: (f64, f64),
    window_step: f64,
    progress: Progress<'_>,
    stop_point: Progress<'_>,
) -> Result<CaptureResult, Error> {
    let calibration = match trigger {
        Some(settings) => {
            let mut slender = scenario.clone();
            slender.parcel = trigger::fig3_parcel();
            Some(
                trigger::calibrate(&slender, speeds, settings, stop_point)
                    .map_err(|e| Error::failed(format!("trigger calibration: {e}")))?,
            )
        }
        None => None,
    };
    let starts: Vec<Option<f64>> = match &calibration {
        Some(c) => c.points.iter().map(|p| p.root().map(|r| r.start)).collect(),
        None => vec![Some(scenario.machine.start_position); speeds.len()],
    };
    let cases: Vec<(f64, f64)> = speeds
        .iter()
        .zip(&starts)
        .filter_map(|(&v, s)| s.map(|s| (v, s)))
        .collect();
    let done = capture::capture_sweep(scenario, &cases, CURVE_POINTS, progress)
        .map_err(|e: CaptureError| Error::failed(e))?;
    let grid = window_grid(window, window_step);
    let mut done = done.into_iter();
    let mut rows = Vec::with_capacity(speeds.len());
    for (&v, s) in speeds.iter().zip(&starts) {
        stop_point();
        let ranges = capture::capture_window(scenario, v, &grid)
            .map(|w| capture::captured_ranges(&w))
            .map_err(Error::failed)?;
        rows.push(CaptureRow {
            speed: v,
            case: s.and_then(|_| done.next()),
            ranges,
        });
    }
    Ok(CaptureResult {
        rows,
        trigger: calibration,
    })
}

pub fn deg(x: f64) -> f64 {
    x.to_degrees()
}

pub fn fmt_opt(v: Option<f64>, digits: usize) -> String {
    v.map_or_else(String::new, |x| format!("{x:.digits$}"))
}

/// capture.csv: the curves α(t), γ_p(t) of every speed, with α_z.
pub fn csv(result: &CaptureResult) -> Result<Vec<u8>, csv::Error> {
    let mut rows = Vec::new();
    for row in &result.rows {
        let Some(c) = &row.case else { continue };
        let az = fmt_opt(c.kinematic.reach_angle.map(deg), 6);
        for p in &c.curve {
            rows.push(vec![
                format!("{}", c.speed),
                format!("{:.6}", c.start),
                format!("{:.6}", p.t),
                format!("{:.6}", deg(p.alpha)),
                format!("{:.6}", deg(p.gamma)),
                az.clone(),
            ]);
        }
    }
    crate::output::csv_bytes(
        &[
            "belt_speed_m_s",
            "start_position_m",
            "t_s",
            "alpha_deg",
            "gamma_deg",
            "alpha_z_deg",
        ],
        &rows,
    )
}

pub fn row_json(row: &CaptureRow) -> Value {
    let Some(c) = &row.case else {
        return json!({"speed": row.speed, "start_position": null, "captured": null,
                      "capture_ranges": row.ranges});
    };
    let k = &c.kinematic;
    let strike = c.sim.first_strike.as_ref();
    json!({
        "speed": c.speed,
        "start_position": c.start,
        "captured": k.captured,
        "corner": k.corner,
        "corner_height": k.corner_height,
        "t_capture": k.crossing.filter(|_| k.captured).map(|x| x.t),
        "alpha_capture_deg": k.crossing.filter(|_| k.captured).map(|x| deg(x.alpha)),
        "t_crossing": k.crossing.map(|x| x.t),
        "alpha_crossing_deg": k.crossing.map(|x| deg(x.alpha)),
        "crossing_distance": k.crossing.map(|x| x.distance),
        "alpha_z_deg": k.reach_angle.map(deg),
        "margin_deg": c.margin().map(deg),
        "capture_ranges": row.ranges,
        "sim": {
            "first_strike_t": strike.map(|i| i.t),
            "first_strike_obstacle": strike.map(|i| i.obstacle.label()),
            "first_strike_point": strike.map(|i| i.point),
            "corner_struck_first": c.sim.corner_struck_first,
            "outcome": c.sim.outcome.label(),
            "reason": c.sim.outcome.reason(),
            "stages": c.sim.stages.iter().map(|s| s.label()).collect::<Vec<_>>(),
            "max_lateral": c.sim.max_lateral,
        },
    })
}

/// The JSON object of `--json`.
pub fn json(result: &CaptureResult, scenario: &Scenario) -> Value {
    json!({
        "cycle_time": scenario.machine.cycle_time,
        "arm_length": scenario.machine.arm_length,
        "parcel": {
            "length": scenario.parcel.length,
            "width": scenario.parcel.width,
            "offset": scenario.parcel.offset,
            "angle_deg": scenario.parcel.angle.to_degrees(),
        },
        "start_from_trigger": result.trigger.is_some(),
        "trigger_target": result.trigger.as_ref().map(|t| t.reference.max_lateral),
        "rows": result.rows.iter().map(row_json).collect::<Vec<_>>(),
    })
}

/// Options of the capture analysis (`divertsim capture`, Python `analysis("capture")`).
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are help text: [m] is a unit
#[derive(Debug, Clone, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default)]
pub struct CaptureOptions {
    /// Belt speeds v [m/s], each in (0, 20]: A,B,C, LO:HI/COUNT or LO:HI:STEP.
    pub speeds: ValueList,
    /// R_s per speed from the trigger calibration (`divertsim trigger`, the paper's Fig. 4:
    /// the slender 0.7 × 0.1 m parcel at ΔP = 0 matching the reference 0.65 m/s, 1.36 s,
    /// 0.8 m on the scenario's machine) instead of the scenario's machine.start_position.
    pub trigger: bool,
    /// R_s interval scanned (kinematic test only) for the start positions that capture
    /// [m], MIN:MAX within [−10, 10].
    pub window: Interval,
    /// Spacing of that scan [m], (0, 1].
    pub window_step: f64,
}

impl Default for CaptureOptions {
    fn default() -> CaptureOptions {
        CaptureOptions {
            speeds: ValueList::spec("1.0,1.5,2.0"),
            trigger: false,
            window: Interval(-0.5, 1.5),
            window_step: 0.01,
        }
    }
}

/// The capture analysis on the analysis contract.
pub struct Capture;

/// Checked options of [`Capture`].
#[derive(Debug, Clone)]
pub struct CaptureInputs {
    /// Belt speeds [m/s].
    pub speeds: Vec<f64>,
    /// The trigger calibration's settings, when R_s comes from it.
    pub trigger: Option<TriggerSettings>,
    /// R_s window scanned \[m].
    pub window: (f64, f64),
    /// Its spacing \[m].
    pub window_step: f64,
}

impl Analysis for Capture {
    const NAME: &'static str = "capture";
    const ABOUT: &'static str =
        "Whether the arm catches a riding parcel: α(t) against the corner angle γ_p(t) (Fig. 5)";
    const DEFAULT_SETS: &'static [&'static str] = &FIG5_PARCEL_SETS;
    type Options = CaptureOptions;
    type Checked = CaptureInputs;
    type Bound = CaptureInputs;
    type Output = CaptureResult;

    fn validate(o: &CaptureOptions) -> Result<CaptureInputs, Vec<Problem>> {
        let window = (o.window.0, o.window.1);
        let mut problems = check(window, o.window_step);
        let speeds = o
            .speeds
            .resolve("speeds", crate::analyses::trigger::SPEED_LIST)
            .map_err(|p| problems.push(p))
            .unwrap_or_default();
        if problems.iter().all(|p| p.key != "speeds") {
            problems.extend(crate::analyses::trigger::check_speeds(&speeds, "speeds"));
        }
        if !problems.is_empty() {
            return Err(problems);
        }
        Ok(CaptureInputs {
            speeds,
            trigger: o.trigger.then(TriggerSettings::default),
            window,
            window_step: o.window_step,
        })
    }

    /// Nothing derives from the scenario before the run.
    fn bind(c: CaptureInputs, _: &Loaded) -> Result<CaptureInputs, Vec<Problem>> {
        Ok(c)
    }

    fn work(c: &CaptureInputs, _: &Loaded) -> Work {
        let at_most = estimated_simulations(c.speeds.len(), c.trigger.as_ref());
        Work {
            at_most: Some(at_most),
            // The trigger's reference run and scan grid run whatever the roots.
            at_least: c.speeds.len() as u64
                + c.trigger
                    .as_ref()
                    .map_or(0, |t| t.least_simulations(c.speeds.len()) as u64),
            units: c.speeds.len() as u64,
            unit: "runs",
            smaller: "use fewer `speeds`",
        }
    }

    fn run(s: &Loaded, c: &CaptureInputs, hooks: &Hooks) -> Result<CaptureResult, Error> {
        compute(
            &s.scenario,
            &c.speeds,
            c.trigger.as_ref(),
            c.window,
            c.window_step,
            hooks.progress,
            &|| hooks.stop_point(),
        )
    }

    fn summary(result: &CaptureResult, _: &CaptureInputs, s: &Loaded) -> Value {
        json(result, &s.scenario)
    }

    fn tables(result: &CaptureResult) -> Result<Vec<(String, Vec<u8>)>, Error> {
        Ok(vec![csv_table("capture.csv", csv(result))?])
    }

    fn text(r: &CaptureResult, _: &CaptureInputs, s: &Loaded) -> String {
        text(r, &s.scenario)
    }
}

pub fn ranges_text(r: &[(f64, f64)]) -> String {
    if r.is_empty() {
        return "none".into();
    }
    r.iter()
        .map(|(a, b)| format!("{a:.2}..{b:.2}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The readable table.
pub fn text(result: &CaptureResult, scenario: &Scenario) -> String {
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
            c.sim.outcome.short_verdict(),
            ranges_text(&row.ranges),
            stage_list(&c.sim.stages),
        );
    }
    s
}
