//! The reliability study's charts (issue 11): failure and overload rates binned against each
//! input with their 95 % intervals, the divert-reserve and overload histograms, and the rate
//! curves of a sweep. Inputs are the core's tallies
//! ([`divertsim_core::analysis::population::reliability`]); an edge writes the charts with
//! [`crate::charts`].

use crate::charts::{Chart, Series, Style};
use divertsim_core::analysis::population::reliability::{Bins, Tally, CONFIDENCE, INPUTS};
use divertsim_core::stats::binomial::{clopper_pearson, Proportion};

/// Bin centres and one value per non-empty bin.
fn bin_series(b: &Bins, value: impl Fn(usize) -> f64) -> Vec<(f64, f64)> {
    (0..b.count.len())
        .filter(|&k| b.count[k] > 0)
        .map(|k| {
            let (lo, hi) = b.edges(k);
            (0.5 * (lo + hi), value(k))
        })
        .collect()
}

/// A histogram as a step outline.
fn steps(b: &Bins) -> Vec<(f64, f64)> {
    let mut pts = Vec::new();
    for k in 0..b.count.len() {
        let (lo, hi) = b.edges(k);
        let c = b.count[k] as f64;
        pts.push((lo, c));
        pts.push((hi, c));
    }
    pts
}

/// Failure and overload rates against one input, each with its 95 % interval (dashed).
pub fn rate_chart(title: String, x_label: &str, b: &Bins) -> Chart {
    let mut series = Vec::new();
    let mut top: f64 = 0.0;
    for (label, counts, color) in [
        ("failure rate", &b.failed, 3),
        ("overload rate", &b.overloaded, 0),
    ] {
        let ci = |k: usize| clopper_pearson(counts[k], b.count[k], CONFIDENCE);
        let mut rate = Series::new(label, bin_series(b, |k| ci(k).estimate), Style::LinePoints);
        rate.color = Some(color);
        let mut lo = Series::new("", bin_series(b, |k| ci(k).lower), Style::Dashed);
        lo.color = Some(color);
        let hi_pts = bin_series(b, |k| ci(k).upper);
        top = hi_pts.iter().fold(top, |t, p| t.max(p.1));
        let mut hi = Series::new("", hi_pts, Style::Dashed);
        hi.color = Some(color);
        series.extend([rate, lo, hi]);
    }
    Chart {
        title,
        x_label: x_label.to_string(),
        y_label: "rate (dashed: 95 % interval)".into(),
        series,
        y_range: Some((0.0, (top * 1.15).clamp(0.01, 1.0))),
        ..Chart::default()
    }
}

/// The rate chart of every binned input of `tally`, in the order of [`INPUTS`].
pub fn input_rate_charts(tally: &Tally) -> Vec<Chart> {
    tally
        .input_bins
        .iter()
        .zip(INPUTS)
        .filter_map(|(b, name)| {
            b.as_ref()
                .map(|b| rate_chart(format!("by {name}"), name, b))
        })
        .collect()
}

/// A histogram titled `title`, with a dashed vertical line at `reference` when given.
pub fn histogram(title: String, b: &Bins, x_label: &str, reference: Option<f64>) -> Chart {
    let mut chart = Chart {
        title,
        x_label: x_label.to_string(),
        y_label: "samples".into(),
        series: vec![Series::new("", steps(b), Style::Line)],
        ..Chart::default()
    };
    if let Some(x) = reference {
        // A vertical reference drawn as a series.
        let top = b.count.iter().copied().max().unwrap_or(1) as f64;
        let mut s = Series::new(
            format!("{x_label} = {x}"),
            vec![(x, 0.0), (x, top)],
            Style::Dashed,
        );
        s.color = Some(3);
        chart.series.push(s);
    }
    chart
}

/// The divert-rate and overload-rate curves of a sweep over `key`: one tally per value at
/// `xs`, labelled `x_label`.
pub fn sweep_charts(key: &str, x_label: &str, xs: &[f64], tallies: &[&Tally]) -> [Chart; 2] {
    let curve = |title: &str, f: &dyn Fn(&Tally) -> Proportion, color: usize| {
        let pts = |g: &dyn Fn(&Proportion) -> f64| -> Vec<(f64, f64)> {
            xs.iter()
                .zip(tallies)
                .map(|(x, t)| (*x, g(&f(t))))
                .collect()
        };
        let mut est = Series::new(title, pts(&|p| p.estimate), Style::LinePoints);
        est.color = Some(color);
        let mut lo = Series::new("95 % interval", pts(&|p| p.lower), Style::Dashed);
        lo.color = Some(7);
        let mut hi = Series::new("", pts(&|p| p.upper), Style::Dashed);
        hi.color = Some(7);
        Chart {
            title: format!("{title} against {key}"),
            x_label: x_label.to_string(),
            y_label: title.to_string(),
            series: vec![est, lo, hi],
            ..Chart::default()
        }
    };
    [
        curve("divert rate", &|t| t.divert_rate(CONFIDENCE), 0),
        curve("overload rate", &|t| t.overload_rate(CONFIDENCE), 3),
    ]
}
