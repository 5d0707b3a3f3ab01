//! `divertsim overload`: the worst-case parcel's impulse against belt speed for the
//! scenario's cycle time, with free-fall references (paper Fig. 16), computed by
//! `divertsim_core::analysis::paper::overload` for the `[design.overload]` parcel; with `--search`
//! also the searched worst case at each speed (`divertsim_core::analysis::design::worst_case`: any
//! parcel of the `[design.search]` class, pose, arrival and start position); a table,
//! overload.csv, overload.svg, or JSON.

use std::path::Path;

use super::analysis::{self, OptionArgs, View};
use super::common::{OutputArgs, ScenarioArgs};
use divertsim_api::analyses::overload::{Overload, OverloadReport};
use divertsim_figures::charts::{line_chart, Chart, HLine, Series, Style};
use divertsim_figures::plot::PlotError;

/// Worst-case impulse against belt speed, with free-fall references: the scenario, the
/// analysis's options (from [`divertsim_api::analyses::overload::OverloadOptions`]) and the
/// outputs.
#[derive(Debug, Clone, clap::Args)]
pub struct OverloadArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub output: OutputArgs,
    #[command(flatten)]
    pub options: OptionArgs<Overload>,
}

/// Draw S(v) with the free-fall references to `path` (.svg or .png).
pub fn draw(r: &OverloadReport, path: &Path) -> Result<(), PlotError> {
    let chart = Chart {
        title: format!(
            "Worst-case impulse, {} kg parcel, t_c = {} s (paper Fig. 16)",
            r.mass, r.cycle_time
        ),
        x_label: "belt speed v [m/s]".into(),
        y_label: "impulse S [N·s]".into(),
        series: std::iter::once(Series::new(
            "paper's worst case: tip strike at the largest α̇",
            r.points
                .iter()
                .map(|p| (p.worst.belt_speed, p.worst.impulse))
                .collect(),
            Style::LinePoints,
        ))
        .chain(r.searched.as_ref().map(|v| {
            Series::new(
                format!(
                    "searched worst case (any parcel and pose), as S/S_fall × {:.2} N·s",
                    r.fall_impulse
                ),
                v.iter()
                    .map(|q| (q.belt_speed, q.worst.value * r.fall_impulse))
                    .collect(),
                Style::LinePoints,
            )
        }))
        .collect(),
        hlines: r
            .drop_heights
            .iter()
            .zip(&r.fall_impulses)
            .map(|(h, f)| HLine {
                y: *f,
                label: format!("free fall H₀ = {h} m: {f:.2} N·s"),
            })
            .collect(),
        ..Chart::default()
    };
    line_chart(path, &chart)
}

/// `divertsim overload`.
pub fn run(args: &OverloadArgs) -> i32 {
    analysis::run::<Overload>(
        &args.scenario,
        None,
        &args.output,
        &args.options,
        View::new(&|report, path| draw(report, path).map_err(|e| e.to_string())),
    )
}
