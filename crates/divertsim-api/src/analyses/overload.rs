//! Overload (paper Fig. 16, §4.3): the worst-case parcel's impulse S against belt speed for
//! the scenario's cycle time, with free-fall references S_fall(H₀), by
//! `divertsim_core::analysis::paper::overload` for the `[design.overload]` parcel; optionally the
//! searched worst case at each speed (any parcel of `[design.search]`, pose, arrival and
//! start position; `divertsim_core::analysis::design::worst_case`).

use crate::analyses::capacity;
use crate::analyses::poses::{pose_json, pose_text_no_phase};
use crate::analyses::worst_case::{SearchBudget, WorstChoice};
use crate::config::MachineConfig;
use crate::config::{Loaded, Problem};
use crate::contract::{csv_table, Analysis, Error, Hooks, Interval, ValueList, Work};
use divertsim_core::analysis::design::worst_case::{searched_overload_curve, SearchedOverload};
use divertsim_core::analysis::paper::overload::{overload_curve, OverloadPoint};
use divertsim_core::model::impact::free_fall_impulse;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

/// Problems with the free-fall reference heights H₀ (key `drop_heights`): 1 to 10 values
/// in (0, 10] m.
pub fn check_heights(heights: &[f64]) -> Option<Problem> {
    let bad = |why: String| {
        Some(Problem::new(
            "drop_heights",
            format!("{why}; allowed: 1 to 10 heights in (0, 10] m"),
        ))
    };
    if heights.is_empty() || heights.len() > 10 {
        return bad(format!("{} values", heights.len()));
    }
    match heights
        .iter()
        .find(|h| !(h.is_finite() && **h > 0.0 && **h <= 10.0))
    {
        Some(h) => bad(format!("{h} out of range")),
        None => None,
    }
}

/// The curve and its references.
#[derive(Debug, Clone, PartialEq)]
pub struct OverloadReport {
    /// t_c \[s]
    pub cycle_time: f64,
    /// m of the worst-case parcel \[kg]
    pub mass: f64,
    /// H₀ values \[m]
    pub drop_heights: Vec<f64>,
    /// S_fall for each H₀ [N·s]
    pub fall_impulses: Vec<f64>,
    /// One point per belt speed.
    pub points: Vec<OverloadPoint>,
    /// With `worst` search: the searched worst case per belt speed.
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

/// How the search (`worst` search) runs: the R_s range and the search settings.
pub type SearchPlan = (
    (f64, f64),
    divertsim_core::analysis::design::worst_case::SearchSettings,
);

/// The curve for a loaded scenario: its cycle time, drive, arm length, materials and the
/// `[design.overload]` parcel; with `search`, the searched worst case at each speed.
/// Simulations of the run: the closed-form curve runs none; a search runs its
/// evaluations per speed.
pub fn estimated_simulations(speeds: usize, search: Option<&SearchPlan>) -> u64 {
    search.map_or(0, |p| p.1.evaluations * speeds) as u64
}

fn compute(
    loaded: &Loaded,
    speeds: &[f64],
    heights: &[f64],
    search: Option<&SearchPlan>,
    progress: &(dyn Fn() + Sync),
) -> Result<OverloadReport, Error> {
    let parcel = &loaded.design.overload_parcel;
    let s = &loaded.scenario;
    let points = overload_curve(s, parcel, speeds, heights).map_err(Error::failed)?;
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
            .map_err(Error::failed)?,
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

use super::cells::num;

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
    crate::output::csv_bytes(&h, &rows)
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

/// Options of the overload analysis (`divertsim overload`, Python `analysis("overload")`).
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are help text: [m] is a unit
#[derive(Debug, Clone, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default)]
pub struct OverloadOptions {
    /// Belt speeds v [m/s], each in [0, 20]: A,B,C, LO:HI/COUNT or LO:HI:STEP.
    pub speeds: ValueList,
    /// Free-fall reference heights H₀ [m], 1 to 10 values in (0, 10].
    pub drop_heights: Vec<f64>,
    /// The worst case: "search" (the default, as for capacity, optimize and check: besides
    /// the paper's closed-form tip strike, search the true worst case at each speed: any
    /// parcel of [design.search], in any pose and arrival, at any start position of the
    /// start range, simulated) or "paper" (the paper's tip strike alone, Fig. 16, closed
    /// form).
    pub worst: WorstChoice,
    /// Start positions R_s the search covers [m], MIN:MAX within [−5, 5] (with `worst`
    /// search).
    pub start_range: Interval,
    #[serde(flatten)]
    #[allow(missing_docs)]
    pub budget: SearchBudget,
}

impl Default for OverloadOptions {
    fn default() -> OverloadOptions {
        OverloadOptions {
            speeds: ValueList::spec("0.5:2.5/41"),
            drop_heights: vec![0.2, 0.3],
            worst: WorstChoice::Search,
            start_range: Interval(0.0, 0.9),
            budget: SearchBudget::default(),
        }
    }
}

/// The overload analysis on the analysis contract.
pub struct Overload;

/// Checked options of [`Overload`].
#[derive(Debug, Clone)]
pub struct OverloadInputs {
    /// Belt speeds [m/s].
    pub speeds: Vec<f64>,
    /// Free-fall reference heights \[m].
    pub drop_heights: Vec<f64>,
    /// The searched worst case's R_s range and settings, with the search.
    pub search: Option<SearchPlan>,
}

impl Analysis for Overload {
    const NAME: &'static str = "overload";
    const ABOUT: &'static str =
        "Worst-case impulse against belt speed with free-fall references (paper Fig. 16)";
    type Options = OverloadOptions;
    type Checked = OverloadInputs;
    type Bound = OverloadInputs;
    type Output = OverloadReport;

    fn validate(o: &OverloadOptions) -> Result<OverloadInputs, Vec<Problem>> {
        let mut problems: Vec<Problem> = check_heights(&o.drop_heights).into_iter().collect();
        let speeds = match o.speeds.resolve(
            "speeds",
            MachineConfig::BELT_SPEED.list(capacity::MAX_COUNT),
        ) {
            Ok(v) => {
                problems.extend(capacity::check_list(
                    "speeds",
                    &v,
                    &MachineConfig::BELT_SPEED,
                ));
                v
            }
            Err(p) => {
                problems.push(p);
                Vec::new()
            }
        };
        let mut plan = None;
        if o.worst == WorstChoice::Search {
            if speeds.iter().any(|&v| v <= 0.0) {
                problems.push(Problem::new(
                    "speeds",
                    "the worst-case search needs a moving belt; allowed: speeds > 0 m/s (or `worst` paper)",
                ));
            }
            problems.extend(capacity::check_start_range(
                o.start_range.0,
                o.start_range.1,
            ));
            match o.budget.checked() {
                Ok(s) => plan = Some(((o.start_range.0, o.start_range.1), s)),
                Err(p) => problems.extend(p),
            }
        }
        match problems.is_empty() {
            true => Ok(OverloadInputs {
                speeds,
                drop_heights: o.drop_heights.clone(),
                search: plan,
            }),
            false => Err(problems),
        }
    }

    /// Nothing derives from the scenario before the run.
    fn bind(c: OverloadInputs, _: &Loaded) -> Result<OverloadInputs, Vec<Problem>> {
        Ok(c)
    }

    fn work(c: &OverloadInputs, _: &Loaded) -> Work {
        let simulations = estimated_simulations(c.speeds.len(), c.search.as_ref());
        Work {
            at_most: Some(simulations),
            at_least: simulations,
            units: simulations,
            unit: "runs",
            smaller: "use fewer `speeds` or a smaller `search_budget`",
        }
    }

    fn run(s: &Loaded, c: &OverloadInputs, hooks: &Hooks) -> Result<OverloadReport, Error> {
        compute(
            s,
            &c.speeds,
            &c.drop_heights,
            c.search.as_ref(),
            hooks.progress,
        )
    }

    fn summary(r: &OverloadReport, _: &OverloadInputs, _: &Loaded) -> Value {
        to_json(r)
    }

    fn tables(r: &OverloadReport) -> Result<Vec<(String, Vec<u8>)>, Error> {
        Ok(vec![csv_table("overload.csv", csv(r))?])
    }

    fn text(r: &OverloadReport, _: &OverloadInputs, _: &Loaded) -> String {
        text(r)
    }
}

/// The readable table.
pub fn text(r: &OverloadReport) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "the paper's worst case: the {} kg [design.overload] parcel struck by the arm tip at the largest arm speed, t_c = {} s",
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
            "the paper's case: largest S = {:.3} N·s is {} the H₀ = {h} m reference ({f:.3} N·s) at every speed",
            r.max_impulse(),
            if b { "below" } else { "NOT below" }
        );
    }
    if let Some(searched) = &r.searched {
        let _ = writeln!(
            s,
            "\nthe searched worst case (any parcel of [design.search], any pose, arrival and R_s; ordinary parcels can beat the paper's case), S/S_fall at H₀ of the scenario:"
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
