//! Settings that hold against the searched worst case: rounds of a method's run and a
//! worst-case search at its best point (`divertsim_core::analysis::design::robust`).

use super::*;

/// The robust rounds of a single run against the searched worst case (a design set with
/// `WorstDefinition::Search`).
pub struct RobustRun {
    pub optimum: RobustOptimum,
    pub settings: RobustSettings,
}

/// Optimise against the searched worst case: rounds of `run_method` and a worst-case search
/// at its best point ([`robust_optimize`]). `new_round` is called before each round's solver
/// run (an edge's progress bar grows by a round). Returns the last round's problem and run.
pub fn run_robust(
    loaded: &Loaded,
    bounds: &Bounds,
    method: Method,
    settings: &MethodSettings,
    robust: &RobustSettings,
    ctx: &RunContext<'_>,
    new_round: &dyn Fn(),
) -> Result<(SettingsProblem, RunOutcome, RobustRun), OptimizeError> {
    let objectives = objectives_of(method);
    let make = |set: DesignSet| {
        SettingsProblem::new(loaded.scenario.clone(), set, bounds.clone(), objectives)
    };
    let mut last: Option<RunOutcome> = None;
    let mut solve = |p: &SettingsProblem| {
        new_round();
        let run = run_method(p, settings, ctx)?;
        let result = run.result.clone();
        last = Some(run);
        Ok(result)
    };
    let optimum = robust_optimize(
        &loaded.scenario,
        &loaded.design,
        robust,
        &make,
        &mut solve,
        ctx.progress,
    )?;
    // The last round's problem: the pose set it was solved against.
    let problem = make(optimum.solved.clone())?;
    let run = last.ok_or_else(|| OptimizeError::InvalidSetting {
        name: "rounds",
        reason: "no round ran".into(),
    })?;
    Ok((
        problem,
        run,
        RobustRun {
            optimum,
            settings: robust.clone(),
        },
    ))
}

/// The names of the worst-pose constraints that are active at the last round's best point
/// (its evaluation is in the solver's result: `problem` is that round's).
pub fn active_poses(problem: &SettingsProblem, rr: &RobustRun) -> Vec<String> {
    problem
        .constraint_names()
        .iter()
        .zip(&rr.optimum.last().result.best.constraints)
        .filter(|(n, g)| n.starts_with("divert:worst") && g.abs() <= ACTIVE_TOLERANCE)
        .map(|(n, _)| n.clone())
        .collect()
}

/// The rounds of a robust run as JSON.
pub fn robust_json(problem: &SettingsProblem, rr: &RobustRun) -> Value {
    let o = &rr.optimum;
    let set = problem.design_set();
    let last = o.last();
    json!({
        "converged": o.converged,
        "rounds": o.rounds.iter().map(|r| {
            let v = &r.verification;
            json!({
                "poses": r.poses,
                "best_x": r.result.best_x,
                "capacity": capacity_of(&r.result.best_x),
                "feasible_on_pose_set": r.result.best.feasible(),
                "searched_overload_ratio": v.impulse.value,
                "searched_reserve": v.reserve.value,
                "violating_poses": v.violating.len(),
            })
        }).collect::<Vec<_>>(),
        "search": {
            "evaluations": rr.settings.search.evaluations,
            "starts": rr.settings.search.starts,
            "seed": rr.settings.search.seed,
        },
        "scatter": {
            "belt_speed": rr.settings.scatter.belt_speed,
            "phase": rr.settings.scatter.phase,
            "belt_friction": rr.settings.scatter.belt_friction,
        },
        "overload_excess": last.verification.overload_excess(set),
        "divert_shortfall": last.verification.divert_shortfall(set),
        "torque_excess": last.verification.torque_excess(set),
        "worst_impulse_pose": pose_json(&last.verification.impulse.pose),
        "worst_reserve_pose": pose_json(&last.verification.reserve.pose),
        "poses": set.worst_poses.iter().map(pose_json).collect::<Vec<_>>(),
        "active_poses": active_poses(problem, rr),
    })
}
