//! `divertsim worst-case`: the searched worst case of one machine setting (issue 10): the
//! largest impulse and the smallest divert reserve over the `[design.search]` pose box, by
//! `divertsim_core::analysis::design::worst_case`, next to the paper's closed-form definition; the
//! worst poses as scenario files that `simulate` reproduces exactly. Also the search options
//! that `overload --search`, `capacity` and `optimize` share.

use divertsim_core::analysis::design::design_set::{Margins, WorstDefinition};
use divertsim_core::analysis::design::robust::RobustSettings;
// Until optimize takes them from the api directly.
use divertsim_api::analyses::worst_case::{
    self as api, pose_toml, WorstCaseReport, WorstCaseSearch,
};
use divertsim_api::config::Loaded;
use divertsim_core::analysis::design::worst_case::{Scatter, SearchSettings};
use divertsim_core::sim::simulate;
use std::path::Path;

use super::analysis::{self, OptionArgs, View};
use super::common::{self, OutputArgs, ScenarioArgs};
use divertsim_api::config::Problem;
use divertsim_api::output;
use divertsim_figures::plot::{self, PlotOptions};

/// Budget and seed of the worst-case search.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are --help text: [m] is a unit
#[derive(Debug, Clone, clap::Args)]
pub struct SearchArgs {
    /// Simulations per worst-case search (split over the starts, 10 % for the final
    /// refinement).
    #[arg(long, value_name = "N", default_value_t = 2400,
          value_parser = clap::value_parser!(u64).range(100..=10_000_000))]
    pub search_budget: u64,
    /// Independent DE starts per search.
    #[arg(long, value_name = "N", default_value_t = 3,
          value_parser = clap::value_parser!(u64).range(1..=100))]
    pub search_starts: u64,
    /// Seed of the search.
    #[arg(long, value_name = "SEED", default_value_t = 1)]
    pub search_seed: u64,
}

impl SearchArgs {
    /// The core's settings ([`api::search_settings`]).
    pub fn settings(&self) -> SearchSettings {
        api::search_settings(self.search_budget, self.search_starts, self.search_seed)
    }

    /// Problems with the combination (each start needs a population's worth).
    pub fn problems(&self) -> Vec<Problem> {
        common::flags(api::check_search(self.search_budget, self.search_starts))
    }
}

/// An api problem keyed by its flag.
fn flag(p: Problem) -> Problem {
    common::flags(vec![p]).remove(0)
}

/// The worst-case definition on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum WorstArg {
    /// The paper's closed-form tip strike on the [design.overload] parcel.
    Paper,
    /// The searched worst case over [design.search].
    Search,
}

impl WorstArg {
    /// The core's definition.
    pub fn definition(self) -> WorstDefinition {
        match self {
            WorstArg::Paper => WorstDefinition::Paper,
            WorstArg::Search => WorstDefinition::Search,
        }
    }
}

/// What the constraints of `capacity` and `optimize` hold against.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are --help text: [m] is a unit
#[derive(Debug, Clone, clap::Args)]
pub struct RobustArgs {
    /// The worst case the constraints hold against: "search" (the default for capacity and
    /// single optimisations: the searched worst impulse and divert reserve over
    /// [design.search], by rounds that add the violating poses the search finds at the
    /// result) or "paper" (the closed-form tip strike of the paper; the only choice with
    /// optimize --paper-experiment and --compare).
    #[arg(long, value_enum)]
    pub worst: Option<WorstArg>,
    /// Safety margins: overload=RATIO (S/S_fall ≤ 1 − RATIO), divert=M (divert reserve ≥ M
    /// metres), e.g. overload=0.1,divert=0.02.
    #[arg(long, value_name = "NAME=VALUE,...")]
    pub margin: Option<String>,
    /// Require feasibility under scatter (with --worst search): belt_speed=REL,phase=SECONDS,
    /// belt_friction=REL, e.g. belt_speed=0.02,phase=0.01,belt_friction=0.05.
    #[arg(long, value_name = "NAME=VALUE,...")]
    pub scatter: Option<String>,
    /// Largest number of rounds of optimisation (or map) and search (with --worst search).
    #[arg(long, value_name = "N", default_value_t = RobustSettings::default().max_rounds as u64,
          value_parser = clap::value_parser!(u64).range(1..=100))]
    pub rounds: u64,
    #[command(flatten)]
    pub search: SearchArgs,
}

impl RobustArgs {
    /// The chosen definition (`batch`: a mode that supports only the paper's), the margins,
    /// and the robust settings with `--worst search`; or every problem with the options.
    pub fn resolve(
        &self,
        batch: bool,
    ) -> Result<(WorstArg, Margins, Option<RobustSettings>), Vec<Problem>> {
        let mut problems = Vec::new();
        let margins = match self
            .margin
            .as_deref()
            .map(|t| api::parse_margins(t).map_err(flag))
        {
            None => Margins::default(),
            Some(Ok(m)) => m,
            Some(Err(p)) => {
                problems.push(p);
                Margins::default()
            }
        };
        let scatter = match self
            .scatter
            .as_deref()
            .map(|t| api::parse_scatter(t).map_err(flag))
        {
            None => Scatter::default(),
            Some(Ok(s)) => s,
            Some(Err(p)) => {
                problems.push(p);
                Scatter::default()
            }
        };
        let worst = match (self.worst, batch) {
            (Some(WorstArg::Search), true) => {
                problems.push(Problem {
                    key: "--worst".into(),
                    message: "search is not supported with --paper-experiment or --compare; allowed there: paper".into(),
                });
                WorstArg::Paper
            }
            (Some(w), _) => w,
            (None, true) => WorstArg::Paper,
            (None, false) => WorstArg::Search,
        };
        if self.scatter.is_some() && worst == WorstArg::Paper {
            problems.push(Problem {
                key: "--scatter".into(),
                message: "needs --worst search (the paper's closed-form strike has no scatter)"
                    .into(),
            });
        }
        if worst == WorstArg::Search {
            problems.extend(self.search.problems());
        }
        if !problems.is_empty() {
            return Err(problems);
        }
        let robust = (worst == WorstArg::Search).then(|| RobustSettings {
            search: self.search.settings(),
            scatter,
            max_rounds: self.rounds as usize,
            ..RobustSettings::default()
        });
        Ok((worst, margins, robust))
    }
}

/// Search the worst case of one setting.
#[derive(Debug, Clone, clap::Args)]
pub struct WorstCaseArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub options: OptionArgs<WorstCaseSearch>,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// The worst poses as scenario files that `simulate` reproduces, their trajectories, top
/// views and animations.
fn pose_files(report: &WorstCaseReport, loaded: &Loaded, staging: &Path) -> Result<(), String> {
    for w in [&report.impulse, &report.reserve] {
        let name = format!("worst_{}", w.objective.label());
        let toml = pose_toml(loaded, &report.setting, w)
            .map_err(|e| format!("cannot write {name}.toml: {e}"))?;
        let s = w.pose.scenario(&report.setting);
        let r = simulate(&s);
        let csv = output::trajectory_csv(&r)
            .map_err(|e| format!("cannot format {name}_trajectory.csv: {e}"))?;
        let write = |file: String, bytes: &[u8]| {
            std::fs::write(staging.join(&file), bytes).map_err(|e| format!("{file}: {e}"))
        };
        write(format!("{name}.toml"), toml.as_bytes())?;
        write(format!("{name}_trajectory.csv"), &csv)?;
        for ext in ["svg", "png"] {
            plot::top_view(
                &s,
                &r,
                &staging.join(format!("{name}.{ext}")),
                &PlotOptions::default(),
            )
            .map_err(|e| e.to_string())?;
        }
        // The worst run animated, with its resolved scenario.
        write(
            format!("{name}.html"),
            crate::report::single(&s, &r, &toml).as_bytes(),
        )?;
    }
    Ok(())
}

/// `divertsim worst-case`.
pub fn run(args: &WorstCaseArgs) -> i32 {
    analysis::run::<WorstCaseSearch>(
        &args.scenario,
        None,
        &args.output,
        &args.options,
        View {
            draw: None,
            files: Some(&pose_files),
            summary_file: "worst-case.json",
        },
    )
}
