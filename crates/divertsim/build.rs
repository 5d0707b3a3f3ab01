//! Which optional test suites this machine can run, as cfgs, so that a suite it cannot run
//! is reported by the test runner as ignored, with its reason, instead of passing silently:
//! - `divertsim_no_chromium`: no headless Chromium on PATH (and CI does not insist on one
//!   through DIVERTSIM_REQUIRE_CHROMIUM): the browser tests of the HTML reports;
//! - `divertsim_no_python_tests`: DIVERTSIM_PYTHON_TESTS is not set: the Python package's
//!   suite (minutes of building and installing that a plain `cargo test` does not impose);
//! - `divertsim_no_example_tests`: DIVERTSIM_EXAMPLE_TESTS is not set: every README and
//!   `--help` example run as written (minutes);
//! - `divertsim_no_mount`: not root, or no `mount` on PATH: the test that mounts a small
//!   tmpfs (a root that still may not mount, in a container, is told at run time).
//!
//! The binary itself never depends on them.

fn main() {
    println!("cargo::rustc-check-cfg=cfg(divertsim_no_chromium)");
    println!("cargo::rustc-check-cfg=cfg(divertsim_no_python_tests)");
    println!("cargo::rustc-check-cfg=cfg(divertsim_no_mount)");
    println!("cargo::rustc-check-cfg=cfg(divertsim_no_example_tests)");
    println!("cargo::rerun-if-env-changed=DIVERTSIM_EXAMPLE_TESTS");
    println!("cargo::rerun-if-env-changed=PATH");
    println!("cargo::rerun-if-env-changed=DIVERTSIM_REQUIRE_CHROMIUM");
    println!("cargo::rerun-if-env-changed=DIVERTSIM_PYTHON_TESTS");
    let path = std::env::var_os("PATH").unwrap_or_default();
    // Installing a browser adds a file to a directory on PATH without changing PATH: watch
    // the directories themselves (their own mtime moves when an entry is added), so the
    // browser tests run once one is installed (issue 50).
    for dir in std::env::split_paths(&path).filter(|d| d.is_absolute() && d.is_dir()) {
        println!("cargo::rerun-if-changed={}", dir.display());
    }
    let chromium = std::env::split_paths(&path).any(|d| {
        ["chromium", "chromium-browser", "google-chrome"]
            .iter()
            .any(|n| d.join(n).is_file())
    });
    // Where CI insists, the tests run and a missing browser fails them.
    if !chromium && std::env::var_os("DIVERTSIM_REQUIRE_CHROMIUM").is_none() {
        println!("cargo::rustc-cfg=divertsim_no_chromium");
    }
    if std::env::var_os("DIVERTSIM_PYTHON_TESTS").is_none() {
        println!("cargo::rustc-cfg=divertsim_no_python_tests");
    }
    if std::env::var_os("DIVERTSIM_EXAMPLE_TESTS").is_none() {
        println!("cargo::rustc-cfg=divertsim_no_example_tests");
    }
    let root = std::fs::read_to_string("/proc/self/status").is_ok_and(|s| {
        s.lines()
            .find(|l| l.starts_with("Uid:"))
            .and_then(|l| l.split_whitespace().nth(2))
            == Some("0")
    });
    let mount = std::env::split_paths(&path).any(|d| d.join("mount").is_file());
    if !(root && mount) {
        println!("cargo::rustc-cfg=divertsim_no_mount");
    }
}
