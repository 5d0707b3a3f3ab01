//! The sorter line through the library: agreement with `reliability` where the line cannot
//! matter, and the problems of a bad `[line]`, each keyed.

use divertsim_api::analyses::line::LineAnalysis;
use divertsim_api::analyses::reliability::Reliability;
use divertsim_api::config::{Loaded, ScenarioBuilder};
use divertsim_api::contract::{Analysis, Hooks};

const LINE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/paper/line.toml");

fn inline(text: &str) -> toml::Value {
    toml::from_str::<toml::Table>(&format!("v = {text}")).unwrap()["v"].clone()
}

fn loaded(values: &[(&str, &str)]) -> Result<Loaded, Vec<String>> {
    let mut b = ScenarioBuilder::file(LINE);
    for (k, v) in values {
        b = b.value(k, inline(v));
    }
    b.load().map_err(|p| {
        p.0.iter()
            .map(|p| format!("{}: {}", p.key, p.message))
            .collect()
    })
}

fn run<A: Analysis>(l: &Loaded, options: A::Options) -> A::Output {
    let c = A::bind(A::validate(&options).unwrap(), l).unwrap();
    A::run(l, &c, &Hooks::none()).unwrap()
}

/// On the paper preset with one diverter and every gap 3 m (each parcel's cycle is over
/// before the next arrives), the line diverts what `reliability` diverts of the same
/// parcels, and its throughput is the arrival rate times the divert rate.
#[test]
fn line_agrees_with_reliability_at_generous_gaps() {
    let l = loaded(&[("line.gap", "{ kind = \"fixed\", value = 3.0 }")]).unwrap();
    let n = 3000;
    let line = run::<LineAnalysis>(
        &l,
        divertsim_api::analyses::line::Options {
            parcels: n,
            segment: 500,
            ..Default::default()
        },
    );
    let t = &line.results[0].tally;
    assert_eq!(
        t.count("arm_busy") + t.count("collision") + t.count("struck_in_passing"),
        0
    );
    let ours = t.divert_rate(0, 0.95);
    let rel = run::<Reliability>(
        &l,
        divertsim_api::analyses::reliability::Options {
            samples: n,
            shard: 1000,
            ..Default::default()
        },
    );
    let theirs = rel.results[0].0.tally.divert_rate(0.95);
    assert!(
        theirs.estimate >= ours.lower && theirs.estimate <= ours.upper,
        "reliability {} outside the line's [{}, {}]",
        theirs.estimate,
        ours.lower,
        ours.upper
    );
    assert!(
        ours.estimate >= theirs.lower && ours.estimate <= theirs.upper,
        "line {} outside reliability's [{}, {}]",
        ours.estimate,
        theirs.lower,
        theirs.upper
    );
    // The same parcels, the same physics: verdicts differ at most at knife-edges.
    assert!((ours.successes as i64 - theirs.successes as i64).abs() <= 3);
    let expected = t.arrival_rate() * ours.estimate;
    assert!((t.line_throughput() - expected).abs() <= 1e-9 * expected);
}

/// Scenario values by key, as TOML texts.
type Values<'a> = &'a [(&'a str, &'a str)];

#[test]
fn a_bad_line_is_reported_by_key() {
    let cases: [(Values, &str, &str); 4] = [
        (
            &[("line.diverters", "[{ position = 0.5, share = 0.3 }]")],
            "line.diverters[0].position",
            "inside the reach",
        ),
        (
            &[
                ("line.gap", "{ kind = \"normal\", mean = 0.5, sd = 0.2 }"),
                ("line.min_gap", "-1"),
            ],
            "line.min_gap",
            "allowed: [0, 100] m",
        ),
        (
            &[
                ("line.share", "0.7"),
                ("line.diverters", "[{ position = 4.0, share = 0.5 }]"),
            ],
            "line.diverters[0].share",
            "sum to 1.2",
        ),
        (
            &[(
                "line.diverters",
                "[{ position = 4.0, share = 0.2, machine = { belt_speed = 1.0 } }]",
            )],
            "line.diverters[0].machine.belt_speed",
            "the line's",
        ),
    ];
    for (values, key, words) in cases {
        let problems = loaded(values).unwrap_err();
        assert!(
            problems
                .iter()
                .any(|p| p.starts_with(key) && p.contains(words)),
            "{values:?}: {problems:?}"
        );
    }
}

#[test]
fn a_gap_that_can_go_negative_needs_a_minimum() {
    let l = ScenarioBuilder::new()
        .value(
            "line.gap",
            inline("{ kind = \"normal\", mean = 0.5, sd = 0.2 }"),
        )
        .load();
    let p = l.unwrap_err().0;
    assert!(
        p.iter()
            .any(|p| p.key == "line.min_gap" && p.message.contains("below 0")),
        "{p:?}"
    );
}

#[test]
fn a_further_diverters_machine_is_checked_as_the_first() {
    let p = loaded(&[(
        "line.diverters",
        "[{ position = 4.0, share = 0.2, machine = { cycle_time = -1 } }]",
    )])
    .unwrap_err();
    assert!(
        p.iter()
            .any(|p| p.starts_with("line.diverters[0].machine.cycle_time")),
        "{p:?}"
    );
}

#[test]
fn arrival_times_that_do_not_increase_are_refused_with_their_line() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("arrivals.csv"),
        "time\n0.0\n1.5\n1.5\n3.0\n",
    )
    .unwrap();
    let f = dir.path().join("line.toml");
    std::fs::write(&f, "[line]\narrivals = \"arrivals.csv\"\n").unwrap();
    let l = ScenarioBuilder::file(&f).load().unwrap();
    let c = LineAnalysis::validate(&Default::default()).unwrap();
    let p = LineAnalysis::bind(c, &l).unwrap_err();
    assert_eq!(p[0].key, "line.arrivals");
    assert!(
        p[0].message.contains("line 4") && p[0].message.contains("does not increase"),
        "{p:?}"
    );
}

/// Hostile input round four: gap laws with effectively infinite values (lognormal σ 700,
/// uniform up to 1e308) were accepted and gave "arrival rate 0/h"; every draw of a gap law
/// must lie within the stated support, -100 to 1000 m.
#[test]
fn gap_laws_outside_their_support_are_refused() {
    for law in [
        "{ kind = \"lognormal\", median = 1.0, sigma = 700.0 }",
        "{ kind = \"uniform\", min = 0.5, max = 1e308 }",
        "{ kind = \"normal\", mean = 1.0, sd = 1e6 }",
    ] {
        let e = loaded(&[("line.gap", law), ("line.min_gap", "0.1")]).unwrap_err();
        assert!(
            e.iter()
                .any(|m| m.starts_with("line.gap:") && m.contains("-100 to 1000 m")),
            "{law}: {e:?}"
        );
    }
    // A wide but real law is fine.
    loaded(&[(
        "line.gap",
        "{ kind = \"lognormal\", median = 1.0, sigma = 0.8 }",
    )])
    .unwrap();
}

/// Hostile input round four: an arrivals log near 1e300 was accepted; times stay within
/// ±1e10 s and headways within 1e6 s.
#[test]
fn arrivals_outside_their_support_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    for (name, text, expect) in [
        ("huge.csv", "time\n1e300\n2e300\n", "-1e10 to 1e10 s"),
        ("pause.csv", "time\n0\n5e6\n", "headway of at most 1e6 s"),
    ] {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        let l = ScenarioBuilder::new()
            .allow_outside_paths(true)
            .value(
                "line.arrivals",
                toml::Value::String(path.display().to_string()),
            )
            .load();
        let e = match l {
            Err(p) => p.to_string(),
            Ok(l) => {
                let o = divertsim_api::analyses::line::Options {
                    parcels: 20,
                    segment: 10,
                    ..Default::default()
                };
                let c = LineAnalysis::validate(&o).unwrap();
                match LineAnalysis::bind(c, &l) {
                    Err(p) => divertsim_api::config::Problems(p).to_string(),
                    Ok(_) => panic!("{name} accepted"),
                }
            }
        };
        assert!(
            e.contains("line.arrivals") && e.contains(expect),
            "{name}: {e}"
        );
    }
}
