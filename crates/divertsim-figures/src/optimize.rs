//! The optimisation figures: the history of runs (paper Figs 10 and 11 style: best capacity
//! and the variables against generation or iteration) and the NSGA-II Pareto front coloured by
//! the divert reserve. Inputs are the core's optimiser records
//! ([`divertsim_core::optimize`]).

use crate::charts::{along, fit, least_covered_corner, tick, PALETTE};
use crate::plot::{draw_err, ensure_font, format_of, Format, PlotError, FONT};
use divertsim_core::analysis::design::settings_problem::{capacity_of, SYMBOLS, UNITS};
use divertsim_core::optimize::nsga2::FrontPoint;
use divertsim_core::optimize::{IterationSummary, Record};
use plotters::prelude::*;
use std::path::Path;

/// One run of a history figure.
pub struct HistoryRun<'a> {
    pub label: String,
    pub history: &'a [IterationSummary],
}

/// What the first panel of a history shows of the best point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HistoryObjective {
    /// The paper's capacity W of the best point's setting.
    Capacity,
    /// The line's measured throughput (minus 1000 times the objective).
    Throughput,
}

impl HistoryObjective {
    fn label(self) -> &'static str {
        match self {
            HistoryObjective::Capacity => "best W [parcels/h]",
            HistoryObjective::Throughput => "best line throughput [parcels/h]",
        }
    }

    fn value(self, h: &IterationSummary) -> f64 {
        match self {
            HistoryObjective::Capacity => capacity_of(&h.best_x),
            HistoryObjective::Throughput => -1000.0 * h.best_objective,
        }
    }
}

/// Paper Figs 10/11 style: best capacity and the variables (v, t_c, R_s; S_d too when it
/// varies) against generation / iteration, one line per run; the capacity is dashed while the
/// best point is still infeasible.
pub fn draw_history(
    path: &Path,
    title: &str,
    x_label: &str,
    runs: &[HistoryRun<'_>],
) -> Result<(), PlotError> {
    draw_history_of(path, title, x_label, runs, HistoryObjective::Capacity)
}

/// [`draw_history`] with `objective` in the first panel.
pub fn draw_history_of(
    path: &Path,
    title: &str,
    x_label: &str,
    runs: &[HistoryRun<'_>],
    objective: HistoryObjective,
) -> Result<(), PlotError> {
    let format = format_of(path)?;
    ensure_font()?;
    let size = (1100, 800);
    match format {
        Format::Svg => render_history(
            SVGBackend::new(path, size).into_drawing_area(),
            title,
            x_label,
            runs,
            objective,
        ),
        Format::Png => render_history(
            BitMapBackend::new(path, size).into_drawing_area(),
            title,
            x_label,
            runs,
            objective,
        ),
    }
}

/// What a history panel plots of each iteration.
type PanelValue = Box<dyn Fn(&IterationSummary) -> f64>;

fn render_history<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    x_label: &str,
    runs: &[HistoryRun<'_>],
    objective: HistoryObjective,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(draw_err)?;
    let root = root.titled(title, (FONT, 20)).map_err(draw_err)?;
    let sd_varies = runs.iter().any(|r| {
        r.history
            .iter()
            .any(|h| h.best_x.get(3) != r.history.first().and_then(|f| f.best_x.get(3)))
    });
    // Panel 0: the capacity; then v, t_c, R_s (and S_d when it varies).
    let vars: Vec<usize> = if sd_varies {
        vec![0, 1, 2, 3]
    } else {
        vec![0, 1, 2]
    };
    let panels = root.split_evenly(((1 + vars.len()).div_ceil(2), 2));
    let x_max = runs
        .iter()
        .flat_map(|r| r.history.iter().map(|h| h.iteration as f64))
        .fold(1.0, f64::max);
    for (k, area) in panels.iter().enumerate().take(1 + vars.len()) {
        let (y_label, value): (String, PanelValue) = if k == 0 {
            (
                objective.label().into(),
                Box::new(move |h: &IterationSummary| objective.value(h)),
            )
        } else {
            let i = vars[k - 1];
            (
                format!("{} [{}]", SYMBOLS[i], UNITS[i]),
                Box::new(move |h: &IterationSummary| h.best_x.get(i).copied().unwrap_or(f64::NAN)),
            )
        };
        let y = fit(runs.iter().flat_map(|r| r.history.iter().map(&value)));
        let mut ctx = ChartBuilder::on(area)
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(65)
            .build_cartesian_2d(0.0..x_max, y.0..y.1)
            .map_err(draw_err)?;
        ctx.configure_mesh()
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .x_desc(x_label)
            .y_desc(&y_label)
            .label_style((FONT, 12))
            .axis_desc_style((FONT, 14))
            .light_line_style(RGBColor(0xEE, 0xEE, 0xEE))
            .draw()
            .map_err(draw_err)?;
        for (j, run) in runs.iter().enumerate() {
            let color = PALETTE[j % PALETTE.len()];
            let solid = color.stroke_width(2);
            let thin = color.stroke_width(1);
            // Split into feasible / infeasible stretches (the capacity panel only).
            let mut stretch: Vec<(f64, f64)> = Vec::new();
            let mut stretch_feasible = true;
            let mut labelled = false;
            let mut flush = |pts: &mut Vec<(f64, f64)>, feasible: bool| -> Result<(), PlotError> {
                if pts.is_empty() {
                    return Ok(());
                }
                let anno = if feasible || k != 0 {
                    ctx.draw_series(LineSeries::new(pts.clone(), solid))
                        .map_err(draw_err)?
                } else {
                    ctx.draw_series(DashedLineSeries::new(pts.clone(), 6, 4, thin))
                        .map_err(draw_err)?
                };
                if k == 0 && !labelled && (feasible || pts.len() > 1) {
                    labelled = true;
                    anno.label(&run.label)
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], solid));
                }
                Ok(())
            };
            for h in run.history {
                let p = (h.iteration as f64, value(h));
                if !p.1.is_finite() {
                    continue;
                }
                let feasible = h.best_violation == 0.0;
                if feasible != stretch_feasible && !stretch.is_empty() {
                    let last = *stretch.last().unwrap_or(&p);
                    flush(&mut stretch, stretch_feasible)?;
                    stretch = vec![last];
                }
                stretch_feasible = feasible;
                stretch.push(p);
            }
            flush(&mut stretch, stretch_feasible)?;
        }
        if k == 0 && !runs.is_empty() {
            let drawn: Vec<(f64, f64)> = runs
                .iter()
                .flat_map(|r| {
                    along(
                        &r.history
                            .iter()
                            .map(|h| (h.iteration as f64, value(h)))
                            .collect::<Vec<_>>(),
                    )
                })
                .collect();
            let labels: Vec<&str> = runs.iter().map(|r| r.label.as_str()).collect();
            let corner =
                least_covered_corner(&drawn, &labels, area.dim_in_pixel(), (0.0, x_max), y);
            ctx.configure_series_labels()
                .label_font((FONT, 12))
                .background_style(WHITE.mix(0.85))
                .border_style(RGBColor(0xB0, 0xB0, 0xB0))
                .position(corner)
                .draw()
                .map_err(draw_err)?;
        }
    }
    root.present().map_err(draw_err)?;
    Ok(())
}

/// The Pareto front: capacity against the overload ratio, colour = divert reserve d_min
/// (viridis, dark = small), with every other feasible evaluation in light grey behind.
pub fn draw_front(path: &Path, front: &[FrontPoint], log: &[Record]) -> Result<(), PlotError> {
    let format = format_of(path)?;
    ensure_font()?;
    let size = (950, 650);
    match format {
        Format::Svg => render_front(SVGBackend::new(path, size).into_drawing_area(), front, log),
        Format::Png => render_front(
            BitMapBackend::new(path, size).into_drawing_area(),
            front,
            log,
        ),
    }
}

fn render_front<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    front: &[FrontPoint],
    log: &[Record],
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(draw_err)?;
    let feasible: Vec<(f64, f64)> = log
        .iter()
        .filter(|r| r.evaluation.feasible() && r.evaluation.objectives.len() > 1)
        .map(|r| (capacity_of(&r.x), r.evaluation.objectives[1]))
        .collect();
    let pts: Vec<(f64, f64, f64)> = front
        .iter()
        .map(|f| {
            (
                capacity_of(&f.x),
                f.evaluation.objectives[1],
                -f.evaluation.objectives[2],
            )
        })
        .collect();
    let x = fit(feasible.iter().map(|p| p.0).chain(pts.iter().map(|p| p.0)));
    let y = fit(feasible.iter().map(|p| p.1).chain(pts.iter().map(|p| p.1)));
    let (d_lo, d_hi) = pts
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.2), b.max(p.2))
        });
    let d_span = if d_hi > d_lo { d_hi - d_lo } else { 1.0 };
    let mut ctx = ChartBuilder::on(&root)
        .caption(
            format!(
                "NSGA-II Pareto front: capacity vs overload; colour = divert reserve d_min {:.3}..{:.3} m (dark = small)",
                if d_lo.is_finite() { d_lo } else { 0.0 },
                if d_hi.is_finite() { d_hi } else { 0.0 }
            ),
            (FONT, 15),
        )
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(65)
        .build_cartesian_2d(x.0..x.1, y.0..y.1)
        .map_err(draw_err)?;
    ctx.configure_mesh()
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .x_desc("capacity W [parcels/h]")
        .y_desc("overload ratio S/S_fall")
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 15))
        .light_line_style(RGBColor(0xEE, 0xEE, 0xEE))
        .draw()
        .map_err(draw_err)?;
    let grey = RGBColor(0xD0, 0xD0, 0xD0);
    ctx.draw_series(feasible.iter().map(|&p| Circle::new(p, 2, grey.filled())))
        .map_err(draw_err)?
        .label("feasible evaluations")
        .legend(move |(x, y)| Circle::new((x + 10, y), 3, grey.filled()));
    let mid = crate::capacity::ramp(0.5);
    ctx.draw_series(pts.iter().map(|&(w, o, d)| {
        Circle::new(
            (w, o),
            5,
            crate::capacity::ramp((d - d_lo) / d_span).filled(),
        )
    }))
    .map_err(draw_err)?
    .label("front (colour: divert reserve)")
    .legend(move |(x, y)| Circle::new((x + 10, y), 5, mid.filled()));
    let drawn: Vec<(f64, f64)> = feasible
        .iter()
        .copied()
        .chain(pts.iter().map(|p| (p.0, p.1)))
        .collect();
    let corner = least_covered_corner(
        &drawn,
        &["feasible evaluations", "front (colour: divert reserve)"],
        root.dim_in_pixel(),
        x,
        y,
    );
    ctx.configure_series_labels()
        .label_font((FONT, 13))
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(0xB0, 0xB0, 0xB0))
        .position(corner)
        .draw()
        .map_err(draw_err)?;
    root.present().map_err(draw_err)?;
    Ok(())
}
