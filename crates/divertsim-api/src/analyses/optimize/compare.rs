//! Every method over several seeds on the same problem: best capacity, evaluations to the
//! first feasible point and to within 0.5 % of the best known, the medians per method.

use super::tables::{bounds_json, finite, num, opt_json};
use super::*;

/// One run of the comparison.
#[derive(Debug, Clone, PartialEq)]
pub struct CompareRow {
    pub method: Method,
    pub seed: u64,
    /// Best feasible capacity [parcels/h] (NaN if none).
    pub best_capacity: f64,
    pub best_x: Vec<f64>,
    pub evaluations: usize,
    pub first_feasible: Option<usize>,
    /// Evaluations until a feasible point within 0.5 % of the best known capacity (1-based
    /// count), `None` if never.
    pub to_within: Option<usize>,
    pub feasible_count: usize,
    /// NSGA-II only: front size.
    pub front_size: Option<usize>,
    pub wall_time: f64,
}

/// Tolerance of "reaching the best capacity" in the comparison (issue 5: 0.5 %).
pub const WITHIN: f64 = 0.005;

/// Methods of the comparison, in order.
pub const COMPARE_METHODS: [Method; 5] = [
    Method::Ga,
    Method::Gradient,
    Method::De,
    Method::Cmaes,
    Method::Nsga2,
];

/// A gradient starting point for a seed: SplitMix64 draws, uniform in the bounds (the
/// gradient method has no randomness of its own, so the seeds vary its start).
pub fn seeded_start(bounds: &Bounds, seed: u64) -> Vec<f64> {
    let mut rng = divertsim_core::stats::splitmix::SplitMix64(
        seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03,
    );
    let mut next = || rng.next_f64();
    (0..bounds.dim())
        .map(|i| {
            let u = next();
            if bounds.is_fixed(i) {
                bounds.lower[i]
            } else {
                bounds.lower[i] + u * (bounds.upper[i] - bounds.lower[i])
            }
        })
        .collect()
}

/// The runs of the comparison: (method, seed, options).
pub fn compare_plan(bounds: &Bounds, o: &RunOptions, seeds: u64) -> Vec<(Method, u64, RunOptions)> {
    let mut plan = Vec::new();
    for method in COMPARE_METHODS {
        for k in 0..seeds {
            let seed = o.seed + k;
            let (population, generations) = match method {
                Method::Ga | Method::Nsga2 => (o.population, o.generations),
                _ => (None, None),
            };
            plan.push((
                method,
                seed,
                RunOptions {
                    population,
                    generations,
                    budget: o.budget,
                    polish: o.polish,
                    seed,
                    start: (method == Method::Gradient).then(|| seeded_start(bounds, seed)),
                },
            ));
        }
    }
    plan
}

/// Run the comparison; the "within 0.5 %" counts refer to the best feasible capacity over
/// every run.
pub fn compare(
    loaded: &Loaded,
    bounds: &Bounds,
    o: &RunOptions,
    seeds: u64,
    ctx: &RunContext<'_>,
) -> Result<(Vec<CompareRow>, f64), OptimizeError> {
    let mut done: Vec<(RunOutcome, u64)> = Vec::new();
    for (method, seed, opts) in compare_plan(bounds, o, seeds) {
        let problem = settings_problem(loaded, bounds, method)?;
        let settings = method_settings(method, &opts);
        done.push((run_method(&problem, &settings, ctx)?, seed));
    }
    let best_known = done
        .iter()
        .flat_map(|(r, _)| r.log.iter())
        .filter(|r| r.evaluation.feasible())
        .map(|r| capacity_of(&r.x))
        .fold(f64::NAN, f64::max);
    let rows = done
        .into_iter()
        .map(|(r, seed)| {
            let best_feasible = r
                .log
                .iter()
                .filter(|e| e.evaluation.feasible())
                .map(|e| (capacity_of(&e.x), e.x.clone()))
                .fold((f64::NAN, Vec::new()), |a, b| {
                    if a.0.is_nan() || b.0 > a.0 {
                        b
                    } else {
                        a
                    }
                });
            CompareRow {
                method: r.method,
                seed,
                best_capacity: best_feasible.0,
                best_x: if best_feasible.1.is_empty() {
                    r.result.best_x.clone()
                } else {
                    best_feasible.1
                },
                evaluations: r.result.evaluations,
                first_feasible: r.result.first_feasible.map(|i| i + 1),
                to_within: if best_known.is_finite() {
                    first_reaching(&r.log, (1.0 - WITHIN) * best_known).map(|i| i + 1)
                } else {
                    None
                },
                feasible_count: r.result.feasible_count,
                front_size: r.front.as_ref().map(Vec::len),
                wall_time: r.wall_time,
            }
        })
        .collect();
    Ok((rows, best_known))
}

/// Median of the values; `None` counts as +∞ (a run that never got there); `None` when the
/// median itself is such a run or there are no values.
pub fn median(values: &[Option<f64>]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let mut v: Vec<f64> = values
        .iter()
        .map(|x| x.filter(|v| !v.is_nan()).unwrap_or(f64::INFINITY))
        .collect();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    let m = if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    };
    m.is_finite().then_some(m)
}

/// Medians of one method: (best capacity, first feasible, to within 0.5 %, evaluations,
/// wall time, front size).
pub fn method_medians(rows: &[CompareRow], method: Method) -> [Option<f64>; 6] {
    let r: Vec<&CompareRow> = rows.iter().filter(|r| r.method == method).collect();
    let f = |g: &dyn Fn(&CompareRow) -> Option<f64>| {
        median(&r.iter().map(|x| g(x)).collect::<Vec<_>>())
    };
    [
        f(&|x| Some(x.best_capacity)),
        f(&|x| x.first_feasible.map(|v| v as f64)),
        f(&|x| x.to_within.map(|v| v as f64)),
        f(&|x| Some(x.evaluations as f64)),
        f(&|x| Some(x.wall_time)),
        f(&|x| x.front_size.map(|v| v as f64)),
    ]
}

/// comparison.csv (one row per run) and comparison_medians.csv (one row per method, the
/// medians over its seeds): tidy tables, an empty cell where there is no value.
pub fn compare_csv(rows: &[CompareRow]) -> Result<(Vec<u8>, Vec<u8>), csv::Error> {
    let o = |v: Option<usize>| v.map_or(String::new(), |i| i.to_string());
    let of = |v: Option<f64>| v.map_or(String::new(), num);
    let runs: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            vec![
                r.method.name().to_string(),
                r.seed.to_string(),
                num(r.best_capacity),
                num(r.best_x[0]),
                num(r.best_x[1]),
                num(r.best_x[2]),
                num(r.best_x[3]),
                r.evaluations.to_string(),
                o(r.first_feasible),
                o(r.to_within),
                r.feasible_count.to_string(),
                o(r.front_size),
                num(r.wall_time),
            ]
        })
        .collect();
    let medians: Vec<Vec<String>> = COMPARE_METHODS
        .into_iter()
        .filter(|&m| rows.iter().any(|r| r.method == m))
        .map(|m| {
            let md = method_medians(rows, m);
            vec![
                m.name().to_string(),
                rows.iter().filter(|r| r.method == m).count().to_string(),
                of(md[0]),
                of(md[3]),
                of(md[1]),
                of(md[2]),
                of(md[5]),
                of(md[4]),
            ]
        })
        .collect();
    let runs = csv_bytes(
        &[
            "method",
            "seed",
            "best_capacity_per_h",
            "belt_speed_m_s",
            "cycle_time_s",
            "start_position_m",
            "light_barrier_m",
            "evaluations",
            "first_feasible",
            "evaluations_to_within_half_percent",
            "feasible_count",
            "front_size",
            "wall_time_s",
        ],
        &runs,
    )?;
    let medians = csv_bytes(
        &[
            "method",
            "seeds",
            "best_capacity_per_h",
            "evaluations",
            "first_feasible",
            "evaluations_to_within_half_percent",
            "front_size",
            "wall_time_s",
        ],
        &medians,
    )?;
    Ok((runs, medians))
}

/// The comparison as JSON.
pub fn compare_json(rows: &[CompareRow], best_known: f64, bounds: &Bounds) -> Value {
    let oj = |v: Option<f64>| v.map_or(Value::Null, |x| json!(x));
    json!({
        "bounds": bounds_json(bounds),
        "best_known_capacity": finite(best_known),
        "within": WITHIN,
        "runs": rows.iter().map(|r| json!({
            "method": r.method.name(),
            "seed": r.seed,
            "best_capacity": finite(r.best_capacity),
            "best_x": r.best_x,
            "evaluations": r.evaluations,
            "first_feasible": opt_json(r.first_feasible),
            "to_within": opt_json(r.to_within),
            "feasible_count": r.feasible_count,
            "front_size": opt_json(r.front_size),
            "wall_time_s": r.wall_time,
        })).collect::<Vec<_>>(),
        "medians": COMPARE_METHODS.iter().filter(|m| rows.iter().any(|r| r.method == **m)).map(|&m| {
            let md = method_medians(rows, m);
            json!({
                "method": m.name(),
                "best_capacity": oj(md[0]),
                "first_feasible": oj(md[1]),
                "to_within": oj(md[2]),
                "evaluations": oj(md[3]),
                "wall_time_s": oj(md[4]),
                "front_size": oj(md[5]),
            })
        }).collect::<Vec<_>>(),
    })
}
