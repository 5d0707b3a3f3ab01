//! Issue 50, item 4: every figure and marked number of README.md and docs/validation.md is
//! what a fresh run of docs/runs.toml gives (`divertsim docs --check`), and the check fails,
//! naming the place, when one is not.

use crate::common::divertsim;
use std::path::Path;

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

/// The committed documents against fresh runs: the whole manifest (about ten minutes of
/// CPU), as a user's `divertsim docs --check` runs it.
#[test]
fn the_documents_figures_and_numbers_are_those_of_a_fresh_run() {
    let o = divertsim()
        .args(["docs", "--check", "--quiet", "--root", ROOT])
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

/// A copy of the repository's documents with one run of the manifest: a number changed by
/// hand and a figure that differs are both named with --check (exit 1) and nothing is
/// written; without --check both are put back from the run.
#[test]
fn a_committed_number_or_figure_that_differs_from_its_run_fails_the_check() {
    let t = tempfile::tempdir().unwrap();
    let root = t.path();
    let copy = |rel: &str| {
        let to = root.join(rel);
        std::fs::create_dir_all(to.parent().unwrap()).unwrap();
        std::fs::copy(Path::new(ROOT).join(rel), &to).unwrap();
    };
    for f in [
        "configs/paper/machine.toml",
        "configs/paper/mix.toml",
        "docs/images/mix/failure_rate.svg",
    ] {
        copy(f);
    }
    std::fs::write(
        root.join("docs/runs.toml"),
        r#"documents = ["README.md"]

[[run]]
name = "small"
about = "a small mix"
args = ["reliability", "configs/paper/mix.toml", "--samples", "200"]
figures = { "failure_rate.svg" = "docs/images/mix/failure_rate.svg" }
"#,
    )
    .unwrap();
    // The committed figure is another run's (100,000 samples): it differs.
    let readme = "Fails: <!--n small /points/0/failure_rate/estimate pct:2-->12.34<!--/n--> %.\n";
    std::fs::write(root.join("README.md"), readme).unwrap();
    let check = divertsim()
        .args(["docs", "--check", "--quiet", "--root"])
        .arg(root)
        .output()
        .unwrap();
    assert_eq!(check.status.code(), Some(1));
    let said = String::from_utf8_lossy(&check.stdout);
    assert!(
        said.contains(
            "README.md:1: small /points/0/failure_rate/estimate: committed 12.34, fresh "
        ),
        "{said}"
    );
    assert!(
        said.contains(
            "docs/images/mix/failure_rate.svg: differs from run small's failure_rate.svg"
        ),
        "{said}"
    );
    assert_eq!(
        std::fs::read_to_string(root.join("README.md")).unwrap(),
        readme
    );
    // Written: then the check passes.
    let write = divertsim()
        .args(["docs", "--quiet", "--root"])
        .arg(root)
        .output()
        .unwrap();
    assert_eq!(
        write.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&write.stderr)
    );
    let text = std::fs::read_to_string(root.join("README.md")).unwrap();
    assert!(!text.contains(">12.34<"), "{text}");
    let again = divertsim()
        .args(["docs", "--check", "--quiet", "--root"])
        .arg(root)
        .output()
        .unwrap();
    assert_eq!(
        again.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&again.stdout)
    );
}

/// An unknown --only is bad input (exit 2) naming the runs there are, before any run (a
/// marker naming no run is the unit test's).
#[test]
fn an_unknown_only_is_refused_naming_the_runs() {
    let t = tempfile::tempdir().unwrap();
    let root = t.path();
    std::fs::create_dir_all(root.join("docs")).unwrap();
    std::fs::write(
        root.join("docs/runs.toml"),
        "documents = [\"README.md\"]\n\n[[run]]\nname = \"a\"\nabout = \"example\"\nargs = [\"example\"]\n",
    )
    .unwrap();
    std::fs::write(root.join("README.md"), "<!--n b /x int-->1<!--/n-->\n").unwrap();
    let o = divertsim()
        .args(["docs", "--check", "--quiet", "--only", "zzz", "--root"])
        .arg(root)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--only: no run named \"zzz\"; allowed: a"));
}
