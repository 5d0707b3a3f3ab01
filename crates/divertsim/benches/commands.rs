//! Wall times of the commands a designer waits for (issue 28), as criterion medians of the
//! built `divertsim` binary run as a user runs it, on 2 worker threads:
//! - `robust_map`: `divertsim capacity configs/paper/machine.toml` (the robust 20 × 20
//!   map of the paper preset, `--worst search` by default);
//! - `robust_optimize`: `divertsim optimize configs/paper/machine.toml` (DE + polish
//!   against the searched worst case, rounds and a confirmation search);
//! - `worst_case`: `divertsim worst-case configs/paper/machine.toml` (both objectives at the
//!   preset's setting).
//!
//! Each sample is one whole command (process start and scenario loading included, a few
//! milliseconds), so ten samples of the map take minutes: run it alone,
//! `cargo bench -p divertsim --bench commands`, or one of them with a filter
//! (`-- robust_map`). Figures in BENCHMARKS.md.

use criterion::{criterion_group, criterion_main, Criterion};
use std::path::PathBuf;
use std::process::Command;
use std::time::Duration;

/// The paper preset, from the workspace root.
fn preset() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../configs/paper/machine.toml")
}

/// Runs `divertsim ARGS --threads 2 -q --json` and insists on success.
fn run(args: &[&str]) {
    let out = Command::new(env!("CARGO_BIN_EXE_divertsim"))
        .args(args)
        .arg(preset())
        .args(["--threads", "2", "-q", "--json"])
        .output()
        .expect("divertsim runs");
    assert!(
        out.status.success(),
        "divertsim {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn commands(c: &mut Criterion) {
    let mut g = c.benchmark_group("command");
    g.sample_size(10).measurement_time(Duration::from_secs(30));
    g.bench_function("worst_case", |b| b.iter(|| run(&["worst-case"])));
    g.bench_function("robust_optimize", |b| b.iter(|| run(&["optimize"])));
    g.bench_function("robust_map", |b| b.iter(|| run(&["capacity"])));
    g.finish();
}

criterion_group!(benches, commands);
criterion_main!(benches);
