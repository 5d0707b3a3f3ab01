//! The top view of one run (the paper's Fig. 3 view): the machine, the arm at several
//! instants, the parcel outline at several instants and the path of its centre coloured by
//! stage, with the events marked and a legend.

use super::*;
use crate::charts::short;

/// Draw the top view of `result` for `scenario` to `path` (`.svg` or `.png`).
///
/// Writes to `path` only. Degenerate input does not fail: an empty trajectory draws the
/// machine alone, and samples with non-finite t, x, y or φ are skipped.
pub fn top_view(
    scenario: &Scenario,
    result: &SimResult,
    path: &Path,
    options: &PlotOptions,
) -> Result<(), PlotError> {
    let format = format_of(path)?;
    let (width, height) = checked_size(options)?;
    let scene = Scene::new(scenario, result, options);
    match format {
        Format::Svg => {
            let root = SVGBackend::new(path, (width, height)).into_drawing_area();
            render(&root, &scene, options)?;
            root.present().map_err(draw_err)
        }
        Format::Png => {
            let root = BitMapBackend::new(path, (width, height)).into_drawing_area();
            render(&root, &scene, options)?;
            root.present().map_err(draw_err)
        }
    }
}

/// The top view of `result` for `scenario` as SVG text (what [`top_view`](fn@top_view) writes to a
/// `.svg` file), for edges that show the figure inline (the Python package's notebook view).
pub fn top_view_svg(
    scenario: &Scenario,
    result: &SimResult,
    options: &PlotOptions,
) -> Result<String, PlotError> {
    let (width, height) = checked_size(options)?;
    let scene = Scene::new(scenario, result, options);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
        render(&root, &scene, options)?;
        root.present().map_err(draw_err)?;
    }
    Ok(svg)
}

/// The default title: the outcome label (with its reason when short), the parcel (a × b, ΔP,
/// φ) and the setting (v, t_c, R_s).
fn default_title(scenario: &Scenario, result: &SimResult) -> String {
    let outcome = match &result.outcome {
        Outcome::Diverted => result.outcome.label().to_string(),
        other => match other.reason() {
            Some(r) if r.chars().count() <= 40 => format!("{} ({r})", other.label()),
            _ => other.label().to_string(),
        },
    };
    let outcome = match result.overload.exceeds_text() {
        Some(x) => format!("{outcome}, {x}"),
        None => outcome,
    };
    let (m, p) = (&scenario.machine, &scenario.parcel);
    format!(
        "{outcome} — parcel {:.2}×{:.2} m at ΔP = {} m, φ = {:.0}°; v = {} m/s, t_c = {} s, R_s = {} m",
        p.length,
        p.width,
        short(p.offset),
        p.angle.to_degrees(),
        short(m.belt_speed),
        short(m.cycle_time),
        short(m.start_position)
    )
}

/// One parcel outline: its instant and the corners of the footprint.
pub(super) struct Outline {
    pub(super) t: f64,
    pub(super) corners: [DVec2; 4],
    /// Contact points at this instant.
    pub(super) contacts: Vec<(f64, f64)>,
}

/// Everything to draw, in metres, computed before any drawing.
pub(super) struct Scene {
    /// P_max: belt width \[m]
    pub(super) belt_width: f64,
    /// R_z: arm length \[m]
    pub(super) arm_length: f64,
    /// (t \[s], α \[rad]) of the arm positions drawn, in time order.
    pub(super) arms: Vec<(f64, f64)>,
    /// Whether the arm moves at all (α > 0 somewhere).
    pub(super) arm_moves: bool,
    /// Parcel outlines in time order (first and last emphasised).
    pub(super) outlines: Vec<Outline>,
    /// Pieces of the centre's path, one per stretch of a single stage.
    pub(super) runs: Vec<(Stage, Vec<(f64, f64)>)>,
    /// Stages present on the path, in legend order.
    pub(super) stages: Vec<Stage>,
    /// Strike points (contact point of each impact).
    pub(super) strikes: Vec<(f64, f64)>,
    /// Whether the side guide runs along the whole pivot-side edge (`near_side = "guide"`).
    pub(super) full_guide: bool,
    /// A jam: its time \[s] and the points that hold the parcel.
    pub(super) jam: Option<(f64, Vec<(f64, f64)>)>,
    /// Centre G at the first and the last drawable sample.
    pub(super) start: Option<(f64, f64)>,
    pub(super) end: Option<(f64, f64)>,
    pub(super) title: String,
    /// Everything that must be visible.
    pub(super) bounds: Bounds,
}

impl Scene {
    pub(super) fn new(scenario: &Scenario, result: &SimResult, options: &PlotOptions) -> Scene {
        let positive = |v: f64| if v.is_finite() && v > 0.0 { v } else { 0.0 };
        let belt_width = positive(scenario.machine.belt_width);
        let arm_length = positive(scenario.machine.arm_length);
        let rect = Rect {
            length: scenario.parcel.length,
            width: scenario.parcel.width,
        };

        let moving: Vec<&Sample> = result
            .trajectory
            .iter()
            .filter(|s| s.state.t.is_finite() && s.arm_angle.is_finite() && s.arm_angle > 0.0)
            .collect();
        let arm_moves = !moving.is_empty();
        let arms = if arm_moves {
            let times: Vec<f64> = moving.iter().map(|s| s.state.t).collect();
            let angles: Vec<f64> = moving.iter().map(|s| s.arm_angle).collect();
            let mut arms: Vec<(f64, f64)> = arm_indices(&times, &angles, options.arm_positions)
                .into_iter()
                .map(|i| (times[i], angles[i]))
                .collect();
            // A jammed run ends with the arm where it jams: drawn last, darkest.
            if let (Some(_), Some(&t), Some(&a)) = (&result.jam, times.last(), angles.last()) {
                if arms.last().is_none_or(|l| l.0 < t) {
                    arms.push((t, a));
                }
            }
            arms
        } else {
            vec![(0.0, 0.0)]
        };

        let valid: Vec<&Sample> = result.trajectory.iter().filter(|s| state_ok(s)).collect();
        let times: Vec<f64> = valid.iter().map(|s| s.state.t).collect();
        let outlines: Vec<Outline> = spread_indices(&times, options.outlines)
            .into_iter()
            .map(|i| {
                let st = &valid[i].state;
                Outline {
                    t: st.t,
                    corners: rect.corners(DVec2::new(st.x, st.y), st.phi),
                    contacts: valid[i]
                        .contacts
                        .iter()
                        .flatten()
                        .filter(|p| p[0].is_finite() && p[1].is_finite())
                        .map(|p| (p[0], p[1]))
                        .collect(),
                }
            })
            .collect();

        // A new stage's stretch starts at the previous point, so that the path stays
        // continuous and the segment after an event takes the colour of the stage entered.
        let mut runs: Vec<(Stage, Vec<(f64, f64)>)> = Vec::new();
        for s in &valid {
            let p = (s.state.x, s.state.y);
            match runs.last_mut() {
                Some((stage, pts)) if *stage == s.stage => pts.push(p),
                Some((_, pts)) => {
                    let prev = pts[pts.len() - 1];
                    runs.push((s.stage, vec![prev, p]));
                }
                None => runs.push((s.stage, vec![p])),
            }
        }
        let stages = ALL_STAGES
            .iter()
            .copied()
            .filter(|st| runs.iter().any(|(s, _)| s == st))
            .collect();
        let start = valid.first().map(|s| (s.state.x, s.state.y));
        let strikes: Vec<(f64, f64)> = result
            .impacts
            .iter()
            .map(|i| (i.point[0], i.point[1]))
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .collect();
        let end = valid.last().map(|s| (s.state.x, s.state.y));
        let jam = result.jam.as_ref().map(|j| {
            let points = j
                .contacts
                .iter()
                .map(|(_, p)| (p[0], p[1]))
                .filter(|p| p.0.is_finite() && p.1.is_finite())
                .collect();
            (j.t, points)
        });

        let mut bounds = Bounds::empty();
        bounds.add(0.0, 0.0);
        bounds.add(0.0, belt_width);
        // Show the arm's full reach along the belt and some of the guide upstream of O.
        bounds.add(arm_length, 0.0);
        bounds.add(-0.25 * arm_length.max(belt_width).max(0.2), 0.0);
        for &(_, a) in &arms {
            bounds.add(arm_length * a.cos(), arm_length * a.sin());
        }
        for o in &outlines {
            for c in o.corners {
                bounds.add(c.x, c.y);
            }
        }
        for (_, pts) in &runs {
            for &(x, y) in pts {
                bounds.add(x, y);
            }
        }

        let title = options
            .title
            .clone()
            .unwrap_or_else(|| default_title(scenario, result));
        Scene {
            belt_width,
            arm_length,
            arms,
            arm_moves,
            outlines,
            runs,
            stages,
            strikes,
            full_guide: scenario.machine.near_side == NearSide::Guide,
            jam,
            start,
            end,
            title,
            bounds,
        }
    }
}

/// The legend entries for `scene`.
fn legend_entries(scene: &Scene, z: &Sizes) -> Vec<(Swatch, String)> {
    let mut e = vec![
        (Swatch::Band, "belt (0 ≤ y ≤ P_max)".to_string()),
        guide_entry(scene.full_guide, z),
        (Swatch::Pivot, "arm pivot O".to_string()),
    ];
    let arm = match (scene.arm_moves, scene.arms.first(), scene.arms.last()) {
        (true, Some(a), Some(b)) if scene.arms.len() > 1 => {
            format!("arm, t = {}…{} s (light → dark)", fmt_t(a.0), fmt_t(b.0))
        }
        (true, Some(a), _) => format!("arm, t = {} s", fmt_t(a.0)),
        _ => "arm (retracted, never moves)".to_string(),
    };
    e.push((Swatch::Line(ARM.mix(0.8), z.w(5.0)), arm));
    match scene.outlines.as_slice() {
        [] => {}
        [only] => e.push((
            Swatch::Outline(Some(FIRST_FILL), z.w(3.0)),
            format!("parcel, t = {} s", fmt_t(only.t)),
        )),
        [first, mid @ .., last] => {
            e.push((
                Swatch::Outline(Some(FIRST_FILL), z.w(3.0)),
                format!("parcel first, t = {} s", fmt_t(first.t)),
            ));
            if !mid.is_empty() {
                let step = (last.t - first.t) / (mid.len() + 1) as f64;
                e.push((
                    Swatch::Outline(None, z.w(1.0)),
                    format!("parcel, about every {} s", fmt_t(step)),
                ));
            }
            e.push((
                Swatch::Outline(Some(LAST_FILL), z.w(3.0)),
                format!("parcel last, t = {} s", fmt_t(last.t)),
            ));
        }
    }
    for &st in &scene.stages {
        e.push((
            Swatch::Line(stage_color(st).to_rgba(), z.w(3.0)),
            format!("path of G: {}", st.label()),
        ));
    }
    if !scene.strikes.is_empty() {
        e.push((Swatch::Strike, "strike (contact point)".to_string()));
    }
    if let Some((t, _)) = &scene.jam {
        e.push((Swatch::Jam, format!("jammed here, t = {} s", fmt_t(*t))));
    }
    if scene.outlines.iter().any(|o| !o.contacts.is_empty()) {
        e.push((Swatch::Contact, "contact point (on outlines)".to_string()));
    }
    if scene.start.is_some() {
        e.push((Swatch::StartMarker, "start of G".to_string()));
        e.push((Swatch::EndMarker, "end of G".to_string()));
    }
    e
}

/// Draw the whole figure on `root`: the title, the chart, and the legend in its own panel.
fn render<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    scene: &Scene,
    options: &PlotOptions,
) -> Result<(), PlotError> {
    let z = Sizes::new(options);
    let entries = legend_entries(scene, &z);
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

    // Parcel outlines: the intermediate ones thin, then the path, then first and last on top.
    // Backend coordinates are whole pixels: points much closer than a line width round to a
    // zigzag, so the path keeps only points about 3 px apart (and both ends).
    let min_step = z.px(3.0) as f64 * (xr.end - xr.start) / f64::from(pixels.0.max(1));
    let n_out = scene.outlines.len();
    let mid = if n_out > 2 {
        &scene.outlines[1..n_out - 1]
    } else {
        &[]
    };
    chart
        .draw_series(
            mid.iter().map(|o| {
                PathElement::new(closed(&o.corners), OUTLINE.mix(0.8).stroke_width(z.w(1.0)))
            }),
        )
        .map_err(draw_err)?;
    chart
        .draw_series(scene.runs.iter().map(|(st, pts)| {
            PathElement::new(thin(pts, min_step), stage_color(*st).stroke_width(z.w(3.0)))
        }))
        .map_err(draw_err)?;
    let ends: Vec<(&Outline, RGBColor)> = match scene.outlines.as_slice() {
        [] => Vec::new(),
        [only] => vec![(only, FIRST_FILL)],
        [first, .., last] => vec![(first, FIRST_FILL), (last, LAST_FILL)],
    };
    for (o, fill) in ends {
        chart
            .draw_series(std::iter::once(Polygon::new(
                closed(&o.corners),
                fill.mix(0.45).filled(),
            )))
            .map_err(draw_err)?;
        chart
            .draw_series(std::iter::once(PathElement::new(
                closed(&o.corners),
                OUTLINE.stroke_width(z.w(3.0)),
            )))
            .map_err(draw_err)?;
    }

    // Contact points on the drawn outlines.
    for o in &scene.outlines {
        for &p in &o.contacts {
            chart
                .draw_series(std::iter::once(Circle::new(p, z.px(4.0), CONTACT.filled())))
                .map_err(draw_err)?;
        }
    }

    // Markers: strikes, start and end of G, the pivot O.
    for &p in &scene.strikes {
        chart
            .draw_series(std::iter::once(Cross::new(
                p,
                z.px(7.0),
                STRIKE.stroke_width(z.w(3.0)),
            )))
            .map_err(draw_err)?;
    }
    for &p in scene.jam.iter().flat_map(|(_, points)| points) {
        chart
            .draw_series(std::iter::once(Circle::new(
                p,
                z.px(7.0),
                JAM.stroke_width(z.w(3.0)),
            )))
            .map_err(draw_err)?;
    }
    let mr = z.px(6.0);
    if let (Some(s), Some(e)) = (scene.start, scene.end) {
        chart
            .draw_series(std::iter::once(Circle::new(s, mr, WHITE.filled())))
            .map_err(draw_err)?;
        chart
            .draw_series(std::iter::once(Circle::new(
                s,
                mr,
                BLACK.stroke_width(z.w(2.0)),
            )))
            .map_err(draw_err)?;
        chart
            .draw_series(std::iter::once(
                EmptyElement::at(e) + Rectangle::new([(-mr, -mr), (mr, mr)], BLACK.filled()),
            ))
            .map_err(draw_err)?;
    }
    draw_pivot_and_edge_labels(&mut chart, &xr, scene.belt_width, &z)
}
