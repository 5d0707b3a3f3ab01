//! Studies in pieces (`divertsim_api::pieces`): a line run and a reliability run, their
//! pieces run apart (in reverse order, as a cluster may return them) and handed back, give
//! the report of one machine's run exactly; a piece of another run (another seed, another
//! scenario) or one given twice is refused, and a piece left out is run by the merge.

use divertsim_api::analyses::line::{self, LineAnalysis};
use divertsim_api::analyses::reliability::{self, Reliability};
use divertsim_api::config::{Loaded, ScenarioBuilder};
use divertsim_api::contract::{report, Analysis, Error, Hooks};
use divertsim_api::pieces::{run_from_pieces, Pieces};

const LINE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/paper/line.toml");
const HUB: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/mix/hub.toml");

fn loaded(path: &str) -> Loaded {
    ScenarioBuilder::file(path).load().unwrap()
}

/// Every piece run apart, in reverse order: (key, bytes).
fn run_apart<A: Pieces>(bound: &A::Bound, prepared: &A::Prepared) -> Vec<(u64, Vec<u8>)> {
    let mut pieces: Vec<(u64, Vec<u8>)> = A::pieces(bound)
        .into_iter()
        .map(|p| (p.key, A::run_piece(bound, prepared, p.point, p.k).unwrap()))
        .collect();
    pieces.reverse();
    pieces
}

fn refusal(e: Error) -> String {
    match e {
        Error::Invalid(p) => p[0].message.clone(),
        other => panic!("not refused as input: {other:?}"),
    }
}

fn check_pieces<A: Pieces>(l: &Loaded, options: A::Options, other: A::Options, count: usize) {
    let bound = A::bind(A::validate(&options).unwrap(), l).unwrap();
    let prepared = A::prepare(&bound).unwrap();
    let pieces = run_apart::<A>(&bound, &prepared);
    assert_eq!(pieces.len(), count);
    let out = A::run(l, &bound, &Hooks::none()).unwrap();
    let one = report::<A>(&out, &bound, l).unwrap();
    let merged = run_from_pieces::<A>(l, &bound, pieces.clone(), Some(2)).unwrap();
    assert_eq!(merged.summary, one.summary);
    assert_eq!(merged.tables, one.tables);
    assert_eq!(merged.text, one.text);
    // A piece left out is run by the merge: the same report.
    let fewer = pieces[1..].to_vec();
    let again = run_from_pieces::<A>(l, &bound, fewer, Some(1)).unwrap();
    assert_eq!(again.summary, one.summary);

    let twice = [pieces.clone(), pieces[..1].to_vec()].concat();
    let e = run_from_pieces::<A>(l, &bound, twice, None).unwrap_err();
    assert!(refusal(e).contains("given twice"));
    let other = A::bind(A::validate(&other).unwrap(), l).unwrap();
    let other_prepared = A::prepare(&other).unwrap();
    let foreign = run_apart::<A>(&other, &other_prepared);
    let e = run_from_pieces::<A>(l, &bound, foreign, None).unwrap_err();
    assert!(refusal(e).contains("is not one of this run's"));
}

#[test]
fn a_line_run_from_its_pieces_is_the_run_of_one_machine() {
    let l = loaded(LINE);
    let options = |seed| line::Options {
        parcels: 300,
        segment: 100,
        seed: Some(seed),
        ..Default::default()
    };
    check_pieces::<LineAnalysis>(&l, options(3), options(4), 3);
    let bound = LineAnalysis::bind(LineAnalysis::validate(&options(3)).unwrap(), &l).unwrap();
    let prepared = LineAnalysis::prepare(&bound).unwrap();
    let e = LineAnalysis::run_piece(&bound, &prepared, 0, 3).unwrap_err();
    assert!(refusal(e).contains("no segment 3; this run has 3"));
}

#[test]
fn a_reliability_run_from_its_pieces_is_the_run_of_one_machine() {
    let l = loaded(HUB);
    let options = |seed| reliability::Options {
        samples: 400,
        shard: 100,
        seed: Some(seed),
        ..Default::default()
    };
    check_pieces::<Reliability>(&l, options(3), options(4), 4);
}

/// The defect: a reliability shard's key named its point by swept value and seed only, so
/// the shards of a run on another scenario with the same seed and options were merged as
/// this run's. Its key now names the point's scenario and mix; the line's always did.
#[test]
fn a_shard_of_another_scenario_with_the_same_seed_is_refused() {
    let reliability = reliability::Options {
        samples: 400,
        shard: 100,
        seed: Some(3),
        ..Default::default()
    };
    another_scenarios_pieces_are_refused::<Reliability>(&loaded(HUB), reliability);
    let line = line::Options {
        parcels: 300,
        segment: 100,
        seed: Some(3),
        ..Default::default()
    };
    another_scenarios_pieces_are_refused::<LineAnalysis>(&loaded(LINE), line);
}

/// Pieces of a run on another scenario, with the same seed and options (the same points,
/// shards and sample indices), are another run's.
fn another_scenarios_pieces_are_refused<A: Pieces>(l: &Loaded, options: A::Options) {
    let mut faster = ScenarioBuilder::resolved(l);
    faster = faster.value("machine.belt_speed", toml::Value::Float(2.25));
    let faster = faster.load().unwrap();
    let bound = A::bind(A::validate(&options).unwrap(), l).unwrap();
    let theirs = A::bind(A::validate(&options).unwrap(), &faster).unwrap();
    let foreign = run_apart::<A>(&theirs, &A::prepare(&theirs).unwrap());
    let e = run_from_pieces::<A>(l, &bound, foreign, None).unwrap_err();
    assert!(refusal(e).contains("is not one of this run's"));
}
