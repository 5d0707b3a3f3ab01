//! `[line]`: a sorter line for `divertsim line`: how parcels follow each other (drawn gaps
//! or a log of arrival times), where they are bound, what a controller does when its arm is
//! busy, and the diverters after the first. `[machine]` is the first diverter, at the line's
//! origin; each further diverter is `[machine]` with its own keys over it, at its position
//! down the belt. The belt (speed and width) is the line's.

// The sibling files this one uses, named so that the import-cycle check sees them.
use super::bounds::Bound;
use super::convert::to_scenario;
use super::mix::DistConfig;
use super::problems::Problem;
use super::schema::{MachineConfig, ScenarioFile};
#[allow(unused_imports)]
use super::*;
use divertsim_core::analysis::line::inherit::MachineChanges;
use divertsim_core::model::params::Machine;
use divertsim_core::stats::distribution::Distribution;

/// A sorter line (`divertsim line`): the stream, the destinations and the diverters after
/// the first ([machine] is the first, at position 0). Every key is optional; by default one
/// diverter takes every parcel, with clear gaps of 2.5 m ± 16 % (at least 0.1 m).
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, divertsim_keys::Keys)]
#[serde(deny_unknown_fields, default)]
#[keys(section = "line", default)]
pub struct LineConfig {
    /// The share of parcels bound for the first diverter ([machine]) [-].
    #[key(default = 1.0, range = Bound::closed(0.0, 1.0, ""))]
    pub share: f64,
    /// The induction's target clear gap between consecutive parcels, the rear of one to the
    /// front of the next along the belt [m].
    #[key(default = 2.5, range = Bound::closed(0.0, 100.0, "m"))]
    pub gap_target: f64,
    /// The scatter of the gaps around the target, as a fraction of it (the standard
    /// deviation of a normal); induction gaps scatter ±15–20 %.
    #[key(default = 0.16, range = Bound::closed(0.0, 1.0, ""))]
    pub gap_scatter: f64,
    /// Any distribution of the clear gap [m] instead of gap_target and gap_scatter (see
    /// mix for the kinds); every value it can draw must lie within -100 to 1000 m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gap: Option<DistConfig>,
    /// The induction's smallest gap [m]: a drawn gap below it is raised to it.
    /// Needed with a `gap` distribution that can go below 0. Default 0.1 with gap_target,
    /// else 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[key(range = Bound::closed(0.0, 100.0, "m"))]
    pub min_gap: Option<f64>,
    /// CSV of logged arrival times instead of drawn gaps, relative to this file and in its
    /// directory or below: a header with a column `time` [s] (when each parcel's front passed
    /// the first pivot), strictly increasing, within -1e10 to 1e10 s, with headways of at
    /// most 1e6 s; its headways are replayed in order, from the start again when the stream
    /// has more parcels than the log (the report says how many times).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub arrivals: Option<String>,
    /// What a controller does with a parcel bound for its chute whose planned start falls in
    /// the arm's running cycle: "skip" (default: not served, outcome arm_busy), "late"
    /// (start as soon as the arm is free, if within max_delay), or "barrier" (skip it
    /// already when its front passes the light barrier during a cycle: one parcel at a
    /// time, as the paper's W assumes).
    pub busy_rule: BusyRuleConfig,
    /// With busy_rule = "late": the longest delay of a start [s].
    #[key(default = 0.2, range = Bound::closed(0.0, 10.0, "s"))]
    pub max_delay: f64,
    /// The diverters after the first, in order down the belt.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub diverters: Vec<DiverterConfig>,
}

/// What a controller does when its arm is busy.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum BusyRuleConfig {
    #[default]
    Skip,
    Late,
    Barrier,
}

/// A diverter after the first.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, divertsim_keys::Keys)]
#[serde(deny_unknown_fields)]
#[keys(section = "line.diverters[]")]
pub struct DiverterConfig {
    /// X_d: its pivot's distance down the belt from the first diverter's pivot [m], beyond
    /// the reach of the diverter before it.
    #[key(range = Bound::closed(f64::NEG_INFINITY, 1e4, "m"))]
    pub position: f64,
    /// The share of parcels bound for its chute [-]; the shares of all diverters sum to at
    /// most 1 (the rest go straight through).
    #[key(range = Bound::closed(0.0, 1.0, ""))]
    pub share: f64,
    /// The [machine] keys in which it differs from the first diverter (any but belt_speed
    /// and belt_width, the line's), e.g. { cycle_time = 1.2, start_position = 0.1 }.
    #[serde(default, skip_serializing_if = "toml::Table::is_empty")]
    #[schemars(with = "serde_json::Map<String, serde_json::Value>")]
    pub machine: toml::Table,
}

impl LineConfig {
    pub fn is_default(&self) -> bool {
        *self == LineConfig::default()
    }

    /// The gap law and its minimum \[m].
    pub fn gap(&self) -> (Distribution, f64) {
        match &self.gap {
            None => {
                let sd = self.gap_scatter * self.gap_target;
                let law = match sd > 0.0 {
                    true => Distribution::Normal {
                        mean: self.gap_target,
                        sd,
                    },
                    false => Distribution::Fixed(self.gap_target),
                };
                (law, self.min_gap.unwrap_or(0.1))
            }
            Some(g) => (g.distribution(), self.min_gap.unwrap_or(0.0)),
        }
    }
}

/// The scenario file of diverter `k` (0: the file itself; k ≥ 1: `line.diverters[k − 1]`'s
/// machine over the first's), or the problem of its machine table.
pub fn diverter_file(f: &ScenarioFile, k: usize) -> Result<ScenarioFile, Problem> {
    if k == 0 {
        return Ok(f.clone());
    }
    let key = format!("line.diverters[{}].machine", k - 1);
    let d = &f.line.diverters[k - 1];
    let mut table =
        toml::Table::try_from(&f.machine).map_err(|e| Problem::new(&key, e.to_string()))?;
    merge(&mut table, d.machine.clone());
    let machine = MachineConfig::deserialize(toml::Value::Table(table))
        .map_err(|e| Problem::new(&key, e.message().to_string()))?;
    let mut out = f.clone();
    out.machine = machine;
    out.line = LineConfig::default();
    Ok(out)
}

/// A further diverter's changes over the first machine, in SI: the values of its machine
/// (`merged`: its table over the first's, converted) that its own `[machine]` table
/// states, or derives (the arm's inertia from its length or mass); the rest it inherits.
pub fn machine_changes(table: &toml::Table, merged: &Machine) -> MachineChanges {
    let named = |k: &str| table.contains_key(k);
    MachineChanges {
        arm_length: named("arm_length").then_some(merged.arm_length),
        cycle_time: named("cycle_time").then_some(merged.cycle_time),
        start_position: named("start_position").then_some(merged.start_position),
        light_barrier: named("light_barrier").then_some(merged.light_barrier),
        drive: named("drive").then(|| merged.drive.clone()),
        near_side: named("near_side").then_some(merged.near_side),
        trigger: (named("trigger") || named("adaptive")).then(|| merged.trigger.clone()),
        arm_face_bottom: named("arm_face_bottom").then_some(merged.arm_face_bottom),
        arm_face_top: named("arm_face_top").then_some(merged.arm_face_top),
        arm_inertia: (named("arm_inertia") || named("arm_mass") || named("arm_length"))
            .then_some(merged.arm_inertia),
    }
}

/// Largest arrivals file read \[bytes].
pub const MAX_ARRIVALS_BYTES: u64 = 256 << 20;

/// Largest arrival time in a log \[s], either sign: past any clock a log keeps (Unix time
/// to the year 2286), and where f64 still resolves microseconds.
pub const MAX_ARRIVAL_TIME: f64 = 1e10;

/// Largest headway between two logged arrivals \[s]: a pause of days, not an empty log.
pub const MAX_HEADWAY: f64 = 1e6;

/// Read a log of arrival times: a header with a column `time` \[s], at least two rows,
/// strictly increasing. Errors name the line, never echo a cell.
pub fn read_arrivals(path: &Path) -> Result<Vec<f64>, String> {
    let file = super::files::open_regular(path, MAX_ARRIVALS_BYTES, "an arrivals file")
        .map_err(|e| format!("cannot read: {e}"))?;
    let mut r = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_reader(std::io::Read::take(file, MAX_ARRIVALS_BYTES));
    let headers = r
        .headers()
        .map_err(|_| "the first line must be a CSV header".to_string())?
        .clone();
    let col = headers
        .iter()
        .position(|h| h.eq_ignore_ascii_case("time"))
        .ok_or("the header has no column time (the arrival times [s])")?;
    let mut out: Vec<f64> = Vec::new();
    for (i, row) in r.records().enumerate() {
        let line = i + 2;
        let row = row.map_err(|_| format!("line {line}: not valid CSV"))?;
        let t: f64 = row
            .get(col)
            .unwrap_or("")
            .parse()
            .map_err(|_| format!("line {line}, column time: not a number"))?;
        if !t.is_finite() || t.abs() > MAX_ARRIVAL_TIME {
            return Err(format!(
                "line {line}, column time: allowed: a number from -1e10 to 1e10 s"
            ));
        }
        if let Some(&before) = out.last() {
            if t - before > MAX_HEADWAY {
                return Err(format!(
                    "line {line}, column time: {} s after the line before; allowed: a headway \
                     of at most 1e6 s (11.6 days)",
                    t - before
                ));
            }
            if t <= before {
                return Err(format!(
                    "line {line}, column time: {t} s does not increase (the line before says \
                     {before} s); the times must increase strictly"
                ));
            }
        }
        out.push(t);
    }
    if out.len() < 2 {
        return Err("needs at least two arrival times below the header".into());
    }
    Ok(out)
}

/// `top`'s keys over `bottom`'s, tables merged key by key (a drive table's `kind` alone
/// keeps the first diverter's other drive keys).
fn merge(bottom: &mut toml::Table, top: toml::Table) {
    for (k, v) in top {
        match (bottom.get_mut(&k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(t)) => merge(b, t),
            (_, v) => {
                bottom.insert(k, v);
            }
        }
    }
}

/// Every diverter's scenario file and the core's scenario of it, in order down the belt
/// (the first is the file's own); a further diverter's conversion problems are keyed under
/// `line.diverters[K].`.
pub fn diverter_scenarios(f: &ScenarioFile) -> Result<Vec<(ScenarioFile, Scenario)>, Vec<Problem>> {
    let mut out = Vec::new();
    let mut problems = Vec::new();
    for k in 0..=f.line.diverters.len() {
        let prefix = |mut p: Problem| {
            if k > 0 {
                p.key = format!("line.diverters[{}].{}", k - 1, p.key);
            }
            p
        };
        match diverter_file(f, k)
            .map_err(|p| vec![p])
            .and_then(|file| to_scenario(&file).map(|(s, _)| (file, s)))
        {
            Ok(pair) => out.push(pair),
            Err(ps) => problems.extend(ps.into_iter().map(prefix)),
        }
    }
    if problems.is_empty() {
        Ok(out)
    } else {
        Err(problems)
    }
}
