//! Top view of one run (the paper's Fig. 3 view): the belt, the side guide, the arm at several
//! instants, the parcel outline at several instants and the path of its centre G coloured by
//! stage, written to SVG or PNG with plotters ([`top_view`](fn@top_view)). [`overlay_view`] draws several
//! runs in one such view, each path in its own colour with its stages named where they begin
//! (the paper's Figs 6–8 and 13–15 compared side by side; `divertsim paths`).
//!
//! Frame and symbols follow docs/model.md §1: origin at the arm pivot O, x downstream (belt
//! motion), y across the belt towards the discharge side; the belt occupies 0 ≤ y ≤ P_max, the
//! side guide is the line y = 0 for x ≤ 0, and the arm is the segment from O to
//! R_z (cos α, sin α). Both axes have the same scale (a metre on x is a metre on y), as a top
//! view must: the data ranges are widened to the drawing area's aspect ratio.
//!
//! Text uses the bundled DejaVu Sans (`assets/DejaVuSans.ttf`, Bitstream Vera licence in
//! `assets/DejaVu-LICENSE.txt`), registered once with plotters as "sans-serif", so rendering
//! needs no system fonts. That registration is plotters' own process-wide font table.
//!
//! The module holds what both views share (fonts, formats, colours, sizes, the frame, the
//! machine and the legend layout); [`top_view`](mod@top_view) draws one run, [`overlay`]
//! several.

pub mod overlay;
pub mod top_view;

pub use overlay::{case_color, overlay_view, OverlayCase};
pub use top_view::{top_view, top_view_svg};

use std::ops::Range;
use std::path::Path;
use std::sync::OnceLock;

use divertsim_core::geometry::Rect;
use divertsim_core::model::params::{NearSide, Scenario};
use divertsim_core::sim::{Outcome, Sample, SimResult, Stage};
use glam::DVec2;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::data::float::FloatPrettyPrinter;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{register_font, FontStyle};

/// The font family name every text element uses.
pub const FONT: &str = "sans-serif";
/// DejaVu Sans, bundled so that the plot renders on machines without system fonts.
static FONT_BYTES: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");
/// Whether the bundled font registered (plotters' font table is process-wide: do it once).
static FONT_REGISTERED: OnceLock<bool> = OnceLock::new();

/// Smallest and largest accepted image side \[px]: below the minimum the labels cannot fit,
/// above the maximum a bitmap would need hundreds of megabytes.
const MIN_SIDE: u32 = 200;
const MAX_SIDE: u32 = 8_192;

/// The file formats `top_view` can write, by extension.
const ALLOWED_EXTENSIONS: &str = ".svg, .png";

/// Belt band fill, belt edges, side guide, arm and outline colours.
const BELT_FILL: RGBColor = RGBColor(0xE6, 0xED, 0xF1);
const BELT_EDGE: RGBColor = RGBColor(0x78, 0x90, 0x9C);
const GUIDE: RGBColor = RGBColor(0x21, 0x21, 0x21);
const ARM: RGBColor = RGBColor(0x8C, 0x56, 0x4B);
const OUTLINE: RGBColor = RGBColor(0x37, 0x37, 0x37);
const FIRST_FILL: RGBColor = RGBColor(0xFF, 0xE0, 0x82);
const LAST_FILL: RGBColor = RGBColor(0xB0, 0xBE, 0xC5);
const GRID: RGBColor = RGBColor(0xB8, 0xB8, 0xB8);
const STRIKE: RGBColor = RGBColor(0xC6, 0x28, 0x28);
/// A jam's holding contacts: a ring, apart from the strikes' crosses.
const JAM: RGBColor = RGBColor(0x8E, 0x24, 0xAA);
const CONTACT: RGBColor = RGBColor(0x1B, 0x5E, 0x20);

/// Every stage, in the order the legend lists them.
const ALL_STAGES: [Stage; 13] = Stage::ALL;

/// The path colour of a stage (Tableau-10 hues; the arm's brown is kept out of this set).
pub fn stage_color(stage: Stage) -> RGBColor {
    match stage {
        Stage::Ride => RGBColor(0x7F, 0x7F, 0x7F),
        Stage::F1 => RGBColor(0xD6, 0x27, 0x28),
        Stage::F2 => RGBColor(0x1F, 0x77, 0xB4),
        Stage::F3 => RGBColor(0xFF, 0x7F, 0x0E),
        Stage::F4 => RGBColor(0x2C, 0xA0, 0x2C),
        Stage::F5 => RGBColor(0x94, 0x67, 0xBD),
        Stage::F6 => RGBColor(0x17, 0xBE, 0xCF),
        Stage::F5Guide => RGBColor(0xE3, 0x77, 0xC2),
        Stage::Guide => RGBColor(0xBC, 0xBD, 0x22),
        Stage::Tip => RGBColor(0x39, 0x3B, 0x79),
        Stage::TipGuide => RGBColor(0x63, 0x79, 0x39),
        Stage::ArmTip => RGBColor(0x8C, 0x6D, 0x31),
        Stage::Contact => RGBColor(0x84, 0x3C, 0x39),
    }
}

/// What to draw and how large.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotOptions {
    /// How many parcel outlines to draw, evenly spread in time, the first and the last
    /// included (0: none).
    pub outlines: usize,
    /// How many arm positions to draw, spread over the instants at which the arm is out
    /// (α > 0); an arm that never moves is drawn once, retracted.
    pub arm_positions: usize,
    /// The title; `None`: the outcome and the parcel size.
    pub title: Option<String>,
    /// Image width \[px].
    pub width: u32,
    /// Image height \[px].
    pub height: u32,
}

impl Default for PlotOptions {
    fn default() -> Self {
        PlotOptions {
            outlines: 8,
            arm_positions: 6,
            title: None,
            width: 1000,
            height: 700,
        }
    }
}

/// Why a plot could not be written.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The file name's extension names no supported format (the path is given).
    #[error("cannot tell the image format of {0:?}: the file name must end in one of {ALLOWED_EXTENSIONS}")]
    UnknownExtension(String),
    /// The image size is outside the accepted range.
    #[error("image size {width}×{height} px is outside the accepted {MIN_SIDE}..={MAX_SIDE} px per side")]
    InvalidSize {
        /// Requested width \[px].
        width: u32,
        /// Requested height \[px].
        height: u32,
    },
    /// The bundled font could not be loaded.
    #[error("the bundled DejaVu Sans font could not be loaded")]
    Font,
    /// Drawing or writing the file failed.
    #[error("drawing the top view failed: {0}")]
    Draw(String),
}

/// Output formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Svg,
    Png,
}

/// The format named by `path`'s extension (case-insensitive).
pub fn format_of(path: &Path) -> Result<Format, PlotError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("svg") => Ok(Format::Svg),
        Some("png") => Ok(Format::Png),
        _ => Err(PlotError::UnknownExtension(path.display().to_string())),
    }
}

/// Register the bundled font once; later calls only read the outcome.
pub fn ensure_font() -> Result<(), PlotError> {
    let ok =
        *FONT_REGISTERED.get_or_init(|| register_font(FONT, FontStyle::Normal, FONT_BYTES).is_ok());
    if ok {
        Ok(())
    } else {
        Err(PlotError::Font)
    }
}

pub fn draw_err<E: std::error::Error + Send + Sync>(e: DrawingAreaErrorKind<E>) -> PlotError {
    PlotError::Draw(e.to_string())
}

/// The image size of `options` once checked against the accepted range, with the bundled
/// font registered.
fn checked_size(options: &PlotOptions) -> Result<(u32, u32), PlotError> {
    let (width, height) = (options.width, options.height);
    if !(MIN_SIDE..=MAX_SIDE).contains(&width) || !(MIN_SIDE..=MAX_SIDE).contains(&height) {
        return Err(PlotError::InvalidSize { width, height });
    }
    ensure_font()?;
    Ok((width, height))
}

/// A sample whose parcel state can be drawn.
fn state_ok(s: &Sample) -> bool {
    let st = &s.state;
    st.t.is_finite() && st.x.is_finite() && st.y.is_finite() && st.phi.is_finite()
}

/// The index into the non-decreasing `times` nearest to `t`.
fn nearest(times: &[f64], t: f64) -> usize {
    let i = times.partition_point(|&x| x < t);
    if i == 0 {
        0
    } else if i >= times.len() {
        times.len() - 1
    } else if (times[i] - t).abs() < (t - times[i - 1]).abs() {
        i
    } else {
        i - 1
    }
}

/// Indices of at most `n` samples nearest to `n` instants evenly spread from the first to
/// the last time, both ends included; distinct and increasing.
fn spread_indices(times: &[f64], n: usize) -> Vec<usize> {
    if times.is_empty() || n == 0 {
        return Vec::new();
    }
    let last = times.len() - 1;
    if n == 1 {
        return vec![0];
    }
    let (t0, t1) = (times[0], times[last]);
    let mut out: Vec<usize> = (0..n)
        .map(|k| match k {
            0 => 0,
            k if k == n - 1 => last,
            k => nearest(times, t0 + (t1 - t0) * k as f64 / (n - 1) as f64),
        })
        .collect();
    out.dedup();
    out
}

/// Indices of at most `n` arm samples spread in time over the moving interval. The instants
/// sit a third of a step after the start of each of n equal sub-intervals, so that the out-
/// and return-stroke positions of a symmetric drive (α(t) = α(t_c − t)) do not coincide;
/// a single position is the largest swing.
fn arm_indices(times: &[f64], angles: &[f64], n: usize) -> Vec<usize> {
    if times.is_empty() || n == 0 {
        return Vec::new();
    }
    if n == 1 {
        let best = angles
            .iter()
            .enumerate()
            .fold(0, |b, (i, &a)| if a > angles[b] { i } else { b });
        return vec![best];
    }
    let (t0, t1) = (times[0], times[times.len() - 1]);
    let mut out: Vec<usize> = (0..n)
        .map(|k| nearest(times, t0 + (t1 - t0) * (k as f64 + 1.0 / 3.0) / n as f64))
        .collect();
    out.dedup();
    out
}

/// The points of `pts` at least `min_step` \[m] from the previous kept one, plus the last.
fn thin(pts: &[(f64, f64)], min_step: f64) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(pts.len());
    for (i, &p) in pts.iter().enumerate() {
        let far = match out.last() {
            Some(&(x, y)) => (p.0 - x).hypot(p.1 - y) >= min_step,
            None => true,
        };
        if far || i + 1 == pts.len() {
            out.push(p);
        }
    }
    out
}

/// An axis-aligned box grown point by point; non-finite points are ignored.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Bounds {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
}

impl Bounds {
    fn empty() -> Bounds {
        Bounds {
            x0: f64::INFINITY,
            x1: f64::NEG_INFINITY,
            y0: f64::INFINITY,
            y1: f64::NEG_INFINITY,
        }
    }

    fn add(&mut self, x: f64, y: f64) {
        if x.is_finite() && y.is_finite() {
            self.x0 = self.x0.min(x);
            self.x1 = self.x1.max(x);
            self.y0 = self.y0.min(y);
            self.y1 = self.y1.max(y);
        }
    }

    fn is_empty(&self) -> bool {
        !(self.x0 <= self.x1 && self.y0 <= self.y1)
    }
}

/// The x and y ranges \[m] showing `b` with a margin of `margin` × the larger span on every
/// side, one of them then widened (about its centre) so that a metre is as many pixels on x as
/// on y in a plotting area of `pixels` = (width, height).
fn equal_aspect(b: Bounds, margin: f64, pixels: (u32, u32)) -> (Range<f64>, Range<f64>) {
    let b = if b.is_empty() {
        Bounds {
            x0: -1.0,
            x1: 1.0,
            y0: -0.5,
            y1: 1.0,
        }
    } else {
        b
    };
    // A single point still needs a window: 1 m across.
    let span = (b.x1 - b.x0).max(b.y1 - b.y0).max(1e-9);
    let span = if span < 1e-6 { 1.0 } else { span };
    let m = margin * span;
    let (mut x0, mut x1, mut y0, mut y1) = (b.x0 - m, b.x1 + m, b.y0 - m, b.y1 + m);
    let ratio = f64::from(pixels.0.max(1)) / f64::from(pixels.1.max(1));
    let (sx, sy) = (x1 - x0, y1 - y0);
    if sx / sy > ratio {
        let grow = 0.5 * (sx / ratio - sy);
        y0 -= grow;
        y1 += grow;
    } else {
        let grow = 0.5 * (sy * ratio - sx);
        x0 -= grow;
        x1 += grow;
    }
    if [x0, x1, y0, y1].iter().all(|v| v.is_finite()) && x0 < x1 && y0 < y1 {
        (x0..x1, y0..y1)
    } else {
        // Coordinates near f64::MAX overflow the margins: show the default window instead.
        equal_aspect(Bounds::empty(), margin, pixels)
    }
}

/// A legend swatch.
enum Swatch {
    Band,
    Line(RGBAColor, u32),
    Outline(Option<RGBColor>, u32),
    StartMarker,
    EndMarker,
    Pivot,
    Strike,
    /// Where a jammed parcel is held (docs/model.md §6b).
    Jam,
    Contact,
    /// Where a stage begins on an overlaid path.
    StageMark,
    /// An overlaid parcel outline: thin and tinted (false) or bold (true).
    CaseOutline(bool),
}

/// Pixel sizes derived from the image size (the defaults are tuned for 1000 × 700).
struct Sizes {
    s: f64,
}

impl Sizes {
    fn new(options: &PlotOptions) -> Sizes {
        // The geometric mean keeps text readable on tall or narrow images.
        let s = (f64::from(options.width) / 1000.0 * f64::from(options.height) / 700.0).sqrt();
        Sizes {
            s: s.clamp(0.5, 4.0),
        }
    }
    /// A length of `v` px at the reference size.
    fn px(&self, v: f64) -> i32 {
        (v * self.s).round().max(1.0) as i32
    }
    /// A stroke width of `v` px at the reference size.
    fn w(&self, v: f64) -> u32 {
        (v * self.s).round().max(1.0) as u32
    }
    fn font(&self, v: f64) -> f64 {
        v * self.s
    }
}

/// A tick label: plotters' own float format, with ticks within rounding of 0 shown as "0.0"
/// rather than "-0.0".
fn tick_label(v: f64, span: f64) -> String {
    let v = if v.abs() <= 1e-9 * span.abs() { 0.0 } else { v };
    FloatPrettyPrinter {
        allow_scientific: false,
        min_decimal: 1,
        max_decimal: 5,
    }
    .print(v)
}

fn fmt_t(t: f64) -> String {
    format!("{t:.2}")
}

/// Chart margin and axis label areas [px at the reference size].
const CHART_MARGIN: f64 = 10.0;
const X_LABEL_AREA: f64 = 52.0;
const Y_LABEL_AREA: f64 = 62.0;
/// Margin around the data, as a fraction of its larger span.
const DATA_MARGIN: f64 = 0.06;

/// A chart on `area` with the fixed margins and label areas. Building draws nothing (there is
/// no caption), so it can also be used only to measure the plotting area.
fn build_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    z: &Sizes,
    xr: Range<f64>,
    yr: Range<f64>,
) -> Result<ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>, PlotError> {
    ChartBuilder::on(area)
        .margin(z.px(CHART_MARGIN))
        .x_label_area_size(z.px(X_LABEL_AREA))
        .y_label_area_size(z.px(Y_LABEL_AREA))
        .build_cartesian_2d(xr, yr)
        .map_err(draw_err)
}

/// Pixels per metre that a plotting area of `pixels` gives the data within `bounds`.
fn scale_for(bounds: Bounds, pixels: (u32, u32)) -> f64 {
    let (xr, _) = equal_aspect(bounds, DATA_MARGIN, pixels);
    f64::from(pixels.0) / (xr.end - xr.start)
}

/// The area left for a chart and the size of its plotting area \[px].
type ChartArea<DB> = (DrawingArea<DB, Shift>, (u32, u32));

/// The title band and the legend panel (right of the chart, or below it when that leaves a
/// larger drawing, so that the legend never hides the drawing), drawn on `root`. Returns the
/// area left for the chart and the size of its plotting area \[px].
fn frame<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    entries: &[(Swatch, String)],
    bounds: Bounds,
    z: &Sizes,
) -> Result<ChartArea<DB>, PlotError> {
    root.fill(&WHITE).map_err(draw_err)?;
    // The title gets its own band (plotters' `titled` puts it flush with the top edge).
    let title_h = z.px(40.0);
    let (title_area, body) = root.split_vertically(title_h);
    let (w, _) = title_area.dim_in_pixel();
    // A long title (an outcome with its reason, an over-limit strike) shrinks to the width
    // rather than run off both edges, down to 60 % of its size.
    let mut size = z.font(21.0);
    let fits = |size: f64| {
        let style = TextStyle::from((FONT, size).into_font());
        title_area
            .estimate_text_size(title, &style)
            .is_ok_and(|(tw, _)| tw + 2 * z.px(8.0) as u32 <= w)
    };
    let smallest = 0.6 * size;
    while size > smallest && !fits(size) {
        size *= 0.95;
    }
    let title_style = TextStyle::from((FONT, size).into_font())
        .color(&BLACK)
        .pos(Pos::new(HPos::Center, VPos::Center));
    title_area
        .draw(&Text::new(
            title,
            (w as i32 / 2, title_h / 2 + z.px(3.0)),
            title_style,
        ))
        .map_err(draw_err)?;

    let legend_font = TextStyle::from((FONT, z.font(13.0)).into_font())
        .color(&BLACK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    let lay = LegendLayout::new(&body, entries, &legend_font, z)?;
    let (body_w, body_h) = body.dim_in_pixel();
    let (body_w, body_h) = (body_w as i32, body_h as i32);

    // Side panel: one column, as wide as the longest entry (at most 2/5 of the width).
    let side_w = (lay.col_w + 2 * lay.pad).min(body_w * 2 / 5);
    // Bottom panel: as many columns as fit, filled column by column.
    let cols = ((body_w - 2 * lay.pad) / lay.col_w.max(1)).clamp(1, entries.len().max(1) as i32);
    let rows = (entries.len() as i32 + cols - 1) / cols;
    let bottom_h = (z.px(CHART_MARGIN) + lay.box_height(rows) + lay.pad).min(body_h / 2);

    let (side_plot, side_legend) = body.split_horizontally(body_w - side_w);
    let (bottom_plot, bottom_legend) = body.split_vertically(body_h - bottom_h);
    let side_px = build_chart(&side_plot, z, 0.0..1.0, 0.0..1.0)?
        .plotting_area()
        .dim_in_pixel();
    let bottom_px = build_chart(&bottom_plot, z, 0.0..1.0, 0.0..1.0)?
        .plotting_area()
        .dim_in_pixel();
    if scale_for(bounds, bottom_px) > 1.05 * scale_for(bounds, side_px) {
        lay.draw(&bottom_legend, entries, &legend_font, z, cols, rows)?;
        Ok((bottom_plot, bottom_px))
    } else {
        lay.draw(
            &side_legend,
            entries,
            &legend_font,
            z,
            1,
            entries.len() as i32,
        )?;
        Ok((side_plot, side_px))
    }
}

/// The chart every top view draws on, in the plotting area `frame` gave: metres on both axes
/// at one scale, the machine and the arm at `arms` already drawn; with its x range.
#[allow(clippy::too_many_arguments)]
fn machine_chart<'a, DB: DrawingBackend>(
    plot_area: &'a DrawingArea<DB, Shift>,
    pixels: (u32, u32),
    bounds: Bounds,
    (belt_width, full_guide): (f64, bool),
    arms: &[(f64, f64)],
    arm_length: f64,
    z: &Sizes,
) -> Result<(TopChart<'a, DB>, Range<f64>), PlotError> {
    let (xr, yr) = equal_aspect(bounds, DATA_MARGIN, pixels);
    let mut chart = build_chart(plot_area, z, xr.clone(), yr.clone())?;
    draw_machine(&mut chart, (&xr, &yr), pixels, belt_width, full_guide, z)?;
    draw_arms(&mut chart, arms, arm_length, z)?;
    Ok((chart, xr))
}

/// A parcel outline as a closed polyline (the first corner again at the end).
fn closed(corners: &[DVec2; 4]) -> Vec<(f64, f64)> {
    let mut v: Vec<(f64, f64)> = corners.iter().map(|c| (c.x, c.y)).collect();
    v.push(v[0]);
    v
}

/// A top-view chart: metres on both axes.
type TopChart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The side guide's legend entry: upstream of the pivot, or along the whole pivot-side edge
/// (`near_side = "guide"`).
fn guide_entry(full_guide: bool, z: &Sizes) -> (Swatch, String) {
    let label = if full_guide {
        "side guide (y = 0, the whole pivot-side edge)"
    } else {
        "side guide (y = 0, x ≤ 0)"
    };
    (Swatch::Line(GUIDE.to_rgba(), z.w(6.0)), label.to_string())
}

/// The belt band, the grid and axes, the belt edges and the side guide (up to the pivot, or
/// along the whole edge when `full_guide`).
fn draw_machine<DB: DrawingBackend>(
    chart: &mut TopChart<'_, DB>,
    (xr, yr): (&Range<f64>, &Range<f64>),
    pixels: (u32, u32),
    belt_width: f64,
    full_guide: bool,
    z: &Sizes,
) -> Result<(), PlotError> {
    let p = belt_width;
    chart
        .draw_series(std::iter::once(Rectangle::new(
            [(xr.start, 0.0), (xr.end, p)],
            BELT_FILL.filled(),
        )))
        .map_err(draw_err)?;
    // About one grid line per 60 px on both axes, so that the steps come out equal.
    let x_ticks = (pixels.0 as usize / z.px(60.0) as usize).max(2);
    let y_ticks = (pixels.1 as usize / z.px(60.0) as usize).max(2);
    let (x_span, y_span) = (xr.end - xr.start, yr.end - yr.start);
    chart
        .configure_mesh()
        .x_desc("x [m] (belt direction)")
        .y_desc("y [m] (across the belt)")
        .x_labels(x_ticks)
        .y_labels(y_ticks)
        .x_label_formatter(&|v| tick_label(*v, x_span))
        .y_label_formatter(&|v| tick_label(*v, y_span))
        .label_style((FONT, z.font(13.0)))
        .axis_desc_style((FONT, z.font(15.0)))
        .bold_line_style(GRID.mix(0.5))
        .light_line_style(TRANSPARENT)
        .draw()
        .map_err(draw_err)?;

    // Belt edges and the side guide.
    let edge = BELT_EDGE.stroke_width(z.w(2.0));
    chart
        .draw_series([
            PathElement::new(vec![(xr.start, 0.0), (xr.end, 0.0)], edge),
            PathElement::new(vec![(xr.start, p), (xr.end, p)], edge),
        ])
        .map_err(draw_err)?;
    let guide_end = if full_guide { xr.end } else { 0.0 };
    if xr.start < guide_end {
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(xr.start, 0.0), (guide_end, 0.0)],
                GUIDE.stroke_width(z.w(6.0)),
            )))
            .map_err(draw_err)?;
    }
    Ok(())
}

/// The arm at the instants `arms` = (t, α), fading in over time.
fn draw_arms<DB: DrawingBackend>(
    chart: &mut TopChart<'_, DB>,
    arms: &[(f64, f64)],
    arm_length: f64,
    z: &Sizes,
) -> Result<(), PlotError> {
    let n_arms = arms.len();
    let r = arm_length;
    chart
        .draw_series(arms.iter().enumerate().map(|(i, &(_, a))| {
            let alpha = if n_arms > 1 {
                0.25 + 0.7 * i as f64 / (n_arms - 1) as f64
            } else {
                0.9
            };
            PathElement::new(
                vec![(0.0, 0.0), (r * a.cos(), r * a.sin())],
                ARM.mix(alpha).stroke_width(z.w(5.0)),
            )
        }))
        .map_err(draw_err)?;
    Ok(())
}

/// The pivot O and the belt-edge labels where nothing else is drawn: the far edge upstream
/// (the parcel starts well inside the belt), the pivot-side edge downstream below the belt
/// (the arm is at y ≥ 0).
fn draw_pivot_and_edge_labels<DB: DrawingBackend>(
    chart: &mut TopChart<'_, DB>,
    xr: &Range<f64>,
    belt_width: f64,
    z: &Sizes,
) -> Result<(), PlotError> {
    let label = |h: HPos, v: VPos| {
        TextStyle::from((FONT, z.font(13.0)).into_font())
            .color(&BLACK)
            .pos(Pos::new(h, v))
    };
    chart
        .draw_series(std::iter::once(
            EmptyElement::at((0.0, 0.0))
                + Circle::new((0, 0), z.px(5.0), BLACK.filled())
                + Text::new("O", (z.px(6.0), z.px(5.0)), label(HPos::Left, VPos::Top)),
        ))
        .map_err(draw_err)?;
    let edge_label = |h: HPos, v: VPos| {
        TextStyle::from((FONT, z.font(12.0)).into_font())
            .color(&BELT_EDGE)
            .pos(Pos::new(h, v))
    };
    chart
        .draw_series([
            EmptyElement::at((xr.start, belt_width))
                + Text::new(
                    "far edge (P_max)",
                    (z.px(6.0), -z.px(4.0)),
                    edge_label(HPos::Left, VPos::Bottom),
                ),
            EmptyElement::at((xr.end, 0.0))
                + Text::new(
                    "pivot-side edge",
                    (-z.px(6.0), z.px(4.0)),
                    edge_label(HPos::Right, VPos::Top),
                ),
        ])
        .map_err(draw_err)?;
    Ok(())
}

/// Stage changes grouped into labels: a cluster starts at a change farther than `min_gap`
/// \[m] from the current cluster's first point and is labelled there with its stages in order of
/// first appearance, joined by "/".
fn stage_clusters(marks: &[(Stage, (f64, f64))], min_gap: f64) -> Vec<((f64, f64), String)> {
    let mut clusters: Vec<((f64, f64), Vec<Stage>)> = Vec::new();
    for &(stage, p) in marks {
        match clusters.last_mut() {
            Some((q, stages)) if (p.0 - q.0).hypot(p.1 - q.1) < min_gap => {
                if !stages.contains(&stage) {
                    stages.push(stage);
                }
            }
            _ => clusters.push((p, vec![stage])),
        }
    }
    clusters
        .into_iter()
        .map(|(p, stages)| {
            let names: Vec<&str> = stages.iter().map(|s| s.label()).collect();
            (p, names.join("/"))
        })
        .collect()
}

/// Legend geometry \[px]: entry columns of equal width.
struct LegendLayout {
    /// Width of one column: swatch, gap, longest label, gap.
    col_w: i32,
    swatch_w: i32,
    pad: i32,
    row: i32,
}

impl LegendLayout {
    fn new<DB: DrawingBackend>(
        area: &DrawingArea<DB, Shift>,
        entries: &[(Swatch, String)],
        style: &TextStyle,
        z: &Sizes,
    ) -> Result<LegendLayout, PlotError> {
        let mut text_w = 0;
        for (_, label) in entries {
            let (w, _) = area.estimate_text_size(label, style).map_err(draw_err)?;
            text_w = text_w.max(w as i32);
        }
        let (swatch_w, pad) = (z.px(34.0), z.px(8.0));
        // The estimate runs a few per cent short of the rendered bitmap text: leave room.
        let text_w = (f64::from(text_w) * 1.06).ceil() as i32;
        Ok(LegendLayout {
            col_w: swatch_w + text_w + 3 * pad,
            swatch_w,
            pad,
            row: z.px(24.0),
        })
    }

    /// Height of the box for `rows` rows.
    fn box_height(&self, rows: i32) -> i32 {
        2 * self.pad + self.row * rows
    }

    /// Draw the box and its entries at the top of `area`, centred across it, in `cols`
    /// columns of `rows` rows, filled column by column.
    fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        entries: &[(Swatch, String)],
        text_style: &TextStyle,
        z: &Sizes,
        cols: i32,
        rows: i32,
    ) -> Result<(), PlotError> {
        let (w, _) = area.dim_in_pixel();
        let pad = self.pad;
        let box_w = (cols * self.col_w + pad).min(w as i32 - 2 * pad);
        let x0 = ((w as i32 - box_w) / 2).max(0);
        let (x1, y0) = (x0 + box_w, z.px(CHART_MARGIN));
        let y1 = y0 + self.box_height(rows);
        area.draw(&Rectangle::new([(x0, y0), (x1, y1)], WHITE.filled()))
            .map_err(draw_err)?;
        area.draw(&Rectangle::new(
            [(x0, y0), (x1, y1)],
            RGBColor(0x90, 0x90, 0x90).stroke_width(z.w(1.0)),
        ))
        .map_err(draw_err)?;
        let half = z.px(7.0);
        for (i, (swatch, label)) in entries.iter().enumerate() {
            let (col, row) = (i as i32 / rows.max(1), i as i32 % rows.max(1));
            let cy = y0 + pad + self.row * row + self.row / 2;
            let sx0 = x0 + pad + col * self.col_w;
            let sx1 = sx0 + self.swatch_w;
            let cx = (sx0 + sx1) / 2;
            match swatch {
                Swatch::Band => {
                    area.draw(&Rectangle::new(
                        [(sx0, cy - half), (sx1, cy + half)],
                        BELT_FILL.filled(),
                    ))
                    .map_err(draw_err)?;
                    for y in [cy - half, cy + half] {
                        area.draw(&PathElement::new(
                            vec![(sx0, y), (sx1, y)],
                            BELT_EDGE.stroke_width(z.w(2.0)),
                        ))
                        .map_err(draw_err)?;
                    }
                }
                Swatch::Line(color, width) => {
                    area.draw(&PathElement::new(
                        vec![(sx0, cy), (sx1, cy)],
                        color.stroke_width(*width),
                    ))
                    .map_err(draw_err)?;
                }
                Swatch::Outline(fill, width) => {
                    let pts = vec![
                        (sx0 + 3, cy - half),
                        (sx1 - 3, cy - half),
                        (sx1 - 3, cy + half),
                        (sx0 + 3, cy + half),
                    ];
                    if let Some(f) = fill {
                        area.draw(&Polygon::new(pts.clone(), f.mix(0.45).filled()))
                            .map_err(draw_err)?;
                    }
                    let mut closed = pts;
                    closed.push(closed[0]);
                    area.draw(&PathElement::new(closed, OUTLINE.stroke_width(*width)))
                        .map_err(draw_err)?;
                }
                Swatch::StartMarker => {
                    area.draw(&Circle::new((cx, cy), z.px(6.0), WHITE.filled()))
                        .map_err(draw_err)?;
                    area.draw(&Circle::new(
                        (cx, cy),
                        z.px(6.0),
                        BLACK.stroke_width(z.w(2.0)),
                    ))
                    .map_err(draw_err)?;
                }
                Swatch::EndMarker => {
                    let r = z.px(6.0);
                    area.draw(&Rectangle::new(
                        [(cx - r, cy - r), (cx + r, cy + r)],
                        BLACK.filled(),
                    ))
                    .map_err(draw_err)?;
                }
                Swatch::Pivot => {
                    area.draw(&Circle::new((cx, cy), z.px(5.0), BLACK.filled()))
                        .map_err(draw_err)?;
                }
                Swatch::Contact => {
                    area.draw(&Circle::new((cx, cy), z.px(4.0), CONTACT.filled()))
                        .map_err(draw_err)?;
                }
                Swatch::StageMark => {
                    area.draw(&Circle::new((cx, cy), z.px(4.0), GRID.filled()))
                        .map_err(draw_err)?;
                    area.draw(&Circle::new(
                        (cx, cy),
                        z.px(4.0),
                        BLACK.stroke_width(z.w(1.0)),
                    ))
                    .map_err(draw_err)?;
                }
                Swatch::CaseOutline(bold) => {
                    let pts = vec![
                        (sx0 + 3, cy - half),
                        (sx1 - 3, cy - half),
                        (sx1 - 3, cy + half),
                        (sx0 + 3, cy + half),
                    ];
                    if !bold {
                        area.draw(&Polygon::new(pts.clone(), OUTLINE.mix(0.15).filled()))
                            .map_err(draw_err)?;
                    }
                    let mut closed = pts;
                    closed.push(closed[0]);
                    let w = if *bold { z.w(3.0) } else { z.w(1.0) };
                    area.draw(&PathElement::new(closed, OUTLINE.stroke_width(w)))
                        .map_err(draw_err)?;
                }
                Swatch::Strike => {
                    area.draw(&Cross::new(
                        (cx, cy),
                        z.px(7.0),
                        STRIKE.stroke_width(z.w(3.0)),
                    ))
                    .map_err(draw_err)?;
                }
                Swatch::Jam => {
                    area.draw(&Circle::new(
                        (cx, cy),
                        z.px(7.0),
                        JAM.stroke_width(z.w(3.0)),
                    ))
                    .map_err(draw_err)?;
                }
            }
            area.draw(&Text::new(
                label.as_str(),
                (sx1 + pad, cy),
                text_style.clone(),
            ))
            .map_err(draw_err)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use divertsim_core::sim::{NotDivertedReason, State};
    use std::f64::consts::FRAC_PI_4;

    /// The built-in default scenario (the paper's machine and compact parcel).
    fn scenario() -> Scenario {
        Scenario::paper_default()
    }

    fn smoothstep(u: f64) -> f64 {
        let u = u.clamp(0.0, 1.0);
        u * u * (3.0 - 2.0 * u)
    }

    /// A synthetic diverted run: ride, F1, F4, F5, F2; the arm rises 0 → 45° → 0 over t_c.
    fn result() -> SimResult {
        let (tc, dt) = (1.36, 0.01);
        let trajectory: Vec<Sample> = (0..=240)
            .map(|k| {
                let t = k as f64 * dt;
                let u = smoothstep((t - 0.25) / 1.2);
                let state = State {
                    t,
                    x: -0.2 + 2.0 * t * (1.0 - 0.35 * u),
                    y: 0.35 + 0.75 * u,
                    phi: 0.5 * u,
                    vx: 2.0,
                    vy: 0.0,
                    omega: 0.0,
                };
                let stage = match t {
                    t if t < 0.245 => Stage::Ride,
                    t if t < 0.255 => Stage::F1,
                    t if t < 0.6 => Stage::F4,
                    t if t < 0.9 => Stage::F5,
                    _ => Stage::F2,
                };
                let arm_angle = if t <= tc {
                    FRAC_PI_4 * 0.5 * (1.0 - (std::f64::consts::TAU * t / tc).cos())
                } else {
                    0.0
                };
                Sample {
                    state,
                    arm_angle,
                    stage,
                    contacts: [None, None],
                }
            })
            .collect();
        let final_state = trajectory.last().map(|s| s.state).unwrap_or_default();
        let max_lateral = trajectory
            .iter()
            .map(|s| s.state.y)
            .fold(f64::MIN, f64::max);
        SimResult {
            outcome: Outcome::Diverted,
            stages: vec![Stage::Ride, Stage::F1, Stage::F4, Stage::F5, Stage::F2],
            events: Vec::new(),
            trajectory,
            final_state,
            max_lateral,
            along_range: (0.0, 1.0),
            impacts: vec![divertsim_core::sim::Impact {
                t: 0.3,
                stage: Stage::F1,
                obstacle: divertsim_core::sim::Obstacle::ArmFace,
                point: [0.2, 0.3],
                normal_impulse: 1.0,
                tangential_impulse: -0.3,
                impulse: 1.04,
                approach_speed: 1.5,
                compression_work: -0.5,
                dissipated: 0.4,
                persistent: false,
            }],
            overload: Default::default(),
            contact_check: Default::default(),
            tipping: Default::default(),
            arm_torque: Vec::new(),
            arm_strikes: Vec::new(),
            jam: None,
        }
    }

    fn empty_result() -> SimResult {
        SimResult {
            outcome: Outcome::NotDiverted(NotDivertedReason::LeftOnBelt),
            stages: Vec::new(),
            events: Vec::new(),
            trajectory: Vec::new(),
            final_state: State::default(),
            max_lateral: 0.0,
            along_range: (0.0, 0.0),
            impacts: Vec::new(),
            overload: Default::default(),
            contact_check: Default::default(),
            tipping: Default::default(),
            arm_torque: Vec::new(),
            arm_strikes: Vec::new(),
            jam: None,
        }
    }

    /// Width and height from a PNG's signature and IHDR chunk.
    fn png_size(bytes: &[u8]) -> (u32, u32) {
        assert!(bytes.len() > 24, "PNG too short");
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
        assert_eq!(&bytes[12..16], b"IHDR", "first chunk must be IHDR");
        let be =
            |i: usize| u32::from_be_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
        (be(16), be(20))
    }

    fn count(haystack: &str, needle: &str) -> usize {
        haystack.matches(needle).count()
    }

    #[test]
    fn svg_has_labels_legend_and_outlines() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("top.svg");
        let options = PlotOptions::default();
        top_view(&scenario(), &result(), &path, &options).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        for text in [
            "x [m] (belt direction)",
            "y [m] (across the belt)",
            "pivot-side edge",
            "far edge (P_max)",
            "side guide",
            "diverted — parcel 0.40×0.26 m",
        ] {
            assert!(svg.contains(text), "SVG lacks {text:?}");
        }
        for st in [Stage::Ride, Stage::F1, Stage::F2, Stage::F4, Stage::F5] {
            assert!(
                svg.contains(&format!("path of G: {}", st.label())),
                "legend lacks {st:?}"
            );
        }
        for st in [Stage::F3, Stage::F6] {
            assert!(
                !svg.contains(&format!("path of G: {}", st.label())),
                "legend lists absent {st:?}"
            );
        }
        let shapes = count(&svg, "<polygon") + count(&svg, "<polyline");
        assert!(
            shapes >= options.outlines,
            "{shapes} polygons/polylines < {} outlines",
            options.outlines
        );
        // Each arm position is one polyline in the arm colour (plus the legend swatch).
        assert_eq!(count(&svg, "stroke=\"#8C564B\""), options.arm_positions + 1);
        assert!(!svg.contains("NaN"));
    }

    #[test]
    fn svg_string_is_the_svg_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("top.svg");
        let options = PlotOptions::default();
        top_view(&scenario(), &result(), &path, &options).unwrap();
        let file = std::fs::read_to_string(&path).unwrap();
        let text = top_view_svg(&scenario(), &result(), &options).unwrap();
        assert!(text.starts_with("<svg"), "{}", &text[..40.min(text.len())]);
        assert_eq!(text, file);
        let bad = PlotOptions {
            width: 0,
            ..PlotOptions::default()
        };
        assert!(matches!(
            top_view_svg(&scenario(), &result(), &bad),
            Err(PlotError::InvalidSize { .. })
        ));
    }

    #[test]
    fn png_has_the_requested_size() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("top.png");
        let options = PlotOptions {
            width: 900,
            height: 640,
            ..PlotOptions::default()
        };
        top_view(&scenario(), &result(), &path, &options).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(png_size(&bytes), (900, 640));
        // A blank 900 × 640 image compresses to a few kB; the drawing does not.
        assert!(
            bytes.len() > 20_000,
            "PNG suspiciously small: {} bytes",
            bytes.len()
        );
    }

    #[test]
    fn unknown_extension_is_an_error_and_writes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        for name in ["top.jpg", "top", "top.svg.txt"] {
            let path = dir.path().join(name);
            let err = top_view(&scenario(), &result(), &path, &PlotOptions::default()).unwrap_err();
            assert!(
                matches!(err, PlotError::UnknownExtension(_)),
                "{name}: {err:?}"
            );
            let msg = err.to_string();
            assert!(
                msg.contains(name) && msg.contains(".svg") && msg.contains(".png"),
                "{msg}"
            );
            assert!(!path.exists());
        }
        // The extension is case-insensitive.
        let path = dir.path().join("TOP.SVG");
        top_view(&scenario(), &result(), &path, &PlotOptions::default()).unwrap();
        assert!(path.exists());
    }

    #[test]
    fn unwritable_path_is_a_draw_error() {
        let dir = tempfile::tempdir().unwrap();
        for name in ["top.svg", "top.png"] {
            let path = dir.path().join("missing-dir").join(name);
            let err = top_view(&scenario(), &result(), &path, &PlotOptions::default()).unwrap_err();
            assert!(matches!(err, PlotError::Draw(_)), "{name}: {err:?}");
        }
    }

    /// A parcel the returning arm wedges against a full-length guide (configs/wedge.toml):
    /// the top view draws the guide along the whole edge, the arm where it jams (drawn
    /// last) and rings at the holding contacts; the default machine's guide stops at O.
    #[test]
    fn a_jam_shows_the_whole_guide_the_arm_where_it_jams_and_the_holding_contacts() {
        let mut s = Scenario::paper_default();
        s.machine.near_side = NearSide::Guide;
        s.machine.belt_speed = 0.5;
        s.machine.start_position = 0.6;
        s.parcel.length = 0.25;
        s.parcel.width = 0.12;
        s.parcel.mass = 2.0;
        s.parcel.offset = 0.0;
        s.run.cycle_starts = vec![-0.68];
        let r = divertsim_core::sim::simulate(&s);
        let jam = r.jam.as_ref().expect("jammed");
        let scene = super::top_view::Scene::new(&s, &r, &PlotOptions::default());
        assert!(scene.full_guide);
        assert_eq!(scene.arms.last().map(|a| a.0), Some(jam.t));
        assert_eq!(
            scene.jam.as_ref().map(|j| j.1.len()),
            Some(jam.contacts.len())
        );
        let svg = top_view_svg(&s, &r, &PlotOptions::default()).unwrap();
        assert!(svg.contains("the whole pivot-side edge"), "guide legend");
        assert!(svg.contains("jammed here, t = 0.48 s"), "jam legend");

        let svg = top_view_svg(&scenario(), &result(), &PlotOptions::default()).unwrap();
        assert!(svg.contains("side guide (y = 0, x ≤ 0)") && !svg.contains("jammed here"));
    }

    #[test]
    fn bad_size_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("top.png");
        for (width, height) in [(0, 700), (1000, 0), (100, 700), (20_000, 700)] {
            let options = PlotOptions {
                width,
                height,
                ..PlotOptions::default()
            };
            let err = top_view(&scenario(), &result(), &path, &options).unwrap_err();
            assert!(
                matches!(err, PlotError::InvalidSize { .. }),
                "{width}×{height}: {err:?}"
            );
        }
    }

    #[test]
    fn empty_trajectory_draws_the_machine_only() {
        let dir = tempfile::tempdir().unwrap();
        for name in ["empty.svg", "empty.png"] {
            let path = dir.path().join(name);
            top_view(&scenario(), &empty_result(), &path, &PlotOptions::default()).unwrap();
            assert!(path.metadata().unwrap().len() > 0);
        }
        let svg = std::fs::read_to_string(dir.path().join("empty.svg")).unwrap();
        assert!(svg.contains("side guide") && svg.contains("pivot-side edge"));
        assert!(svg.contains("arm (retracted, never moves)"));
        assert!(svg.contains("not_diverted (left_on_belt) — parcel 0.40×0.26 m"));
        assert!(!svg.contains("path of G") && !svg.contains("start of G"));
        assert_eq!(
            png_size(&std::fs::read(dir.path().join("empty.png")).unwrap()),
            (1000, 700)
        );
    }

    /// Issue 50, item 20: a run whose strike exceeds the free fall says so in its title,
    /// and the longer title shrinks to fit the picture instead of running off its edges.
    #[test]
    fn an_over_limit_strike_heads_the_picture() {
        let mut r = result();
        r.overload.overload_ratio = 1.2365;
        let svg = top_view_svg(&scenario(), &r, &PlotOptions::default()).unwrap();
        assert!(
            svg.contains("EXCEEDS the free fall: S/S_fall = 1.24 — parcel"),
            "{}",
            &svg[..svg.len().min(2000)]
        );
        r.overload.overload_ratio = 0.99;
        let svg = top_view_svg(&scenario(), &r, &PlotOptions::default()).unwrap();
        assert!(!svg.contains("EXCEEDS"));
    }

    #[test]
    fn non_finite_samples_are_skipped() {
        let mut r = result();
        for (k, s) in r.trajectory.iter_mut().enumerate() {
            match k % 7 {
                0 => s.state.x = f64::NAN,
                1 => s.state.phi = f64::INFINITY,
                2 => s.arm_angle = f64::NAN,
                _ => {}
            }
        }
        r.trajectory[5].state.t = f64::NAN;
        let mut sc = scenario();
        sc.parcel.length = f64::NAN;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("nan.svg");
        let options = PlotOptions {
            title: Some("custom title".into()),
            ..PlotOptions::default()
        };
        top_view(&sc, &r, &path, &options).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(
            !svg.contains("NaN") && !svg.contains("inf"),
            "non-finite coordinates written"
        );
        assert!(svg.contains("custom title"));
        top_view(&sc, &r, &dir.path().join("nan.png"), &options).unwrap();
    }

    #[test]
    fn equal_aspect_matches_pixels_and_contains_data() {
        let cases = [
            (
                Bounds {
                    x0: -0.3,
                    x1: 3.0,
                    y0: 0.0,
                    y1: 1.0,
                },
                (800, 500),
            ),
            (
                Bounds {
                    x0: -0.3,
                    x1: 0.5,
                    y0: -0.1,
                    y1: 4.0,
                },
                (800, 500),
            ),
            (
                Bounds {
                    x0: 1.0,
                    x1: 1.0,
                    y0: 2.0,
                    y1: 2.0,
                },
                (300, 900),
            ),
            (Bounds::empty(), (640, 480)),
            (
                Bounds {
                    x0: -1e308,
                    x1: 1e308,
                    y0: 0.0,
                    y1: 1.0,
                },
                (640, 480),
            ),
        ];
        for (b, px) in cases {
            let (xr, yr) = equal_aspect(b, 0.06, px);
            let metres_per_px_x = (xr.end - xr.start) / f64::from(px.0);
            let metres_per_px_y = (yr.end - yr.start) / f64::from(px.1);
            approx::assert_relative_eq!(metres_per_px_x, metres_per_px_y, max_relative = 1e-12);
            assert!([xr.start, xr.end, yr.start, yr.end]
                .iter()
                .all(|v| v.is_finite()));
            if !b.is_empty() && b.x1 - b.x0 < 1e300 {
                assert!(
                    xr.start < b.x0 && xr.end > b.x1 && yr.start < b.y0 && yr.end > b.y1,
                    "{b:?}"
                );
            }
        }
    }

    #[test]
    fn tick_labels_have_no_negative_zero() {
        assert_eq!(tick_label(-1e-17, 1.5), "0.0");
        assert_eq!(tick_label(-0.3, 1.5), "-0.3");
        assert_eq!(tick_label(0.5, 1.5), "0.5");
    }

    #[test]
    fn huge_coordinates_do_not_panic() {
        let mut r = result();
        r.trajectory[100].state.x = 1e307;
        r.trajectory[101].state.y = -1e307;
        let dir = tempfile::tempdir().unwrap();
        top_view(
            &scenario(),
            &r,
            &dir.path().join("huge.png"),
            &PlotOptions::default(),
        )
        .unwrap();
    }

    #[test]
    fn outline_instants_include_first_and_last() {
        let times: Vec<f64> = (0..=100).map(|k| 0.03 * k as f64).collect();
        for n in 2..=12 {
            let idx = spread_indices(&times, n);
            assert_eq!(idx.len(), n);
            assert_eq!((idx[0], idx[n - 1]), (0, 100));
            assert!(idx.windows(2).all(|w| w[0] < w[1]));
            // Evenly spread: every gap within one sample of the ideal 100/(n−1).
            let ideal = 100.0 / (n - 1) as f64;
            assert!(
                idx.windows(2)
                    .all(|w| ((w[1] - w[0]) as f64 - ideal).abs() <= 1.0),
                "{idx:?}"
            );
        }
        assert_eq!(spread_indices(&times, 1), vec![0]);
        assert!(spread_indices(&times, 0).is_empty() && spread_indices(&[], 5).is_empty());
        // More instants than samples: each sample once.
        assert_eq!(spread_indices(&[0.0, 1.0, 2.0], 8), vec![0, 1, 2]);
    }

    #[test]
    fn arm_instants_are_distinct_for_a_symmetric_drive() {
        let times: Vec<f64> = (1..136).map(|k| 0.01 * k as f64).collect();
        let angles: Vec<f64> = times
            .iter()
            .map(|t| (std::f64::consts::PI * t / 1.36).sin())
            .collect();
        for n in 2..=9 {
            let idx = arm_indices(&times, &angles, n);
            assert_eq!(idx.len(), n);
            assert!(idx.windows(2).all(|w| w[0] < w[1]));
            let mut a: Vec<f64> = idx.iter().map(|&i| angles[i]).collect();
            a.sort_by(f64::total_cmp);
            assert!(
                a.windows(2).all(|w| w[1] - w[0] > 1e-3),
                "coinciding arm angles for n = {n}: {a:?}"
            );
        }
        let peak = arm_indices(&times, &angles, 1)[0];
        assert!((times[peak] - 0.68).abs() < 0.006);
    }

    /// The synthetic run shifted across the belt by `dy` and relabelled not diverted.
    fn shifted(dy: f64) -> SimResult {
        let mut r = result();
        for s in &mut r.trajectory {
            s.state.y -= dy;
        }
        r.outcome = Outcome::NotDiverted(NotDivertedReason::LeftOnBelt);
        r
    }

    #[test]
    fn overlay_svg_has_every_case_its_stages_and_one_arm_fan() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("paths.svg");
        let (s, a, b) = (scenario(), result(), shifted(0.3));
        let cases = [
            OverlayCase {
                label: "first: diverted",
                scenario: &s,
                result: &a,
            },
            OverlayCase {
                label: "second: not_diverted",
                scenario: &s,
                result: &b,
            },
        ];
        let options = PlotOptions::default();
        overlay_view(&cases, &path, &options).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        for text in [
            "first: diverted",
            "second: not_diverted",
            "Paths of the parcel centre G, 2 cases",
            "stage begins (its name)",
            "far edge (P_max)",
            "x [m] (belt direction)",
        ] {
            assert!(svg.contains(text), "SVG lacks {text:?}");
        }
        // Each case's path, dots and labels in its own colour.
        for i in 0..2 {
            let hex = {
                let c = case_color(i);
                format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2)
            };
            assert!(svg.contains(&hex), "no {hex} for case {i}");
        }
        // Stage labels: ride at the start, F1 and F4 one sample apart share a label, F5, F2;
        // twice each (two cases).
        for label in ["ride", "F1/F4", "F5", "F2"] {
            let n = svg.lines().filter(|l| l.trim() == label).count();
            assert_eq!(n, 2, "label {label:?} appears {n} times");
        }
        // The arm fan is drawn once (the first case's), plus its legend swatch.
        assert_eq!(count(&svg, "stroke=\"#8C564B\""), options.arm_positions + 1);
        assert!(!svg.contains("NaN"));
    }

    #[test]
    fn overlay_png_size_and_errors() {
        let dir = tempfile::tempdir().unwrap();
        let (s, a) = (scenario(), result());
        let cases = [OverlayCase {
            label: "only",
            scenario: &s,
            result: &a,
        }];
        let png = dir.path().join("paths.png");
        let options = PlotOptions {
            width: 800,
            height: 600,
            ..PlotOptions::default()
        };
        overlay_view(&cases, &png, &options).unwrap();
        assert_eq!(png_size(&std::fs::read(&png).unwrap()), (800, 600));
        let gif = dir.path().join("paths.gif");
        assert!(matches!(
            overlay_view(&cases, &gif, &options),
            Err(PlotError::UnknownExtension(_))
        ));
        assert!(!gif.exists());
        let tiny = PlotOptions {
            width: 10,
            ..PlotOptions::default()
        };
        assert!(matches!(
            overlay_view(&cases, &dir.path().join("t.svg"), &tiny),
            Err(PlotError::InvalidSize { .. })
        ));
    }

    #[test]
    fn overlay_of_nothing_or_empty_runs_draws_the_machine() {
        let dir = tempfile::tempdir().unwrap();
        let none = dir.path().join("none.svg");
        overlay_view(&[], &none, &PlotOptions::default()).unwrap();
        let svg = std::fs::read_to_string(&none).unwrap();
        assert!(svg.contains("side guide") && !svg.contains("stage begins"));
        let (s, e) = (scenario(), empty_result());
        let empty = dir.path().join("empty.svg");
        let cases = [OverlayCase {
            label: "empty",
            scenario: &s,
            result: &e,
        }];
        overlay_view(&cases, &empty, &PlotOptions::default()).unwrap();
        let svg = std::fs::read_to_string(&empty).unwrap();
        assert!(svg.contains("empty") && !svg.contains("NaN"));
    }

    #[test]
    fn stage_changes_cluster_into_labels() {
        let marks = [
            (Stage::Ride, (0.0, 0.0)),
            (Stage::F6, (0.001, 0.0)),
            (Stage::F4, (1.0, 0.0)),
            (Stage::F3, (1.001, 0.0)),
            (Stage::F4, (1.002, 0.0)),
            (Stage::F2, (2.0, 0.0)),
        ];
        let got = stage_clusters(&marks, 0.01);
        assert_eq!(
            got,
            vec![
                ((0.0, 0.0), "ride/F6".to_string()),
                ((1.0, 0.0), "F4/F3".to_string()),
                ((2.0, 0.0), "F2".to_string()),
            ]
        );
        // A zero gap keeps every change apart; no marks, no labels.
        assert_eq!(stage_clusters(&marks, 0.0).len(), marks.len());
        assert!(stage_clusters(&[], 0.01).is_empty());
    }
}
