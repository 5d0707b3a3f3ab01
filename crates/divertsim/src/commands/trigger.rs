//! `divertsim trigger` (paper Fig. 4): for each belt speed, the start position R_s that gives
//! the parcel the same transverse displacement as the reference setting (v = 0.65 m/s,
//! t_c = 1.36 s, R_s = 0.8 m). The computation is `divertsim_core::analysis::paper::trigger`; this
//! file parses the options, prints the table and writes trigger.csv and trigger.svg.

use super::common::{self, OutputArgs, ScenarioArgs};
use divertsim_api::analyses::trigger::{
    self as api, compute, csv, json, stage_list, stage_set, FIG3_PARCEL_SETS, MAX_SPEEDS,
};
use divertsim_api::config::Problem;
use divertsim_core::analysis::paper::trigger::{self, TriggerCurve, TriggerError, TriggerSettings};
use divertsim_core::sim::Outcome;
use divertsim_figures::charts::{line_chart, Chart, Series, Style};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// Options of `divertsim trigger`.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are --help text: [m] is a unit
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

/// Parse a list of speeds in the one grammar of [`parse_values`](divertsim_api::config::values::parse_values) (`a,b,c`,
/// `LO:HI/N`, `LO:HI:STEP`); every speed in (0, 20] m/s. The problem names `key`; a range
/// that gives a single value is warned about on stderr.
pub fn parse_speeds(spec: &str, key: &str) -> Result<Vec<f64>, Problem> {
    let (speeds, warning) =
        divertsim_api::config::values::parse_values(key, spec, 0.0, 20.0, "m/s", MAX_SPEEDS)?;
    if let Some(w) = warning {
        eprintln!("{w}");
    }
    if speeds.contains(&0.0) {
        return Err(Problem::new(
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
        _ => Err(Problem::new(
            key,
            format!("{spec:?}: expected MIN:MAX with −10 ≤ MIN < MAX ≤ 10 m"),
        )),
    }
}

/// The settings and speeds from the options, or every problem with them (the api's checks,
/// keyed by their flags).
pub fn settings_of(args: &TriggerArgs) -> Result<(TriggerSettings, Vec<f64>), Vec<Problem>> {
    let mut problems = Vec::new();
    let speeds = parse_speeds(&args.speeds, "--speeds")
        .map_err(|p| problems.push(p))
        .ok();
    let search = parse_interval(&args.search, "--search")
        .map_err(|p| problems.push(p))
        .ok();
    let settings = TriggerSettings {
        reference_speed: args.reference_speed,
        reference_cycle: args.reference_cycle,
        reference_start: args.reference_start,
        search: search.unwrap_or((-0.5, 1.5)),
        scan_step: args.scan_step,
        tolerance: args.tolerance,
    };
    problems.extend(common::flags(api::check(
        &settings,
        speeds.as_deref().unwrap_or(&[1.0]),
    )));
    match speeds {
        Some(speeds) if problems.is_empty() => Ok((settings, speeds)),
        _ => Err(problems),
    }
}

fn outcome_label(o: &Outcome) -> String {
    match o.reason() {
        Some(r) if !matches!(o, Outcome::Failed(_)) => format!("{} ({r})", o.label()),
        _ => o.label().to_string(),
    }
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
    let result = divertsim_api::threads::with_threads(args.output.threads.map(usize::from), || {
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
