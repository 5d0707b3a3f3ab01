//! `divertsim capacity`: the capacity map W(t_c, S_d) by the paper's §4.2 algorithm (paper
//! Fig. 9), computed by `divertsim_core::analysis::paper::capacity` over the scenario's `[design]`
//! set; a table, capacity.csv, a heat map capacity.svg, or JSON.

use std::path::Path;
use std::time::Instant;

use divertsim_api::analyses::capacity::{self as api, compute, compute_robust, csv};
use divertsim_core::analysis::paper::capacity::{pieces, CapacityMap, CapacityOptions};
use plotters::prelude::*;

use super::common::{self, OutputArgs, ScenarioArgs};
use super::worst_case::{RobustArgs, WorstArg};
use divertsim_api::analyses::worst_case::pose_text;
use divertsim_api::config::Problem;
use divertsim_core::analysis::design::robust::RobustMap;
use divertsim_figures::plot::{draw_err, ensure_font, format_of, Format, PlotError, FONT};

/// Compute the capacity map over a grid of cycle times and light-barrier positions.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are --help text: [m] is a unit
#[derive(Debug, Clone, clap::Args)]
pub struct CapacityArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub output: OutputArgs,
    #[command(flatten)]
    pub resume: common::ResumeArgs,
    /// Cycle times t_c [s] (the map's x axis): LO:HI/COUNT, LO:HI:STEP or A,B,C.
    #[arg(long, value_name = "LO:HI/COUNT", default_value = "1.0:1.5/20")]
    pub cycle_times: String,
    /// Light-barrier positions S_d [m] (the map's y axis): LO:HI/COUNT, LO:HI:STEP or A,B,C.
    #[arg(
        long,
        value_name = "LO:HI/COUNT",
        default_value = "0:0.9/20",
        allow_hyphen_values = true
    )]
    pub light_barriers: String,
    /// Belt speeds v searched at every cell [m/s]: LO:HI/COUNT, LO:HI:STEP or A,B,C.
    #[arg(long, value_name = "LO:HI/COUNT", default_value = "1.0:2.3/14")]
    pub speeds: String,
    /// Start positions R_s searched, as MIN:MAX [m].
    #[arg(
        long,
        value_name = "MIN:MAX",
        default_value = "0:0.9",
        allow_hyphen_values = true
    )]
    pub start_range: String,
    /// Step of the R_s grid [m].
    #[arg(
        long,
        value_name = "M",
        default_value_t = 0.05,
        allow_negative_numbers = true
    )]
    pub start_step: f64,
    /// Bisection tolerance on the boundaries of the feasible R_s intervals [m].
    #[arg(
        long,
        value_name = "M",
        default_value_t = 0.005,
        allow_negative_numbers = true
    )]
    pub start_tolerance: f64,
    #[command(flatten)]
    pub robust: RobustArgs,
}

/// Parse `--start-range MIN:MAX` with −5 ≤ MIN ≤ MAX ≤ 5 m.
pub fn parse_start_range(text: &str) -> Result<(f64, f64), Problem> {
    let range: Vec<f64> = text
        .split(':')
        .map(|s| s.trim().parse::<f64>().unwrap_or(f64::NAN))
        .collect();
    match range[..] {
        [a, b]
            if a.is_finite()
                && b.is_finite()
                && (-5.0..=5.0).contains(&a)
                && (a..=5.0).contains(&b) =>
        {
            Ok((a, b))
        }
        _ => Err(Problem {
            key: "--start-range".into(),
            message: format!("'{text}': allowed: MIN:MAX with -5 ≤ MIN ≤ MAX ≤ 5 m"),
        }),
    }
}

/// Largest number of values in a list.
pub use api::MAX_COUNT;

/// Parse a list of values in the one grammar of [`parse_values`](divertsim_api::config::values::parse_values) with every value
/// in [lo, hi] and at most [`MAX_COUNT`] values; a range that gives a single value is warned
/// about on stderr.
pub fn parse_range(
    key: &str,
    text: &str,
    lo: f64,
    hi: f64,
    unit: &str,
) -> Result<Vec<f64>, Problem> {
    let (values, warning) =
        divertsim_api::config::values::parse_values(key, text, lo, hi, unit, MAX_COUNT)?;
    if let Some(w) = warning {
        eprintln!("{w}");
    }
    Ok(values)
}

/// The options from the command line, or every problem with them (exit 2).
pub fn options(args: &CapacityArgs) -> Result<CapacityOptions, Vec<Problem>> {
    let mut problems = Vec::new();
    let mut take = |r: Result<Vec<f64>, Problem>| match r {
        Ok(v) => v,
        Err(p) => {
            problems.push(p);
            Vec::new()
        }
    };
    let cycle_times = take(parse_range(
        "--cycle-times",
        &args.cycle_times,
        0.2,
        10.0,
        "s",
    ));
    let light_barriers = take(parse_range(
        "--light-barriers",
        &args.light_barriers,
        -5.0,
        5.0,
        "m",
    ));
    let belt_speeds = take(parse_range("--speeds", &args.speeds, 0.05, 10.0, "m/s"));
    let (start_min, start_max) = parse_start_range(&args.start_range).unwrap_or_else(|p| {
        problems.push(p);
        (0.0, 0.0)
    });
    let options = CapacityOptions {
        cycle_times,
        light_barriers,
        belt_speeds,
        start_min,
        start_max,
        start_step: args.start_step,
        start_tolerance: args.start_tolerance,
    };
    if problems.is_empty() {
        problems = common::flags(api::check(&options));
    }
    if problems.is_empty() {
        Ok(options)
    } else {
        Err(problems)
    }
}

/// The rounds of a robust map, for the table.
pub fn robust_text(r: &RobustMap) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "against the searched worst case: {} round{}, {}",
        r.rounds.len(),
        if r.rounds.len() == 1 { "" } else { "s" },
        if r.converged {
            "converged (no violating pose at any feasible cell's setting)"
        } else {
            "NOT converged (raise --rounds): some feasible cells may not hold"
        }
    );
    for (k, m) in r.rounds.iter().enumerate() {
        let _ = writeln!(
            s,
            "  round {}: {} worst poses, {} settings verified, {} poses added, {} simulations",
            k + 1,
            m.poses,
            m.verified,
            m.added,
            m.simulations
        );
    }
    for (k, p) in r.set.worst_poses.iter().enumerate() {
        let _ = writeln!(s, "  worst{}: {}", k + 1, pose_text(p));
    }
    s
}

/// The readable table: W [parcels/h] with S_d down and t_c across; "x" marks no feasible
/// setting.
pub fn table(map: &CapacityMap) -> String {
    use std::fmt::Write;
    let o = &map.options;
    let nsd = o.light_barriers.len();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "capacity W [parcels/h] by the paper's §4.2 algorithm; x = no feasible (v, R_s)"
    );
    let _ = write!(s, "{:>9} |", "S_d \\ t_c");
    for tc in &o.cycle_times {
        let _ = write!(s, "{tc:>6.3}");
    }
    let _ = writeln!(s);
    let _ = writeln!(s, "{}", "-".repeat(11 + 6 * o.cycle_times.len()));
    for (j, sd) in o.light_barriers.iter().enumerate().rev() {
        let _ = write!(s, "{sd:>9.3} |");
        for i in 0..o.cycle_times.len() {
            let c = &map.cells[i * nsd + j];
            if c.feasible {
                let _ = write!(s, "{:>6.0}", c.capacity);
            } else {
                let _ = write!(s, "{:>6}", "x");
            }
        }
        let _ = writeln!(s);
    }
    let feasible = map.cells.iter().filter(|c| c.feasible).count();
    let _ = writeln!(
        s,
        "feasible cells: {feasible} of {}; simulations: {}",
        map.cells.len(),
        map.simulations
    );
    match map.best() {
        Some(b) => {
            let _ = writeln!(
                s,
                "best: W = {:.1} parcels/h at t_c = {} s, S_d = {} m with v = {} m/s, R_s = {:.4} m (overload ratio {:.3})",
                b.capacity,
                b.cycle_time,
                b.light_barrier,
                b.belt_speed.unwrap_or(f64::NAN),
                b.start_position.unwrap_or(f64::NAN),
                b.overload_ratio.unwrap_or(f64::NAN)
            );
        }
        None => {
            let _ = writeln!(s, "no feasible setting anywhere on the grid");
        }
    }
    s
}

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
/// the best cell; a colour bar) to `path` (.svg or .png).
pub fn draw(map: &CapacityMap, path: &Path) -> Result<(), PlotError> {
    let format = format_of(path)?;
    ensure_font()?;
    let size = (1000, 700);
    match format {
        Format::Svg => render(SVGBackend::new(path, size).into_drawing_area(), map),
        Format::Png => render(BitMapBackend::new(path, size).into_drawing_area(), map),
    }
}

fn render<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    map: &CapacityMap,
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
            "Capacity W [parcels/h] (paper Fig. 9); grey × = no feasible setting",
            (FONT, 18),
        )
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(65)
        .build_cartesian_2d(xe[0]..xe[xe.len() - 1], ye[0]..ye[ye.len() - 1])
        .map_err(draw_err)?;
    chart
        .configure_mesh()
        .disable_mesh()
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
            .map_err(draw_err)?
            .label(format!(
                "best W = {:.0} /h (v = {} m/s, R_s = {:.3} m)",
                b.capacity,
                b.belt_speed.unwrap_or(f64::NAN),
                b.start_position.unwrap_or(f64::NAN)
            ))
            .legend(|(x, y)| Circle::new((x + 10, y), 5, RED.stroke_width(2)));
        chart
            .configure_series_labels()
            .label_font((FONT, 13))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(0xB0, 0xB0, 0xB0))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(draw_err)?;
    }

    // Colour bar.
    let mut bar = ChartBuilder::on(&right)
        .margin_top(50)
        .margin_bottom(57)
        .margin_right(10)
        .y_label_area_size(70)
        .caption("W [/h]", (FONT, 14))
        .build_cartesian_2d(0.0..1.0, w_lo..w_hi)
        .map_err(draw_err)?;
    bar.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
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

/// `divertsim capacity`.
pub fn run(args: &CapacityArgs) -> i32 {
    let loaded = common::load_scenario(&args.scenario);
    let mut problems = common::out_problems(&args.output);
    let options = match options(args) {
        Ok(o) => Some(o),
        Err(p) => {
            problems.extend(p);
            None
        }
    };
    let (worst, margins, robust) = match args.robust.resolve(false) {
        Ok(r) => r,
        Err(p) => {
            problems.extend(p);
            (WorstArg::Paper, Default::default(), None)
        }
    };
    let loaded = match common::checked(loaded, problems) {
        Ok(l) => l,
        Err(code) => return code,
    };
    let Some(options) = options else { return 2 };
    let mut loaded = loaded;
    loaded.design.worst = worst.definition();
    loaded.design.margins = margins;
    let sims = divertsim_api::analyses::capacity::estimated_simulations(
        &loaded,
        &options,
        robust.as_ref(),
    );
    if let Err(code) = common::within_budget(
        "capacity",
        sims,
        &args.output,
        "use fewer or coarser --cycle-times, --light-barriers, --speeds or --start-step",
    ) {
        return code;
    }
    let journal = match common::open_journal(
        args.output.out.as_deref(),
        args.resume.resume,
        "capacity",
        &(&loaded.scenario, &loaded.design, &options, &robust),
    ) {
        Ok(j) => j,
        Err(code) => return code,
    };
    let memo = common::memo_of(&journal);
    // A robust map's rounds announce their searches (a tick per simulation) and the next
    // round's pieces as they come.
    let unit = if robust.is_some() { "steps" } else { "pieces" };
    let bar = common::progress_bar_of(pieces(&options) as u64, "capacity", unit, args.output.quiet);
    let tick = || bar.inc(1);
    let announce = |n: u64| bar.inc_length(n);
    let started = Instant::now();
    let result =
        divertsim_api::threads::with_threads(
            args.output.threads.map(usize::from),
            || match &robust {
                None => compute(&loaded, &options, &tick, memo).map(|m| (Some(m), None)),
                Some(r) => compute_robust(&loaded, &options, r, &tick, &announce, memo)
                    .map(|rm| (None, Some(rm))),
            },
        );
    bar.finish_and_clear();
    let (plain, robust_map) = match result {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {e}");
            return 3;
        }
    };
    // The robust run's map is its last round's; a plain run has only the map.
    let Some(map) = robust_map.as_ref().map(|r| &r.map).or(plain.as_ref()) else {
        return 3;
    };
    if !args.output.quiet {
        eprintln!(
            "capacity: {} simulations in {:.1} s",
            // A robust map: every round's map and searches.
            robust_map.as_ref().map_or(map.simulations, |r| r
                .rounds
                .iter()
                .map(|x| x.simulations)
                .sum()),
            started.elapsed().as_secs_f64()
        );
    }
    let code = common::finish(
        &args.output,
        "capacity",
        &loaded,
        || csv(map),
        |p| draw(map, p).map_err(|e| e.to_string()),
        || api::summary_of(&loaded, map, robust_map.as_ref()),
        || {
            let mut t = table(map);
            if let Some(r) = &robust_map {
                t += &robust_text(r);
            }
            t
        },
    );
    common::close_journal(journal, code)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_parse_and_reject() {
        assert_eq!(
            parse_range("--x", "1:2:3", 0.0, 5.0, "s").unwrap(),
            vec![1.0, 1.5, 2.0]
        );
        assert_eq!(
            parse_range("--x", "1:1:1", 0.0, 5.0, "s").unwrap(),
            vec![1.0]
        );
        for bad in [
            "1:2", "a:2:3", "1:2:0", "2:1:3", "1:9:3", "1:1:2", "1:2:x", "nan:2:2",
        ] {
            let e = parse_range("--x", bad, 0.0, 5.0, "s").unwrap_err();
            assert_eq!(e.key, "--x");
            assert!(e.message.contains("[0, 5] s"), "{}", e.message);
        }
    }

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
