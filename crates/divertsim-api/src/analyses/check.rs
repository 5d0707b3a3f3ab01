//! "Is my setting safe?" (issue 27, A1): one verdict on a setting against its parcel class,
//! from the checks the other analyses make:
//! - **divert**: the searched smallest divert reserve d over every parcel of the class
//!   (`[design.search]`, any pose and arrival) and each named `[design]` parcel: a parcel left
//!   on the belt fails;
//! - **overload**: the searched largest S/S_fall over the class: above the limit 1 (the free
//!   fall from H₀) fails;
//! - **mix** (when the scenario has a `[mix]`): `reliability`'s divert and overload rates over
//!   the mix, with their intervals.
//!
//! The verdict: **unsafe** when a check fails (naming the parcel, whose pose is written as a
//! scenario file that reproduces it); **marginal** when every check passes but a reserve is
//! below the stated margins (`reserve_margin`, `overload_margin`) or some parcel of the mix
//! fails; **safe** otherwise. The searches are `worst_case`'s (docs/validation.md, "The
//! searched worst case"); the mix is `reliability`'s.

use crate::analyses::cells::pct;
use crate::analyses::population::{proportion_json, sample_file};
use crate::analyses::poses::{against_limit, pose_json, pose_text, pose_toml};
use crate::analyses::reliability::{Options as ReliabilityOptions, Reliability, StudyInputs};
use crate::analyses::worst_case::{self, SearchBudget, WorstCaseReport};
use crate::config::mix::MixConfig;
use crate::config::{Loaded, Problem, ScenarioFile};
use crate::contract::{Analysis, Error, Hooks, Work};
use divertsim_core::analysis::design::design_set::{evaluate, CaseEvaluation, DesignPoint};
use divertsim_core::analysis::design::pose::PoseBox;
use divertsim_core::analysis::design::worst_case::{SearchSettings, WorstCase};
use divertsim_core::analysis::population::reliability::CONFIDENCE;
use divertsim_core::sim::{NotDivertedReason, Outcome};
use divertsim_core::stats::binomial::Proportion;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};
use std::fmt::Write as _;

/// The overload limit: S/S_fall of the free fall from H₀.
pub const OVERLOAD_LIMIT: f64 = 1.0;
/// Samples of the mix by default (the scenario's `[mix]`, else `reliability`'s default).
pub const MIX_SAMPLES: u64 = 10_000;

/// Options of `check` (`divertsim check`, Python `check`).
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are help text: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default)]
pub struct CheckOptions {
    /// A divert reserve below this [m] makes a passing setting marginal, 0 to 1 (default 0,
    /// as the margins of the searched capacity map and optimisation: `--margin divert=M`).
    #[schemars(extend("x-value" = "M"))]
    pub reserve_margin: f64,
    /// A worst S/S_fall above 1 − this makes a passing setting marginal, 0 to 0.9.
    #[schemars(extend("x-value" = "RATIO"))]
    pub overload_margin: f64,
    /// Parcels of the mix's reliability run: the scenario's [mix], else `reliability`'s
    /// default one (default 10000; 0 skips it, and the search then keeps parcel.height),
    /// 0 to 10000000.
    #[schemars(extend("x-value" = "N"))]
    pub samples: Option<u64>,
    #[serde(flatten)]
    #[allow(missing_docs)]
    pub budget: SearchBudget,
}

impl Default for CheckOptions {
    fn default() -> CheckOptions {
        CheckOptions {
            reserve_margin: crate::analyses::worst_case::DEFAULT_RESERVE_MARGIN,
            overload_margin: 0.0,
            samples: None,
            budget: SearchBudget::default(),
        }
    }
}

/// The checked options.
#[derive(Debug, Clone)]
pub struct CheckSettings {
    pub options: CheckOptions,
    pub search: SearchSettings,
}

/// The checked options bound to a scenario ([`Analysis::bind`]).
#[derive(Debug, Clone)]
pub struct CheckInputs {
    pub options: CheckOptions,
    pub search: SearchSettings,
    /// The mix's reliability run (`None`: no mix run).
    pub mix: Option<StudyInputs>,
}

/// The verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    Safe,
    Marginal,
    Unsafe,
}

impl Verdict {
    pub fn label(self) -> &'static str {
        match self {
            Verdict::Safe => "safe",
            Verdict::Marginal => "marginal",
            Verdict::Unsafe => "unsafe",
        }
    }
}

/// One check's status, worst first.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Status {
    Passes,
    Marginal,
    Fails,
}

impl Status {
    fn label(self) -> &'static str {
        match self {
            Status::Passes => "passes",
            Status::Marginal => "MARGINAL",
            Status::Fails => "FAILS",
        }
    }
}

/// The mix's rates.
#[derive(Debug, Clone)]
pub struct MixCheck {
    pub divert: Proportion,
    pub overload: Proportion,
    /// The share that tipped over.
    pub tipped: Proportion,
    /// The first parcel of the mix that tipped over, among its first failures (the study
    /// keeps 20), as a scenario file that `simulate` runs again.
    pub tipped_example: Option<crate::config::ScenarioFile>,
    /// Whether it is the scenario's own `[mix]` (else `reliability`'s default one).
    pub own: bool,
    /// The heights it draws \[m] ([`divertsim_core::analysis::population::mix::ParcelMix::height_range`]).
    pub heights: (f64, f64),
}

/// The checks of one setting and its verdict.
#[derive(Debug, Clone)]
pub struct CheckReport {
    pub worst: WorstCaseReport,
    /// The named `[design]` parcels at the setting.
    pub cases: Vec<CaseEvaluation>,
    pub mix: Option<MixCheck>,
    pub options: CheckOptions,
    pub divert: Status,
    pub overload: Status,
    pub mix_status: Option<Status>,
    pub verdict: Verdict,
    /// The scenario as the mix's run resolved it (its `[mix]` stated, defaults included),
    /// when the mix ran: what `scenario.toml` and the summary describe.
    pub described: Option<crate::config::ScenarioFile>,
}

/// Whether the scenario describes a parcel mix of its own.
pub fn has_mix(loaded: &Loaded) -> bool {
    loaded.file.mix != MixConfig::default()
}

fn samples(o: &CheckOptions) -> u64 {
    o.samples.unwrap_or(MIX_SAMPLES)
}

/// The class the search explores: `[design.search]`, with the height band of the mix that
/// `check` runs where the scenario states none (issue 47: a class without its heights
/// cannot see a parcel tip over, so `check` and `reliability` would disagree).
pub fn class_box(o: &CheckOptions, loaded: &Loaded) -> PoseBox {
    let mut b = loaded.design.search.clone();
    if b.height.is_none() && samples(o) > 0 {
        b.height = Some(loaded.mix.height_range());
    }
    b
}

fn reliability_options(n: u64) -> ReliabilityOptions {
    ReliabilityOptions {
        samples: n,
        ..ReliabilityOptions::default()
    }
}

/// The divert check's status: a parcel not diverted (searched, or a named case) fails;
/// a reserve below the margin is marginal.
fn divert_status(reserve: f64, cases: &[CaseEvaluation], margin: f64) -> Status {
    if reserve < 0.0 || cases.iter().any(|c| c.overshoot < 0.0) {
        Status::Fails
    } else if reserve < margin || cases.iter().any(|c| c.overshoot < margin) {
        Status::Marginal
    } else {
        Status::Passes
    }
}

fn overload_status(ratio: f64, margin: f64) -> Status {
    if ratio.is_nan() || ratio > OVERLOAD_LIMIT {
        Status::Fails
    } else if ratio > OVERLOAD_LIMIT - margin {
        Status::Marginal
    } else {
        Status::Passes
    }
}

/// A mix with a parcel that tipped over fails (a toppled parcel jams the chute); one with
/// any other parcel not diverted or overloaded is marginal: the class passes, the mix has
/// parcels outside it or between its searched poses.
fn mix_status(m: &MixCheck) -> Status {
    if m.tipped.successes > 0 {
        Status::Fails
    } else if m.divert.successes == m.divert.trials && m.overload.successes == 0 {
        Status::Passes
    } else {
        Status::Marginal
    }
}

/// The verdict of the checks' statuses.
pub fn verdict_of(statuses: &[Status]) -> Verdict {
    match statuses.iter().max() {
        Some(Status::Fails) => Verdict::Unsafe,
        Some(Status::Marginal) => Verdict::Marginal,
        _ => Verdict::Safe,
    }
}

/// `check` on the analysis contract.
pub struct Check;

impl Analysis for Check {
    const NAME: &'static str = "check";
    const ABOUT: &'static str = "Is a setting safe? One verdict (safe, marginal or unsafe) on the setting against its parcel class: every parcel diverted (the searched smallest divert reserve and the [design] parcels), the searched worst overload against the free fall, and the mix's rates when the scenario has a [mix]";
    type Options = CheckOptions;
    type Checked = CheckSettings;
    type Bound = CheckInputs;
    type Output = CheckReport;

    fn validate(o: &CheckOptions) -> Result<CheckSettings, Vec<Problem>> {
        let mut problems = Vec::new();
        if !(o.reserve_margin.is_finite() && (0.0..=1.0).contains(&o.reserve_margin)) {
            problems.push(Problem::new(
                "reserve_margin",
                format!("{} is out of range; allowed: 0 to 1 m", o.reserve_margin),
            ));
        }
        if !(o.overload_margin.is_finite() && (0.0..=0.9).contains(&o.overload_margin)) {
            problems.push(Problem::new(
                "overload_margin",
                format!("{} is out of range; allowed: 0 to 0.9", o.overload_margin),
            ));
        }
        if let Some(n) = o.samples.filter(|n| *n > 10_000_000) {
            problems.push(Problem::new(
                "samples",
                format!("{n} is out of range; allowed: 0 to 10000000"),
            ));
        }
        let search = o.budget.checked();
        if let Err(p) = &search {
            problems.extend(p.iter().cloned());
        }
        match search {
            Ok(search) if problems.is_empty() => Ok(CheckSettings {
                options: o.clone(),
                search,
            }),
            _ => Err(problems),
        }
    }

    /// The mix's reliability run, checked and bound here.
    fn bind(c: CheckSettings, s: &Loaded) -> Result<CheckInputs, Vec<Problem>> {
        let mix = match samples(&c.options) {
            0 => None,
            n => {
                let r = Reliability::validate(&reliability_options(n))?;
                Some(Reliability::bind(r, s)?)
            }
        };
        Ok(CheckInputs {
            options: c.options,
            search: c.search,
            mix,
        })
    }

    fn work(c: &CheckInputs, s: &Loaded) -> Work {
        let search = worst_case::estimated_simulations(&c.search, false);
        let sims = search + s.design.check_count() as u64 + samples(&c.options);
        Work {
            at_most: Some(sims),
            at_least: sims,
            units: sims,
            unit: "runs",
            smaller: "use a smaller `search_budget` or fewer `samples`",
        }
    }

    fn run(s: &Loaded, c: &CheckInputs, hooks: &Hooks) -> Result<CheckReport, Error> {
        let o = &c.options;
        let worst = worst_case::compute_in(s, class_box(o, s), &c.search, false, hooks.progress)?;
        let m = &s.scenario.machine;
        let point = DesignPoint {
            belt_speed: m.belt_speed,
            cycle_time: m.cycle_time,
            start_position: m.start_position,
            light_barrier: m.light_barrier,
        };
        let cases = evaluate(&s.scenario, &s.design, &point).cases;
        let mut described = None;
        let mix = match &c.mix {
            None => None,
            Some(r) => {
                let study = Reliability::run(s, r, hooks)?;
                described = study.points.first().map(|p| p.loaded.file.clone());
                let t = &study.results[0].0.tally;
                Some(MixCheck {
                    divert: t.divert_rate(CONFIDENCE),
                    overload: t.overload_rate(CONFIDENCE),
                    tipped: t.tipping_rate(CONFIDENCE),
                    tipped_example: t
                        .first_failures
                        .iter()
                        .find(|s| s.tipped())
                        .map(|s| sample_file(&study.points[0], s)),
                    own: has_mix(s),
                    heights: s.mix.height_range(),
                })
            }
        };
        let divert = divert_status(worst.reserve.value, &cases, o.reserve_margin);
        let overload = overload_status(worst.impulse.value, o.overload_margin);
        let mix_status = mix.as_ref().map(mix_status);
        let verdict = verdict_of(
            &[divert, overload]
                .into_iter()
                .chain(mix_status)
                .collect::<Vec<_>>(),
        );
        Ok(CheckReport {
            worst,
            cases,
            mix,
            options: o.clone(),
            divert,
            overload,
            mix_status,
            verdict,
            described,
        })
    }

    fn summary(r: &CheckReport, _: &CheckInputs, _: &Loaded) -> Value {
        let m = &r.worst.setting.machine;
        json!({
            "verdict": r.verdict.label(),
            "setting": {
                "belt_speed": m.belt_speed,
                "cycle_time": m.cycle_time,
                "start_position": m.start_position,
                "light_barrier": m.light_barrier,
            },
            "divert": {
                "status": r.divert.label().to_lowercase(),
                "smallest_reserve_m": r.worst.reserve.value,
                "outcome": r.worst.reserve.run.outcome.label(),
                "reason": r.worst.reserve.run.outcome.reason(),
                "class_heights_m": r.worst.pose_box.height.map(|(lo, hi)| json!([lo, hi])),
                "reserve_margin_m": r.options.reserve_margin,
                "pose": pose_json(&r.worst.reserve.pose),
                "cases": r.cases.iter().map(|c| json!({
                    "name": c.name,
                    "outcome": c.outcome.label(),
                    "reserve_m": c.overshoot,
                })).collect::<Vec<_>>(),
            },
            "overload": {
                "status": r.overload.label().to_lowercase(),
                "largest_ratio": r.worst.impulse.value,
                "limit": OVERLOAD_LIMIT,
                "overload_margin": r.options.overload_margin,
                "pose": pose_json(&r.worst.impulse.pose),
            },
            "mix": r.mix.as_ref().map(|m| json!({
                "status": r.mix_status.map(|s| s.label().to_lowercase()),
                "source": if m.own { "scenario" } else { "default" },
                "divert_rate": proportion_json(&m.divert),
                "overload_rate": proportion_json(&m.overload),
                "tipped_rate": proportion_json(&m.tipped),
            })),
            "files": failing_names(r),
        })
    }

    fn described_file<'a>(r: &'a CheckReport, scenario: &'a Loaded) -> &'a ScenarioFile {
        r.described.as_ref().unwrap_or(&scenario.file)
    }

    fn tables(_: &CheckReport) -> Result<Vec<(String, Vec<u8>)>, Error> {
        Ok(Vec::new())
    }

    fn text(r: &CheckReport, _: &CheckInputs, _: &Loaded) -> String {
        text(r)
    }
}

/// The worst poses that fail, as (file name, the searched case): the files an edge writes
/// so that `simulate` reproduces each.
pub fn failing_files(r: &CheckReport) -> Vec<(String, &WorstCase)> {
    let mut files = Vec::new();
    if r.worst.reserve.value < 0.0 {
        files.push(("unsafe_divert.toml".to_string(), &r.worst.reserve));
    }
    if r.overload == Status::Fails {
        files.push(("unsafe_overload.toml".to_string(), &r.worst.impulse));
    }
    files
}

/// The tipped mix parcel's file name (a parcel of the mix that tipped over).
const TIPPING_FILE: &str = "unsafe_tipping.toml";

/// The names of every file an edge writes for a failing setting: [`failing_files`], then
/// unsafe_tipping.toml when a parcel of the mix tipped over.
pub fn failing_names(r: &CheckReport) -> Vec<String> {
    let mut names: Vec<String> = failing_files(r).into_iter().map(|(n, _)| n).collect();
    if r.mix.as_ref().is_some_and(|m| m.tipped_example.is_some()) {
        names.push(TIPPING_FILE.to_string());
    }
    names
}

/// The scenario files of [`failing_names`], with their text.
pub fn failing_tomls(r: &CheckReport, loaded: &Loaded) -> Result<Vec<(String, String)>, Error> {
    let mut files = failing_files(r)
        .into_iter()
        .map(|(name, w)| Ok((name, pose_toml(loaded, &r.worst.setting, w)?)))
        .collect::<Result<Vec<_>, Error>>()?;
    if let Some(file) = r.mix.as_ref().and_then(|m| m.tipped_example.as_ref()) {
        let heading = "A parcel of the mix that tipped over at this setting (divertsim check); \
                       `divertsim simulate` runs it again.";
        files.push((
            TIPPING_FILE.to_string(),
            crate::config::to_toml(file, heading)?,
        ));
    }
    Ok(files)
}

/// The readable report: each check with its status, then the verdict in words.
pub fn text(r: &CheckReport) -> String {
    let m = &r.worst.setting.machine;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "check: belt speed v = {} m/s, cycle time t_c = {} s, arm start R_s = {} m, light barrier S_d = {} m",
        m.belt_speed, m.cycle_time, m.start_position, m.light_barrier
    );
    let _ = writeln!(
        s,
        "\ndivert ({}): the smallest divert reserve over the class{} is d = {:.4} m{}",
        r.divert.label(),
        r.worst
            .pose_box
            .height
            .map(|(lo, hi)| format!(" (heights {lo}–{hi} m)"))
            .unwrap_or_default(),
        r.worst.reserve.value,
        match r.worst.reserve.value {
            _ if r.worst.reserve.run.outcome == Outcome::NotDiverted(NotDivertedReason::Tipped) => {
                " (a parcel tipped over)".to_string()
            }
            d if d < 0.0 => " (a parcel is not diverted)".to_string(),
            d if d < r.options.reserve_margin => {
                format!(" (below the margin {} m)", r.options.reserve_margin)
            }
            _ => " (every searched parcel is diverted)".to_string(),
        }
    );
    let _ = writeln!(
        s,
        "  the parcel with the least reserve: {}",
        pose_text(&r.worst.reserve.pose)
    );
    for c in &r.cases {
        let _ = writeln!(
            s,
            "  [design] parcel {}: {}, reserve {:.4} m",
            c.name,
            c.outcome.label(),
            c.overshoot
        );
    }
    let i = &r.worst.impulse;
    let _ = writeln!(
        s,
        "\noverload ({}): the largest strike over the class is S/S_fall = {:.4}, {}",
        r.overload.label(),
        i.value,
        against_limit(i.value, OVERLOAD_LIMIT)
    );
    let _ = writeln!(s, "  the parcel struck hardest: {}", pose_text(&i.pose));
    if let (Some(mix), Some(st)) = (&r.mix, r.mix_status) {
        let _ = writeln!(
            s,
            "\nmix ({}, {}): {} parcels, {} not diverted, of which {} tipped over; diverted {} (95 % interval {} to {}), struck harder than the free fall {} ({} to {})",
            st.label(),
            match mix.own {
                true => "the scenario's [mix]".to_string(),
                false => {
                    let (lo, hi) = mix.heights;
                    format!("`reliability`'s default mix: the paper's class, heights {lo}–{hi} m")
                }
            },
            mix.divert.trials,
            mix.divert.trials - mix.divert.successes,
            mix.tipped.successes,
            pct(mix.divert.estimate, 3),
            pct(mix.divert.lower, 3),
            pct(mix.divert.upper, 3),
            pct(mix.overload.estimate, 3),
            pct(mix.overload.lower, 3),
            pct(mix.overload.upper, 3),
        );
    }
    let _ = writeln!(s, "\nverdict: {}", r.verdict.label().to_uppercase());
    let why = match r.verdict {
        Verdict::Safe => "every parcel of the class is diverted and no strike exceeds the free fall, with the margins asked for".to_string(),
        Verdict::Marginal => "every check passes, but with less than the margins asked for (or some parcels of the mix fail)".to_string(),
        Verdict::Unsafe => {
            let names = failing_names(r);
            let mut w = String::from(if r.divert == Status::Fails || r.overload == Status::Fails {
                "a parcel of the class fails"
            } else {
                "a parcel of the mix tipped over"
            });
            if !names.is_empty() {
                w += &format!(
                    "; --out DIR writes {} (`divertsim simulate` reproduces each)",
                    names.join(" and ")
                );
            }
            w
        }
    };
    let _ = writeln!(s, "  {why}");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_worst_status_decides() {
        assert_eq!(verdict_of(&[Status::Passes, Status::Passes]), Verdict::Safe);
        assert_eq!(
            verdict_of(&[Status::Passes, Status::Marginal]),
            Verdict::Marginal
        );
        assert_eq!(
            verdict_of(&[Status::Fails, Status::Marginal]),
            Verdict::Unsafe
        );
        assert_eq!(overload_status(1.0, 0.0), Status::Passes);
        assert_eq!(overload_status(1.0001, 0.0), Status::Fails);
        assert_eq!(overload_status(f64::NAN, 0.0), Status::Fails);
        assert_eq!(overload_status(0.97, 0.05), Status::Marginal);
        assert_eq!(divert_status(0.003, &[], 0.005), Status::Marginal);
        assert_eq!(divert_status(-0.001, &[], 0.0), Status::Fails);
        assert_eq!(divert_status(0.01, &[], 0.005), Status::Passes);
    }
}
