//! Several runs in one top view, each path in its own colour with its stages named where they
//! begin (the paper's Figs 6–8 and 13–15 side by side; `divertsim paths`).

use super::top_view::Scene;
use super::*;

/// Path colours of overlaid cases (Tableau-10 without the arm's brown), in case order,
/// repeating after nine cases.
const CASE_COLORS: [RGBColor; 9] = [
    RGBColor(0x1F, 0x77, 0xB4),
    RGBColor(0xD6, 0x27, 0x28),
    RGBColor(0x2C, 0xA0, 0x2C),
    RGBColor(0xFF, 0x7F, 0x0E),
    RGBColor(0x94, 0x67, 0xBD),
    RGBColor(0x17, 0xBE, 0xCF),
    RGBColor(0xE3, 0x77, 0xC2),
    RGBColor(0xBC, 0xBD, 0x22),
    RGBColor(0x7F, 0x7F, 0x7F),
];

/// The path colour of the `i`-th overlaid case.
pub fn case_color(i: usize) -> RGBColor {
    CASE_COLORS[i % CASE_COLORS.len()]
}

/// One run in an overlay of several ([`overlay_view`]).
#[derive(Debug, Clone, Copy)]
pub struct OverlayCase<'a> {
    /// Its legend label.
    pub label: &'a str,
    /// The scenario it ran (its parcel size gives the outlines).
    pub scenario: &'a Scenario,
    /// Its result (the path of G, the stages and the arm angle come from the samples).
    pub result: &'a SimResult,
}

/// What an overlay draws of one case, in metres.
struct CaseScene {
    label: String,
    color: RGBColor,
    /// The path of G (drawable samples only).
    path: Vec<(f64, f64)>,
    /// Where each stretch of one stage begins (the first sample included): the stage and G.
    stage_marks: Vec<(Stage, (f64, f64))>,
    /// The parcel's footprint at the first and the last drawable sample.
    first: Option<[DVec2; 4]>,
    last: Option<[DVec2; 4]>,
}

impl CaseScene {
    fn new(i: usize, case: &OverlayCase<'_>) -> CaseScene {
        let rect = Rect {
            length: case.scenario.parcel.length,
            width: case.scenario.parcel.width,
        };
        let valid: Vec<&Sample> = case
            .result
            .trajectory
            .iter()
            .filter(|s| state_ok(s))
            .collect();
        let path = valid.iter().map(|s| (s.state.x, s.state.y)).collect();
        let mut stage_marks: Vec<(Stage, (f64, f64))> = Vec::new();
        let mut previous: Option<Stage> = None;
        for s in &valid {
            if previous != Some(s.stage) {
                stage_marks.push((s.stage, (s.state.x, s.state.y)));
                previous = Some(s.stage);
            }
        }
        let footprint = |s: &&Sample| rect.corners(DVec2::new(s.state.x, s.state.y), s.state.phi);
        CaseScene {
            label: case.label.to_string(),
            color: case_color(i),
            path,
            stage_marks,
            first: valid.first().map(footprint),
            last: valid.last().map(footprint),
        }
    }
}

/// Everything an overlay draws, in metres.
struct OverlayScene {
    belt_width: f64,
    /// Whether the first case's side guide runs along the whole pivot-side edge.
    full_guide: bool,
    arm_length: f64,
    /// (t, α) of the first case's arm positions drawn.
    arms: Vec<(f64, f64)>,
    cases: Vec<CaseScene>,
    title: String,
    bounds: Bounds,
}

impl OverlayScene {
    fn new(cases: &[OverlayCase<'_>], options: &PlotOptions) -> OverlayScene {
        let positive = |v: f64| if v.is_finite() && v > 0.0 { v } else { 0.0 };
        let (belt_width, arm_length) = cases
            .first()
            .map(|c| {
                (
                    positive(c.scenario.machine.belt_width),
                    positive(c.scenario.machine.arm_length),
                )
            })
            .unwrap_or((0.0, 0.0));
        // The arm fan of the first case, as in the single top view.
        let arms = cases
            .first()
            .map(|c| Scene::new(c.scenario, c.result, options).arms)
            .unwrap_or_else(|| vec![(0.0, 0.0)]);
        let scenes: Vec<CaseScene> = cases
            .iter()
            .enumerate()
            .map(|(i, c)| CaseScene::new(i, c))
            .collect();

        let mut bounds = Bounds::empty();
        bounds.add(0.0, 0.0);
        bounds.add(0.0, belt_width);
        bounds.add(arm_length, 0.0);
        bounds.add(-0.25 * arm_length.max(belt_width).max(0.2), 0.0);
        for &(_, a) in &arms {
            bounds.add(arm_length * a.cos(), arm_length * a.sin());
        }
        for c in &scenes {
            for &(x, y) in &c.path {
                bounds.add(x, y);
            }
            for corners in c.first.iter().chain(c.last.iter()) {
                for p in corners {
                    bounds.add(p.x, p.y);
                }
            }
        }
        let title = options.title.clone().unwrap_or_else(|| match cases.len() {
            1 => "Path of the parcel centre G".to_string(),
            n => format!("Paths of the parcel centre G, {n} cases"),
        });
        OverlayScene {
            belt_width,
            full_guide: cases
                .first()
                .is_some_and(|c| c.scenario.machine.near_side == NearSide::Guide),
            arm_length,
            arms,
            cases: scenes,
            title,
            bounds,
        }
    }
}

/// Draw several runs in one top view (the paper's Figs 6–8 and 13–15 side by side): the
/// belt, the side guide and the arm positions of the first case, and for every case the path
/// of its centre G in its own colour ([`case_color`]), a marker and the stage's name where
/// each stage begins, the parcel outline at the start (thin, tinted) and at the end (thick),
/// and a legend entry with its label. Writes `path` (`.svg` or `.png`) only.
///
/// The belt width and arm length drawn are the first case's. Degenerate input does not fail:
/// no cases draws the machine alone, and samples with non-finite t, x, y or φ are skipped.
pub fn overlay_view(
    cases: &[OverlayCase<'_>],
    path: &Path,
    options: &PlotOptions,
) -> Result<(), PlotError> {
    let format = format_of(path)?;
    let (width, height) = (options.width, options.height);
    if !(MIN_SIDE..=MAX_SIDE).contains(&width) || !(MIN_SIDE..=MAX_SIDE).contains(&height) {
        return Err(PlotError::InvalidSize { width, height });
    }
    ensure_font()?;
    let scene = OverlayScene::new(cases, options);
    match format {
        Format::Svg => {
            let root = SVGBackend::new(path, (width, height)).into_drawing_area();
            render_overlay(&root, &scene, options)?;
            root.present().map_err(draw_err)
        }
        Format::Png => {
            let root = BitMapBackend::new(path, (width, height)).into_drawing_area();
            render_overlay(&root, &scene, options)?;
            root.present().map_err(draw_err)
        }
    }
}

/// The legend of an overlay: the machine, then one entry per case, then the markers.
fn overlay_legend(scene: &OverlayScene, z: &Sizes) -> Vec<(Swatch, String)> {
    let mut e = vec![
        (Swatch::Band, "belt (0 ≤ y ≤ P_max)".to_string()),
        guide_entry(scene.full_guide, z),
        (Swatch::Pivot, "arm pivot O".to_string()),
    ];
    let moving = scene.arms.iter().any(|&(_, a)| a > 0.0);
    let arm = match (moving, scene.arms.first(), scene.arms.last()) {
        (true, Some(a), Some(b)) if scene.arms.len() > 1 => {
            format!("arm (first case), t = {}…{} s", fmt_t(a.0), fmt_t(b.0))
        }
        (true, Some(a), _) => format!("arm (first case), t = {} s", fmt_t(a.0)),
        _ => "arm (retracted)".to_string(),
    };
    e.push((Swatch::Line(ARM.mix(0.8), z.w(5.0)), arm));
    for c in &scene.cases {
        e.push((Swatch::Line(c.color.to_rgba(), z.w(3.0)), c.label.clone()));
    }
    if scene.cases.iter().any(|c| !c.stage_marks.is_empty()) {
        e.push((Swatch::StageMark, "stage begins (its name)".to_string()));
        e.push((
            Swatch::CaseOutline(false),
            "parcel at the start (tinted)".to_string(),
        ));
        e.push((
            Swatch::CaseOutline(true),
            "parcel at the end (bold)".to_string(),
        ));
    }
    e
}

fn render_overlay<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    scene: &OverlayScene,
    options: &PlotOptions,
) -> Result<(), PlotError> {
    let z = Sizes::new(options);
    let entries = overlay_legend(scene, &z);
    let (plot_area, pixels) = frame(root, &scene.title, &entries, scene.bounds, &z)?;
    let (mut chart, xr) = machine_chart(
        &plot_area,
        pixels,
        scene.bounds,
        (scene.belt_width, scene.full_guide),
        &scene.arms,
        scene.arm_length,
        &z,
    )?;

    let metres_per_px = (xr.end - xr.start) / f64::from(pixels.0.max(1));
    let min_step = z.px(3.0) as f64 * metres_per_px;
    // Start outlines under everything, then the paths, then the end outlines.
    for c in &scene.cases {
        if let Some(first) = &c.first {
            chart
                .draw_series(std::iter::once(Polygon::new(
                    closed(first),
                    c.color.mix(0.15).filled(),
                )))
                .map_err(draw_err)?;
            chart
                .draw_series(std::iter::once(PathElement::new(
                    closed(first),
                    c.color.stroke_width(z.w(1.0)),
                )))
                .map_err(draw_err)?;
        }
    }
    for c in &scene.cases {
        chart
            .draw_series(std::iter::once(PathElement::new(
                thin(&c.path, min_step),
                c.color.stroke_width(z.w(3.0)),
            )))
            .map_err(draw_err)?;
    }
    for c in &scene.cases {
        if let Some(last) = &c.last {
            chart
                .draw_series(std::iter::once(PathElement::new(
                    closed(last),
                    c.color.stroke_width(z.w(3.0)),
                )))
                .map_err(draw_err)?;
        }
    }

    // Stage marks: a ringed dot at every stage change, and one label per cluster of changes
    // within about 16 px of the cluster's first (rapid F3/F4 alternations would otherwise
    // pile up unreadably): the cluster's stages in order of first appearance, "F4/F3".
    let min_gap = z.px(16.0) as f64 * metres_per_px;
    for c in &scene.cases {
        let style = TextStyle::from((FONT, z.font(12.0)).into_font())
            .color(&c.color)
            .pos(Pos::new(HPos::Left, VPos::Bottom));
        chart
            .draw_series(c.stage_marks.iter().map(|&(_, p)| {
                EmptyElement::at(p)
                    + Circle::new((0, 0), z.px(4.0), c.color.filled())
                    + Circle::new((0, 0), z.px(4.0), BLACK.stroke_width(z.w(1.0)))
            }))
            .map_err(draw_err)?;
        chart
            .draw_series(
                stage_clusters(&c.stage_marks, min_gap)
                    .into_iter()
                    .map(|(p, text)| {
                        EmptyElement::at(p)
                            + Text::new(text, (z.px(5.0), -z.px(3.0)), style.clone())
                    }),
            )
            .map_err(draw_err)?;
    }
    draw_pivot_and_edge_labels(&mut chart, &xr, scene.belt_width, &z)
}
