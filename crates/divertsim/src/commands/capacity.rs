//! `divertsim capacity`: the capacity map W(t_c, S_d) by the paper's §4.2 algorithm (paper
//! Fig. 9), computed by `divertsim_core::analysis::paper::capacity` over the scenario's `[design]`
//! set; a table, capacity.csv, a heat map capacity.svg, or JSON.

use divertsim_api::analyses::capacity::{Capacity, CapacityResult};
use divertsim_core::analysis::paper::capacity::CapacityMap;

use super::analysis::{self, OptionArgs, View};
use super::common::{self, OutputArgs, ScenarioArgs};
use divertsim_api::analyses::worst_case::pose_text;
use divertsim_core::analysis::design::robust::RobustMap;
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

/// The rounds of a robust map, for the table.
pub fn robust_text(r: &RobustMap) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "against the searched worst case: {} round{}, {}",
        r.rounds.len(),
        if r.rounds.len() == 1 { "" } else { "s" },
        if r.converged {
            "converged (no violating pose at any feasible cell's setting)"
        } else {
            "NOT converged (raise --rounds): some feasible cells may not hold"
        }
    );
    for (k, m) in r.rounds.iter().enumerate() {
        let _ = writeln!(
            s,
            "  round {}: {} worst poses, {} settings verified, {} poses added, {} simulations",
            k + 1,
            m.poses,
            m.verified,
            m.added,
            m.simulations
        );
    }
    for (k, p) in r.set.worst_poses.iter().enumerate() {
        let _ = writeln!(s, "  worst{}: {}", k + 1, pose_text(p));
    }
    s
}

/// The readable table: W [parcels/h] with S_d down and t_c across; "x" marks no feasible
/// setting.
pub fn table(map: &CapacityMap) -> String {
    use std::fmt::Write;
    let o = &map.options;
    let nsd = o.light_barriers.len();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "capacity W [parcels/h] by the paper's §4.2 algorithm; x = no feasible (v, R_s)"
    );
    let _ = write!(s, "{:>9} |", "S_d \\ t_c");
    for tc in &o.cycle_times {
        let _ = write!(s, "{tc:>6.3}");
    }
    let _ = writeln!(s);
    let _ = writeln!(s, "{}", "-".repeat(11 + 6 * o.cycle_times.len()));
    for (j, sd) in o.light_barriers.iter().enumerate().rev() {
        let _ = write!(s, "{sd:>9.3} |");
        for i in 0..o.cycle_times.len() {
            let c = &map.cells[i * nsd + j];
            if c.feasible {
                let _ = write!(s, "{:>6.0}", c.capacity);
            } else {
                let _ = write!(s, "{:>6}", "x");
            }
        }
        let _ = writeln!(s);
    }
    let feasible = map.cells.iter().filter(|c| c.feasible).count();
    let _ = writeln!(
        s,
        "feasible cells: {feasible} of {}; simulations: {}",
        map.cells.len(),
        map.simulations
    );
    match map.best() {
        Some(b) => {
            let _ = writeln!(
                s,
                "best: W = {:.1} parcels/h at t_c = {} s, S_d = {} m with v = {} m/s, R_s = {:.4} m (overload ratio {:.3})",
                b.capacity,
                b.cycle_time,
                b.light_barrier,
                b.belt_speed.unwrap_or(f64::NAN),
                b.start_position.unwrap_or(f64::NAN),
                b.overload_ratio.unwrap_or(f64::NAN)
            );
        }
        None => {
            let _ = writeln!(s, "no feasible setting anywhere on the grid");
        }
    }
    s
}

/// `divertsim capacity`.
pub fn run(args: &CapacityArgs) -> i32 {
    analysis::run::<Capacity>(
        &args.scenario,
        Some(&args.resume),
        &args.output,
        &args.options,
        View::new(
            &|r: &CapacityResult, _, _| {
                let mut t = table(&r.map);
                if let Some(rm) = &r.robust {
                    t += &robust_text(rm);
                }
                t
            },
            &|r: &CapacityResult, path| draw(&r.map, path).map_err(|e| e.to_string()),
        ),
    )
}
