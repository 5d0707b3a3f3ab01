//! `divertsim overload`: the worst-case parcel's impulse against belt speed for the
//! scenario's cycle time, with free-fall references (paper Fig. 16), computed by
//! `divertsim_core::analysis::overload` for the `[design.overload]` parcel; with `--search`
//! also the searched worst case at each speed (`divertsim_core::analysis::worst_case`: any
//! parcel of the `[design.search]` class, pose, arrival and start position); a table,
//! overload.csv, overload.svg, or JSON.

use std::path::Path;

use divertsim_core::analysis::overload::{overload_curve, OverloadPoint};
use divertsim_core::analysis::worst_case::{searched_overload_curve, SearchedOverload};
use divertsim_core::model::impact::free_fall_impulse;
use serde_json::{json, Value};

use super::capacity::{parse_range, parse_start_range};
use super::common::{self, OutputArgs, ScenarioArgs};
use super::worst_case::{pose_json, pose_text_no_phase, SearchArgs};
use divertsim_api::config::{Loaded, Problem};
use divertsim_figures::charts::{line_chart, Chart, HLine, Series, Style};
use divertsim_figures::plot::PlotError;

/// Worst-case impulse against belt speed, with free-fall references.
#[derive(Debug, Clone, clap::Args)]
pub struct OverloadArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub output: OutputArgs,
    /// Belt speeds v [m/s]: A,B,C, LO:HI/COUNT or LO:HI:STEP.
    #[arg(long, value_name = "LO:HI/COUNT", default_value = "0.5:2.5/41")]
    pub speeds: String,
    /// Free-fall reference heights H₀ [m], comma-separated.
    #[arg(long, value_name = "H,H,...", default_value = "0.2,0.3")]
    pub drop_heights: String,
    /// Also search the true worst case at each speed: any parcel of [design.search], in any
    /// pose and arrival, at any start position of --start-range (simulated).
    #[arg(long)]
    pub search: bool,
    /// Start positions R_s the search covers, MIN:MAX [m] (with --search).
    #[arg(
        long,
        value_name = "MIN:MAX",
        default_value = "0:0.9",
        allow_hyphen_values = true
    )]
    pub start_range: String,
    #[command(flatten)]
    pub search_args: SearchArgs,
}

/// The curve and its references.
#[derive(Debug, Clone, PartialEq)]
pub struct OverloadReport {
    /// t_c [s]
    pub cycle_time: f64,
    /// m of the worst-case parcel [kg]
    pub mass: f64,
    /// H₀ values [m]
    pub drop_heights: Vec<f64>,
    /// S_fall for each H₀ [N·s]
    pub fall_impulses: Vec<f64>,
    /// One point per belt speed.
    pub points: Vec<OverloadPoint>,
    /// With `--search`: the searched worst case per belt speed.
    pub searched: Option<Vec<SearchedOverload>>,
    /// S_fall(H₀) of the `[design.overload]` parcel at the scenario's H₀ [N·s]
    pub fall_impulse: f64,
}

impl OverloadReport {
    /// Largest S over the speeds [N·s].
    pub fn max_impulse(&self) -> f64 {
        self.points
            .iter()
            .map(|p| p.worst.impulse)
            .fold(0.0, f64::max)
    }

    /// For each H₀: whether S < S_fall(H₀) at every speed.
    pub fn below(&self) -> Vec<bool> {
        self.fall_impulses
            .iter()
            .map(|&f| self.points.iter().all(|p| p.worst.impulse < f))
            .collect()
    }
}

/// Parse `--drop-heights`: 1 to 10 values in (0, 10] m.
pub fn parse_heights(text: &str) -> Result<Vec<f64>, Problem> {
    let bad = |why: String| Problem {
        key: "--drop-heights".into(),
        message: format!("'{text}': {why}; allowed: 1 to 10 comma-separated heights in (0, 10] m"),
    };
    let v: Vec<f64> = text
        .split(',')
        .map(|s| {
            s.trim()
                .parse::<f64>()
                .map_err(|_| bad(format!("'{}' is not a number", s.trim())))
        })
        .collect::<Result<_, _>>()?;
    if v.is_empty() || v.len() > 10 {
        return Err(bad(format!("{} values", v.len())));
    }
    if let Some(h) = v
        .iter()
        .find(|h| !(h.is_finite() && **h > 0.0 && **h <= 10.0))
    {
        return Err(bad(format!("{h} out of range")));
    }
    Ok(v)
}

/// How `--search` runs: the R_s range and the search settings.
pub type SearchPlan = (
    (f64, f64),
    divertsim_core::analysis::worst_case::SearchSettings,
);

/// The curve for a loaded scenario: its cycle time, drive, arm length, materials and the
/// `[design.overload]` parcel; with `search`, the searched worst case at each speed.
pub fn compute(
    loaded: &Loaded,
    speeds: &[f64],
    heights: &[f64],
    search: Option<&SearchPlan>,
    progress: &(dyn Fn() + Sync),
) -> Result<OverloadReport, String> {
    let parcel = &loaded.design.overload_parcel;
    let s = &loaded.scenario;
    let points = overload_curve(s, parcel, speeds, heights).map_err(|e| e.to_string())?;
    let searched = match search {
        None => None,
        Some((starts, settings)) => Some(
            searched_overload_curve(
                s,
                &loaded.design.search,
                speeds,
                *starts,
                settings,
                progress,
            )
            .map_err(|e| e.to_string())?,
        ),
    };
    Ok(OverloadReport {
        searched,
        fall_impulse: free_fall_impulse(parcel.mass, s.materials.restitution, s.limits.drop_height),
        cycle_time: s.machine.cycle_time,
        mass: parcel.mass,
        drop_heights: heights.to_vec(),
        fall_impulses: heights
            .iter()
            .map(|&h| free_fall_impulse(parcel.mass, s.materials.restitution, h))
            .collect(),
        points,
    })
}

fn num(v: f64) -> String {
    format!("{v}")
}

/// overload.csv: one row per speed.
pub fn csv(r: &OverloadReport) -> Result<Vec<u8>, csv::Error> {
    let mut header: Vec<String> = [
        "belt_speed_m_s",
        "drop_height_m",
        "overload_ratio",
        "impulse_n_s",
        "normal_impulse_n_s",
        "tangential_impulse_n_s",
        "approach_speed_m_s",
        "arm_angle_deg",
        "arm_rate_rad_s",
        "equivalent_drop_height_m",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    if r.searched.is_some() {
        header.extend(
            [
                "searched_ratio",
                "searched_start_position_m",
                "searched_length_m",
                "searched_width_m",
                "searched_mass_kg",
                "searched_angle_deg",
                "searched_offset_m",
                "searched_outcome",
            ]
            .map(String::from),
        );
    }
    // Tidy: one row per (speed, reference drop height).
    let rows: Vec<Vec<String>> = r
        .points
        .iter()
        .enumerate()
        .flat_map(|(k, p)| {
            r.drop_heights
                .iter()
                .zip(&p.ratios)
                .map(move |(&h, &ratio)| (k, p, h, ratio))
        })
        .map(|(k, p, h, ratio)| {
            let w = &p.worst;
            let mut row = vec![
                num(w.belt_speed),
                num(h),
                num(ratio),
                num(w.impulse),
                num(w.normal_impulse),
                num(w.tangential_impulse),
                num(w.approach_speed),
                num(w.peak.angle.to_degrees()),
                num(w.peak.rate),
                num(w.equivalent_drop_height),
            ];
            if let Some(q) = r.searched.as_ref().and_then(|v| v.get(k)) {
                let pose = &q.worst.pose;
                row.extend([
                    num(q.worst.value),
                    num(q.start_position),
                    num(pose.length),
                    num(pose.width),
                    num(pose.mass),
                    num(pose.angle_deg),
                    num(pose.offset),
                    q.worst.run.outcome.label().to_string(),
                ]);
            }
            row
        })
        .collect();
    let h: Vec<&str> = header.iter().map(String::as_str).collect();
    common::csv_bytes(&h, &rows)
}

/// The result as one JSON object.
pub fn to_json(r: &OverloadReport) -> Value {
    let first = r.points.first().map(|p| p.worst);
    json!({
        "cycle_time": r.cycle_time,
        "mass": r.mass,
        "arm_peak": first.map(|w| json!({
            "time": w.peak.time,
            "angle_deg": w.peak.angle.to_degrees(),
            "rate": w.peak.rate,
            "reach": w.reach,
        })),
        "references": r.drop_heights.iter().zip(&r.fall_impulses).zip(r.below()).map(|((h, f), b)| json!({
            "drop_height": h,
            "fall_impulse": f,
            "below_at_every_speed": b,
        })).collect::<Vec<_>>(),
        "max_impulse": r.max_impulse(),
        "points": r.points.iter().enumerate().map(|(k, p)| {
            let w = &p.worst;
            let searched = r.searched.as_ref().and_then(|v| v.get(k)).map(|q| json!({
                "overload_ratio": q.worst.value,
                "paper_overload_ratio": w.ratio,
                "start_position": q.start_position,
                "pose": pose_json(&q.worst.pose),
                "outcome": q.worst.run.outcome.label(),
                "evaluations": q.worst.evaluations,
                "failed_runs": q.worst.failed_runs,
            }));
            json!({
                "searched": searched,
                "belt_speed": w.belt_speed,
                "impulse": w.impulse,
                "normal_impulse": w.normal_impulse,
                "tangential_impulse": w.tangential_impulse,
                "approach_speed": w.approach_speed,
                "equivalent_drop_height": w.equivalent_drop_height,
                "energy_ratio": w.energy_ratio,
                "ratios": p.ratios,
            })
        }).collect::<Vec<_>>(),
    })
}

/// The readable table.
pub fn table(r: &OverloadReport) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "worst-case overload: {} kg parcel struck by the arm tip at the largest arm speed, t_c = {} s",
        r.mass, r.cycle_time
    );
    if let Some(p) = r.points.first() {
        let w = &p.worst;
        let _ = writeln!(
            s,
            "arm: largest α̇ = {:.5} rad/s at t = {:.4} s, α = {:.3}°, reach R_z = {} m",
            w.peak.rate,
            w.peak.time,
            w.peak.angle.to_degrees(),
            w.reach
        );
    }
    for (h, f) in r.drop_heights.iter().zip(&r.fall_impulses) {
        let _ = writeln!(s, "free fall from H₀ = {h} m: S_fall = {f:.3} N·s");
    }
    let _ = write!(
        s,
        "{:>8} {:>10} {:>9} {:>9}",
        "v [m/s]", "S [N·s]", "u_n0", "H_eq [m]"
    );
    for h in &r.drop_heights {
        let _ = write!(s, " {:>9}", format!("S/S({h})"));
    }
    let _ = writeln!(s);
    for p in &r.points {
        let w = &p.worst;
        let _ = write!(
            s,
            "{:>8.3} {:>10.4} {:>9.4} {:>9.4}",
            w.belt_speed, w.impulse, w.approach_speed, w.equivalent_drop_height
        );
        for x in &p.ratios {
            let _ = write!(s, " {x:>9.4}");
        }
        let _ = writeln!(s);
    }
    for ((h, f), b) in r.drop_heights.iter().zip(&r.fall_impulses).zip(r.below()) {
        let _ = writeln!(
            s,
            "largest S = {:.3} N·s is {} the H₀ = {h} m reference ({f:.3} N·s) at every speed",
            r.max_impulse(),
            if b { "below" } else { "NOT below" }
        );
    }
    if let Some(searched) = &r.searched {
        let _ = writeln!(
            s,
            "\nsearched worst case (any parcel of [design.search], any pose, arrival and R_s), S/S_fall at H₀ of the scenario:"
        );
        let _ = writeln!(
            s,
            "{:>8} {:>9} {:>9} {:>8}  worst pose",
            "v [m/s]", "searched", "paper", "R_s [m]"
        );
        for (q, p) in searched.iter().zip(&r.points) {
            let _ = writeln!(
                s,
                "{:>8.3} {:>9.4} {:>9.4} {:>8.3}  {}",
                q.belt_speed,
                q.worst.value,
                p.worst.ratio,
                q.start_position,
                pose_text_no_phase(&q.worst.pose)
            );
        }
        let over = searched.iter().filter(|q| q.worst.value > 1.0).count();
        let _ = writeln!(
            s,
            "the searched worst case exceeds the free fall at {over} of {} speeds (the paper's definition: {})",
            searched.len(),
            r.points.iter().filter(|p| p.worst.ratio > 1.0).count()
        );
    }
    s
}

/// Draw S(v) with the free-fall references to `path` (.svg or .png).
pub fn draw(r: &OverloadReport, path: &Path) -> Result<(), PlotError> {
    let chart = Chart {
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
    };
    line_chart(path, &chart)
}

/// `divertsim overload`.
pub fn run(args: &OverloadArgs) -> i32 {
    let loaded = common::load_scenario(&args.scenario);
    let mut problems = common::out_problems(&args.output);
    let speeds = parse_range("--speeds", &args.speeds, 0.0, 20.0, "m/s")
        .map_err(|p| problems.push(p))
        .ok();
    let heights = parse_heights(&args.drop_heights)
        .map_err(|p| problems.push(p))
        .ok();
    let starts = parse_start_range(&args.start_range)
        .map_err(|p| problems.push(p))
        .ok();
    if args.search {
        problems.extend(args.search_args.problems());
        if let Some(v) = &speeds {
            if v.iter().any(|&v| v <= 0.0) {
                problems.push(Problem {
                    key: "--speeds".into(),
                    message: format!(
                        "'{}': --search needs a moving belt; allowed: speeds > 0 m/s",
                        args.speeds
                    ),
                });
            }
        }
    }
    let loaded = match common::checked(loaded, problems) {
        Ok(l) => l,
        Err(code) => return code,
    };
    let (Some(speeds), Some(heights), Some(starts)) = (speeds, heights, starts) else {
        return 2;
    };
    let plan = args.search.then(|| (starts, args.search_args.settings()));
    let total = plan.as_ref().map_or(0, |p| p.1.evaluations * speeds.len());
    // The closed-form curve runs no simulation; the search runs its evaluations per speed.
    if let Err(code) = common::within_budget(
        "overload",
        total as u64,
        &args.output,
        "use fewer --speeds or a smaller --search-budget",
    ) {
        return code;
    }
    let bar = common::progress_bar(total as u64, "overload", args.output.quiet || total == 0);
    let tick = || bar.inc(1);
    let report = match common::with_threads(args.output.threads, || {
        compute(&loaded, &speeds, &heights, plan.as_ref(), &tick)
    }) {
        Ok(r) => r,
        Err(e) => {
            bar.finish_and_clear();
            eprintln!("error: {e}");
            return 3;
        }
    };
    bar.finish_and_clear();
    common::finish(
        &args.output,
        "overload",
        &loaded,
        || csv(&report),
        |p| draw(&report, p).map_err(|e| e.to_string()),
        || to_json(&report),
        || table(&report),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heights_parse_and_reject() {
        assert_eq!(parse_heights("0.2, 0.3").unwrap(), vec![0.2, 0.3]);
        for bad in ["", "0.2,x", "0", "-1", "11", "nan"] {
            let e = parse_heights(bad).unwrap_err();
            assert_eq!(e.key, "--drop-heights");
            assert!(e.message.contains("(0, 10] m"));
        }
    }
}
