//! Instruction counts of whole runs (issue 16), stable on a noisy machine: each scene of
//! `scene_set.rs` and the fixed mix, verdict-only, counted by `valgrind --tool=callgrind`.
//!
//! `cargo bench -p divertsim --bench instructions` runs this binary under valgrind once per
//! case and run count: the difference between 3 runs and 1 run, halved, is one run's count
//! (set-up and process start cancel); for the mix (and "mix+loads": each run with its
//! stroke's arm loads, as a reliability sample has them), one pass over the 1,000 scenarios minus
//! none, divided by 1,000. Needs `valgrind` on the PATH (it says so and exits otherwise).

mod scene_set;
use scene_set as scenes;

use divertsim_core::sim::arm_loads::StrokeProfile;
use divertsim_core::sim::simulate_verdict;
use std::hint::black_box;
use std::process::Command;

const CASE: &str = "DIVERTSIM_IC_CASE";
const RUNS: &str = "DIVERTSIM_IC_RUNS";

/// Inside valgrind: run one case `runs` times.
fn run_case(case: &str, runs: usize) {
    if case == "mix+loads" {
        // What a reliability sample adds: the stroke's loads from the machine's profile,
        // built before the counted passes (a study builds it once per shard).
        let mix = scenes::mix();
        let profiles: Vec<_> = mix.iter().map(StrokeProfile::of).collect();
        for _ in 0..runs {
            for (s, p) in mix.iter().zip(&profiles) {
                let r = simulate_verdict(black_box(s));
                black_box(p.as_ref().map(|p| r.arm_loads_with(s, p)));
            }
        }
        return;
    }
    if case == "mix" {
        let mix = scenes::mix();
        for _ in 0..runs {
            for s in &mix {
                black_box(simulate_verdict(black_box(s)));
            }
        }
        return;
    }
    let scenes = scenes::scenes();
    let Some((_, s)) = scenes.iter().find(|(n, _)| *n == case) else {
        eprintln!("unknown case {case}");
        std::process::exit(2);
    };
    for _ in 0..runs {
        black_box(simulate_verdict(black_box(s)));
    }
}

/// Instructions of this binary running `case` `runs` times under callgrind.
fn count(case: &str, runs: usize) -> Result<u64, String> {
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let out = Command::new("valgrind")
        .args(["--tool=callgrind", "--callgrind-out-file=/dev/null"])
        .arg(&exe)
        .env(CASE, case)
        .env(RUNS, runs.to_string())
        .output()
        .map_err(|e| format!("cannot start valgrind ({e}); install it to count instructions"))?;
    let log = String::from_utf8_lossy(&out.stderr);
    log.lines()
        .find_map(|l| l.split("Collected :").nth(1))
        .and_then(|v| v.trim().parse().ok())
        .ok_or_else(|| format!("no instruction count in valgrind's output:\n{log}"))
}

fn main() {
    if let (Ok(case), Ok(runs)) = (std::env::var(CASE), std::env::var(RUNS)) {
        run_case(&case, runs.parse().unwrap_or(1));
        return;
    }
    // `cargo bench` passes `--bench`; a filter argument picks cases by substring.
    let filter: Option<String> = std::env::args().skip(1).find(|a| !a.starts_with("--"));
    let mut cases: Vec<&str> = scenes::scenes().iter().map(|(n, _)| *n).collect();
    cases.push("mix");
    cases.push("mix+loads");
    println!("{:<16} {:>14}", "case", "instructions/run");
    for case in cases {
        if filter.as_deref().is_some_and(|f| !case.contains(f)) {
            continue;
        }
        let (lo, hi, per) = if case.starts_with("mix") {
            (0, 1, scenes::MIX_SIZE as f64)
        } else {
            (1, 3, 2.0)
        };
        match (count(case, lo), count(case, hi)) {
            (Ok(a), Ok(b)) => println!("{case:<16} {:>14.0}", (b as f64 - a as f64) / per),
            (Err(e), _) | (_, Err(e)) => {
                eprintln!("{e}");
                return;
            }
        }
    }
}
