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
use divertsim_api::analyses::worst_case::pose_text_no_phase;
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

/// The readable table.
pub fn table(r: &OverloadReport) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "worst-case overload: {} kg parcel struck by the arm tip at the largest arm speed, t_c = {} s",
        r.mass, r.cycle_time
    );
    if let Some(p) = r.points.first() {
        let w = &p.worst;
        let _ = writeln!(
            s,
            "arm: largest α̇ = {:.5} rad/s at t = {:.4} s, α = {:.3}°, reach R_z = {} m",
            w.peak.rate,
            w.peak.time,
            w.peak.angle.to_degrees(),
            w.reach
        );
    }
    for (h, f) in r.drop_heights.iter().zip(&r.fall_impulses) {
        let _ = writeln!(s, "free fall from H₀ = {h} m: S_fall = {f:.3} N·s");
    }
    let _ = write!(
        s,
        "{:>8} {:>10} {:>9} {:>9}",
        "v [m/s]", "S [N·s]", "u_n0", "H_eq [m]"
    );
    for h in &r.drop_heights {
        let _ = write!(s, " {:>9}", format!("S/S({h})"));
    }
    let _ = writeln!(s);
    for p in &r.points {
        let w = &p.worst;
        let _ = write!(
            s,
            "{:>8.3} {:>10.4} {:>9.4} {:>9.4}",
            w.belt_speed, w.impulse, w.approach_speed, w.equivalent_drop_height
        );
        for x in &p.ratios {
            let _ = write!(s, " {x:>9.4}");
        }
        let _ = writeln!(s);
    }
    for ((h, f), b) in r.drop_heights.iter().zip(&r.fall_impulses).zip(r.below()) {
        let _ = writeln!(
            s,
            "largest S = {:.3} N·s is {} the H₀ = {h} m reference ({f:.3} N·s) at every speed",
            r.max_impulse(),
            if b { "below" } else { "NOT below" }
        );
    }
    if let Some(searched) = &r.searched {
        let _ = writeln!(
            s,
            "\nsearched worst case (any parcel of [design.search], any pose, arrival and R_s), S/S_fall at H₀ of the scenario:"
        );
        let _ = writeln!(
            s,
            "{:>8} {:>9} {:>9} {:>8}  worst pose",
            "v [m/s]", "searched", "paper", "R_s [m]"
        );
        for (q, p) in searched.iter().zip(&r.points) {
            let _ = writeln!(
                s,
                "{:>8.3} {:>9.4} {:>9.4} {:>8.3}  {}",
                q.belt_speed,
                q.worst.value,
                p.worst.ratio,
                q.start_position,
                pose_text_no_phase(&q.worst.pose)
            );
        }
        let over = searched.iter().filter(|q| q.worst.value > 1.0).count();
        let _ = writeln!(
            s,
            "the searched worst case exceeds the free fall at {over} of {} speeds (the paper's definition: {})",
            searched.len(),
            r.points.iter().filter(|p| p.worst.ratio > 1.0).count()
        );
    }
    s
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
        View::new(&|report, _, _| table(report), &|report, path| {
            draw(report, path).map_err(|e| e.to_string())
        }),
    )
}
