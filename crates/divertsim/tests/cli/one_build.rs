//! One compile for a newcomer (issue 27, B4): the main job (`cargo run --release`, the CLI
//! alone), the test command (`cargo test --workspace --release`: every crate with its
//! dev-dependencies) and the Python install (maturin, the Python crate alone) share
//! target/release only if cargo resolves every dependency they share with the same
//! features. crates/workspace-hack makes it so; this test catches a new dependency or
//! feature that breaks it, by asking `cargo tree` for each build's features.

use std::collections::{BTreeMap, BTreeSet};
use std::process::Command;

/// Each package of one build's graph ("name vX.Y.Z") with its enabled features.
fn features(args: &[&str]) -> BTreeMap<String, BTreeSet<String>> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
    let out = Command::new(cargo)
        .current_dir(root)
        .args(["tree", "--locked", "--prefix", "none", "--no-dedupe"])
        .args(["-f", "{p} {f}"])
        .args(args)
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "cargo tree {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut map: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for line in String::from_utf8_lossy(&out.stdout).lines() {
        let tokens: Vec<&str> = line.split_whitespace().collect();
        // Feature nodes ("serde feature \"derive\"") name a feature, not a build unit.
        if tokens.len() < 2 || tokens[1] == "feature" {
            continue;
        }
        let feats = map
            .entry(format!("{} {}", tokens[0], tokens[1]))
            .or_default();
        for t in &tokens[2..] {
            if !t.starts_with('(') && !t.ends_with(')') {
                feats.extend(t.split(',').map(str::to_string));
            }
        }
    }
    map
}

#[test]
fn main_job_tests_and_python_build_share_every_dependency() {
    let builds = [
        (
            "the main job",
            features(&["-p", "divertsim", "-e", "normal,build,features"]),
        ),
        (
            "the test command",
            features(&["--workspace", "-e", "normal,build,dev,features"]),
        ),
        (
            "the Python build",
            features(&["-p", "divertsim-py", "-e", "normal,build,features"]),
        ),
    ];
    // The graphs are real: the CLI's and the Python crate's own dependencies are there.
    assert!(builds[0].1.keys().any(|k| k.starts_with("clap ")));
    assert!(builds[2].1.keys().any(|k| k.starts_with("pyo3 ")));
    let mut shared = 0;
    let mut differ = Vec::new();
    for (i, (a_name, a)) in builds.iter().enumerate() {
        for (b_name, b) in &builds[i + 1..] {
            for (pkg, fa) in a {
                if let Some(fb) = b.get(pkg) {
                    shared += 1;
                    if fa != fb && !pkg.starts_with("divertsim") {
                        differ.push(format!("{pkg}: {a_name} {fa:?}, {b_name} {fb:?}"));
                    }
                }
            }
        }
    }
    assert!(
        shared > 300,
        "only {shared} shared packages: the parse is wrong"
    );
    assert!(
        differ.is_empty(),
        "these would compile twice; add the union of their features to \
         crates/workspace-hack/Cargo.toml:\n{}",
        differ.join("\n")
    );
}
