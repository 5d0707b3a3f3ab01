//! Filmed tracks against their simulations: the overlay of a measured marker path and the
//! simulated one (paper Figs 13–15 style), for `compare` and `calibrate`.

use std::path::Path;

use crate::charts::{self, Chart, HLine, Series, Style};
use crate::plot::PlotError;
use divertsim_core::analysis::measurement::track::{Comparison, MarkerPath, Track};
use divertsim_core::model::params::Scenario;
use divertsim_core::sim::SimResult;
use glam::DVec2;

/// The overlay of a measured and a simulated marker path (SVG or PNG by extension).
pub fn marker_overlay(
    path: &Path,
    name: &str,
    s: &Scenario,
    result: &SimResult,
    marker_offset: DVec2,
    track: &Track,
    c: &Comparison,
) -> Result<(), PlotError> {
    // The simulated marker every 5 ms over the track's time span.
    let marker = MarkerPath::new(s, result, marker_offset);
    let (t_first, t_last) = (track.times[0], track.times[track.times.len() - 1]);
    let steps = (((t_last - t_first) / 0.005).ceil() as usize).clamp(1, 20_000);
    let dense: Vec<(f64, f64)> = (0..=steps)
        .map(|k| {
            let tv = t_first + (t_last - t_first) * k as f64 / steps as f64;
            let q = marker.at(tv - c.offset);
            (q.x, q.y)
        })
        .collect();
    let p = &s.parcel;
    let chart = Chart {
        title: format!(
            "{name}: {:.2} × {:.2} m at ΔP = {} m; v = {} m/s, t_c = {} s, R_s = {} m",
            p.length,
            p.width,
            crate::charts::short(p.offset),
            crate::charts::short(s.machine.belt_speed),
            crate::charts::short(s.machine.cycle_time),
            crate::charts::short(s.machine.start_position)
        ),
        x_label: "x [m] (along the belt)".into(),
        y_label: "y [m] (across the belt)".into(),
        series: vec![
            Series::new("simulated marker", dense, Style::Line),
            Series::new(
                format!("measured ({} points)", track.points.len()),
                track.points.iter().map(|q| (q.x, q.y)).collect(),
                Style::Points,
            ),
        ],
        hlines: vec![HLine {
            y: s.machine.belt_width,
            label: "far belt edge".into(),
        }],
        ..Chart::default()
    };
    charts::line_chart(path, &chart)
}
