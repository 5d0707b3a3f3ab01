//! Line charts for the analysis commands (trigger, capture, overload, optimisation histories):
//! several x–y series, optional horizontal reference lines, a legend, axis labels and a title,
//! written to SVG or PNG with plotters and the bundled font of [`crate::plot`].

use std::path::Path;

use plotters::prelude::*;

use crate::plot::{draw_err, ensure_font, format_of, Format, PlotError, FONT};

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    /// A solid polyline.
    Line,
    /// A dashed polyline.
    Dashed,
    /// Markers only.
    Points,
    /// A polyline with markers.
    LinePoints,
    /// A polyline filled down to y = 0 (stacked areas: give the cumulative series, the
    /// largest first).
    Area,
}

/// One named data series.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    pub label: String,
    /// (x, y) points; non-finite points are skipped and break a line.
    pub points: Vec<(f64, f64)>,
    pub style: Style,
    /// Index into the palette; `None`: the series' position.
    pub color: Option<usize>,
}

impl Series {
    pub fn new(label: impl Into<String>, points: Vec<(f64, f64)>, style: Style) -> Series {
        Series {
            label: label.into(),
            points,
            style,
            color: None,
        }
    }
}

/// A horizontal reference line (e.g. the free-fall impulse).
#[derive(Debug, Clone, PartialEq)]
pub struct HLine {
    pub y: f64,
    pub label: String,
}

/// A whole chart.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Chart {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
    pub hlines: Vec<HLine>,
    /// Fixed axis ranges; `None`: fitted to the data with a 5 % margin.
    pub x_range: Option<(f64, f64)>,
    pub y_range: Option<(f64, f64)>,
    /// Image size \[px]; (0, 0) means the default 900 × 600.
    pub size: (u32, u32),
}

/// Tableau-10: distinguishable, colour-blind-friendlier than the plotters defaults.
pub const PALETTE: [RGBColor; 10] = [
    RGBColor(0x1F, 0x77, 0xB4),
    RGBColor(0xFF, 0x7F, 0x0E),
    RGBColor(0x2C, 0xA0, 0x2C),
    RGBColor(0xD6, 0x27, 0x28),
    RGBColor(0x94, 0x67, 0xBD),
    RGBColor(0x8C, 0x56, 0x4B),
    RGBColor(0xE3, 0x77, 0xC2),
    RGBColor(0x7F, 0x7F, 0x7F),
    RGBColor(0xBC, 0xBD, 0x22),
    RGBColor(0x17, 0xBE, 0xCF),
];

/// The range of the finite values, widened by 5 % (and made non-empty).
pub fn fit(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let span = if hi > lo {
        hi - lo
    } else {
        lo.abs().max(1.0) * 0.1
    };
    (lo - 0.05 * span, hi + 0.05 * span)
}

/// A number for a title or a legend: at most 4 decimals, no trailing zeros, no "-0"
/// (`1.2319`, `0.7` for 0.7000000000000001, `2`).
pub fn short(v: f64) -> String {
    trimmed(v, 4)
}

/// A tick label: at most 6 decimals, no trailing zeros, no "-0" (`2000`, `0.25`, `0`).
pub fn tick(v: f64) -> String {
    trimmed(v, 6)
}

/// `v` to at most `decimals` decimals, no trailing zeros, no "-0".
fn trimmed(v: f64, decimals: usize) -> String {
    let text = format!("{v:.decimals$}");
    match text.trim_end_matches('0').trim_end_matches('.') {
        "-0" | "" => "0".into(),
        t => t.to_string(),
    }
}

/// Split a series into runs of finite points (a non-finite point breaks the line).
fn runs(points: &[(f64, f64)]) -> Vec<Vec<(f64, f64)>> {
    let mut out = vec![Vec::new()];
    for &(x, y) in points {
        if x.is_finite() && y.is_finite() {
            out.last_mut().expect("non-empty").push((x, y));
        } else if !out.last().expect("non-empty").is_empty() {
            out.push(Vec::new());
        }
    }
    out.retain(|r| !r.is_empty());
    out
}

/// The corner where the legend covers the least data: the legend's box is estimated from
/// its entries and longest label; each corner counts the series points (and points along
/// each segment) and reference lines inside that box; ties go to upper right, upper left,
/// lower right, lower left, in this order.
pub fn legend_corner(chart: &Chart, x: (f64, f64), y: (f64, f64)) -> SeriesLabelPosition {
    let labels: Vec<&str> = chart
        .series
        .iter()
        .map(|s| s.label.as_str())
        .filter(|l| !l.is_empty())
        .chain(chart.hlines.iter().map(|h| h.label.as_str()))
        .collect();
    let size = if chart.size == (0, 0) {
        (900, 600)
    } else {
        chart.size
    };
    let mut pts: Vec<(f64, f64)> = Vec::new();
    for s in &chart.series {
        for run in runs(&s.points) {
            pts.extend(along(&run));
        }
    }
    for hl in chart.hlines.iter().filter(|h| h.y.is_finite()) {
        pts.extend((0..=20).map(|k| (x.0 + k as f64 / 20.0 * (x.1 - x.0), hl.y)));
    }
    least_covered_corner(&pts, &labels, size, x, y)
}

/// `line`'s vertices and nine points along each of its segments (data coordinates), for
/// [`least_covered_corner`].
pub fn along(line: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut pts = Vec::with_capacity(line.len() * 10);
    for w in line.windows(2) {
        for k in 0..10 {
            let t = k as f64 / 10.0;
            pts.push((
                w[0].0 + t * (w[1].0 - w[0].0),
                w[0].1 + t * (w[1].1 - w[0].1),
            ));
        }
    }
    pts.extend(line.last());
    pts
}

/// The corner of a `size` (pixels) chart over `x` × `y` where a legend of `labels` covers
/// the fewest of `points` (data coordinates; non-finite ones are ignored). Every chart with
/// an inset legend places it through this; ties go to upper right, upper left, lower
/// right, lower left, in this order.
pub fn least_covered_corner(
    points: &[(f64, f64)],
    labels: &[&str],
    size: (u32, u32),
    x: (f64, f64),
    y: (f64, f64),
) -> SeriesLabelPosition {
    let longest = labels.iter().map(|l| l.chars().count()).max().unwrap_or(0) as f64;
    // About 6.5 px per character at 13 px plus the sample line; 20 px per entry.
    let w = ((longest * 6.5 + 50.0) / (size.0 as f64 - 100.0)).clamp(0.2, 1.0);
    let h = ((labels.len() as f64 * 20.0 + 12.0) / (size.1 as f64 - 100.0)).clamp(0.1, 1.0);
    let pts: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .map(|p| ((p.0 - x.0) / (x.1 - x.0), (p.1 - y.0) / (y.1 - y.0)))
        .collect();
    let corners = [
        (
            SeriesLabelPosition::UpperRight,
            (1.0 - w, 1.0),
            (1.0 - h, 1.0),
        ),
        (SeriesLabelPosition::UpperLeft, (0.0, w), (1.0 - h, 1.0)),
        (SeriesLabelPosition::LowerRight, (1.0 - w, 1.0), (0.0, h)),
        (SeriesLabelPosition::LowerLeft, (0.0, w), (0.0, h)),
    ];
    let covered = |(xa, xb): (f64, f64), (ya, yb): (f64, f64)| {
        pts.iter()
            .filter(|(px, py)| *px >= xa && *px <= xb && *py >= ya && *py <= yb)
            .count()
    };
    let mut best = (usize::MAX, SeriesLabelPosition::UpperRight);
    for (pos, xs, ys) in corners {
        let c = covered(xs, ys);
        if c < best.0 {
            best = (c, pos);
        }
    }
    best.1
}

/// Draw `chart` to `path` (`.svg` or `.png`).
pub fn line_chart(path: &Path, chart: &Chart) -> Result<(), PlotError> {
    let format = format_of(path)?;
    ensure_font()?;
    let size = if chart.size == (0, 0) {
        (900, 600)
    } else {
        chart.size
    };
    match format {
        Format::Svg => render(SVGBackend::new(path, size).into_drawing_area(), chart),
        Format::Png => render(BitMapBackend::new(path, size).into_drawing_area(), chart),
    }
}

/// Draw several charts as panels of one image under a title, `columns` per row, each panel
/// `panel_size` pixels.
pub fn panels(
    path: &Path,
    title: &str,
    charts: &[Chart],
    columns: usize,
    panel_size: (u32, u32),
) -> Result<(), PlotError> {
    let format = format_of(path)?;
    ensure_font()?;
    let columns = columns.clamp(1, charts.len().max(1));
    let rows = charts.len().div_ceil(columns).max(1);
    // 40 px for the title.
    let size = (
        panel_size.0 * columns as u32,
        panel_size.1 * rows as u32 + 40,
    );
    let grid = (rows, columns);
    match format {
        Format::Svg => draw_panels(
            SVGBackend::new(path, size).into_drawing_area(),
            title,
            charts,
            grid,
        ),
        Format::Png => draw_panels(
            BitMapBackend::new(path, size).into_drawing_area(),
            title,
            charts,
            grid,
        ),
    }
}

fn draw_panels<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    charts: &[Chart],
    grid: (usize, usize),
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(draw_err)?;
    let body = root.titled(title, (FONT, 22)).map_err(draw_err)?;
    for (area, chart) in body.split_evenly(grid).into_iter().zip(charts) {
        render_into(&area, chart)?;
    }
    root.present().map_err(draw_err)
}

fn render<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    chart: &Chart,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(draw_err)?;
    render_into(&root, chart)?;
    root.present().map_err(draw_err)?;
    Ok(())
}

/// Draw `chart` into an area (no fill, no present).
fn render_into<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    chart: &Chart,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let all = || chart.series.iter().flat_map(|s| s.points.iter());
    let x_range = chart.x_range.unwrap_or_else(|| fit(all().map(|p| p.0)));
    let y_range = chart
        .y_range
        .unwrap_or_else(|| fit(all().map(|p| p.1).chain(chart.hlines.iter().map(|h| h.y))));
    let mut ctx = ChartBuilder::on(root)
        .caption(&chart.title, (FONT, 20))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(65)
        .build_cartesian_2d(x_range.0..x_range.1, y_range.0..y_range.1)
        .map_err(draw_err)?;
    ctx.configure_mesh()
        .x_desc(&chart.x_label)
        .y_desc(&chart.y_label)
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 15))
        .light_line_style(RGBColor(0xEE, 0xEE, 0xEE))
        .draw()
        .map_err(draw_err)?;

    for (i, s) in chart.series.iter().enumerate() {
        let color = PALETTE[s.color.unwrap_or(i) % PALETTE.len()];
        let line = color.stroke_width(2);
        let mut labelled = false;
        for run in runs(&s.points) {
            if s.style == Style::LinePoints {
                ctx.draw_series(run.iter().map(|&p| Circle::new(p, 3, color.filled())))
                    .map_err(draw_err)?;
            }
            let anno = match s.style {
                Style::Line | Style::LinePoints => ctx
                    .draw_series(LineSeries::new(run.clone(), line))
                    .map_err(draw_err)?,
                Style::Dashed => ctx
                    .draw_series(DashedLineSeries::new(run.clone(), 8, 5, line))
                    .map_err(draw_err)?,
                Style::Points => ctx
                    .draw_series(run.iter().map(|&p| Circle::new(p, 3, color.filled())))
                    .map_err(draw_err)?,
                Style::Area => ctx
                    .draw_series(
                        AreaSeries::new(
                            run.clone(),
                            0.0f64.clamp(y_range.0, y_range.1),
                            color.filled(),
                        )
                        .border_style(WHITE.stroke_width(1)),
                    )
                    .map_err(draw_err)?,
            };
            if !labelled && !s.label.is_empty() {
                labelled = true;
                let style = s.style;
                anno.label(&s.label).legend(move |(x, y)| match style {
                    Style::Points => Circle::new((x + 10, y), 3, color.filled()).into_dyn(),
                    Style::Area => {
                        Rectangle::new([(x, y - 5), (x + 20, y + 5)], color.filled()).into_dyn()
                    }
                    _ => PathElement::new(vec![(x, y), (x + 20, y)], line).into_dyn(),
                });
            }
        }
    }
    for (i, h) in chart.hlines.iter().enumerate() {
        if !h.y.is_finite() {
            continue;
        }
        let color = RGBColor(0x40, 0x40, 0x40);
        let style = color.stroke_width(1 + (i % 2) as u32);
        ctx.draw_series(DashedLineSeries::new(
            vec![(x_range.0, h.y), (x_range.1, h.y)],
            10,
            6,
            style,
        ))
        .map_err(draw_err)?
        .label(&h.label)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
    }
    if chart.series.iter().any(|s| !s.label.is_empty()) || !chart.hlines.is_empty() {
        ctx.configure_series_labels()
            .label_font((FONT, 13))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(0xB0, 0xB0, 0xB0))
            .position(legend_corner(chart, x_range, y_range))
            .draw()
            .map_err(draw_err)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_plain_numbers() {
        assert_eq!(tick(2000.0), "2000");
        assert_eq!(short(0.7000000000000001), "0.7");
        assert_eq!(short(1.2319021110885857), "1.2319");
        assert_eq!(short(-0.00001), "0");
        assert_eq!(tick(0.25), "0.25");
        assert_eq!(tick(-0.0), "0");
        assert_eq!(tick(-1e-9), "0");
        assert_eq!(tick(-2.5), "-2.5");
        assert_eq!(tick(1.0 / 3.0), "0.333333");
    }

    /// Rising lines fill the upper right: the legend goes to the upper left; falling ones
    /// fill the upper left: upper right.
    #[test]
    fn legend_avoids_the_data() {
        let chart = |pts: Vec<(f64, f64)>| Chart {
            series: vec![Series::new("a long enough label", pts, Style::Line)],
            ..Chart::default()
        };
        let rising = chart((0..=10).map(|i| (i as f64, i as f64)).collect());
        assert!(matches!(
            legend_corner(&rising, (0.0, 10.0), (0.0, 10.0)),
            SeriesLabelPosition::UpperLeft
        ));
        let falling = chart((0..=10).map(|i| (i as f64, 10.0 - i as f64)).collect());
        assert!(matches!(
            legend_corner(&falling, (0.0, 10.0), (0.0, 10.0)),
            SeriesLabelPosition::UpperRight
        ));
    }

    /// A scatter (a Pareto front) filling the upper half: the legend goes to a lower
    /// corner, on the side with fewer points; an empty chart keeps the upper right.
    #[test]
    fn scatter_legend_takes_the_emptiest_corner() {
        let labels = ["feasible evaluations", "front (colour: divert reserve)"];
        let mut pts: Vec<(f64, f64)> = (0..100)
            .map(|i| (i as f64 / 10.0, 5.0 + (i % 10) as f64 / 2.0))
            .collect();
        pts.extend((0..20).map(|i| (i as f64 / 10.0, 1.0)));
        let corner = least_covered_corner(&pts, &labels, (950, 650), (0.0, 10.0), (0.0, 10.0));
        assert!(
            matches!(corner, SeriesLabelPosition::LowerRight),
            "{corner:?}"
        );
        let corner = least_covered_corner(&[], &labels, (950, 650), (0.0, 10.0), (0.0, 10.0));
        assert!(matches!(corner, SeriesLabelPosition::UpperRight));
    }

    #[test]
    fn svg_has_series_labels_and_reference_lines() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.svg");
        let chart = Chart {
            title: "Impulse against belt speed".into(),
            x_label: "v [m/s]".into(),
            y_label: "S [N s]".into(),
            series: vec![
                Series::new("t_c = 1.36 s", vec![(0.5, 10.0), (1.0, 20.0)], Style::Line),
                Series::new(
                    "measured",
                    vec![(0.7, 12.0), (f64::NAN, 1.0)],
                    Style::Points,
                ),
            ],
            hlines: vec![HLine {
                y: 47.3,
                label: "free fall 0.3 m".into(),
            }],
            ..Chart::default()
        };
        line_chart(&path, &chart).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        for text in ["t_c = 1.36 s", "measured", "free fall 0.3 m", "v [m/s]"] {
            assert!(svg.contains(text), "missing {text}");
        }
    }

    #[test]
    fn empty_chart_and_bad_extension() {
        let dir = tempfile::tempdir().unwrap();
        line_chart(&dir.path().join("e.png"), &Chart::default()).unwrap();
        assert!(matches!(
            line_chart(&dir.path().join("e.pdf"), &Chart::default()),
            Err(PlotError::UnknownExtension(_))
        ));
    }

    #[test]
    fn runs_break_at_non_finite_points() {
        let r = runs(&[(0.0, 0.0), (1.0, f64::NAN), (2.0, 2.0), (3.0, 3.0)]);
        assert_eq!(r, vec![vec![(0.0, 0.0)], vec![(2.0, 2.0), (3.0, 3.0)]]);
    }
}
