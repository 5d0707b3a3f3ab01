//! The paper's experiment (§4.3, Figs 10/11): three GA runs on the wide and narrow boxes
//! and three gradient runs from the paper's starts, next to the paper's reported optimum.

use super::tables::{best_json, bounds_json, num, opt_json};
use super::*;

/// One run of the paper's experiment.
#[derive(Debug, Clone)]
pub struct PaperRun {
    /// "GA 1", "gradient 2", ...
    pub label: String,
    /// What distinguishes it: the box and seed, or the start.
    pub description: String,
    pub bounds: Bounds,
    pub outcome: RunOutcome,
    pub best: BestReport,
}

/// The paper's runs in order: (label, description, method, bounds, options).
pub fn paper_plan(o: &RunOptions) -> Vec<(String, String, Method, Bounds, RunOptions)> {
    let mut plan = Vec::new();
    for (k, (b, seed)) in [(PAPER_WIDE, 1u64), (PAPER_NARROW, 2), (PAPER_NARROW, 3)]
        .into_iter()
        .enumerate()
    {
        plan.push((
            format!("GA {}", k + 1),
            format!(
                "v {}-{}, t_c {}-{}, R_s {}-{}, seed {seed}",
                b[0].0, b[0].1, b[1].0, b[1].1, b[2].0, b[2].1
            ),
            Method::Ga,
            paper_box(b),
            RunOptions {
                seed,
                start: None,
                ..o.clone()
            },
        ));
    }
    for (k, s) in PAPER_STARTS.iter().enumerate() {
        plan.push((
            format!("gradient {}", k + 1),
            format!("start ({}, {}, {})", s[0], s[1], s[2]),
            Method::Gradient,
            paper_box(PAPER_WIDE),
            RunOptions {
                start: Some(vec![s[0], s[1], s[2], 0.0]),
                population: None,
                generations: None,
                ..o.clone()
            },
        ));
    }
    plan
}

/// A paper box for (v, t_c, R_s), S_d fixed at 0.
fn paper_box(b: [(f64, f64); 3]) -> Bounds {
    Bounds::new(
        vec![b[0].0, b[1].0, b[2].0, 0.0],
        vec![b[0].1, b[1].1, b[2].1, 0.0],
    )
    .expect("valid constant box")
}

/// Run the paper's experiment on a loaded scenario.
pub fn paper_experiment(
    loaded: &Loaded,
    o: &RunOptions,
    ctx: &RunContext<'_>,
) -> Result<Vec<PaperRun>, OptimizeError> {
    let mut runs = Vec::new();
    for (label, description, method, bounds, opts) in paper_plan(o) {
        let problem = settings_problem(loaded, &bounds, method)?;
        let settings = method_settings(method, &opts);
        let outcome = run_method(&problem, &settings, ctx)?;
        let best = best_report(&problem, &outcome.result);
        runs.push(PaperRun {
            label,
            description,
            bounds,
            outcome,
            best,
        });
    }
    Ok(runs)
}

/// The paper's reported optimum, for the table: GA (v, t_c, R_s) ranges and the proposed
/// setting.
pub const PAPER_GA_OPTIMUM: [(f64, f64); 3] = [(1.91, 1.99), (1.30, 1.31), (0.05, 0.10)];
/// The paper's proposed setting (v, t_c, R_s).
pub const PAPER_PROPOSED: [f64; 3] = [2.0, 1.36, 0.0];

/// The design evaluation of the paper's proposed setting ([`PAPER_PROPOSED`], S_d = 0) on
/// this scenario (one evaluation, not counted in any run).
pub fn paper_point(loaded: &Loaded) -> Result<DesignEvaluation, OptimizeError> {
    let problem = settings_problem(loaded, &paper_box(PAPER_WIDE), Method::Ga)?;
    let x = [PAPER_PROPOSED[0], PAPER_PROPOSED[1], PAPER_PROPOSED[2], 0.0];
    Ok(problem.design_evaluation(&x))
}

/// paper_experiment.csv: one row per run.
pub fn paper_csv(runs: &[PaperRun]) -> Result<Vec<u8>, csv::Error> {
    let rows: Vec<Vec<String>> = runs
        .iter()
        .map(|r| {
            let res = &r.outcome.result;
            vec![
                r.label.clone(),
                r.description.clone(),
                num(r.best.x[0]),
                num(r.best.x[1]),
                num(r.best.x[2]),
                num(r.best.capacity),
                r.best.feasible.to_string(),
                res.evaluations.to_string(),
                res.feasible_count.to_string(),
                res.first_feasible.map_or(String::new(), |i| i.to_string()),
                r.best.active.len().to_string(),
                num(r.outcome.wall_time),
            ]
        })
        .collect();
    csv_bytes(
        &[
            "run",
            "setup",
            "belt_speed_m_s",
            "cycle_time_s",
            "start_position_m",
            "capacity_per_h",
            "feasible",
            "evaluations",
            "feasible_evaluations",
            "first_feasible",
            "active_constraints",
            "wall_time_s",
        ],
        &rows,
    )
}

/// The paper experiment as JSON; `paper_point` is the design evaluation of the paper's
/// proposed setting on this scenario.
pub fn paper_json(runs: &[PaperRun], paper_point: &DesignEvaluation) -> Value {
    json!({
        "runs": runs.iter().map(|r| json!({
            "run": r.label,
            "setup": r.description,
            "bounds": bounds_json(&r.bounds),
            "best": best_json(&r.best),
            "evaluations": r.outcome.result.evaluations,
            "feasible_evaluations": r.outcome.result.feasible_count,
            "first_feasible": opt_json(r.outcome.result.first_feasible),
            "wall_time_s": r.outcome.wall_time,
        })).collect::<Vec<_>>(),
        "paper": {
            "ga_optimum": {"belt_speed": PAPER_GA_OPTIMUM[0], "cycle_time": PAPER_GA_OPTIMUM[1], "start_position": PAPER_GA_OPTIMUM[2]},
            "proposed": {"belt_speed": PAPER_PROPOSED[0], "cycle_time": PAPER_PROPOSED[1], "start_position": PAPER_PROPOSED[2]},
            "ga_feasible_evaluations": 8,
            "proposed_on_this_machine": {
                "capacity": paper_point.capacity,
                "feasible": paper_point.feasible,
                "overload_ratio": paper_point.overload.as_ref().ok().map(|o| o.ratio),
                "diverted": paper_point.cases.iter().map(|c| json!({"name": c.name, "diverted": c.outcome == Outcome::Diverted})).collect::<Vec<_>>(),
            },
        },
    })
}
