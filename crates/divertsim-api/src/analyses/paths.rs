//! Several scenarios simulated side by side (the paper's Figs 3, 6–8 and 13–15: where the
//! slender and the compact parcel go at the documented and at the optimised setting). The
//! cases run in parallel with their order kept ([`super::runs`]), so results do not depend
//! on the number of threads.

use divertsim_core::model::params::Scenario;
use divertsim_core::run::sweep::{par_map, Progress};
use divertsim_core::sim::{simulate, SimResult};
use serde_json::{json, Value};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One simulated case.
#[derive(Debug, Clone)]
pub struct PathCase {
    /// The scenario file it came from.
    pub file: PathBuf,
    /// Its name: the `--label` text, or the file stem.
    pub name: String,
    /// The scenario it ran (file + `--set`).
    pub scenario: Scenario,
    /// The run.
    pub result: SimResult,
}

impl PathCase {
    /// The legend label: the name and the outcome.
    pub fn legend(&self) -> String {
        format!("{}: {}", self.name, self.result.outcome.label())
    }
}

/// The name of a case without a `--label`: the file stem.
pub fn default_name(file: &Path) -> String {
    file.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| file.display().to_string())
}

/// Simulate every (file, name, scenario) in parallel, results in input order.
pub fn compute(inputs: Vec<(PathBuf, String, Scenario)>, progress: Progress<'_>) -> Vec<PathCase> {
    let results = par_map(&inputs, progress, |(_, _, s)| simulate(s));
    inputs
        .into_iter()
        .zip(results)
        .map(|((file, name, scenario), result)| PathCase {
            file,
            name,
            scenario,
            result,
        })
        .collect()
}

/// `paths.csv`: one row per trajectory sample of every case (case, t \[s], x \[m], y \[m],
/// phi_deg \[deg], stage), the cases in order.
pub fn csv(cases: &[PathCase]) -> Result<Vec<u8>, csv::Error> {
    let rows: Vec<Vec<String>> = cases
        .iter()
        .flat_map(|c| {
            c.result.trajectory.iter().map(move |s| {
                vec![
                    c.name.clone(),
                    s.state.t.to_string(),
                    s.state.x.to_string(),
                    s.state.y.to_string(),
                    s.state.phi.to_degrees().to_string(),
                    s.stage.label().to_string(),
                ]
            })
        })
        .collect();
    crate::output::csv_bytes(&["case", "t_s", "x_m", "y_m", "phi_deg", "stage"], &rows)
}

/// The readable table: one line per case.
pub fn text(cases: &[PathCase]) -> String {
    let width = cases
        .iter()
        .map(|c| c.name.chars().count())
        .max()
        .unwrap_or(4)
        .max(4);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<width$}  {:<26}  {:>11}  stages",
        "case", "outcome", "max y [m]"
    );
    for c in cases {
        let verdict = c.result.outcome.verdict();
        let stages: Vec<&str> = c.result.stages.iter().map(|x| x.label()).collect();
        let _ = writeln!(
            s,
            "{:<width$}  {:<26}  {:>11.4}  {}",
            c.name,
            verdict,
            c.result.max_lateral,
            stages.join(" → ")
        );
    }
    s
}

/// The `--json` object: `{"cases": [{file, label, outcome, reason, max_lateral, stages}]}`.
pub fn json(cases: &[PathCase]) -> Value {
    json!({
        "cases": cases.iter().map(|c| json!({
            "file": c.file.display().to_string(),
            "label": c.name,
            "outcome": c.result.outcome.label(),
            "reason": c.result.outcome.reason(),
            "max_lateral": c.result.max_lateral,
            "stages": c.result.stages.iter().map(|s| s.label()).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
    })
}
