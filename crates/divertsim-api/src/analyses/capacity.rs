//! Sorting capacity (paper §4.2, Fig. 9): over a grid of cycle times t_c and light-barrier
//! positions S_d, the largest capacity W [parcels/h] at a belt speed and start position R_s
//! that divert every design parcel within the overload limit, by
//! `divertsim_core::analysis::design::capacity`; optionally against the searched worst case, by
//! rounds of map and search (`divertsim_core::analysis::design::robust`).

use crate::analyses::poses::{pose_json, pose_text};
use crate::analyses::worst_case::RobustOptions;
use crate::config::bounds::{
    Bound, SEARCHED_BELT_SPEED, SEARCHED_CYCLE_TIME, SEARCHED_LIGHT_BARRIER,
    SEARCHED_START_POSITION,
};
use crate::config::{Loaded, Problem};
use crate::contract::{csv_table, Analysis, Error, Hooks, Interval, ValueList, Work};
use divertsim_core::analysis::design::capacity::{
    capacity_map_kept, CapacityCell, CapacityMap, CapacityOptions,
};
use divertsim_core::analysis::design::design_set::{Margins, WorstDefinition};
use divertsim_core::analysis::design::robust::{robust_capacity_map, RobustMap, RobustSettings};
use divertsim_core::analysis::design::worst_case::WorstObjective;
use divertsim_core::run::memo::Memo;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

/// Largest number of values in a list of the grid.
pub const MAX_COUNT: usize = 1000;

/// A list of 1 to [`MAX_COUNT`] values, each in the closed range `b`; a problem names `key`.
pub fn check_list(key: &str, values: &[f64], b: &Bound) -> Option<Problem> {
    let (lo, hi, unit) = (b.lo, b.hi, b.unit);
    if values.is_empty() || values.len() > MAX_COUNT {
        return Some(Problem::new(
            key,
            format!("{} values; allowed: 1 to {MAX_COUNT}", values.len()),
        ));
    }
    values.iter().find(|v| !(lo..=hi).contains(*v)).map(|v| {
        Problem::new(
            key,
            format!("{v} is out of range; allowed: [{lo}, {hi}] {unit}"),
        )
    })
}

/// The R_s range `a:b` of the searches: −5 ≤ a ≤ b ≤ 5 m (key `start_range`).
pub fn check_start_range(a: f64, b: f64) -> Option<Problem> {
    let (lo, hi, unit) = SEARCHED_START_POSITION.ends();
    (!(a.is_finite() && b.is_finite() && (lo..=hi).contains(&a) && (a..=hi).contains(&b))).then(
        || {
            Problem::new(
                "start_range",
                format!("{a}:{b}: allowed: MIN:MAX with {lo} ≤ MIN ≤ MAX ≤ {hi} {unit}"),
            )
        },
    )
}

/// The summary of a map ([`to_json`]) with the worst case and margins it held against and,
/// for a map against the searched worst case, its rounds.
pub fn summary_of(loaded: &Loaded, map: &CapacityMap, robust: Option<&RobustMap>) -> Value {
    let mut j = to_json(loaded, map);
    j["worst"] = json!(loaded.design.worst.label());
    j["margins"] = json!({
        "overload": loaded.design.margins.overload,
        "divert": loaded.design.margins.divert,
        "drive_torque": loaded.design.margins.drive_torque,
    });
    j["robust"] = robust.map_or(Value::Null, robust_json);
    if let Some(r) = robust {
        // The run's own count: every round's map and searches, not the last map's.
        j["last_map_simulations"] = j["simulations"].clone();
        j["simulations"] = json!(total_simulations(r));
    }
    j
}

/// Every simulation of a robust map's rounds (maps and searches).
pub fn total_simulations(r: &RobustMap) -> usize {
    r.rounds.iter().map(|x| x.simulations).sum()
}

/// Every problem with the grid's options (keys are the option names): t_c in [0.2, 10] s,
/// S_d in [−5, 5] m, v in [0.05, 10] m/s, 1 to [`MAX_COUNT`] values each; the R_s range
/// within [−5, 5] m, its step in [0.001, 5] m and the tolerance in [1e-5, 1] m.
pub fn check(o: &CapacityOptions) -> Vec<Problem> {
    let mut problems = Vec::new();
    problems.extend(check_list(
        "cycle_times",
        &o.cycle_times,
        &SEARCHED_CYCLE_TIME,
    ));
    problems.extend(check_list(
        "light_barriers",
        &o.light_barriers,
        &SEARCHED_LIGHT_BARRIER,
    ));
    problems.extend(check_list("speeds", &o.belt_speeds, &SEARCHED_BELT_SPEED));
    problems.extend(check_start_range(o.start_min, o.start_max));
    if !(o.start_step.is_finite() && o.start_step >= 1e-3 && o.start_step <= 5.0) {
        problems.push(Problem::new(
            "start_step",
            format!("{} is out of range; allowed: [0.001, 5] m", o.start_step),
        ));
    } else if o.start_max >= o.start_min {
        // The core's limit on the R_s grid, checked here so that it is a usage error (exit
        // 2 naming the option), not a failed run.
        use divertsim_core::analysis::design::capacity::MAX_START_POINTS;
        let span = o.start_max - o.start_min;
        if span / o.start_step > (MAX_START_POINTS - 1) as f64 {
            problems.push(Problem::new(
                "start_step",
                format!(
                    "{} m over the start range [{}, {}] m gives {} R_s grid points; allowed: at most {MAX_START_POINTS} (a step of at least {} m, or a shorter range)",
                    o.start_step,
                    o.start_min,
                    o.start_max,
                    (span / o.start_step).floor() as u64 + 1,
                    span / (MAX_START_POINTS - 1) as f64
                ),
            ));
        }
    }
    if !(o.start_tolerance.is_finite() && o.start_tolerance >= 1e-5 && o.start_tolerance <= 1.0) {
        problems.push(Problem::new(
            "start_tolerance",
            format!(
                "{} is out of range; allowed: [0.00001, 1] m",
                o.start_tolerance
            ),
        ));
    }
    problems
}

/// The most simulations of a map (no robust rounds) on `loaded`'s design set. A robust
/// map's are not bounded before it runs: its searches run at the feasible cells its rounds
/// find, its rounds go on while they find new poses, and each announces its work as it
/// starts.
pub fn estimated_simulations(
    loaded: &Loaded,
    options: &CapacityOptions,
    robust: Option<&RobustSettings>,
) -> Option<u64> {
    robust.is_none().then(|| {
        divertsim_core::analysis::design::capacity::estimated_simulations(options, &loaded.design)
            as u64
    })
}

/// The simulations the map (a robust map's first round) runs whatever its verdicts.
pub fn least_simulations(loaded: &Loaded, options: &CapacityOptions) -> u64 {
    divertsim_core::analysis::design::capacity::least_simulations(
        &loaded.scenario,
        options,
        &loaded.design,
    ) as u64
}

/// The capacity map for a loaded scenario (its machine, materials, limits and `[design]`,
/// whose worst definition and margins apply).
/// Finished pieces are kept in and recalled from `memo` (a checkpoint).
fn compute(
    loaded: &Loaded,
    options: &CapacityOptions,
    progress: &(dyn Fn() + Sync),
    memo: &dyn Memo,
) -> Result<CapacityMap, Error> {
    capacity_map_kept(&loaded.scenario, &loaded.design, options, progress, memo)
        .map_err(Error::failed)
}

/// The map against the searched worst case (rounds of map and search).
fn compute_robust(
    loaded: &Loaded,
    options: &CapacityOptions,
    robust: &RobustSettings,
    progress: &(dyn Fn() + Sync),
    announce: &(dyn Fn(u64) + Sync),
    memo: &dyn Memo,
) -> Result<RobustMap, Error> {
    robust_capacity_map(
        &loaded.scenario,
        &loaded.design,
        options,
        robust,
        progress,
        announce,
        memo,
    )
    .map_err(Error::failed)
}

/// The rounds of a robust map as JSON.
pub fn robust_json(r: &RobustMap) -> Value {
    // Every search of the last round: the whole ones, and those stopped at a violation (a
    // map that did not converge: its largest ratio is then a violation found, not
    // necessarily the worst).
    let searches = r
        .verifications
        .iter()
        .flat_map(|v| [Some(&v.impulse), Some(&v.reserve), v.torque.as_ref()])
        .flatten()
        .chain(r.violations.iter().flat_map(|(_, s)| s));
    let of = |o: WorstObjective| searches.clone().filter(move |w| w.objective == o);
    let ratio = of(WorstObjective::Impulse)
        .map(|w| w.value)
        .fold(f64::NEG_INFINITY, f64::max);
    let reserve = of(WorstObjective::Reserve)
        .map(|w| w.value)
        .fold(f64::INFINITY, f64::min);
    let torque = of(WorstObjective::Torque)
        .map(|w| w.value)
        .fold(f64::NEG_INFINITY, f64::max);
    json!({
        "converged": r.converged,
        "rounds": r.rounds.iter().map(|m| json!({
            "poses": m.poses,
            "verified_settings": m.verified,
            "searched_settings": m.searched,
            "added_poses": m.added,
            "simulations": m.simulations,
        })).collect::<Vec<_>>(),
        "poses": r.set.worst_poses.iter().map(pose_json).collect::<Vec<_>>(),
        "largest_searched_overload_ratio": if ratio.is_finite() { Some(ratio) } else { None },
        "smallest_searched_reserve": if reserve.is_finite() { Some(reserve) } else { None },
        "largest_searched_drive_torque": torque.is_finite().then_some(torque),
    })
}

use super::cells::{num, opt};

/// capacity.csv: one row per cell, t_c-major.
pub fn csv(map: &CapacityMap) -> Result<Vec<u8>, csv::Error> {
    let rows: Vec<Vec<String>> = map
        .cells
        .iter()
        .map(|c| {
            vec![
                num(c.cycle_time),
                num(c.light_barrier),
                num(c.capacity),
                opt(c.belt_speed),
                opt(c.start_position),
                c.feasible.to_string(),
                num(c.worst_margin),
                opt(c.overload_ratio),
            ]
        })
        .collect();
    crate::output::csv_bytes(
        &[
            "cycle_time_s",
            "light_barrier_m",
            "capacity_per_h",
            "belt_speed_m_s",
            "start_position_m",
            "feasible",
            "worst_margin",
            "overload_ratio",
        ],
        &rows,
    )
}

pub fn cell_json(c: &CapacityCell) -> Value {
    json!({
        "cycle_time": c.cycle_time,
        "light_barrier": c.light_barrier,
        "capacity": c.capacity,
        "belt_speed": c.belt_speed,
        "start_position": c.start_position,
        "feasible": c.feasible,
        "worst_margin": c.worst_margin,
        "overload_ratio": c.overload_ratio,
    })
}

/// Facts for finding (g): the best cell, the range of W, the share of feasible cells, and
/// W along the edges of the map.
pub fn summary(map: &CapacityMap) -> Value {
    let feasible: Vec<&CapacityCell> = map.cells.iter().filter(|c| c.feasible).collect();
    let w_min = feasible
        .iter()
        .map(|c| c.capacity)
        .fold(f64::INFINITY, f64::min);
    let w_max = feasible.iter().map(|c| c.capacity).fold(0.0, f64::max);
    let best = map.best();
    // Cells within 1 % of the best W: how narrow the best region is.
    let near_best = best.map_or(0, |b| {
        feasible
            .iter()
            .filter(|c| c.capacity >= 0.99 * b.capacity)
            .count()
    });
    json!({
        "cells": map.cells.len(),
        "feasible_cells": feasible.len(),
        "capacity_min": if feasible.is_empty() { Value::Null } else { json!(w_min) },
        "capacity_max": if feasible.is_empty() { Value::Null } else { json!(w_max) },
        "best": best.map(cell_json),
        "best_on_edges": map.best_on_edges(),
        "cells_within_1pct_of_best": near_best,
    })
}

/// What a map's cells hold against, in words (its texts and its picture's title).
pub fn against(worst: WorstDefinition) -> &'static str {
    match worst {
        WorstDefinition::Search => "the searched worst case",
        WorstDefinition::Paper => "the paper's worst case (its tip strike, paper Fig. 9)",
    }
}

/// The note on a best cell at the grid's bounds ([`CapacityMap::best_on_edges`]), or None.
pub fn edge_note(map: &CapacityMap) -> Option<String> {
    let edges = map.best_on_edges();
    (!edges.is_empty()).then(|| {
        let each: Vec<String> = edges
            .iter()
            .map(|e| format!("the {} of `{}` ({})", e.end, e.option, e.value))
            .collect();
        format!(
            "the best cell is on the grid's edge, at {}: W may grow past it; widen the grid there to look",
            each.join(", ")
        )
    })
}

/// The whole result as one JSON object.
pub fn to_json(loaded: &Loaded, map: &CapacityMap) -> Value {
    let o = &map.options;
    json!({
        "options": {
            "cycle_times": o.cycle_times,
            "light_barriers": o.light_barriers,
            "belt_speeds": o.belt_speeds,
            "start_min": o.start_min,
            "start_max": o.start_max,
            "start_step": o.start_step,
            "start_tolerance": o.start_tolerance,
        },
        "design": loaded.design.cases.iter().map(|c| json!({
            "name": c.name,
            "length": c.parcel.length,
            "width": c.parcel.width,
            "mass": c.parcel.mass,
            "offset": c.parcel.offset,
            "angle_deg": c.parcel.angle.to_degrees(),
        })).collect::<Vec<_>>(),
        "overload_parcel": {
            "length": loaded.design.overload_parcel.length,
            "width": loaded.design.overload_parcel.width,
            "mass": loaded.design.overload_parcel.mass,
        },
        "simulations": map.simulations,
        "summary": summary(map),
        "settings": map.settings.iter().map(|s| json!({
            "cycle_time": s.cycle_time,
            "belt_speed": s.belt_speed,
            "overload_ratio": s.overload.as_ref().ok().map(|w| w.ratio),
            "overload_error": s.overload.as_ref().err(),
            "feasible_starts": s.feasible_starts.iter().map(|&(a, b)| [a, b]).collect::<Vec<_>>(),
            "simulations": s.simulations,
        })).collect::<Vec<_>>(),
        "cells": map.cells.iter().map(cell_json).collect::<Vec<_>>(),
    })
}

/// Options of the capacity map (`divertsim capacity`, Python `analysis("capacity")`).
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are help text: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default)]
pub struct CapacityMapOptions {
    /// Cycle times t_c [s] (the map's x axis), each in [0.2, 10]: LO:HI/COUNT, LO:HI:STEP or
    /// A,B,C.
    pub cycle_times: ValueList,
    /// Light-barrier positions S_d [m] (the map's y axis), each in [−5, 5]: LO:HI/COUNT,
    /// LO:HI:STEP or A,B,C.
    pub light_barriers: ValueList,
    /// Belt speeds v searched at every cell [m/s], each in [0.05, 10]: LO:HI/COUNT,
    /// LO:HI:STEP or A,B,C.
    pub speeds: ValueList,
    /// Start positions R_s searched, as MIN:MAX [m] within [−5, 5].
    pub start_range: Interval,
    /// Step of the R_s grid [m], in [0.001, 5].
    pub start_step: f64,
    /// Bisection tolerance on the boundaries of the feasible R_s intervals [m], in
    /// [0.00001, 1].
    pub start_tolerance: f64,
    #[serde(flatten)]
    #[allow(missing_docs)]
    pub robust: RobustOptions,
}

impl Default for CapacityMapOptions {
    fn default() -> CapacityMapOptions {
        let o = CapacityOptions::default();
        CapacityMapOptions {
            cycle_times: ValueList::spec("1.0:1.5/20"),
            light_barriers: ValueList::spec("0:0.9/20"),
            speeds: ValueList::spec("1.0:2.3/14"),
            start_range: Interval(o.start_min, o.start_max),
            start_step: o.start_step,
            start_tolerance: o.start_tolerance,
            robust: RobustOptions::default(),
        }
    }
}

/// Checked options of [`Capacity`]: the grid, the worst case, the margins and, against the
/// searched worst case, the robust settings.
#[derive(Debug, Clone)]
pub struct CapacityInputs {
    /// The grid and the R_s search.
    pub grid: CapacityOptions,
    /// The worst case the constraints hold against.
    pub worst: WorstDefinition,
    /// The safety margins.
    pub margins: Margins,
    /// Rounds of map and search (with the searched worst case).
    pub robust: Option<RobustSettings>,
}

impl CapacityInputs {
    /// The scenario with this worst case and these margins in its design.
    pub fn designed(&self, loaded: &Loaded) -> Loaded {
        let mut l = loaded.clone();
        l.design.worst = self.worst;
        l.design.margins = self.margins;
        l
    }
}

/// A capacity map and, against the searched worst case, its rounds.
#[derive(Debug, Clone)]
pub struct CapacityResult {
    /// The map (a robust run's last round's).
    pub map: CapacityMap,
    /// The rounds of map and search.
    pub robust: Option<RobustMap>,
}

impl CapacityResult {
    /// The worst case its cells hold against: the searched one when it has rounds.
    pub fn worst(&self) -> WorstDefinition {
        match self.robust {
            Some(_) => WorstDefinition::Search,
            None => WorstDefinition::Paper,
        }
    }
}

/// The capacity map on the analysis contract.
pub struct Capacity;

impl Analysis for Capacity {
    const NAME: &'static str = "capacity";
    const ABOUT: &'static str =
        "Capacity map W(t_c, S_d) by the paper's §4.2 algorithm (paper Fig. 9)";
    type Options = CapacityMapOptions;
    type Checked = CapacityInputs;
    type Bound = CapacityInputs;
    type Output = CapacityResult;

    fn validate(o: &CapacityMapOptions) -> Result<CapacityInputs, Vec<Problem>> {
        let mut problems = Vec::new();
        let mut list = |key: &str, v: &ValueList, b: &Bound| match v.resolve(key, b.list(MAX_COUNT))
        {
            Ok(v) => v,
            Err(p) => {
                problems.push(p);
                Vec::new()
            }
        };
        let grid = CapacityOptions {
            cycle_times: list("cycle_times", &o.cycle_times, &SEARCHED_CYCLE_TIME),
            light_barriers: list("light_barriers", &o.light_barriers, &SEARCHED_LIGHT_BARRIER),
            belt_speeds: list("speeds", &o.speeds, &SEARCHED_BELT_SPEED),
            start_min: o.start_range.0,
            start_max: o.start_range.1,
            start_step: o.start_step,
            start_tolerance: o.start_tolerance,
        };
        if problems.is_empty() {
            problems = check(&grid);
        }
        match (o.robust.resolve(), problems.is_empty()) {
            (Ok((worst, margins, robust)), true) => Ok(CapacityInputs {
                grid,
                worst,
                margins,
                robust,
            }),
            (r, _) => Err(problems
                .into_iter()
                .chain(r.err().unwrap_or_default())
                .collect()),
        }
    }

    fn bind(c: CapacityInputs, s: &Loaded) -> Result<CapacityInputs, Vec<Problem>> {
        let unarmed = crate::analyses::worst_case::torque_limit_problems(&c.margins, s);
        match unarmed.is_empty() {
            true => Ok(c),
            false => Err(unarmed),
        }
    }

    fn work(c: &CapacityInputs, s: &Loaded) -> Work {
        let designed = c.designed(s);
        Work {
            at_most: estimated_simulations(&designed, &c.grid, c.robust.as_ref()),
            at_least: least_simulations(&designed, &c.grid),
            units: divertsim_core::analysis::design::capacity::pieces(&c.grid) as u64,
            // A robust map's rounds announce their searches (a tick per simulation) and the
            // next round's pieces as they come.
            unit: if c.robust.is_some() {
                "steps"
            } else {
                "pieces"
            },
            smaller:
                "use fewer or coarser `cycle_times`, `light_barriers`, `speeds` or `start_step`",
        }
    }

    fn run(s: &Loaded, c: &CapacityInputs, hooks: &Hooks) -> Result<CapacityResult, Error> {
        let s = c.designed(s);
        match &c.robust {
            None => Ok(CapacityResult {
                map: compute(&s, &c.grid, hooks.progress, hooks.memo)?,
                robust: None,
            }),
            Some(r) => {
                let rm = compute_robust(&s, &c.grid, r, hooks.progress, hooks.more, hooks.memo)?;
                Ok(CapacityResult {
                    map: rm.map.clone(),
                    robust: Some(rm),
                })
            }
        }
    }

    fn summary(r: &CapacityResult, c: &CapacityInputs, s: &Loaded) -> Value {
        summary_of(&c.designed(s), &r.map, r.robust.as_ref())
    }

    fn tables(r: &CapacityResult) -> Result<Vec<(String, Vec<u8>)>, Error> {
        Ok(vec![csv_table("capacity.csv", csv(&r.map))?])
    }

    fn text(r: &CapacityResult, c: &CapacityInputs, s: &Loaded) -> String {
        let mut t = text(&r.map, Self::simulations(r).unwrap_or(0) as usize, c.worst);
        if let Some(limit) = c.margins.drive_torque {
            t += &format!(
                "every run held to a peak drive torque of at most {limit} N·m at the arm (arm inertia {} kg·m²)\n",
                s.scenario.machine.arm_inertia
            );
        }
        if let Some(rm) = &r.robust {
            t += &robust_text(rm);
        }
        t
    }

    fn simulations(r: &CapacityResult) -> Option<u64> {
        // A robust map: every round's map and searches.
        Some(
            r.robust
                .as_ref()
                .map_or(r.map.simulations, total_simulations) as u64,
        )
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
            "  round {}: {} worst poses, {} settings verified ({} searched), {} poses added, {} simulations",
            k + 1,
            m.poses,
            m.verified,
            m.searched,
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
/// setting. `simulations`: the run's whole count (a robust map's every round); `worst`: the
/// worst case its cells hold against.
pub fn text(map: &CapacityMap, simulations: usize, worst: WorstDefinition) -> String {
    use std::fmt::Write;
    let o = &map.options;
    let nsd = o.light_barriers.len();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "capacity W [parcels/h] by the paper's §4.2 algorithm, against {}; x = no feasible (v, R_s)",
        against(worst)
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
        crate::analyses::count_text(simulations as u64)
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
            if let Some(note) = edge_note(map) {
                let _ = writeln!(s, "{note}");
            }
        }
        None => {
            let _ = writeln!(s, "no feasible setting anywhere on the grid");
        }
    }
    s
}
