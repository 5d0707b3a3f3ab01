//! Trigger calibration (paper Fig. 4, §4.1): for each belt speed v, the start position R_s
//! that gives the parcel the transverse displacement of the reference setting
//! (v = 0.65 m/s, t_c = 1.36 s, R_s = 0.8 m). The search is
//! `divertsim_core::analysis::paper::trigger`; this module checks the options, runs it and gives
//! its tidy table and JSON summary.

use crate::config::MachineConfig;
use crate::config::MOVING_BELT_SPEED;
use crate::config::{Loaded, Problem};
use crate::contract::{csv_table, Analysis, Error, Hooks, Interval, ValueList, Work};
use divertsim_core::analysis::paper::trigger::{
    self, TriggerCurve, TriggerError, TriggerPoint, TriggerSettings,
};
use divertsim_core::sim::Stage;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};
use std::fmt::Write as _;

/// Every problem with `settings` and `speeds`; keys are the option names
/// (`reference_speed`, …, `speeds`).
pub fn check(settings: &TriggerSettings, speeds: &[f64]) -> Vec<Problem> {
    let mut problems = Vec::new();
    problems.extend(check_speeds(speeds, "speeds"));
    let v = settings.reference_speed;
    problems.extend(range_problem(
        "reference_speed",
        v,
        MOVING_BELT_SPEED.contains(v),
        &MOVING_BELT_SPEED.range(),
    ));
    let tc = settings.reference_cycle;
    problems.extend(range_problem(
        "reference_cycle",
        tc,
        tc > 0.0 && tc <= 60.0,
        "(0, 60] s",
    ));
    let rs = settings.reference_start;
    problems.extend(range_problem(
        "reference_start",
        rs,
        (-10.0..=10.0).contains(&rs),
        "[-10, 10] m",
    ));
    let (lo, hi) = settings.search;
    if !(lo.is_finite() && hi.is_finite() && -10.0 <= lo && lo < hi && hi <= 10.0) {
        problems.push(Problem::new(
            "search",
            format!("{lo}:{hi}: expected MIN:MAX with −10 ≤ MIN < MAX ≤ 10 m"),
        ));
    }
    let h = settings.scan_step;
    problems.extend(range_problem(
        "scan_step",
        h,
        h > 0.0 && h <= 1.0,
        "(0, 1] m",
    ));
    let tol = settings.tolerance;
    problems.extend(range_problem(
        "tolerance",
        tol,
        (1e-9..=0.1).contains(&tol) && !(h.is_finite() && tol >= h),
        "[1e-9, 0.1] m and below the scan step",
    ));
    if h.is_finite() && h > 0.0 && (hi - lo) / h > 1e5 {
        problems.push(Problem::new(
            "scan_step",
            format!(
                "{h} m gives more than 100000 scan points over the search interval; allowed: ≥ {} m",
                (hi - lo) / 1e5
            ),
        ));
    }
    problems
}

/// Speeds are each in (0, 20] m/s, at least one and at most [`MAX_SPEEDS`].
pub fn check_speeds(speeds: &[f64], key: &str) -> Option<Problem> {
    if speeds.is_empty() || speeds.len() > MAX_SPEEDS {
        return Some(Problem::new(
            key,
            format!("{} speeds; allowed: 1 to {MAX_SPEEDS}", speeds.len()),
        ));
    }
    speeds
        .iter()
        .find(|v| !MOVING_BELT_SPEED.contains(**v))
        .map(|v| {
            Problem::new(
                key,
                format!(
                    "{v} is out of range; allowed: {}",
                    MOVING_BELT_SPEED.range()
                ),
            )
        })
}

/// Scenario keys that make the built-in default scenario the paper preset's machine
/// (configs/paper/machine.toml: its arm, four-bar drive and materials), on which the paper's
/// Figs 3–5 cases are set: the built-in machine is another one, on which the Fig. 3 reference
/// run is diverted and gives no target.
pub const PAPER_MACHINE_SETS: [&str; 8] = [
    "machine.arm_length=1.15",
    "machine.drive.kind=\"crank-rocker\"",
    "machine.drive.max_swing_deg=45.0",
    "machine.drive.coupler=0.3",
    "machine.drive.rocker=0.15",
    "materials.belt_friction=0.5",
    "materials.arm_friction=0.38",
    "materials.restitution=0.3",
];

/// The paper's machine ([`PAPER_MACHINE_SETS`]) followed by a figure's parcel keys: one
/// list of the machine for every figure's default sets.
pub const fn on_paper_machine<const P: usize, const N: usize>(
    parcel: [&'static str; P],
) -> [&'static str; N] {
    assert!(
        N == PAPER_MACHINE_SETS.len() + P,
        "N is the machine's keys and the parcel's"
    );
    let mut out = [""; N];
    let mut i = 0;
    while i < N {
        out[i] = if i < PAPER_MACHINE_SETS.len() {
            PAPER_MACHINE_SETS[i]
        } else {
            parcel[i - PAPER_MACHINE_SETS.len()]
        };
        i += 1;
    }
    out
}

/// Scenario keys that make the built-in default scenario the paper's Fig. 3 case (the slender
/// 0.7 × 0.1 × 0.1 m parcel, 1.5 kg, at ΔP = 0, φ = 0) on the paper's machine
/// ([`PAPER_MACHINE_SETS`]), applied before the user's `--set` when no scenario file is given.
pub const FIG3_PARCEL_SETS: [&str; 14] = on_paper_machine([
    "parcel.length=0.7",
    "parcel.width=0.1",
    "parcel.height=0.1",
    "parcel.mass=1.5",
    "parcel.offset=0.0",
    "parcel.angle_deg=0.0",
]);

/// Largest number of belt speeds in one list.
pub const MAX_SPEEDS: usize = 10_000;

pub fn range_problem(key: &str, v: f64, ok: bool, allowed: &str) -> Option<Problem> {
    (!(v.is_finite() && ok))
        .then(|| Problem::new(key, format!("{v} is out of range; allowed: {allowed}")))
}

/// "ride F1 F2 F5": the stages, space separated.
pub fn stage_list(stages: &[Stage]) -> String {
    stages
        .iter()
        .map(|s| s.label())
        .collect::<Vec<_>>()
        .join(" ")
}

/// The contact stages F5, F6 the run realises ("F5+F6": the labels of the paper's Fig. 4),
/// or "none".
pub fn stage_set(stages: &[Stage]) -> String {
    let mut set: Vec<&str> = [Stage::F5, Stage::F6]
        .iter()
        .filter(|s| stages.contains(s))
        .map(|s| s.label())
        .collect();
    if set.is_empty() {
        set.push("none");
    }
    set.join("+")
}

pub fn fmt_opt(v: Option<f64>, digits: usize) -> String {
    v.map_or_else(String::new, |x| format!("{x:.digits$}"))
}

/// trigger.csv: one row per speed, its chosen root (every root is in summary.json).
pub fn csv(curve: &TriggerCurve) -> Result<Vec<u8>, csv::Error> {
    let rows: Vec<Vec<String>> = curve
        .points
        .iter()
        .map(|p| {
            let r = p.root();
            vec![
                format!("{}", p.speed),
                fmt_opt(r.map(|r| r.start), 6),
                fmt_opt(r.map(|r| r.max_lateral), 6),
                fmt_opt(r.map(|r| r.max_lateral - curve.reference.max_lateral), 6),
                r.map_or("none".into(), |r| r.kind.label().into()),
                r.map_or(String::new(), |r| stage_set(&r.stages)),
                r.map_or(String::new(), |r| stage_list(&r.stages)),
                r.map_or(String::new(), |r| r.outcome.label().into()),
                r.map_or(String::new(), |r| r.outcome.reason().unwrap_or_default()),
                r.map_or(String::new(), |r| r.iterations.to_string()),
                p.simulations.to_string(),
                p.roots.len().to_string(),
            ]
        })
        .collect();
    crate::output::csv_bytes(
        &[
            "belt_speed_m_s",
            "start_position_m",
            "max_lateral_m",
            "residual_m",
            "root_kind",
            "stage_set",
            "stage_sequence",
            "outcome",
            "reason",
            "iterations",
            "simulations",
            "roots",
        ],
        &rows,
    )
}

/// The JSON object of `--json`.
pub fn json(curve: &TriggerCurve, settings: &TriggerSettings) -> Value {
    let r = &curve.reference;
    let point = |p: &TriggerPoint| {
        let root = p.root();
        json!({
            "speed": p.speed,
            "start_position": root.map(|r| r.start),
            "max_lateral": root.map(|r| r.max_lateral),
            "residual": root.map(|r| r.max_lateral - curve.reference.max_lateral),
            "root_kind": root.map(|r| r.kind.label()),
            "stage_set": root.map(|r| stage_set(&r.stages)),
            "stages": root.map(|r| r.stages.iter().map(|s| s.label()).collect::<Vec<_>>()),
            "outcome": root.map(|r| r.outcome.label()),
            "reason": root.and_then(|r| r.outcome.reason()),
            "iterations": root.map(|r| r.iterations),
            "simulations": p.simulations,
            "roots": p.roots.iter().map(|r| json!({
                "start_position": r.start,
                "max_lateral": r.max_lateral,
                "root_kind": r.kind.label(),
                "stage_set": stage_set(&r.stages),
                "outcome": r.outcome.label(),
            })).collect::<Vec<_>>(),
        })
    };
    json!({
        "reference": {
            "speed": r.speed,
            "cycle_time": r.cycle,
            "start_position": r.start,
            "max_lateral": r.max_lateral,
            "stages": r.stages.iter().map(|s| s.label()).collect::<Vec<_>>(),
            "outcome": r.outcome.label(),
            "reason": r.outcome.reason(),
        },
        "search": [settings.search.0, settings.search.1],
        "scan_step": settings.scan_step,
        "tolerance": settings.tolerance,
        "points": curve.points.iter().map(point).collect::<Vec<_>>(),
    })
}

/// Options of the trigger calibration (`divertsim trigger`, Python `analysis("trigger")`).
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are help text: [m] is a unit
#[derive(Debug, Clone, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default)]
pub struct TriggerOptions {
    /// Belt speeds v [m/s], each in (0, 20]: LO:HI:STEP (HI included), LO:HI/COUNT or A,B,C.
    pub speeds: ValueList,
    /// v of the reference setting [m/s], (0, 20].
    pub reference_speed: f64,
    /// t_c of the reference setting [s], (0, 60].
    pub reference_cycle: f64,
    /// R_s of the reference setting [m], [−10, 10].
    pub reference_start: f64,
    /// Bisection tolerance on R_s [m], [1e-9, 0.1] and below the scan step.
    pub tolerance: f64,
    /// Search interval of R_s [m], MIN:MAX within [−10, 10].
    pub search: Interval,
    /// Largest spacing of the R_s scan that brackets the roots [m], (0, 1].
    pub scan_step: f64,
}

impl Default for TriggerOptions {
    fn default() -> TriggerOptions {
        let s = TriggerSettings::default();
        TriggerOptions {
            speeds: ValueList::spec("0.65:2.3:0.05"),
            reference_speed: s.reference_speed,
            reference_cycle: s.reference_cycle,
            reference_start: s.reference_start,
            tolerance: s.tolerance,
            search: Interval(s.search.0, s.search.1),
            scan_step: s.scan_step,
        }
    }
}

/// The trigger calibration on the analysis contract.
pub struct TriggerCalibration;

/// Checked options of [`TriggerCalibration`].
#[derive(Debug, Clone)]
pub struct TriggerInputs {
    /// The belt speeds [m/s].
    pub speeds: Vec<f64>,
    /// The search's settings.
    pub settings: TriggerSettings,
}

/// Belt speeds: (0, 20] m/s, at most [`MAX_SPEEDS`] (zero is refused by [`check_speeds`]).
pub const SPEED_LIST: (f64, f64, &str, usize) = MachineConfig::BELT_SPEED.list(MAX_SPEEDS);

impl Analysis for TriggerCalibration {
    const NAME: &'static str = "trigger";
    const ABOUT: &'static str =
        "Start position R_s per belt speed for the reference transverse displacement (Fig. 4)";
    const DEFAULT_SETS: &'static [&'static str] = &FIG3_PARCEL_SETS;
    type Options = TriggerOptions;
    type Checked = TriggerInputs;
    type Bound = TriggerInputs;
    type Output = TriggerCurve;

    fn validate(o: &TriggerOptions) -> Result<TriggerInputs, Vec<Problem>> {
        let settings = TriggerSettings {
            reference_speed: o.reference_speed,
            reference_cycle: o.reference_cycle,
            reference_start: o.reference_start,
            search: (o.search.0, o.search.1),
            scan_step: o.scan_step,
            tolerance: o.tolerance,
        };
        let speeds = o.speeds.resolve("speeds", SPEED_LIST);
        let problems = check(&settings, speeds.as_deref().unwrap_or(&[1.0]));
        match speeds {
            Ok(speeds) if problems.is_empty() => Ok(TriggerInputs { speeds, settings }),
            Ok(_) => Err(problems),
            Err(p) => Err(std::iter::once(p).chain(problems).collect()),
        }
    }

    /// Nothing derives from the scenario before the run.
    fn bind(c: TriggerInputs, _: &Loaded) -> Result<TriggerInputs, Vec<Problem>> {
        Ok(c)
    }

    fn work(c: &TriggerInputs, _: &Loaded) -> Work {
        Work {
            at_most: Some(c.settings.estimated_simulations(c.speeds.len()) as u64),
            at_least: c.settings.least_simulations(c.speeds.len()) as u64,
            units: c.speeds.len() as u64,
            unit: "speeds",
            smaller: "use fewer `speeds` or a coarser `scan_step`",
        }
    }

    fn run(s: &Loaded, c: &TriggerInputs, hooks: &Hooks) -> Result<TriggerCurve, Error> {
        trigger::calibrate_kept(
            &s.scenario,
            &c.speeds,
            &c.settings,
            hooks.progress,
            hooks.memo,
        )
        .map_err(|e| match e {
            TriggerError::ReferenceFailed(_) => Error::Failed(e.to_string()),
            TriggerError::ReferenceDiverted { .. } => {
                Error::Invalid(vec![Problem::new("reference_start", e.to_string())])
            }
            _ => Error::Invalid(vec![Problem::new("options", e.to_string())]),
        })
    }

    fn summary(curve: &TriggerCurve, c: &TriggerInputs, _: &Loaded) -> Value {
        json(curve, &c.settings)
    }

    fn tables(curve: &TriggerCurve) -> Result<Vec<(String, Vec<u8>)>, Error> {
        Ok(vec![csv_table("trigger.csv", csv(curve))?])
    }

    fn text(curve: &TriggerCurve, _: &TriggerInputs, s: &Loaded) -> String {
        text(curve, s.scenario.machine.cycle_time)
    }

    fn simulations(curve: &TriggerCurve) -> Option<u64> {
        // The reference run and every speed's scan and bisections.
        Some(
            1 + curve
                .points
                .iter()
                .map(|p| p.simulations as u64)
                .sum::<u64>(),
        )
    }
}

/// The readable table.
pub fn text(curve: &TriggerCurve, cycle: f64) -> String {
    let r = &curve.reference;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "reference run: belt speed v = {} m/s, arm cycle t_c = {} s, arm started when the parcel's front is at R_s = {} m",
        r.speed, r.cycle, r.start
    );
    let _ = writeln!(
        s,
        "  its centre reaches {:.4} m across the belt: {} (stages {})",
        r.max_lateral,
        match &r.outcome {
            divertsim_core::sim::Outcome::Diverted => "diverted".to_string(),
            divertsim_core::sim::Outcome::NotDiverted(why) => {
                format!("not diverted, {}", why.words())
            }
            o => o.short_verdict(),
        },
        stage_list(&r.stages)
    );
    let _ = writeln!(
        s,
        "each belt speed below gets the arm start R_s at which its parcel reaches the same {:.4} m (the paper's Fig. 4), at t_c = {cycle} s",
        r.max_lateral
    );
    let _ = writeln!(
        s,
        "  found: crossing (the reach passes the target continuously) or jump (it jumps over it: the nearest R_s); contact: F5 sliding along the arm, F6 arm and side guide, or none;\n  iter: root-finding iterations; roots: how many R_s meet the target (the one shown is chosen as in the module notes)\n"
    );
    let _ = writeln!(
        s,
        "{:>7} {:>9} {:>11} {:>9} {:>8} {:<28} {:<26} {:>5} {:>5}",
        "v [m/s]", "R_s [m]", "reach [m]", "found", "contact", "stages", "outcome", "iter", "roots"
    );
    for p in &curve.points {
        match p.root() {
            Some(x) => {
                let _ = writeln!(
                    s,
                    "{:>7.3} {:>9.4} {:>11.4} {:>9} {:>8} {:<28} {:<26} {:>5} {:>5}",
                    p.speed,
                    x.start,
                    x.max_lateral,
                    x.kind.label(),
                    stage_set(&x.stages),
                    stage_list(&x.stages),
                    x.outcome.short_verdict(),
                    x.iterations,
                    p.roots.len()
                );
            }
            None => {
                let _ = writeln!(
                    s,
                    "{:>7.3} {:>9} {:>11} {:>9} {:>8} {:<28} {:<26} {:>5} {:>5}",
                    p.speed, "no root", "", "", "", "", "", "", 0
                );
            }
        }
    }
    s
}

#[cfg(test)]
mod default_sets {
    use super::*;

    /// The Figs 3–5 defaults are set on the paper preset's machine: the keys put the built-in
    /// default exactly there, and each figure's list starts with them.
    #[test]
    fn the_default_cases_stand_on_the_papers_machine() {
        let sets: Vec<String> = PAPER_MACHINE_SETS.iter().map(|s| s.to_string()).collect();
        let ours = crate::config::load(None, &sets).unwrap();
        let (_, text) = crate::presets::find("paper/machine").unwrap();
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("machine.toml");
        std::fs::write(&file, text).unwrap();
        let paper = crate::config::load(Some(&file), &[]).unwrap();
        let mut m = ours.scenario.machine.clone();
        // The figure's own setting is the file's business.
        m.belt_speed = paper.scenario.machine.belt_speed;
        m.start_position = paper.scenario.machine.start_position;
        assert_eq!(format!("{m:?}"), format!("{:?}", paper.scenario.machine));
        assert_eq!(
            format!("{:?}", ours.scenario.materials),
            format!("{:?}", paper.scenario.materials)
        );
        for list in [
            &FIG3_PARCEL_SETS[..],
            &crate::analyses::capture::FIG5_PARCEL_SETS[..],
        ] {
            assert_eq!(&list[..PAPER_MACHINE_SETS.len()], &PAPER_MACHINE_SETS[..]);
        }
        // On it the Fig. 3 reference is not diverted: `divertsim trigger` runs with no file.
        let fig3: Vec<String> = FIG3_PARCEL_SETS.iter().map(|s| s.to_string()).collect();
        let l = crate::config::load(None, &fig3).unwrap();
        let mut s = l.scenario.clone();
        s.machine.belt_speed = 0.65;
        s.machine.start_position = 0.8;
        assert!(
            divertsim_core::sim::simulate(&s).outcome != divertsim_core::sim::Outcome::Diverted
        );
    }
}
