//! `divertsim trigger` (paper Fig. 4): for each belt speed, the start position R_s that gives
//! the parcel the same transverse displacement as the reference setting (v = 0.65 m/s,
//! t_c = 1.36 s, R_s = 0.8 m). The computation is `divertsim_core::analysis::paper::trigger`; this
//! file parses the options, prints the table and writes trigger.csv and trigger.svg.

use super::analysis::{self, OptionArgs, View};
use super::common::{self, OutputArgs, ScenarioArgs};
use divertsim_api::analyses::trigger::{stage_set, TriggerCalibration};
use divertsim_core::analysis::paper::trigger::{self, TriggerCurve};
use divertsim_figures::charts::{line_chart, short, Chart, Series, Style};
use std::collections::BTreeMap;
use std::path::Path;

/// Options of `divertsim trigger`: the scenario, the analysis's options (from
/// [`divertsim_api::analyses::trigger::TriggerOptions`]) and the outputs.
#[derive(Debug, Clone, clap::Args)]
pub struct TriggerArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub resume: common::ResumeArgs,
    #[command(flatten)]
    pub options: OptionArgs<TriggerCalibration>,
    #[command(flatten)]
    pub output: OutputArgs,
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
            format!("reference ({} m/s, {} m)", short(r.speed), short(r.start)),
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
    analysis::run::<TriggerCalibration>(
        &args.scenario,
        Some(&args.resume),
        &args.output,
        &args.options,
        View::new(&draw),
    )
}
