//! The paper's analyses as pictures and a page: the charts of `trigger` (paper Fig. 4),
//! `capture` (Fig. 5) and `overload` (Fig. 16) as data for
//! [`divertsim_figures::charts::line_chart`], and `replicate`'s index page (every finding with
//! its verdict and figure, findings (a)–(c) animated). Every edge draws the same charts from
//! here; nothing is read or written.

use crate::run::{escape, html, summary_html, ReportRun};
use divertsim_api::analyses::capture::{deg, CaptureResult};
use divertsim_api::analyses::overload::OverloadReport;
use divertsim_api::analyses::replicate::Replication;
use divertsim_api::analyses::trigger::stage_set;
use divertsim_core::analysis::paper::capture::CaptureCase;
use divertsim_core::analysis::paper::trigger::{RootKind, TriggerCurve};
use divertsim_figures::charts::{short, Chart, HLine, Series, Style};
use std::collections::BTreeMap;

/// trigger.svg: R_s against v, one colour per realised stage set, the reference setting
/// marked.
pub fn trigger(curve: &TriggerCurve) -> Chart {
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
            if r.kind == RootKind::Jump {
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
    Chart {
        title: format!(
            "Start position for the reference displacement {:.3} m",
            r.max_lateral
        ),
        x_label: "belt speed v [m/s]".into(),
        y_label: "R_s [m]".into(),
        series,
        ..Chart::default()
    }
}

/// capture.svg: α(t) and γ_p(t) per speed in degrees, α_z as horizontal lines, the capture
/// points marked.
pub fn capture(result: &CaptureResult) -> Chart {
    let cases: Vec<&CaptureCase> = result.rows.iter().filter_map(|r| r.case.as_ref()).collect();
    let mut series = Vec::new();
    if let Some(c) = cases.first() {
        // Every speed shares t_c, hence α(t).
        series.push(Series {
            color: Some(7),
            ..Series::new(
                "α(t) arm",
                c.curve.iter().map(|p| (p.t, deg(p.alpha))).collect(),
                Style::Line,
            )
        });
    }
    let mut captures = Vec::new();
    for (i, c) in cases.iter().enumerate() {
        series.push(Series {
            color: Some(i % 7),
            ..Series::new(
                format!("γ_p(t) v = {} m/s, R_s = {:.3} m", short(c.speed), c.start),
                c.curve.iter().map(|p| (p.t, deg(p.gamma))).collect(),
                Style::Dashed,
            )
        });
        if let Some(x) = c.kinematic.crossing.filter(|_| c.kinematic.captured) {
            captures.push((x.t, deg(x.alpha)));
        }
    }
    if !captures.is_empty() {
        series.push(Series {
            color: Some(3),
            ..Series::new("capture", captures, Style::Points)
        });
    }
    let mut hlines: Vec<HLine> = Vec::new();
    for c in &cases {
        if let Some(az) = c.kinematic.reach_angle.map(deg) {
            if !hlines.iter().any(|h| (h.y - az).abs() < 1e-9) {
                hlines.push(HLine {
                    y: az,
                    label: format!("α_z = {az:.2}°"),
                });
            }
        }
    }
    let ymax = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1))
        .chain(hlines.iter().map(|h| h.y))
        .filter(|y| y.is_finite())
        .fold(0.0f64, f64::max);
    Chart {
        title: "Arm angle α and front-corner angle γ_p (capture above α_z)".into(),
        x_label: "t [s]".into(),
        y_label: "angle [deg]".into(),
        series,
        hlines,
        // Far-upstream corners start near 180°; the arm never passes its swing.
        y_range: Some((0.0, ymax.min(100.0) * 1.05 + 1.0)),
        ..Chart::default()
    }
}

/// overload.svg: the worst-case impulse S against belt speed v, with the free-fall
/// references.
pub fn overload(r: &OverloadReport) -> Chart {
    Chart {
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
    }
}

/// replicate's index.html: every finding with its verdict and figure (`svgs`: each figure's
/// file name and SVG text, inlined), and the (a)–(c) runs animated. Self-contained.
pub fn replicate_index(r: &Replication, svgs: &[(String, String)]) -> String {
    let rows: String = r
        .findings
        .iter()
        .map(|f| {
            format!(
                "<tr><td>({})</td><td>{}</td><td>{}</td><td><a href=\"#{}\">{}</a></td><td><b>{}</b></td></tr>",
                f.id,
                escape(f.paper),
                escape(&f.divertsim),
                escape(f.figure.trim_end_matches(".svg")),
                escape(f.figure),
                f.verdict.label()
            )
        })
        .collect();
    let mut figures: Vec<&str> = r.findings.iter().map(|f| f.figure).collect();
    figures.dedup();
    let mut body = format!(
        "<h2>Findings</h2><table><tr><th>finding</th><th>the paper</th><th>divertsim</th><th>figure</th><th>verdict</th></tr>{rows}</table>"
    );
    for fig in figures {
        let svg = svgs
            .iter()
            .find(|(name, _)| name == fig)
            .map_or("", |(_, s)| s.as_str());
        // The XML declaration is not allowed inside HTML.
        let svg = svg.trim_start_matches(|c| c != '<');
        let svg = if svg.starts_with("<?xml") {
            &svg[svg.find("?>").map_or(0, |i| i + 2)..]
        } else {
            svg
        };
        body += &format!(
            "<h2 id=\"{}\">{}</h2><div style=\"max-width:100%;overflow:auto\">{}</div>",
            escape(fig.trim_end_matches(".svg")),
            escape(fig),
            svg
        );
    }
    let abc = &r.paths_figures[0].1;
    let runs: Vec<ReportRun<'_>> = abc
        .iter()
        .zip(["(a)", "(b)", "(c)"])
        .map(|(c, id)| ReportRun {
            label: format!("{id} {}", c.name),
            scenario: &c.scenario,
            result: &c.result,
            measured: Vec::new(),
        })
        .collect();
    let side = format!("<h2>Findings (a)–(c)</h2>{}", summary_html(&runs));
    html(
        "divertsim: the paper's findings replicated",
        "the slender parcel of findings (a)–(c) animated; every finding below with its figure",
        &runs,
        &side,
        &body,
    )
}
