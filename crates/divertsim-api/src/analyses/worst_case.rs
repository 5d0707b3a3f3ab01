//! The searched worst case of one machine setting: the largest impulse ratio S/S_fall and
//! the smallest divert reserve over the `[design.search]` pose box (parcel class, pose,
//! arrival phase, optional scatter), by `divertsim_core::analysis::design::worst_case`, next to the
//! paper's closed-form definition (§4.3); the worst poses as scenario files that reproduce
//! the run exactly (their views are [`super::poses`]'s). Also the search settings that
//! overload, capacity and optimise share.

pub use super::poses::{against_limit, pose_json, pose_text, pose_text_no_phase, pose_toml};
use crate::config::{Loaded, Problem};
use crate::contract::{Analysis, Error, Hooks, Pairs, Work};
use divertsim_core::analysis::design::design_set::{Margins, WorstDefinition};
use divertsim_core::analysis::design::robust::RobustSettings;
use divertsim_core::analysis::design::worst_case::{
    search, PoseBox, Scatter, SearchSettings, WorstCase, WorstObjective,
};
use divertsim_core::analysis::paper::overload::worst_case_overload;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

/// Simulations per search by default (split over the starts, 10 % for the refinement).
pub const DEFAULT_BUDGET: u64 = 2400;
/// Independent DE starts per search by default.
pub const DEFAULT_STARTS: u64 = 3;

/// The core's settings for a search of `budget` simulations from `starts` DE starts:
/// population 24 (or fewer for a small budget), 10 % of the budget for the refinement.
pub fn search_settings(budget: u64, starts: u64, seed: u64) -> SearchSettings {
    let evaluations = budget as usize;
    let starts = starts.max(1) as usize;
    let refinement = evaluations / 10;
    let population = ((evaluations - refinement) / starts / 4).clamp(4, 24);
    SearchSettings {
        evaluations,
        starts,
        population,
        refinement,
        seed,
    }
}

/// Problems with a search's budget and starts (keys `search_budget`, `search_starts`):
/// budget in [100, 10⁷], starts in [1, 100], and each start needs a population's worth.
pub fn check_search(budget: u64, starts: u64) -> Vec<Problem> {
    let mut problems = Vec::new();
    if !(100..=10_000_000).contains(&budget) {
        problems.push(Problem::new(
            "search_budget",
            format!("{budget} is out of range; allowed: 100 to 10000000"),
        ));
    }
    if !(1..=100).contains(&starts) {
        problems.push(Problem::new(
            "search_starts",
            format!("{starts} is out of range; allowed: 1 to 100"),
        ));
    }
    if problems.is_empty() {
        let s = search_settings(budget, starts, 1);
        if s.validate().is_err() {
            problems.push(Problem::new(
                "search_budget",
                format!(
                    "{} is too small for {} starts; allowed: at least {}",
                    s.evaluations,
                    s.starts,
                    (s.starts * 4 * 10).div_ceil(9)
                ),
            ));
        }
    }
    problems
}

/// Both worst cases of one setting.
#[derive(Debug, Clone)]
pub struct WorstCaseReport {
    /// The setting's scenario (its parcel unused but for the height).
    pub setting: divertsim_core::model::params::Scenario,
    /// The pose box searched.
    pub pose_box: PoseBox,
    pub impulse: WorstCase,
    pub reserve: WorstCase,
    /// The largest peak drive torque at the arm, when asked for (`torque`).
    pub torque: Option<WorstCase>,
    /// The paper definition's ratio at the same setting (None if it could not be computed).
    pub paper_ratio: Option<f64>,
}

/// Simulations of [`compute`]: two searches (impulse and reserve), three with the torque,
/// each its evaluations.
pub fn estimated_simulations(settings: &SearchSettings, torque: bool) -> u64 {
    (2 + u64::from(torque)) * settings.evaluations as u64
}

/// Search both worst cases (and with `torque` the largest peak drive torque) for a loaded
/// scenario's setting.
pub fn compute(
    loaded: &Loaded,
    settings: &SearchSettings,
    scatter: &Scatter,
    torque: bool,
    progress: &(dyn Fn() + Sync),
) -> Result<WorstCaseReport, Error> {
    let pose_box = loaded.design.search.with_scatter(scatter);
    compute_in(loaded, pose_box, settings, torque, progress)
}

/// [`compute`] over a given pose box (`check`'s class with the height band of its mix).
pub fn compute_in(
    loaded: &Loaded,
    pose_box: PoseBox,
    settings: &SearchSettings,
    torque: bool,
    progress: &(dyn Fn() + Sync),
) -> Result<WorstCaseReport, Error> {
    let setting = loaded.scenario.clone();
    let run = |o| search(&setting, &pose_box, o, settings, progress).map_err(Error::failed);
    let impulse = run(WorstObjective::Impulse)?;
    let reserve = run(WorstObjective::Reserve)?;
    let torque = match torque {
        true => Some(run(WorstObjective::Torque)?),
        false => None,
    };
    let paper_ratio = worst_case_overload(
        &setting,
        &loaded.design.overload_parcel,
        setting.machine.cycle_time,
        setting.machine.belt_speed,
    )
    .ok()
    .map(|w| w.ratio);
    Ok(WorstCaseReport {
        setting,
        pose_box,
        impulse,
        reserve,
        torque,
        paper_ratio,
    })
}

pub fn band_json(b: (f64, f64)) -> Value {
    json!([b.0, b.1])
}

pub fn case_json(w: &WorstCase) -> Value {
    json!({
        "value": w.value,
        "overload_ratio": w.run.overload_ratio,
        "reserve": w.run.reserve,
        "drive_torque": w.run.drive_torque,
        "outcome": w.run.outcome.label(),
        "reason": w.run.outcome.reason(),
        "pose": pose_json(&w.pose),
        "start_values": w.start_values,
        "evaluations": w.evaluations,
        "failed_runs": w.failed_runs,
    })
}

/// The result as one JSON object.
pub fn to_json(r: &WorstCaseReport) -> Value {
    let m = &r.setting.machine;
    let b = &r.pose_box;
    let mut v = json!({
        "setting": {
            "belt_speed": m.belt_speed,
            "cycle_time": m.cycle_time,
            "start_position": m.start_position,
        },
        "pose_box": {
            "length": band_json(b.length),
            "width": band_json(b.width),
            "mass": band_json(b.mass),
            "angle_deg": band_json(b.angle_deg),
            "phase": band_json(b.phase),
            "belt_speed_scale": band_json(b.belt_speed_scale),
            "belt_friction_scale": band_json(b.belt_friction_scale),
            "arm_friction": b.arm_friction.map(band_json),
            "restitution": b.restitution.map(band_json),
        },
        "paper_overload_ratio": r.paper_ratio,
        "impulse": case_json(&r.impulse),
        "reserve": case_json(&r.reserve),
        "torque": r.torque.as_ref().map(case_json),
    });
    if let Some(h) = b.height {
        v["pose_box"]["height"] = band_json(h);
    }
    v
}

/// Parse `NAME=VALUE,NAME=VALUE` with the allowed names and ranges: `(name, lo, hi, unit)`.
fn parse_pairs(
    key: &str,
    text: &str,
    allowed: &[(&str, f64, f64, &str)],
) -> Result<Vec<(String, f64)>, Problem> {
    let names: Vec<String> = allowed
        .iter()
        .map(|(n, lo, hi, u)| format!("{n} in [{lo}, {hi}] {u}").trim_end().to_string())
        .collect();
    let bad = |why: String| {
        Problem::new(
            key,
            format!(
                "'{text}': {why}; allowed: NAME=VALUE,... with {}",
                names.join(", ")
            ),
        )
    };
    let mut out: Vec<(String, f64)> = Vec::new();
    for part in text.split(',').filter(|p| !p.trim().is_empty()) {
        let (name, value) = part
            .split_once('=')
            .ok_or_else(|| bad(format!("'{}' is not NAME=VALUE", part.trim())))?;
        let name = name.trim();
        let Some(&(_, lo, hi, _)) = allowed.iter().find(|(n, ..)| *n == name) else {
            return Err(bad(format!("unknown name '{name}'")));
        };
        let v: f64 = value
            .trim()
            .parse()
            .map_err(|_| bad(format!("'{}' is not a number", value.trim())))?;
        if !(v.is_finite() && (lo..=hi).contains(&v)) {
            return Err(bad(format!("{name} = {v} is out of range")));
        }
        if out.iter().any(|(n, _)| n == name) {
            return Err(bad(format!("{name} is given twice")));
        }
        out.push((name.to_string(), v));
    }
    Ok(out)
}

/// The divert reserve a setting keeps by default \[m]: none, in every command (`check`'s
/// `reserve_margin`, the margins of the searched capacity map and optimisation): a margin is
/// asked for, the same way everywhere, so that an optimum found against the search passes
/// `check` by the same rule (issue 50, item 2).
pub const DEFAULT_RESERVE_MARGIN: f64 = 0.0;

/// Parse the margins `overload=0.1,divert=0.02` (a ratio and metres).
pub fn parse_margins(text: &str) -> Result<Margins, Problem> {
    let pairs = parse_pairs(
        "margin",
        text,
        &[
            ("overload", 0.0, 0.9, ""),
            ("divert", 0.0, 1.0, "m"),
            ("drive_torque", 0.01, 1.0e6, "N·m"),
        ],
    )?;
    let mut m = Margins {
        divert: DEFAULT_RESERVE_MARGIN,
        ..Margins::default()
    };
    for (n, v) in pairs {
        match n.as_str() {
            "overload" => m.overload = v,
            "drive_torque" => m.drive_torque = Some(v),
            _ => m.divert = v,
        }
    }
    Ok(m)
}

/// A drive-torque limit needs an arm to load: key `margin`, before any simulation.
pub fn torque_limit_problems(margins: &Margins, loaded: &Loaded) -> Vec<Problem> {
    match (margins.drive_torque, loaded.scenario.run.arm) {
        (Some(t), false) => vec![Problem::new(
            "margin",
            format!(
                "drive_torque={t} limits the arm's drive, but the scenario has no arm (run.arm = false); allowed: drive_torque with run.arm = true"
            ),
        )],
        _ => Vec::new(),
    }
}

/// Parse the scatter `belt_speed=0.02,phase=0.01,belt_friction=0.05` (relative, seconds,
/// relative).
pub fn parse_scatter(text: &str) -> Result<Scatter, Problem> {
    let pairs = parse_pairs(
        "scatter",
        text,
        &[
            ("belt_speed", 0.0, 0.5, ""),
            ("phase", 0.0, 0.5, "s"),
            ("belt_friction", 0.0, 0.9, ""),
        ],
    )?;
    let mut s = Scatter::default();
    for (n, v) in pairs {
        match n.as_str() {
            "belt_speed" => s.belt_speed = v,
            "phase" => s.phase = v,
            _ => s.belt_friction = v,
        }
    }
    Ok(s)
}

/// A worst-case search's budget and seed, an option group shared by the analyses that
/// search (flattened into their options).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default)]
pub struct SearchBudget {
    /// Simulations per worst-case search (split over the starts, 10 % for the final
    /// refinement), 100 to 10000000.
    pub search_budget: u64,
    /// Independent DE starts per search, 1 to 100.
    pub search_starts: u64,
    /// Seed of the search.
    pub search_seed: u64,
}

impl Default for SearchBudget {
    fn default() -> SearchBudget {
        SearchBudget {
            search_budget: DEFAULT_BUDGET,
            search_starts: DEFAULT_STARTS,
            search_seed: 1,
        }
    }
}

impl SearchBudget {
    /// The core's settings, or the problems of [`check_search`].
    pub fn checked(&self) -> Result<SearchSettings, Vec<Problem>> {
        let problems = check_search(self.search_budget, self.search_starts);
        match problems.is_empty() {
            true => Ok(search_settings(
                self.search_budget,
                self.search_starts,
                self.search_seed,
            )),
            false => Err(problems),
        }
    }
}

/// Options of the worst-case search (`divertsim worst-case`, Python
/// `analysis("worst_case")`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default)]
pub struct WorstCaseOptions {
    /// Also require the setting to hold under this scatter (widens the pose box):
    /// belt_speed=REL,phase=SECONDS,belt_friction=REL, e.g. belt_speed=0.02,phase=0.01.
    pub scatter: Option<Pairs>,
    /// Also search the largest peak drive torque at the arm over the stroke (a third
    /// search, worst_torque.toml; give machine.arm_mass or arm_inertia for the arm's own
    /// share).
    pub torque: bool,
    #[serde(flatten)]
    #[allow(missing_docs)]
    pub budget: SearchBudget,
}

/// The checked options of [`WorstCaseSearch`]: the budget, the scatter, whether to search
/// the torque.
pub type WorstCaseInputs = (SearchSettings, Scatter, bool);

/// The searched worst case of one setting on the analysis contract.
pub struct WorstCaseSearch;

impl Analysis for WorstCaseSearch {
    const NAME: &'static str = "worst_case";
    const ABOUT: &'static str =
        "The true worst case of one setting: the largest impulse and the smallest divert reserve over every parcel of the class, pose and arrival (a global search)";
    type Options = WorstCaseOptions;
    type Checked = WorstCaseInputs;
    type Bound = WorstCaseInputs;
    type Output = WorstCaseReport;

    fn validate(o: &WorstCaseOptions) -> Result<WorstCaseInputs, Vec<Problem>> {
        let settings = o.budget.checked();
        let scatter = o.scatter.as_ref().map(|p| parse_scatter(&p.text()));
        match (settings, scatter.transpose()) {
            (Ok(s), Ok(sc)) => Ok((s, sc.unwrap_or_default(), o.torque)),
            (s, sc) => Err(s
                .err()
                .unwrap_or_default()
                .into_iter()
                .chain(sc.err())
                .collect()),
        }
    }

    /// Nothing derives from the scenario before the run.
    fn bind(c: WorstCaseInputs, _: &Loaded) -> Result<WorstCaseInputs, Vec<Problem>> {
        Ok(c)
    }

    fn work((settings, _, torque): &WorstCaseInputs, _: &Loaded) -> Work {
        let simulations = estimated_simulations(settings, *torque);
        Work {
            at_most: Some(simulations),
            at_least: simulations,
            units: simulations,
            unit: "runs",
            smaller: "use a smaller `search_budget`",
        }
    }

    fn run(
        s: &Loaded,
        (settings, scatter, torque): &WorstCaseInputs,
        hooks: &Hooks,
    ) -> Result<WorstCaseReport, Error> {
        compute(s, settings, scatter, *torque, hooks.progress)
    }

    fn summary(r: &WorstCaseReport, _: &WorstCaseInputs, _: &Loaded) -> Value {
        to_json(r)
    }

    fn tables(_: &WorstCaseReport) -> Result<Vec<(String, Vec<u8>)>, Error> {
        Ok(Vec::new())
    }

    fn text(r: &WorstCaseReport, _: &WorstCaseInputs, _: &Loaded) -> String {
        text(r)
    }
}

/// The worst case a setting's constraints hold against: `search` (the searched worst impulse
/// and divert reserve) or `paper` (the paper's closed-form tip strike).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum WorstChoice {
    /// The searched worst case over [design.search].
    Search,
    /// The paper's closed-form tip strike on the [design.overload] parcel.
    Paper,
}

impl WorstChoice {
    /// The core's definition.
    pub fn definition(self) -> WorstDefinition {
        match self {
            WorstChoice::Search => WorstDefinition::Search,
            WorstChoice::Paper => WorstDefinition::Paper,
        }
    }
}

/// What the constraints of the capacity map and the optimisation hold against, an option
/// group flattened into their options.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are help text: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default)]
pub struct RobustOptions {
    /// The worst case the constraints hold against: "search" (the default for capacity and
    /// single optimisations: the searched worst impulse and divert reserve over
    /// [design.search], by rounds that add the violating poses the search finds at the
    /// result) or "paper" (the closed-form tip strike of the paper; the default and the only
    /// choice with optimize's `paper_experiment` and `compare`).
    pub worst: Option<WorstChoice>,
    /// Safety margins and limits: overload=RATIO (S/S_fall ≤ 1 − RATIO; default 0),
    /// divert=M (divert reserve ≥ M metres; default 0, as `check`'s reserve_margin),
    /// drive_torque=NM (each stroke's peak drive torque at the arm ≤ NM
    /// N·m, with machine.arm_mass or arm_inertia for the arm's own share), e.g.
    /// overload=0.1,divert=0.02,drive_torque=150.
    pub margin: Option<Pairs>,
    /// Require feasibility under scatter (with `worst` search):
    /// belt_speed=REL,phase=SECONDS,belt_friction=REL, e.g.
    /// belt_speed=0.02,phase=0.01,belt_friction=0.05.
    pub scatter: Option<Pairs>,
    /// Largest number of rounds of map (or optimisation) and search (with `worst` search),
    /// 1 to 100.
    pub rounds: u64,
    #[serde(flatten)]
    #[allow(missing_docs)]
    pub budget: SearchBudget,
}

impl Default for RobustOptions {
    fn default() -> RobustOptions {
        RobustOptions {
            worst: None,
            margin: None,
            scatter: None,
            rounds: RobustSettings::default().max_rounds as u64,
            budget: SearchBudget::default(),
        }
    }
}

/// The worst-case definition, its margins and, for the searched one, the robust settings.
pub type Robust = (WorstDefinition, Margins, Option<RobustSettings>);

impl RobustOptions {
    /// The definition, the margins and the robust settings, or every problem keyed by
    /// option name.
    pub fn resolve(&self) -> Result<Robust, Vec<Problem>> {
        let mut problems = Vec::new();
        let worst = self.worst.unwrap_or(WorstChoice::Search).definition();
        let margins = match self.margin.as_ref().map(|m| parse_margins(&m.text())) {
            None => Margins {
                divert: DEFAULT_RESERVE_MARGIN,
                ..Margins::default()
            },
            Some(Ok(m)) => m,
            Some(Err(p)) => {
                problems.push(p);
                Margins::default()
            }
        };
        let scatter = match self.scatter.as_ref().map(|m| parse_scatter(&m.text())) {
            None => Scatter::default(),
            Some(Ok(s)) => s,
            Some(Err(p)) => {
                problems.push(p);
                Scatter::default()
            }
        };
        if self.scatter.is_some() && worst == WorstDefinition::Paper {
            problems.push(Problem::new(
                "scatter",
                "needs `worst` search (the paper's closed-form strike has no scatter)",
            ));
        }
        if !(1..=100).contains(&self.rounds) {
            problems.push(Problem::new(
                "rounds",
                format!("{} is out of range; allowed: 1 to 100", self.rounds),
            ));
        }
        let search = match worst {
            WorstDefinition::Search => match self.budget.checked() {
                Ok(s) => Some(s),
                Err(p) => {
                    problems.extend(p);
                    None
                }
            },
            WorstDefinition::Paper => None,
        };
        if !problems.is_empty() {
            return Err(problems);
        }
        let robust = search.map(|search| RobustSettings {
            search,
            scatter,
            max_rounds: self.rounds as usize,
            ..RobustSettings::default()
        });
        Ok((worst, margins, robust))
    }
}

/// The readable table.
pub fn text(r: &WorstCaseReport) -> String {
    use std::fmt::Write;
    let m = &r.setting.machine;
    let b = &r.pose_box;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "worst case at v = {} m/s, t_c = {} s, R_s = {} m",
        m.belt_speed, m.cycle_time, m.start_position
    );
    let _ = writeln!(
        s,
        "searched over: length {}–{} m, width {}–{} m (≤ length), mass {}–{} kg, φ {}–{}°, anywhere across the belt, phase {}–{} s",
        b.length.0, b.length.1, b.width.0, b.width.1, b.mass.0, b.mass.1, b.angle_deg.0,
        b.angle_deg.1, b.phase.0, b.phase.1
    );
    let i = &r.impulse;
    let _ = writeln!(
        s,
        "largest impulse: S/S_fall = {:.4}, {}{}",
        i.value,
        against_limit(i.value, 1.0),
        match r.paper_ratio {
            Some(p) => format!(" (the paper's definition: {p:.4})"),
            None => String::new(),
        }
    );
    let _ = writeln!(s, "  pose: {}", pose_text(&i.pose));
    let _ = writeln!(s, "  outcome: {}", i.run.outcome.label());
    let d = &r.reserve;
    let _ = writeln!(
        s,
        "smallest divert reserve: d = {:.4} m ({})",
        d.value,
        if d.value >= 0.0 {
            "every searched parcel is diverted"
        } else {
            "a parcel is not diverted"
        }
    );
    let _ = writeln!(s, "  pose: {}", pose_text(&d.pose));
    let _ = writeln!(s, "  outcome: {}", d.run.outcome.label());
    if let Some(t) = &r.torque {
        let _ = writeln!(
            s,
            "largest peak drive torque: {:.3} N·m at the arm (arm inertia {} kg·m²)",
            t.value, m.arm_inertia
        );
        let _ = writeln!(s, "  pose: {}", pose_text(&t.pose));
        let _ = writeln!(s, "  outcome: {}", t.run.outcome.label());
    }
    let rounded = |w: &WorstCase| {
        w.start_values
            .iter()
            .map(|v| (v * 1e4).round() / 1e4)
            .collect::<Vec<_>>()
    };
    let (extra_sims, extra_failed) = r
        .torque
        .as_ref()
        .map_or((0, 0), |t| (t.evaluations, t.failed_runs));
    let _ = writeln!(
        s,
        "{} simulations ({} starts each, best of each start: impulse {:?}, reserve {:?}{}); {} failed runs",
        i.evaluations + d.evaluations + extra_sims,
        i.start_values.len(),
        rounded(i),
        rounded(d),
        r.torque
            .as_ref()
            .map(|t| format!(", torque {:?}", rounded(t)))
            .unwrap_or_default(),
        i.failed_runs + d.failed_runs + extra_failed
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn margins_and_scatter_parse_and_reject() {
        let m = parse_margins("overload=0.1,divert=0.02").unwrap();
        assert_eq!((m.overload, m.divert), (0.1, 0.02));
        let s = parse_scatter("belt_speed=0.02, phase=0.01").unwrap();
        assert_eq!((s.belt_speed, s.phase, s.belt_friction), (0.02, 0.01, 0.0));
        for bad in [
            "overload",
            "overload=x",
            "speed=1",
            "overload=2",
            "overload=0.1,overload=0.2",
        ] {
            let e = parse_margins(bad).unwrap_err();
            assert_eq!(e.key, "margin");
            assert!(e.message.contains("overload in [0, 0.9]"), "{}", e.message);
        }
        assert!(parse_scatter("phase=-1").is_err());
    }
}
