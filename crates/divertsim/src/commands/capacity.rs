//! `divertsim capacity`: the capacity map W(t_c, S_d) by the paper's §4.2 algorithm (paper
//! Fig. 9), computed by `divertsim_core::analysis::design::capacity` over the scenario's `[design]`
//! set; a table, capacity.csv, a heat map capacity.svg, or JSON.

use divertsim_api::analyses::capacity::{self, Capacity, CapacityResult};

use super::analysis::{self, View};
use super::common::{self, OutputArgs, ScenarioArgs};
use crate::flags::OptionArgs;
use divertsim_figures::capacity::draw;

/// Compute the capacity map over a grid of cycle times and light-barrier positions.
#[derive(Debug, Clone, clap::Args)]
pub struct CapacityArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub resume: common::ResumeArgs,
    #[command(flatten)]
    pub options: OptionArgs<Capacity>,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// `divertsim capacity`.
pub fn run(args: &CapacityArgs) -> i32 {
    analysis::run::<Capacity>(
        &args.scenario,
        Some(&args.resume),
        &args.output,
        &args.options,
        View::new(&|r: &CapacityResult, path| {
            draw(&r.map, capacity::against(r.worst()), path).map_err(|e| e.to_string())
        }),
    )
}
