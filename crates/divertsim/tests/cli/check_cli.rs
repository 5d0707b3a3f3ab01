//! `divertsim check` (issue 27, A1): the verdict on the paper's proposed setting (unsafe, its
//! failing parcel written and reproduced by `simulate`) and on the robust optimum (safe), its
//! exit codes, and bad options.

use serde_json::Value;

use crate::common::{divertsim, json_stdout};

const PROPOSED: &str = "../../configs/paper/proposed.toml";
const ROBUST: &str = "../../configs/paper/robust_optimum.toml";

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// The paper's proposed setting is unsafe (the searched worst strike 1.24 × the free fall):
/// exit 4, the failing parcel as a scenario file that `simulate` reproduces, and the text
/// says so in words. Without the mix (`--samples 0`) the class keeps parcel.height, so the
/// strike is the only failure.
#[test]
fn check_finds_the_papers_proposed_setting_unsafe() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c");
    let run = divertsim()
        .args(["check", PROPOSED, "--samples", "0", "--json", "-q", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(
        run.status.code(),
        Some(4),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let v: Value = serde_json::from_slice(&run.stdout).unwrap();
    assert_eq!(v["verdict"], "unsafe");
    assert_eq!(v["overload"]["status"], "fails");
    let ratio = f(&v["overload"]["largest_ratio"]);
    assert!(ratio > 1.2, "{ratio}");
    assert_eq!(v["divert"]["status"], "passes");
    assert_eq!(v["divert"]["class_heights_m"], Value::Null);
    assert_eq!(v["mix"], Value::Null);
    assert_eq!(v["files"], serde_json::json!(["unsafe_overload.toml"]));
    for name in ["summary.json", "scenario.toml", "unsafe_overload.toml"] {
        assert!(out.join(name).is_file(), "{name}");
    }
    let sim = json_stdout(
        divertsim()
            .args(["simulate", "--json"])
            .arg(out.join("unsafe_overload.toml")),
    );
    let again = f(&sim["overload_ratio"]);
    assert!((again - ratio).abs() <= 1e-9 * ratio, "{again} vs {ratio}");
    let text = divertsim()
        .args(["check", PROPOSED, "-q"])
        .output()
        .unwrap();
    assert_eq!(text.status.code(), Some(4));
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(text.contains("EXCEEDS the limit 1"), "{text}");
    assert!(text.contains("verdict: UNSAFE"), "{text}");
}

/// Issue 47: `check` searches the heights of the mix it runs. On a scenario without a
/// `[mix]` that is `reliability`'s default (the paper's class, 0.1–0.3 m tall): the search
/// finds a tall narrow parcel that tips over at the robust optimum's setting, as
/// `reliability` does, the setting is UNSAFE, and `simulate` tips the written parcel again.
#[test]
fn check_searches_the_heights_of_its_mix_and_finds_a_tip_over() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c");
    let run = divertsim()
        .args([
            "check",
            ROBUST,
            "--set",
            "mix.height={kind=\"uniform\", min=0.1, max=0.3}",
            "--samples",
            "2000",
            "--json",
            "-q",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(4));
    let v: Value = serde_json::from_slice(&run.stdout).unwrap();
    assert_eq!(v["verdict"], "unsafe", "{v}");
    assert_eq!(v["divert"]["status"], "fails");
    assert_eq!(v["divert"]["reason"], "tipped");
    assert_eq!(
        v["divert"]["class_heights_m"],
        serde_json::json!([0.1, 0.3])
    );
    let h = f(&v["divert"]["pose"]["height"]);
    assert!((0.1..=0.3).contains(&h), "{h}");
    assert_eq!(v["mix"]["source"], "scenario");
    assert!(f(&v["mix"]["tipped_rate"]["estimate"]) > 0.0);
    let sim = json_stdout(
        divertsim()
            .args(["simulate", "--json"])
            .arg(out.join("unsafe_divert.toml")),
    );
    assert_eq!(sim["tipping"]["tipped"], true, "{sim}");
    // Stated heights win over the mix's: a class of flat parcels does not tip.
    let flat = json_stdout(divertsim().args([
        "check",
        ROBUST,
        "--set",
        "mix.height={kind=\"uniform\", min=0.1, max=0.3}",
        "--set",
        "design.search.height=[0.1, 0.12]",
        "--samples",
        "0",
        "--json",
        "-q",
    ]));
    assert_eq!(flat["divert"]["status"], "passes", "{flat}");
    assert_eq!(
        flat["divert"]["class_heights_m"],
        serde_json::json!([0.1, 0.12])
    );
}

/// The robust optimum is safe: exit 0, nothing failing written.
#[test]
fn check_finds_the_robust_optimum_safe() {
    let v = json_stdout(divertsim().args(["check", ROBUST, "--json", "-q"]));
    assert_eq!(v["verdict"], "safe", "{v}");
    assert!(f(&v["overload"]["largest_ratio"]) <= 1.0);
    assert!(f(&v["divert"]["smallest_reserve_m"]) >= 0.005);
    assert_eq!(v["files"], serde_json::json!([]));
    // A margin larger than its reserve makes it marginal, still exit 0.
    let v = json_stdout(divertsim().args([
        "check",
        ROBUST,
        "--json",
        "-q",
        "--overload-margin",
        "0.05",
    ]));
    assert_eq!(v["verdict"], "marginal");
    assert_eq!(v["overload"]["status"], "marginal");
}

#[test]
fn check_refuses_bad_options_with_exit_2() {
    for (args, flag) in [
        (&["--reserve-margin", "-1"][..], "--reserve-margin"),
        (&["--overload-margin", "2"][..], "--overload-margin"),
        (&["--search-budget", "1"][..], "--search-budget"),
    ] {
        let out = divertsim()
            .arg("check")
            .arg(ROBUST)
            .args(args)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(flag), "{args:?}: {err}");
    }
}

/// A parcel of the mix that tips over fails the check (issue 47): the robust optimum, SAFE
/// for the paper's parcels, is UNSAFE against a mix with parcels up to 0.4 m tall, and the
/// first tipped parcel is written as unsafe_tipping.toml, which `simulate` tips again.
#[test]
fn a_mix_parcel_that_tips_over_makes_the_setting_unsafe() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c");
    let run = divertsim()
        .args([
            "check",
            "../../configs/paper/mix.toml",
            "--set",
            "machine.belt_speed=1.0002",
            "--set",
            "machine.cycle_time=1.4776",
            "--set",
            "machine.start_position=0.7046",
            "--set",
            "mix.height={kind=\"uniform\", min=0.1, max=0.4}",
            "--samples",
            "2000",
            "--json",
            "-q",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(
        run.status.code(),
        Some(4),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let v: Value = serde_json::from_slice(&run.stdout).unwrap();
    assert_eq!(v["verdict"], "unsafe", "{v}");
    assert_eq!(v["mix"]["status"], "fails");
    assert!(f(&v["mix"]["tipped_rate"]["estimate"]) > 0.0);
    assert_eq!(
        v["files"],
        serde_json::json!(["unsafe_divert.toml", "unsafe_tipping.toml"])
    );
    let sim = json_stdout(
        divertsim()
            .args(["simulate", "--json"])
            .arg(out.join("unsafe_tipping.toml")),
    );
    assert_eq!(sim["outcome"], "not_diverted", "{sim}");
    assert_eq!(sim["tipping"]["tipped"], true, "{sim}");
}
