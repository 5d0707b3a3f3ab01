//! `divertsim trigger` (paper Fig. 4): for each belt speed, the start position R_s that gives
//! the parcel the same transverse displacement as the reference setting (v = 0.65 m/s,
//! t_c = 1.36 s, R_s = 0.8 m). The computation is `divertsim_core::analysis::trigger`; this
//! file parses the options, prints the table and writes trigger.csv and trigger.svg.

use super::common::{self, OutputArgs, ScenarioArgs};
use divertsim_api::config::Problem;
use divertsim_core::analysis::sweep::Progress;
use divertsim_core::analysis::trigger::{
    self, TriggerCurve, TriggerError, TriggerPoint, TriggerSettings,
};
use divertsim_core::model::params::Scenario;
use divertsim_core::sim::{Outcome, Stage};
use divertsim_figures::charts::{line_chart, Chart, Series, Style};
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// Scenario keys that make the built-in default scenario the paper's Fig. 3 case (the slender
/// 0.7 × 0.1 × 0.1 m parcel, 1.5 kg, at ΔP = 0, φ = 0), applied before the user's `--set`
/// when no scenario file is given.
pub const FIG3_PARCEL_SETS: [&str; 6] = [
    "parcel.length=0.7",
    "parcel.width=0.1",
    "parcel.height=0.1",
    "parcel.mass=1.5",
    "parcel.offset=0.0",
    "parcel.angle_deg=0.0",
];

/// Largest number of belt speeds in one list.
pub const MAX_SPEEDS: usize = 10_000;

/// Options of `divertsim trigger`.
#[derive(Debug, Clone, clap::Args)]
pub struct TriggerArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub resume: common::ResumeArgs,
    /// Belt speeds v [m/s], each in (0, 20]: LO:HI:STEP (HI included), LO:HI/COUNT or A,B,C.
    #[arg(long, value_name = "SPEEDS", default_value = "0.65:2.3:0.05")]
    pub speeds: String,
    /// v of the reference setting [m/s], (0, 20].
    #[arg(long, value_name = "V", default_value_t = trigger::REFERENCE_SPEED)]
    pub reference_speed: f64,
    /// t_c of the reference setting [s], (0, 60].
    #[arg(long, value_name = "TC", default_value_t = trigger::REFERENCE_CYCLE)]
    pub reference_cycle: f64,
    /// R_s of the reference setting [m], [−10, 10].
    #[arg(long, value_name = "RS", default_value_t = trigger::REFERENCE_START, allow_hyphen_values = true)]
    pub reference_start: f64,
    /// Bisection tolerance on R_s [m], [1e-9, 0.1] and below --scan-step.
    #[arg(long, value_name = "M", default_value_t = 1e-4)]
    pub tolerance: f64,
    /// Search interval of R_s [m], MIN:MAX within [−10, 10].
    #[arg(
        long,
        value_name = "MIN:MAX",
        default_value = "-0.5:1.5",
        allow_hyphen_values = true
    )]
    pub search: String,
    /// Largest spacing of the R_s scan that brackets the roots [m], (0, 1].
    #[arg(long, value_name = "M", default_value_t = 0.02)]
    pub scan_step: f64,
    #[command(flatten)]
    pub output: OutputArgs,
}

fn problem(key: &str, message: String) -> Problem {
    Problem {
        key: key.into(),
        message,
    }
}

/// Parse a list of speeds in the one grammar of [`common::parse_values`] (`a,b,c`,
/// `LO:HI/N`, `LO:HI:STEP`); every speed in (0, 20] m/s. The problem names `key`; a range
/// that gives a single value is warned about on stderr.
pub fn parse_speeds(spec: &str, key: &str) -> Result<Vec<f64>, Problem> {
    let (speeds, warning) = common::parse_values(key, spec, 0.0, 20.0, "m/s", MAX_SPEEDS)?;
    if let Some(w) = warning {
        eprintln!("{w}");
    }
    if speeds.contains(&0.0) {
        return Err(problem(
            key,
            format!("'{spec}': 0 is out of range; allowed: (0, 20] m/s"),
        ));
    }
    Ok(speeds)
}

/// Parse `MIN:MAX` with −10 ≤ MIN < MAX ≤ 10.
pub fn parse_interval(spec: &str, key: &str) -> Result<(f64, f64), Problem> {
    let parts: Vec<&str> = spec.split(':').collect();
    let parsed = match parts.as_slice() {
        [a, b] => a
            .trim()
            .parse::<f64>()
            .ok()
            .zip(b.trim().parse::<f64>().ok()),
        _ => None,
    };
    match parsed {
        Some((a, b)) if a.is_finite() && b.is_finite() && -10.0 <= a && a < b && b <= 10.0 => {
            Ok((a, b))
        }
        _ => Err(problem(
            key,
            format!("{spec:?}: expected MIN:MAX with −10 ≤ MIN < MAX ≤ 10 m"),
        )),
    }
}

fn range_problem(key: &str, v: f64, ok: bool, allowed: &str) -> Option<Problem> {
    (!(v.is_finite() && ok))
        .then(|| problem(key, format!("{v} is out of range; allowed: {allowed}")))
}

/// The settings and speeds from the options, or every problem with them.
pub fn settings_of(args: &TriggerArgs) -> Result<(TriggerSettings, Vec<f64>), Vec<Problem>> {
    let mut problems = Vec::new();
    let speeds = parse_speeds(&args.speeds, "--speeds")
        .map_err(|p| problems.push(p))
        .ok();
    let search = parse_interval(&args.search, "--search")
        .map_err(|p| problems.push(p))
        .ok();
    let v = args.reference_speed;
    problems.extend(range_problem(
        "--reference-speed",
        v,
        v > 0.0 && v <= 20.0,
        "(0, 20] m/s",
    ));
    let tc = args.reference_cycle;
    problems.extend(range_problem(
        "--reference-cycle",
        tc,
        tc > 0.0 && tc <= 60.0,
        "(0, 60] s",
    ));
    let rs = args.reference_start;
    problems.extend(range_problem(
        "--reference-start",
        rs,
        (-10.0..=10.0).contains(&rs),
        "[-10, 10] m",
    ));
    let h = args.scan_step;
    problems.extend(range_problem(
        "--scan-step",
        h,
        h > 0.0 && h <= 1.0,
        "(0, 1] m",
    ));
    let tol = args.tolerance;
    problems.extend(range_problem(
        "--tolerance",
        tol,
        (1e-9..=0.1).contains(&tol) && !(h.is_finite() && tol >= h),
        "[1e-9, 0.1] m and below --scan-step",
    ));
    if let Some((lo, hi)) = search {
        if h.is_finite() && h > 0.0 && (hi - lo) / h > 1e5 {
            problems.push(problem(
                "--scan-step",
                format!(
                    "{h} m gives more than 100000 scan points over --search; allowed: ≥ {} m",
                    (hi - lo) / 1e5
                ),
            ));
        }
    }
    match (speeds, search) {
        (Some(speeds), Some(search)) if problems.is_empty() => Ok((
            TriggerSettings {
                reference_speed: v,
                reference_cycle: tc,
                reference_start: rs,
                search,
                scan_step: h,
                tolerance: tol,
            },
            speeds,
        )),
        _ => Err(problems),
    }
}

/// The calibration for a loaded scenario (reusable by `divertsim replicate`).
pub fn compute(
    scenario: &Scenario,
    speeds: &[f64],
    settings: &TriggerSettings,
    progress: Progress<'_>,
    memo: &dyn divertsim_core::analysis::memo::Memo,
) -> Result<TriggerCurve, TriggerError> {
    trigger::calibrate_kept(scenario, speeds, settings, progress, memo)
}

/// "ride F1 F2 F5": the stages, space separated.
pub fn stage_list(stages: &[Stage]) -> String {
    stages
        .iter()
        .map(|s| s.label())
        .collect::<Vec<_>>()
        .join(" ")
}

/// The contact stages F5, F6 the run realises ("F5+F6": the labels of the paper's Fig. 4),
/// or "none".
pub fn stage_set(stages: &[Stage]) -> String {
    let mut set: Vec<&str> = [Stage::F5, Stage::F6]
        .iter()
        .filter(|s| stages.contains(s))
        .map(|s| s.label())
        .collect();
    if set.is_empty() {
        set.push("none");
    }
    set.join("+")
}

fn outcome_label(o: &Outcome) -> String {
    match o.reason() {
        Some(r) if !matches!(o, Outcome::Failed(_)) => format!("{} ({r})", o.label()),
        _ => o.label().to_string(),
    }
}

fn fmt_opt(v: Option<f64>, digits: usize) -> String {
    v.map_or_else(String::new, |x| format!("{x:.digits$}"))
}

/// trigger.csv: one row per speed, its chosen root (every root is in summary.json).
pub fn csv(curve: &TriggerCurve) -> Result<Vec<u8>, csv::Error> {
    let rows: Vec<Vec<String>> = curve
        .points
        .iter()
        .map(|p| {
            let r = p.root();
            vec![
                format!("{}", p.speed),
                fmt_opt(r.map(|r| r.start), 6),
                fmt_opt(r.map(|r| r.max_lateral), 6),
                fmt_opt(r.map(|r| r.max_lateral - curve.reference.max_lateral), 6),
                r.map_or("none".into(), |r| r.kind.label().into()),
                r.map_or(String::new(), |r| stage_set(&r.stages)),
                r.map_or(String::new(), |r| stage_list(&r.stages)),
                r.map_or(String::new(), |r| r.outcome.label().into()),
                r.map_or(String::new(), |r| r.outcome.reason().unwrap_or_default()),
                r.map_or(String::new(), |r| r.iterations.to_string()),
                p.simulations.to_string(),
                p.roots.len().to_string(),
            ]
        })
        .collect();
    common::csv_bytes(
        &[
            "belt_speed_m_s",
            "start_position_m",
            "max_lateral_m",
            "residual_m",
            "root_kind",
            "stage_set",
            "stage_sequence",
            "outcome",
            "reason",
            "iterations",
            "simulations",
            "roots",
        ],
        &rows,
    )
}

/// The JSON object of `--json`.
pub fn json(curve: &TriggerCurve, settings: &TriggerSettings) -> Value {
    let r = &curve.reference;
    let point = |p: &TriggerPoint| {
        let root = p.root();
        json!({
            "speed": p.speed,
            "start_position": root.map(|r| r.start),
            "max_lateral": root.map(|r| r.max_lateral),
            "residual": root.map(|r| r.max_lateral - curve.reference.max_lateral),
            "root_kind": root.map(|r| r.kind.label()),
            "stage_set": root.map(|r| stage_set(&r.stages)),
            "stages": root.map(|r| r.stages.iter().map(|s| s.label()).collect::<Vec<_>>()),
            "outcome": root.map(|r| r.outcome.label()),
            "reason": root.and_then(|r| r.outcome.reason()),
            "iterations": root.map(|r| r.iterations),
            "simulations": p.simulations,
            "roots": p.roots.iter().map(|r| json!({
                "start_position": r.start,
                "max_lateral": r.max_lateral,
                "root_kind": r.kind.label(),
                "stage_set": stage_set(&r.stages),
                "outcome": r.outcome.label(),
            })).collect::<Vec<_>>(),
        })
    };
    json!({
        "reference": {
            "speed": r.speed,
            "cycle_time": r.cycle,
            "start_position": r.start,
            "max_lateral": r.max_lateral,
            "stages": r.stages.iter().map(|s| s.label()).collect::<Vec<_>>(),
            "outcome": r.outcome.label(),
            "reason": r.outcome.reason(),
        },
        "search": [settings.search.0, settings.search.1],
        "scan_step": settings.scan_step,
        "tolerance": settings.tolerance,
        "points": curve.points.iter().map(point).collect::<Vec<_>>(),
    })
}

/// The readable table.
pub fn table(curve: &TriggerCurve, cycle: f64) -> String {
    let r = &curve.reference;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "reference: v = {} m/s, t_c = {} s, R_s = {} m -> max lateral {:.4} m ({}; stages {})",
        r.speed,
        r.cycle,
        r.start,
        r.max_lateral,
        outcome_label(&r.outcome),
        stage_list(&r.stages)
    );
    let _ = writeln!(s, "calibrated at t_c = {cycle} s");
    let _ = writeln!(
        s,
        "{:>7} {:>9} {:>11} {:>9} {:>8} {:<28} {:<26} {:>5} {:>5}",
        "v [m/s]", "R_s [m]", "lateral [m]", "kind", "set", "stages", "outcome", "iter", "roots"
    );
    for p in &curve.points {
        match p.root() {
            Some(x) => {
                let _ = writeln!(
                    s,
                    "{:>7.3} {:>9.4} {:>11.4} {:>9} {:>8} {:<28} {:<26} {:>5} {:>5}",
                    p.speed,
                    x.start,
                    x.max_lateral,
                    x.kind.label(),
                    stage_set(&x.stages),
                    stage_list(&x.stages),
                    outcome_label(&x.outcome),
                    x.iterations,
                    p.roots.len()
                );
            }
            None => {
                let _ = writeln!(
                    s,
                    "{:>7.3} {:>9} {:>11} {:>9} {:>8} {:<28} {:<26} {:>5} {:>5}",
                    p.speed, "no root", "", "", "", "", "", "", 0
                );
            }
        }
    }
    s
}

/// trigger.svg (or .png): R_s against v, one colour per realised stage set, the reference
/// setting marked.
pub fn draw(curve: &TriggerCurve, path: &Path) -> Result<(), String> {
    let mut chosen: Vec<(f64, f64)> = curve
        .points
        .iter()
        .filter_map(|p| p.root().map(|r| (p.speed, r.start)))
        .collect();
    chosen.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut by_set: BTreeMap<String, Vec<(f64, f64)>> = BTreeMap::new();
    for p in &curve.points {
        if let Some(r) = p.root() {
            let mut label = format!("stages {}", stage_set(&r.stages));
            if r.kind == trigger::RootKind::Jump {
                label += " (jump)";
            }
            by_set.entry(label).or_default().push((p.speed, r.start));
        }
    }
    let mut series = vec![Series {
        color: Some(7),
        ..Series::new("R_s(v)", chosen, Style::Line)
    }];
    for (i, (label, pts)) in by_set.into_iter().enumerate() {
        series.push(Series {
            color: Some(i % 7),
            ..Series::new(label, pts, Style::Points)
        });
    }
    let r = &curve.reference;
    series.push(Series {
        color: Some(3),
        ..Series::new(
            format!("reference ({} m/s, {} m)", r.speed, r.start),
            vec![(r.speed, r.start)],
            Style::Points,
        )
    });
    let chart = Chart {
        title: format!(
            "Start position for the reference displacement {:.3} m",
            r.max_lateral
        ),
        x_label: "belt speed v [m/s]".into(),
        y_label: "R_s [m]".into(),
        series,
        ..Chart::default()
    };
    line_chart(path, &chart).map_err(|e| e.to_string())
}

/// `divertsim trigger`: returns the exit code.
pub fn run(args: &TriggerArgs) -> i32 {
    let scenario_args = args.scenario.with_default_sets(&FIG3_PARCEL_SETS);
    let loaded = common::load_scenario(&scenario_args);
    let options = settings_of(args);
    let mut problems = common::out_problems(&args.output);
    if let Err(p) = &options {
        problems.extend(p.iter().cloned());
    }
    let loaded = match common::checked(loaded, problems) {
        Ok(l) => l,
        Err(code) => return code,
    };
    let Ok((settings, speeds)) = options else {
        return 2;
    };
    let scenario = loaded.scenario.clone();
    let sims = settings.estimated_simulations(speeds.len()) as u64;
    if let Err(code) = common::within_budget(
        "trigger",
        sims,
        &args.output,
        "use fewer --speeds or a coarser --scan-step",
    ) {
        return code;
    }
    let journal = match common::open_journal(
        args.output.out.as_deref(),
        args.resume.resume,
        "trigger",
        &(&scenario, &speeds, &settings),
    ) {
        Ok(j) => j,
        Err(code) => return code,
    };
    let bar = common::progress_bar_of(speeds.len() as u64, "trigger", "speeds", args.output.quiet);
    let tick = || bar.inc(1);
    let result = common::with_threads(args.output.threads, || {
        compute(
            &scenario,
            &speeds,
            &settings,
            &tick,
            common::memo_of(&journal),
        )
    });
    bar.finish_and_clear();
    let curve = match result {
        Ok(c) => c,
        Err(e @ TriggerError::ReferenceFailed(_)) => {
            eprintln!("error: {e}");
            return 3;
        }
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let code = common::finish(
        &args.output,
        "trigger",
        &loaded,
        || csv(&curve),
        |p| draw(&curve, p),
        || json(&curve, &settings),
        || table(&curve, scenario.machine.cycle_time),
    );
    common::close_journal(journal, code)
}
