//! The sorter line's throughput curve: parcels per hour diverted into their own chute
//! against the arrival rate, with the arrival rate itself (everything delivered) and the
//! paper's W (one parcel per cycle, summed over the diverters) beside it; below, the share
//! of each outcome, stacked. Input: the core's line and tally of each point of a sweep.

use crate::charts::{panels, Chart, HLine, Series, Style};
use crate::plot::PlotError;
use divertsim_core::analysis::line::tally::LineTally;
use divertsim_core::analysis::line::{Line, LineOutcome};
use divertsim_core::stats::binomial::clopper_pearson;
use std::path::Path;

/// The paper's W = 3600/((R_s − S_d)/v + t_c) summed over a line's diverters \[1/h].
pub fn paper_capacity(line: &Line) -> f64 {
    line.diverters.iter().map(|d| d.paper_capacity()).sum()
}

/// A point of the curve: the swept value as given, its line and its tally.
pub type CurvePoint<'a> = (&'a str, &'a Line, &'a LineTally);

/// The two panels of the curve over `points` (one per swept value), ordered by arrival
/// rate; the title names `what` was swept and the x axis its values at either end, and the
/// points where parcels collided are marked as outside the model (issue 50).
pub fn throughput_charts(what: &str, points: &[CurvePoint<'_>]) -> [Chart; 2] {
    let mut sorted: Vec<&CurvePoint<'_>> = points.iter().collect();
    sorted.sort_by(|a, b| a.2.arrival_rate().total_cmp(&b.2.arrival_rate()));
    let ends = match (sorted.first(), sorted.last()) {
        (Some(a), Some(b)) => format!(" — {what}: {} at the left, {} at the right", a.0, b.0),
        _ => String::new(),
    };
    let collided: Vec<(f64, f64)> = sorted
        .iter()
        .filter(|(_, _, t)| t.count("collision") > 0)
        .map(|(_, _, t)| (t.arrival_rate(), t.line_throughput()))
        .collect();
    let tallies: Vec<&LineTally> = sorted.iter().map(|p| p.2).collect();
    let x = |t: &LineTally| t.arrival_rate();
    let throughput: Vec<(f64, f64)> = tallies
        .iter()
        .map(|t| (x(t), t.line_throughput()))
        .collect();
    // The 95 % band of the throughput: the divert count's interval, scaled.
    let band = |upper: bool| -> Vec<(f64, f64)> {
        tallies
            .iter()
            .map(|t| {
                let p = clopper_pearson(t.count("diverted"), t.parcels, 0.95);
                (
                    x(t),
                    t.arrival_rate() * if upper { p.upper } else { p.lower },
                )
            })
            .collect()
    };
    let arrivals: Vec<(f64, f64)> = tallies.iter().map(|t| (x(t), x(t))).collect();
    let w = sorted.first().map_or(f64::NAN, |p| paper_capacity(p.1));
    let mut lower = Series::new("95 % interval", band(false), Style::Dashed);
    lower.color = Some(7);
    let mut upper = Series::new("", band(true), Style::Dashed);
    upper.color = Some(7);
    let mut arrive = Series::new("arrival rate (all delivered)", arrivals, Style::Dashed);
    arrive.color = Some(1);
    let mut series = vec![
        Series::new("throughput", throughput, Style::LinePoints),
        lower,
        upper,
        arrive,
    ];
    if !collided.is_empty() {
        let mut c = Series::new(
            "parcels collided: outside the model",
            collided,
            Style::Points,
        );
        c.color = Some(3);
        series.push(c);
    }
    let top = Chart {
        title: format!("Throughput of the line ({what})"),
        x_label: format!("arrival rate [parcels/h]{ends}"),
        y_label: "diverted into their own chute [parcels/h]".into(),
        series,
        hlines: vec![HLine {
            y: w,
            label: format!("paper's W = {w:.0}/h (one parcel per cycle)"),
        }],
        ..Chart::default()
    };
    // Stacked shares: each series is the cumulative share up to its outcome, drawn from the
    // top down so that each band shows its own outcome.
    let kinds: Vec<(usize, &str)> = LineOutcome::KINDS
        .iter()
        .enumerate()
        .filter(|(_, k)| tallies.iter().any(|t| t.count(k) > 0))
        .map(|(i, k)| (i, *k))
        .collect();
    let mut stacked = Vec::new();
    for (j, (i, k)) in kinds.iter().enumerate().rev() {
        let cumulative = tallies
            .iter()
            .map(|t| {
                let upto: u64 = kinds[..=j].iter().map(|(_, k)| t.count(k)).sum();
                (x(t), 100.0 * upto as f64 / t.parcels.max(1) as f64)
            })
            .collect();
        let mut s = Series::new(*k, cumulative, Style::Area);
        s.color = Some(*i);
        stacked.push(s);
    }
    let bottom = Chart {
        title: "Outcome of every parcel (stacked)".into(),
        x_label: "arrival rate [parcels/h]".into(),
        y_label: "share of parcels [%]".into(),
        series: stacked,
        y_range: Some((0.0, 100.0)),
        x_range: top.x_range,
        ..Chart::default()
    };
    [top, bottom]
}

/// Draw the curve to `path` (.svg or .png).
pub fn draw_throughput(
    path: &Path,
    what: &str,
    points: &[CurvePoint<'_>],
) -> Result<(), PlotError> {
    panels(
        path,
        "The sorter line",
        &throughput_charts(what, points),
        1,
        (1000, 520),
    )
}
