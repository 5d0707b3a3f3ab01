//! The optimisation's tidy tables (CSV, unit-suffixed columns) and JSON summaries:
//! evaluations, history, NSGA-II's front, the best point explained, the box, summary.json.

use super::*;

pub(super) use crate::analyses::cells::num;

/// The decision variables as unit-suffixed CSV columns (the order of `VARIABLES`).
pub(super) const VARIABLE_COLUMNS: [&str; 4] = [
    "belt_speed_m_s",
    "cycle_time_s",
    "start_position_m",
    "light_barrier_m",
];

pub(super) fn opt_json(v: Option<usize>) -> Value {
    v.map_or(Value::Null, |i| json!(i))
}

pub(super) fn finite(v: f64) -> Value {
    if v.is_finite() {
        json!(v)
    } else {
        Value::Null
    }
}

/// evaluations.csv: every candidate with its variables, capacity, (NSGA-II: overload ratio
/// and divert reserve), each constraint by name, the violation and feasibility.
pub fn evaluations_csv(problem: &SettingsProblem, log: &[Record]) -> Result<Vec<u8>, csv::Error> {
    let trade_off = problem.objectives() == Objectives::TradeOff;
    let rows: Vec<Vec<String>> = log.iter().map(|r| evaluation_row(trade_off, r)).collect();
    let header = evaluation_header(problem);
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    csv_bytes(&header, &rows)
}

/// The columns of evaluations.csv (also the header of a live evaluation stream).
pub fn evaluation_header(problem: &SettingsProblem) -> Vec<String> {
    let trade_off = problem.objectives() == Objectives::TradeOff;
    let names = problem.constraint_names();
    let mut header: Vec<String> = ["index", "iteration"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    header.extend(VARIABLE_COLUMNS.iter().map(|s| s.to_string()));
    header.push("capacity_per_h".into());
    if trade_off {
        header.push("overload_ratio".into());
        header.push("divert_overshoot_m".into());
    }
    header.extend(names.iter().map(|n| format!("g:{n}")));
    header.push("violation".into());
    header.push("feasible".into());
    header
}

/// One row of evaluations.csv; `trade_off`: the problem is NSGA-II's
/// ([`Objectives::TradeOff`]), whose rows carry the overload ratio and divert reserve.
pub fn evaluation_row(trade_off: bool, r: &Record) -> Vec<String> {
    let mut row = vec![r.index.to_string(), r.iteration.to_string()];
    row.extend(r.x.iter().map(|&v| num(v)));
    row.push(num(capacity_of(&r.x)));
    if trade_off {
        row.push(num(r
            .evaluation
            .objectives
            .get(1)
            .copied()
            .unwrap_or(f64::NAN)));
        row.push(num(-r
            .evaluation
            .objectives
            .get(2)
            .copied()
            .unwrap_or(f64::NAN)));
    }
    row.extend(r.evaluation.constraints.iter().map(|&g| num(g)));
    row.push(num(r.evaluation.violation()));
    row.push(r.evaluation.feasible().to_string());
    row
}

/// history.csv: one row per generation / iteration with the best point so far.
pub fn history_csv(history: &[IterationSummary]) -> Result<Vec<u8>, csv::Error> {
    history_csv_of(history, "best_capacity_per_h", &|h| capacity_of(&h.best_x))
}

/// [`history_csv`] with the best point's figure `best` in the column `best_column` (the
/// line's throughput, for its objective).
pub fn history_csv_of(
    history: &[IterationSummary],
    best_column: &str,
    best: &dyn Fn(&IterationSummary) -> f64,
) -> Result<Vec<u8>, csv::Error> {
    let rows: Vec<Vec<String>> = history
        .iter()
        .map(|h| {
            let mut row = vec![
                h.iteration.to_string(),
                h.evaluations.to_string(),
                num(best(h)),
                (h.best_violation == 0.0).to_string(),
                num(h.best_violation),
            ];
            row.extend(h.best_x.iter().map(|&v| num(v)));
            row.push(h.feasible_in_iteration.to_string());
            row.push(h.evaluations_in_iteration.to_string());
            row.push(num(h.mean_violation));
            row
        })
        .collect();
    csv_bytes(
        &[
            "iteration",
            "evaluations",
            best_column,
            "best_feasible",
            "best_violation",
            "belt_speed_m_s",
            "cycle_time_s",
            "start_position_m",
            "light_barrier_m",
            "feasible_in_iteration",
            "evaluations_in_iteration",
            "mean_violation",
        ],
        &rows,
    )
}

/// front.csv: the NSGA-II front, best capacity first.
pub fn front_csv(front: &[FrontPoint]) -> Result<Vec<u8>, csv::Error> {
    let rows: Vec<Vec<String>> = front
        .iter()
        .map(|f| {
            let mut row = vec![
                num(capacity_of(&f.x)),
                num(f.evaluation.objectives[1]),
                num(-f.evaluation.objectives[2]),
            ];
            row.extend(f.x.iter().map(|&v| num(v)));
            row
        })
        .collect();
    csv_bytes(
        &[
            "capacity_per_h",
            "overload_ratio",
            "divert_overshoot_m",
            "belt_speed_m_s",
            "cycle_time_s",
            "start_position_m",
            "light_barrier_m",
        ],
        &rows,
    )
}

/// The best point of a run as JSON: the point, W, feasibility, each constraint g, the active
/// ones, the worst parcel, the overload ratio S/S_fall and every design case.
pub fn best_json(b: &BestReport) -> Value {
    let mut point = serde_json::Map::new();
    for (name, v) in VARIABLES.iter().zip(&b.x) {
        point.insert(name.to_string(), json!(v));
    }
    json!({
        "point": point,
        "capacity": b.capacity,
        "feasible": b.feasible,
        "violation": finite(b.violation),
        "constraints": b.constraints.iter().map(|(n, g)| json!({"name": n, "g": g})).collect::<Vec<_>>(),
        "active": b.active,
        "active_tolerance": ACTIVE_TOLERANCE,
        "worst_parcel": b.worst_parcel.as_ref().map(|(n, g)| json!({"name": n, "g": g})),
        "overload_ratio": finite(b.design.overload_ratio),
        "paper_overload_ratio": b.design.overload.as_ref().ok().map(|o| o.ratio),
        "drive_torque": b.design.drive_torque,
        "cases": b.design.cases.iter().map(|c| json!({
            "name": c.name,
            "diverted": c.outcome == Outcome::Diverted,
            "outcome": format!("{:?}", c.outcome),
            "max_lateral": c.max_lateral,
            "margin": c.margin,
            "overshoot": c.overshoot,
            "drive_torque": c.drive_torque,
        })).collect::<Vec<_>>(),
    })
}

/// The search box as JSON: {variable: [lower, upper]}.
pub fn bounds_json(b: &Bounds) -> Value {
    let mut m = serde_json::Map::new();
    for (i, name) in VARIABLES.iter().enumerate() {
        m.insert(name.to_string(), json!([b.lower[i], b.upper[i]]));
    }
    Value::Object(m)
}

/// summary.json of one run (the CLI's `--json` too): the method and its settings, the box,
/// the best point explained, the counts, NSGA-II's front, the worst-case definition and the
/// margins of `design` (the scenario's design set, as given), and the rounds of a robust
/// run (`problem` is then its last round's).
/// The best point's variables on a bound of the box (within 1e-3 of their range): (index,
/// upper?). The optimum may lie past the box there.
pub fn on_bounds(problem: &SettingsProblem, best: &BestReport) -> Vec<(usize, bool)> {
    problem.bounds().on_bounds(&best.x, 1e-3)
}

pub fn report_json(
    problem: &SettingsProblem,
    run: &RunOutcome,
    best: &BestReport,
    design: &DesignSet,
    robust: Option<&RobustRun>,
) -> Value {
    let r = &run.result;
    let mut report = json!({
        "method": run.method.name(),
        "settings": format!("{:?}", run.settings),
        "bounds": bounds_json(problem.bounds()),
        "constraint_names": problem.constraint_names(),
        "best": best_json(best),
        "on_bounds": on_bounds(problem, best).iter().map(|&(i, upper)| json!({
            "variable": divertsim_core::analysis::design::settings_problem::VARIABLES[i],
            "bound": if upper { "upper" } else { "lower" },
            "value": best.x[i],
        })).collect::<Vec<_>>(),
        "evaluations": r.evaluations,
        "first_feasible": opt_json(r.first_feasible),
        "feasible_count": r.feasible_count,
        "iterations": r.history.len(),
        "front": run.front.as_ref().map(|f| f.iter().map(|p| json!({
            "capacity": capacity_of(&p.x),
            "overload_ratio": p.evaluation.objectives[1],
            "divert_overshoot": -p.evaluation.objectives[2],
            "x": p.x,
        })).collect::<Vec<_>>()),
    });
    report["worst"] = json!(design.worst.label());
    report["margins"] = json!({
        "overload": design.margins.overload,
        "divert": design.margins.divert,
        "drive_torque": design.margins.drive_torque,
    });
    if let Some(rr) = robust {
        report["robust"] = robust_json(problem, rr);
    }
    report
}
