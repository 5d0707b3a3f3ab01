//! The reliability study's charts (issue 11): failure and overload rates binned against each
//! input with their 95 % intervals, the divert-reserve and overload histograms, and the rate
//! curves of a sweep. Inputs are the core's tallies
//! ([`divertsim_core::analysis::population::reliability`]); an edge writes the charts with
//! [`crate::charts`].

use crate::charts::{self, Chart, Series, Style};
use divertsim_core::analysis::population::reliability::{
    Bins, Spectrum, Tally, CONFIDENCE, INPUTS,
};
use divertsim_core::stats::binomial::{clopper_pearson, Proportion};
use std::path::Path;

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

/// A load spectrum as its exceedance curve, the way a fatigue assessment reads it: at each
/// bin's lower edge x, log₁₀ of the loads at or above x per 10⁶ strokes (the loads above the
/// spectrum's ceiling included; a linear count would show only the first bin).
pub fn exceedance_chart(title: String, x_label: &str, sp: &Spectrum, strokes: u64) -> Chart {
    let total: u64 = sp.total();
    let mut left = total;
    let mut pts = Vec::new();
    for k in 0..sp.count.len() {
        if left == 0 {
            break;
        }
        pts.push((
            sp.lower(k),
            (left as f64 * 1e6 / strokes.max(1) as f64).log10(),
        ));
        left -= sp.count[k];
    }
    if left > 0 {
        pts.push((
            *sp.upper.last().unwrap_or(&0.0),
            (left as f64 * 1e6 / strokes.max(1) as f64).log10(),
        ));
    }
    pts.push((sp.max, (1e6 / strokes.max(1) as f64).log10()));
    Chart {
        title,
        x_label: x_label.to_string(),
        y_label: "log₁₀ (loads at or above x per 10⁶ strokes)".into(),
        series: vec![Series::new("", pts, Style::LinePoints)],
        ..Chart::default()
    }
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

/// What the study's plots show: the seed, the first point's setting in words, each sweep
/// point's value (one empty value without a sweep), the tallies, the swept key.
pub struct Study<'a> {
    pub seed: u64,
    pub setting: &'a str,
    pub values: &'a [String],
    pub tallies: &'a [&'a Tally],
    pub sweep_key: Option<&'a str>,
}

/// The study's plots into `dir` (SVG and PNG): without a sweep the failure rate by input
/// (failure_rate) and the reserve and overload histograms (divert_reserve,
/// overload_ratio); with one the rate curves over the swept values (sweep).
pub fn draw_study(dir: &Path, study: &Study<'_>) -> Result<(), String> {
    let both = |name: &str,
                f: &dyn Fn(&Path) -> Result<(), crate::plot::PlotError>|
     -> Result<(), String> {
        for ext in ["svg", "png"] {
            f(&dir.join(format!("{name}.{ext}"))).map_err(|e| format!("{name}.{ext}: {e}"))?;
        }
        Ok(())
    };
    let (seed, setting) = (study.seed, study.setting);
    if let Some(key) = study.sweep_key {
        let numeric: Option<Vec<f64>> = study.values.iter().map(|v| v.parse().ok()).collect();
        let xs: Vec<f64> = numeric
            .clone()
            .unwrap_or_else(|| (0..study.values.len()).map(|i| i as f64).collect());
        let x_label = match numeric {
            Some(_) => key.to_string(),
            None => format!(
                "{key}: {}",
                study
                    .values
                    .iter()
                    .enumerate()
                    .map(|(i, v)| format!("{i} = {v}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        let charts = sweep_charts(key, &x_label, &xs, study.tallies);
        let title = format!(
            "{} samples per point, seed {seed}; at the first point {setting}; {key} swept",
            study.tallies.first().map_or(0, |t| t.samples),
        );
        return both("sweep", &|p| {
            charts::panels(p, &title, &charts, 2, (700, 500))
        });
    }
    let Some(t) = study.tallies.first() else {
        return Ok(());
    };
    let rate_charts = input_rate_charts(t);
    if !rate_charts.is_empty() {
        let title = format!(
            "failure and overload rates by input: {} samples, seed {seed}; {setting}",
            t.samples
        );
        both("failure_rate", &|path| {
            charts::panels(path, &title, &rate_charts, 3, (560, 400))
        })?;
    }
    let hist = |name: &str, b: &Option<Bins>, x_label: &str, reference: Option<f64>| {
        let Some(b) = b else { return Ok(()) };
        let title = format!("{} samples, seed {seed}; {setting}", t.samples);
        let chart = histogram(title, b, x_label, reference);
        both(name, &|path| charts::line_chart(path, &chart))
    };
    hist(
        "divert_reserve",
        &t.reserve_hist,
        "divert reserve d [m] (d ≥ 0 diverted)",
        None,
    )?;
    hist("overload_ratio", &t.overload_hist, "S/S_fall", Some(1.0))?;
    // The arm's load spectra (issue 26): each stroke's peak drive torque, each strike's
    // angular impulse on the arm.
    let spectra: Vec<Chart> = [
        (
            &t.loads.torque_spectrum,
            "each stroke's peak drive torque",
            "M_d [N·m]",
        ),
        (
            &t.loads.strike_spectrum,
            "each strike's angular impulse on the arm",
            "J_c [N·m·s]",
        ),
    ]
    .into_iter()
    .filter_map(|(sp, what, x)| {
        sp.as_ref()
            .map(|sp| exceedance_chart(what.to_string(), x, sp, t.loads.strokes))
    })
    .collect();
    if spectra.is_empty() {
        return Ok(());
    }
    let title = format!(
        "load spectrum over {} strokes, seed {seed}; {setting}",
        t.loads.strokes
    );
    both("load_spectrum", &|path| {
        charts::panels(path, &title, &spectra, 2, (640, 440))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exceedance curve starts with every load at 0, falls by each bin's count, keeps
    /// the loads above the ceiling, and ends with the largest load alone.
    #[test]
    fn exceedance_counts_the_loads_at_or_above_each_edge() {
        let mut sp = Spectrum::for_values([2.0].into_iter()).unwrap(); // ceiling 5
        for x in [0.1, 0.1, 0.2, 1.0, 4.9, 7.0] {
            sp.add(x);
        }
        let c = exceedance_chart("t".into(), "x", &sp, 10);
        let pts = &c.series[0].points;
        let per = |n: f64| (n * 1e6 / 10.0).log10();
        assert_eq!(pts.first(), Some(&(0.0, per(6.0))));
        // After the first bin (0.125 wide) four loads remain: 0.2, 1.0, 4.9 and 7.0.
        assert_eq!(pts[1], (0.125, per(4.0)));
        assert!(pts.contains(&(5.0, per(1.0))), "{pts:?}");
        assert_eq!(pts.last(), Some(&(7.0, per(1.0))));
        assert!(pts.windows(2).all(|w| w[1].0 >= w[0].0 && w[1].1 <= w[0].1));
    }
}
