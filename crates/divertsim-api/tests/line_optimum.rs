//! `optimize` with the line's throughput as its objective (issue 25, item 8): common random
//! numbers, the best point reproduced by `line` on optimum.toml, and the options' problems.

use divertsim_api::analyses::line::{LineAnalysis, Options as LineOptions};
use divertsim_api::analyses::optimize::line::{LineObjective, LineSearch};
use divertsim_api::analyses::optimize::{search_bounds, Optimize, OptimizeOptions, OptimizeResult};
use divertsim_api::config::{Loaded, ScenarioBuilder};
use divertsim_api::contract::{Analysis, Hooks};
use divertsim_core::optimize::Problem;

const LINE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/paper/line.toml");

/// The line preset with tipping only flagged: these tests are about the search (its common
/// random numbers, its optimum's file), not about which parcels topple.
fn loaded() -> Loaded {
    ScenarioBuilder::file(LINE)
        .set("limits.tipping=\"flag\"")
        .load()
        .unwrap()
}

fn objective(parcels: u64) -> LineObjective {
    LineObjective {
        parcels,
        seed: Some(3),
        max_missort: 0.001,
        max_overload: 0.01,
    }
}

fn problem(parcels: u64) -> LineSearch {
    let l = loaded();
    let bounds = search_bounds(&[], 0.0).unwrap();
    LineSearch::new(&l, bounds, objective(parcels)).unwrap()
}

/// Every evaluation sees the same parcels: the gaps are in metres, so the stream's time is
/// exactly inversely proportional to the belt speed, and an evaluation repeated, or made on
/// one thread instead of two, gives the same bits.
#[test]
fn line_objective_uses_common_random_numbers() {
    let p = problem(300);
    let x = [1.4, 1.2, 0.3, 0.0];
    let a = p.measure(&x).unwrap().tally;
    let b = p.measure(&[2.8, 1.2, 0.3, 0.0]).unwrap().tally;
    assert_eq!(a.parcels, b.parcels);
    let ratio = a.time / b.time;
    assert!((ratio - 2.0).abs() < 1e-12, "T(1.4)/T(2.8) = {ratio}");
    let once = p.evaluate(&x);
    assert_eq!(once, p.evaluate(&x));
    let single = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| p.evaluate(&x));
    assert_eq!(once, single);
    // A different stream is a different sample: the objective is the settings', not the luck.
    let other = LineSearch::new(
        &loaded(),
        search_bounds(&[], 0.0).unwrap(),
        LineObjective {
            seed: Some(4),
            ..objective(300)
        },
    )
    .unwrap();
    assert_ne!(other.evaluate(&x), once);
}

/// The objective and constraints are the line's own figures: −throughput/1000, the missort
/// and overload rates less their limits, the barrier order.
#[test]
fn line_evaluation_is_the_lines_figures() {
    let p = problem(200);
    let x = [2.0, 1.36, 0.0, 0.0];
    let t = p.measure(&x).unwrap().tally;
    let e = p.evaluate(&x);
    assert_eq!(e.objectives, vec![-t.line_throughput() / 1000.0]);
    assert_eq!(
        e.constraints[0],
        t.missort_rate(0.95).estimate - 0.001,
        "missort"
    );
    assert_eq!(e.constraints[1], t.overload_rate(0.95).estimate - 0.01);
    assert_eq!(e.constraints[2], 0.0);
    // The paper preset's line at the paper's setting leaves parcels arm_busy: infeasible.
    assert!(t.count("arm_busy") > 0 && !e.feasible());
    // A light barrier past the arm start is run at R_s and reported by the constraint.
    let e = p.evaluate(&[2.0, 1.36, 0.0, 0.1]);
    assert!((e.constraints[2] - 0.1).abs() < 1e-15);
    assert!(!e.feasible());
}

/// A tiny search: its best point meets the limits, beats the scenario as given (which misses
/// them), and `line` on optimum.toml with the same parcels and seed gives the same figures.
#[test]
fn line_optimum_is_reproduced_by_line_on_its_file() {
    let l = loaded();
    let o = OptimizeOptions {
        objective: "line".into(),
        parcels: Some(200),
        stream_seed: Some(3),
        population: Some(6),
        generations: Some(3),
        polish: false,
        max_missort: Some(0.01),
        ..OptimizeOptions::default()
    };
    let bound = Optimize::bind(Optimize::validate(&o).unwrap(), &l).unwrap();
    let OptimizeResult::Line(r) = Optimize::run(&l, &bound, &Hooks::none()).unwrap() else {
        panic!("not a line result");
    };
    assert!(r.best.evaluation.feasible(), "{:?}", r.best.evaluation);
    assert!(!r.given.evaluation.feasible());
    let best = &r.best.measure.tally;
    assert!(best.missort_rate(0.95).estimate <= 0.01);
    // The best point's evaluation is the one the search made of it.
    let logged = r
        .run
        .log
        .iter()
        .find(|rec| rec.x == r.best.x)
        .expect("the best point is in the log");
    assert_eq!(logged.evaluation, r.best.evaluation);

    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("optimum.toml");
    std::fs::write(&file, &r.optimum_toml).unwrap();
    let at = ScenarioBuilder::file(&file).load().unwrap();
    let lo = LineOptions {
        parcels: 200,
        seed: Some(3),
        ..LineOptions::default()
    };
    let c = LineAnalysis::bind(LineAnalysis::validate(&lo).unwrap(), &at).unwrap();
    let again = LineAnalysis::run(&at, &c, &Hooks::none()).unwrap();
    let t = &again.results[0].tally;
    assert_eq!(t.line_throughput(), best.line_throughput());
    assert_eq!(t.outcomes, best.outcomes);
    assert_eq!(t.overloaded, best.overloaded);

    let json = Optimize::summary(&OptimizeResult::Line(r.clone()), &bound, &l);
    assert_eq!(json["objective"], "line");
    assert_eq!(json["best"]["feasible"], true);
    let text = Optimize::text(&OptimizeResult::Line(r), &bound, &l);
    assert!(text.contains("within the limit"), "{text}");
    assert!(text.contains("EXCEEDS the limit"), "{text}");
}

fn problems(o: OptimizeOptions) -> Vec<(String, String)> {
    Optimize::validate(&o)
        .err()
        .unwrap_or_default()
        .into_iter()
        .map(|p| (p.key, p.message))
        .collect()
}

fn keys(o: OptimizeOptions) -> Vec<String> {
    problems(o).into_iter().map(|(k, _)| k).collect()
}

#[test]
fn line_objective_options_are_checked_by_key() {
    let line = || OptimizeOptions {
        objective: "line".into(),
        ..OptimizeOptions::default()
    };
    assert_eq!(
        keys(OptimizeOptions {
            objective: "speed".into(),
            ..OptimizeOptions::default()
        }),
        ["objective"]
    );
    assert_eq!(
        keys(OptimizeOptions {
            parcels: Some(100),
            max_missort: Some(0.01),
            ..OptimizeOptions::default()
        }),
        ["parcels", "max_missort"]
    );
    let p = problems(OptimizeOptions {
        method: Some("gradient".into()),
        ..line()
    });
    assert_eq!(p[0].0, "method");
    assert!(p[0].1.contains("de, ga, cmaes"), "{}", p[0].1);
    assert_eq!(
        keys(OptimizeOptions {
            method: Some("nsga2".into()),
            ..line()
        }),
        ["method"]
    );
    assert_eq!(
        keys(OptimizeOptions {
            compare: true,
            ..line()
        }),
        ["compare"]
    );
    assert_eq!(
        keys(OptimizeOptions {
            max_missort: Some(1.5),
            max_overload: Some(-0.1),
            parcels: Some(5),
            ..line()
        }),
        ["parcels", "max_missort", "max_overload"]
    );
    let p = problems(OptimizeOptions {
        robust: divertsim_api::analyses::worst_case::RobustOptions {
            worst: Some(divertsim_api::analyses::worst_case::WorstChoice::Search),
            ..Default::default()
        },
        ..line()
    });
    assert_eq!(p[0].0, "worst");
    assert!(Optimize::validate(&line()).is_ok());
}

/// With the adaptive trigger the table sets R_s per parcel: a free R_s is refused by key.
#[test]
fn line_objective_with_the_adaptive_trigger_needs_a_fixed_start() {
    let l = ScenarioBuilder::file(LINE)
        .value("machine.trigger", toml::Value::String("adaptive".into()))
        .load()
        .unwrap();
    let o = OptimizeOptions {
        objective: "line".into(),
        ..OptimizeOptions::default()
    };
    let e = Optimize::bind(Optimize::validate(&o).unwrap(), &l).unwrap_err();
    assert_eq!(e[0].key, "bounds");
    assert!(e[0].message.contains("fix R_s"), "{}", e[0].message);
    let fixed = OptimizeOptions {
        fix: vec!["R_s=0.2".into()],
        ..o
    };
    assert!(Optimize::bind(Optimize::validate(&fixed).unwrap(), &l).is_ok());
}
