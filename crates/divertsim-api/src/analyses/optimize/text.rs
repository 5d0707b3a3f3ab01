//! The optimisation's readable reports: one run (the best setting, its constraints and
//! margins), the rounds against the searched worst case, the paper experiment's table and
//! the method comparison with medians. What the CLI prints and Python's `text` holds.

use super::*;
use crate::analyses::poses::against_limit;
use crate::analyses::poses::pose_text;
use divertsim_core::analysis::design::design_set::{DesignEvaluation, WorstDefinition};
use divertsim_core::analysis::design::settings_problem::SettingsProblem;
use divertsim_core::sim::Outcome;

/// A line for a best point on the box's bounds (none inside it): which variable, which end,
/// and the `bounds` to widen.
pub fn bounds_note(problem: &SettingsProblem, best: &BestReport) -> String {
    let on = super::tables::on_bounds(problem, best);
    if on.is_empty() {
        return String::new();
    }
    let b = problem.bounds();
    let each: Vec<String> = on
        .iter()
        .map(|&(i, upper)| {
            format!(
                "{} = {:.4} {} at its {} bound {}",
                SYMBOLS[i],
                best.x[i],
                UNITS[i],
                if upper { "upper" } else { "lower" },
                if upper { b.upper[i] } else { b.lower[i] }
            )
        })
        .collect();
    let names: Vec<String> = on
        .iter()
        .map(|&(i, _)| {
            format!(
                "{}=LO:HI",
                divertsim_core::analysis::design::settings_problem::VARIABLES[i]
            )
        })
        .collect();
    format!(
        "on the box's edge: {}; the best setting may lie past it: widen `bounds` ({}) to look\n",
        each.join(", "),
        names.join(",")
    )
}

pub fn report_text(run: &RunOutcome, best: &BestReport) -> String {
    use std::fmt::Write;
    let r = &run.result;
    let mut s = String::new();
    let _ = writeln!(s, "method: {}", run.method.name());
    let point: Vec<String> = (0..4)
        .map(|i| format!("{} = {:.4} {}", SYMBOLS[i], best.x[i], UNITS[i]))
        .collect();
    let _ = writeln!(
        s,
        "best point: {} ({})",
        point.join(", "),
        if best.feasible {
            "feasible".to_string()
        } else {
            format!("INFEASIBLE, violation {:.4}", best.violation)
        }
    );
    let _ = writeln!(s, "capacity W = {:.1} parcels/h", best.capacity);
    // The overload constraint is g = S/S_fall − (1 − margin): its limit, margin included.
    let limit = |ratio: f64| {
        let g = best.constraints.iter().find(|(n, _)| n == "overload");
        g.map_or(1.0, |(_, g)| ((ratio - g) * 1e9).round() / 1e9)
    };
    match best.design.worst {
        WorstDefinition::Paper => {
            if let Ok(o) = &best.design.overload {
                let _ = writeln!(
                    s,
                    "overload ratio S/S_fall = {:.4} (the paper's worst case), {}",
                    o.ratio,
                    against_limit(o.ratio, limit(o.ratio))
                );
            }
        }
        WorstDefinition::Search => {
            let held = limit(best.design.overload_ratio);
            let slack = divertsim_core::analysis::design::robust::SLACK;
            let _ = writeln!(
                s,
                "overload ratio S/S_fall = {:.4} (largest over the design parcels and worst poses), {} (= 1 − the overload margin {} − {slack}: the rounds keep {slack} in hand so that the longer search at the optimum stays within 1 − margin){}",
                best.design.overload_ratio,
                against_limit(best.design.overload_ratio, held),
                ((1.0 - held - slack) * 1e9).round() / 1e9 + 0.0,
                best.design
                    .overload
                    .as_ref()
                    .map_or(String::new(), |o| format!("; the paper's worst case: {:.4}", o.ratio))
            );
        }
    }
    // The torque is computed only under a limit; g = T/T_max − 1 gives that limit back.
    if let Some(torque) = best.design.drive_torque {
        let limit = torque / (1.0 + best.design.torque_margin);
        let _ = writeln!(
            s,
            "peak drive torque = {:.3} N·m (largest over the design parcels and worst poses), {} the limit {:.3} N·m",
            torque,
            if best.design.torque_margin <= 0.0 { "within" } else { "EXCEEDS" },
            limit
        );
    }
    let _ = writeln!(
        s,
        "active constraints (|g| <= {ACTIVE_TOLERANCE}): {}",
        if best.active.is_empty() {
            "none".to_string()
        } else {
            best.active.join(", ")
        }
    );
    for (n, g) in &best.constraints {
        let _ = writeln!(s, "  g {n:<20} = {g:+.5}");
    }
    if let Some((n, g)) = &best.worst_parcel {
        let _ = writeln!(s, "worst parcel: {n} (divert constraint {g:+.5} m: {})", {
            // g = the margin held − the reserve d.
            let reserve = best
                .design
                .cases
                .iter()
                .find(|c| &c.name == n)
                .map(|c| c.overshoot);
            match reserve {
                Some(d) if d >= 0.0 => format!(
                    "diverted with {d:.4} m reserve, {} the margin held {:.4} m",
                    if *g <= 0.0 { "within" } else { "BELOW" },
                    d + g
                ),
                Some(d) => format!("left {:.4} m short of P_max", -d),
                None if *g <= 0.0 => "diverted".to_string(),
                None => "not diverted with the margin held".to_string(),
            }
        });
    }
    if let Some(front) = &run.front {
        let _ = writeln!(s, "Pareto front: {} points", front.len());
    }
    let _ = writeln!(
        s,
        "evaluations: {}, first feasible: {}, feasible: {}, wall time {:.2} s",
        r.evaluations,
        r.first_feasible
            .map_or("none".to_string(), |i| i.to_string()),
        r.feasible_count,
        run.wall_time
    );
    s
}

/// The paper experiment's table.
pub fn paper_table(runs: &[PaperRun], paper_point: &DesignEvaluation) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<11} {:<38} {:>7} {:>6} {:>6} {:>8} {:>5} {:>6} {:>6} {:>6} {:>7}",
        "run", "setup", "v", "t_c", "R_s", "W [/h]", "feas", "evals", "n_feas", "first", "time_s"
    );
    for r in runs {
        let res = &r.outcome.result;
        let _ = writeln!(
            s,
            "{:<11} {:<38} {:>7.4} {:>6.4} {:>6.4} {:>8.1} {:>5} {:>6} {:>6} {:>6} {:>7.2}",
            r.label,
            r.description,
            r.best.x[0],
            r.best.x[1],
            r.best.x[2],
            r.best.capacity,
            if r.best.feasible { "yes" } else { "no" },
            res.evaluations,
            res.feasible_count,
            res.first_feasible
                .map_or("-".to_string(), |i| i.to_string()),
            r.outcome.wall_time
        );
    }
    let g = PAPER_GA_OPTIMUM;
    let w_lo = 3600.0 / (g[2].1 / g[0].0 + g[1].1);
    let w_hi = 3600.0 / (g[2].0 / g[0].1 + g[1].0);
    let _ = writeln!(
        s,
        "paper GA optimum: v {}-{} m/s, t_c {}-{} s, R_s {}-{} m (W {:.0}-{:.0} /h); 8 feasible evaluations in 100 x 80",
        g[0].0, g[0].1, g[1].0, g[1].1, g[2].0, g[2].1, w_lo, w_hi
    );
    let diverted: Vec<String> = paper_point
        .cases
        .iter()
        .map(|c| {
            format!(
                "{} {}",
                c.name,
                if c.outcome == Outcome::Diverted {
                    "diverted"
                } else {
                    "NOT diverted"
                }
            )
        })
        .collect();
    let _ = writeln!(
        s,
        "paper proposed: v 2, t_c 1.36, R_s 0 (W {:.1} /h); on this machine: {} ({}; overload ratio {})",
        paper_point.capacity,
        if paper_point.feasible { "feasible" } else { "infeasible" },
        diverted.join(", "),
        paper_point
            .overload
            .as_ref()
            .map_or("-".to_string(), |o| format!("{:.3}", o.ratio))
    );
    s
}

/// The comparison's table (medians per method).
pub fn compare_table(rows: &[CompareRow], best_known: f64) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let f = |v: Option<f64>, p: usize| v.map_or("-".to_string(), |x| format!("{x:.p$}"));
    let _ = writeln!(
        s,
        "best known feasible capacity: {best_known:.2} parcels/h; medians over {} seeds",
        rows.iter()
            .filter(|r| r.method == Method::Ga)
            .count()
            .max(1)
    );
    let _ = writeln!(
        s,
        "{:<9} {:>10} {:>12} {:>14} {:>8} {:>9} {:>6}",
        "method", "best W", "1st feasible", "within 0.5 %", "evals", "time [s]", "front"
    );
    for m in COMPARE_METHODS {
        if !rows.iter().any(|r| r.method == m) {
            continue;
        }
        let md = method_medians(rows, m);
        let _ = writeln!(
            s,
            "{:<9} {:>10} {:>12} {:>14} {:>8} {:>9} {:>6}",
            m.name(),
            f(md[0], 1),
            f(md[1], 0),
            f(md[2], 0),
            f(md[3], 0),
            f(md[4], 2),
            f(md[5], 0)
        );
    }
    let ga = method_medians(rows, Method::Ga)[2];
    for m in [Method::De, Method::Cmaes] {
        let other = method_medians(rows, m)[2];
        if let (Some(a), Some(b)) = (ga, other) {
            let _ = writeln!(
                s,
                "GA / {}: {:.1}x fewer evaluations to within 0.5 % of the best",
                m.name(),
                a / b
            );
        }
    }
    s
}

/// The rounds of a robust run, for the table.
pub fn robust_text(problem: &SettingsProblem, rr: &RobustRun) -> String {
    use std::fmt::Write;
    let o = &rr.optimum;
    let set = problem.design_set();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "robust against the searched worst case: {} round{}, {}",
        o.rounds.len(),
        if o.rounds.len() == 1 { "" } else { "s" },
        if o.converged {
            "converged (the search at the optimum finds no violating pose)"
        } else if o.rounds.len() < rr.settings.max_rounds && !o.last().result.best.feasible() {
            "NOT converged: no setting within the bounds holds against the worst poses found \
             (the best point violates them); relax the margins or widen the bounds"
        } else {
            "NOT converged (raise --rounds)"
        }
    );
    for (k, r) in o.rounds.iter().enumerate() {
        let x = &r.result.best_x;
        let _ = writeln!(
            s,
            "  round {}: {} worst poses, best v = {:.4}, t_c = {:.4}, R_s = {:.4}, W = {:.1}; searched S/S_fall = {:.4}, reserve = {:.4} m, {} violating pose(s)",
            k + 1,
            r.poses,
            x[0],
            x[1],
            x[2],
            capacity_of(x),
            r.verification.impulse.value,
            r.verification.reserve.value,
            r.verification.violating.len()
        );
    }
    for (k, p) in set.worst_poses.iter().enumerate() {
        let _ = writeln!(s, "  worst{}: {}", k + 1, pose_text(p));
    }
    let active = active_poses(problem, rr);
    let _ = writeln!(
        s,
        "active worst poses: {}",
        if active.is_empty() {
            "none".to_string()
        } else {
            active.join(", ")
        }
    );
    s
}
