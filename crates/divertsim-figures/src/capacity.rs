//! The capacity map as a heat map (paper Fig. 9): t_c on x, S_d on y, colour W, grey with ×
//! where no setting is feasible, a ring on the best cell (and a warning when it sits on the
//! grid's edge) and a colour bar. Input is the core's [`CapacityMap`].

use crate::charts::{short, tick};
use crate::plot::{draw_err, ensure_font, format_of, Format, PlotError, FONT};
use divertsim_core::analysis::design::capacity::CapacityMap;
use plotters::prelude::*;
use std::path::Path;

/// Colour ramp (viridis stops, linear between them) for t in [0, 1].
pub fn ramp(t: f64) -> RGBColor {
    const STOPS: [(u8, u8, u8); 6] = [
        (0x44, 0x01, 0x54),
        (0x41, 0x44, 0x87),
        (0x2A, 0x78, 0x8E),
        (0x22, 0xA8, 0x84),
        (0x7A, 0xD1, 0x51),
        (0xFD, 0xE7, 0x25),
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (STOPS.len() - 1) as f64;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    let f = x - i as f64;
    let mix = |a: u8, b: u8| (a as f64 + (b as f64 - a as f64) * f).round() as u8;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Cell edges for centre values (half-way between neighbours).
fn edges(values: &[f64]) -> Vec<f64> {
    let n = values.len();
    let half = if n > 1 {
        0.5 * (values[n - 1] - values[0]) / (n - 1) as f64
    } else {
        0.05 * values[0].abs().max(1.0)
    };
    let mut e = Vec::with_capacity(n + 1);
    e.push(values[0] - half);
    for w in values.windows(2) {
        e.push(0.5 * (w[0] + w[1]));
    }
    e.push(values[n - 1] + half);
    e
}

/// Draw the heat map (t_c on x, S_d on y, colour W; grey with × where infeasible; a ring on
/// the best cell; a colour bar) to `path` (.svg or .png). `against` names the worst case the
/// cells hold against, for the title ("the searched worst case").
pub fn draw(map: &CapacityMap, against: &str, path: &Path) -> Result<(), PlotError> {
    let format = format_of(path)?;
    ensure_font()?;
    let size = (1000, 700);
    match format {
        Format::Svg => render(
            SVGBackend::new(path, size).into_drawing_area(),
            map,
            against,
        ),
        Format::Png => render(
            BitMapBackend::new(path, size).into_drawing_area(),
            map,
            against,
        ),
    }
}

fn render<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    map: &CapacityMap,
    against: &str,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(draw_err)?;
    let o = &map.options;
    if o.cycle_times.is_empty() || o.light_barriers.is_empty() {
        root.present().map_err(draw_err)?;
        return Ok(());
    }
    let (left, right) = root.split_horizontally(860);
    // The best cell's legend goes below the map, never over its cells.
    let (left, note) = left.split_vertically(650);
    let xe = edges(&o.cycle_times);
    let ye = edges(&o.light_barriers);
    let nsd = o.light_barriers.len();
    let feasible: Vec<f64> = map
        .cells
        .iter()
        .filter(|c| c.feasible)
        .map(|c| c.capacity)
        .collect();
    let (w_lo, w_hi) = feasible
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &w| {
            (a.min(w), b.max(w))
        });
    let (w_lo, w_hi) = if !w_lo.is_finite() {
        (0.0, 1.0)
    } else if w_hi > w_lo {
        (w_lo, w_hi)
    } else {
        (w_lo - 1.0, w_hi + 1.0)
    };
    let norm = |w: f64| (w - w_lo) / (w_hi - w_lo);

    let mut chart = ChartBuilder::on(&left)
        .caption(
            format!("Capacity W [parcels/h] against {against}; grey × = none feasible"),
            (FONT, 17),
        )
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(65)
        .build_cartesian_2d(xe[0]..xe[xe.len() - 1], ye[0]..ye[ye.len() - 1])
        .map_err(draw_err)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .x_desc("cycle time t_c [s]")
        .y_desc("light barrier S_d [m]")
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 15))
        .draw()
        .map_err(draw_err)?;
    let grey = RGBColor(0xC8, 0xC8, 0xC8);
    for i in 0..o.cycle_times.len() {
        for j in 0..nsd {
            let c = &map.cells[i * nsd + j];
            let (x0, x1, y0, y1) = (xe[i], xe[i + 1], ye[j], ye[j + 1]);
            let fill = if c.feasible {
                ramp(norm(c.capacity))
            } else {
                grey
            };
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(x0, y0), (x1, y1)],
                    fill.filled(),
                )))
                .map_err(draw_err)?;
            if !c.feasible {
                let (dx, dy) = (0.25 * (x1 - x0), 0.25 * (y1 - y0));
                let cross = RGBColor(0x70, 0x70, 0x70).stroke_width(1);
                for seg in [
                    [(x0 + dx, y0 + dy), (x1 - dx, y1 - dy)],
                    [(x0 + dx, y1 - dy), (x1 - dx, y0 + dy)],
                ] {
                    chart
                        .draw_series(std::iter::once(PathElement::new(seg.to_vec(), cross)))
                        .map_err(draw_err)?;
                }
            }
        }
    }
    if let Some(b) = map.best() {
        chart
            .draw_series(std::iter::once(Circle::new(
                (b.cycle_time, b.light_barrier),
                7,
                RED.stroke_width(2),
            )))
            .map_err(draw_err)?;
        note.draw(&Circle::new((90, 12), 6, RED.stroke_width(2)))
            .map_err(draw_err)?;
        note.draw(&Text::new(
            format!(
                "best W = {:.0} /h (v = {} m/s, R_s = {:.3} m, t_c = {} s, S_d = {} m)",
                b.capacity,
                b.belt_speed.map_or("?".into(), tick),
                b.start_position.unwrap_or(f64::NAN),
                short(b.cycle_time),
                short(b.light_barrier)
            ),
            (104, 4),
            (FONT, 13).into_font(),
        ))
        .map_err(draw_err)?;
        let edges = map.best_on_edges();
        if !edges.is_empty() {
            let each: Vec<String> = edges
                .iter()
                .map(|e| format!("the {} of {}", e.end, e.option))
                .collect();
            note.draw(&Text::new(
                format!(
                    "best cell on the grid's edge ({}): W may grow past it, widen the grid",
                    each.join(", ")
                ),
                (104, 26),
                (FONT, 13).into_font().color(&RGBColor(0xB0, 0x20, 0x20)),
            ))
            .map_err(draw_err)?;
        }
    }

    // Colour bar.
    let mut bar = ChartBuilder::on(&right)
        .margin_top(50)
        .margin_bottom(57 + 50) // the map above its note
        .margin_right(10)
        .y_label_area_size(70)
        .caption("W [/h]", (FONT, 14))
        .build_cartesian_2d(0.0..1.0, w_lo..w_hi)
        .map_err(draw_err)?;
    bar.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_label_formatter(&|v| tick(*v))
        .label_style((FONT, 12))
        .draw()
        .map_err(draw_err)?;
    let steps = 64;
    bar.draw_series((0..steps).map(|k| {
        let a = w_lo + (w_hi - w_lo) * k as f64 / steps as f64;
        let b = w_lo + (w_hi - w_lo) * (k + 1) as f64 / steps as f64;
        Rectangle::new(
            [(0.0, a), (1.0, b)],
            ramp((k as f64 + 0.5) / steps as f64).filled(),
        )
    }))
    .map_err(draw_err)?;
    root.present().map_err(draw_err)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_ends_and_edges() {
        assert_eq!(ramp(0.0), RGBColor(0x44, 0x01, 0x54));
        assert_eq!(ramp(1.0), RGBColor(0xFD, 0xE7, 0x25));
        assert_eq!(ramp(f64::NAN), ramp(0.0));
        assert_eq!(ramp(2.0), ramp(1.0));
        assert_eq!(edges(&[1.0, 2.0, 3.0]), vec![0.5, 1.5, 2.5, 3.5]);
        assert_eq!(edges(&[2.0]), vec![1.9, 2.1]);
    }
}
