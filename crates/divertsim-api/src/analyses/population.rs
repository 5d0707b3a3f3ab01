//! What the population studies share (reliability, the sorter line, `check`'s mix, the line
//! optimiser): the points of a study (the scenario, or one per swept value), a machine's
//! trigger (fixed, or its adaptive table), the progress a study reports
//! ([`Watch`]), and the JSON and CSV views of proportions and load spectra. The studies
//! themselves live beside this module, each in its own file, and take these from here.

use crate::config::mix::TriggerConfig;
use crate::config::{Loaded, MachineConfig, Problem, Problems};
use crate::contract::Error;
use divertsim_core::analysis::population::adaptive_trigger::TriggerTable;
use divertsim_core::analysis::population::mix::ParcelMix;
use divertsim_core::analysis::population::reliability::{SampleRun, StartRule, Tally};
use divertsim_core::model::params::Scenario;
use divertsim_core::stats::binomial::Proportion;
use divertsim_core::stats::histogram::Spectrum;
use divertsim_core::stats::loads::StrokeLoads;
use serde_json::{json, Value};
use std::collections::BTreeMap;

/// A sweep as given: the text `KEY=LO:HI/N` / `KEY=LO:HI:STEP` / `KEY=A,B,...`, or
/// `{key: [values]}`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum SweepSpec {
    /// `KEY=LO:HI/N`, `KEY=LO:HI:STEP` or `KEY=A,B,...`.
    Text(String),
    /// One key and its values.
    Map(BTreeMap<String, Value>),
}

impl SweepSpec {
    /// The swept key and its values as `--set` texts, and a warning for a numeric range that
    /// gives a single value; or the problem (keyed `sweep`).
    pub fn resolve(&self) -> Result<(Sweep, Option<String>), Problem> {
        match self {
            SweepSpec::Text(t) => parse_sweep(t),
            SweepSpec::Map(m) if m.len() == 1 => {
                let (k, v) = m.iter().next().expect("one entry");
                let values: Vec<String> = match v {
                    Value::Array(a) => a
                        .iter()
                        .map(|x| match x {
                            Value::String(s) => s.clone(),
                            other => other.to_string(),
                        })
                        .collect(),
                    other => {
                        return Err(Problem::new(
                            "sweep",
                            format!("{other} is not a list of values"),
                        ))
                    }
                };
                Ok(((k.clone(), values), None))
            }
            SweepSpec::Map(_) => Err(Problem::new(
                "sweep",
                "give one key with its list of values, e.g. {\"machine.belt_speed\": [1.8, 2.0]}",
            )),
        }
    }
}

/// The swept key and its values of the text `KEY=...`, with the warning of a numeric range
/// that gives a single value.
fn parse_sweep(text: &str) -> Result<(Sweep, Option<String>), Problem> {
    let bad = |m: String| Problem::new("sweep", m);
    let Some((key, spec)) = text.split_once('=') else {
        return Err(bad(format!(
            "'{text}' is not KEY=LO:HI/N, KEY=LO:HI:STEP or KEY=A,B,... (e.g. machine.belt_speed=1.5:2.3/9)"
        )));
    };
    let (key, spec) = (key.trim(), spec.trim());
    if key.is_empty() || key.split('.').any(str::is_empty) {
        return Err(bad(format!("'{key}' is not a dotted scenario key")));
    }
    // Numbers in the one grammar (A,B,C or LO:HI/N or LO:HI:STEP); other values (strings
    // such as fixed,adaptive) as a comma list.
    let numeric = spec.contains(':')
        || spec
            .split(',')
            .all(|v| v.trim().parse::<f64>().is_ok_and(f64::is_finite));
    let (values, warning): (Vec<String>, Option<String>) = if numeric {
        let (v, warning) =
            crate::config::values::parse_values("sweep", spec, -1e12, 1e12, "", MAX_POINTS)?;
        (v.iter().map(|x| x.to_string()).collect(), warning)
    } else {
        (
            spec.split(',').map(|v| v.trim().to_string()).collect(),
            None,
        )
    };
    if values.iter().any(String::is_empty) || values.len() > MAX_POINTS {
        return Err(bad(format!(
            "'{spec}': allowed: 1 to {MAX_POINTS} values separated by commas"
        )));
    }
    Ok(((key.to_string(), values), warning))
}

/// A swept scenario key and its values as `--set` texts.
pub type Sweep = (String, Vec<String>);

/// A study's options once checked, with the sweep's key and values (reliability's and the
/// line's `Analysis::Checked`; each study makes its own points of it).
#[derive(Debug, Clone)]
pub struct Swept<O> {
    pub options: O,
    pub sweep: Option<Sweep>,
}

/// What a run reports as it goes (every method optional; called from the running thread
/// or, for [`Watch::tick`], from the workers).
pub trait Watch: Sync {
    /// An adaptive trigger table of `nodes` searches starts.
    fn table_started(&self, _nodes: u64) {}
    /// It is done.
    fn table_done(&self, _table: &TriggerTable) {}
    /// Point `i` starts its samples.
    fn point_started(&self, _i: usize) {}
    /// One simulation (of the table or a sample) finished.
    fn tick(&self) {}
    /// A shard of the current point is tallied: `done` of its samples so far.
    fn shard_done(&self, _done: u64) {}
    /// The same moment with the tally so far of point `i` (the rates as they come).
    fn shard_tallied(&self, _i: usize, _tally: &Tally) {}
}

/// Reports nothing.
pub struct Quiet;

impl Watch for Quiet {}

/// The points of a run: the scenario, or one per value of the swept key (`sweep`: the key
/// and its values as `--set` texts), each loaded by `load` with those extra overrides. A
/// problem every point shares is reported once.
pub fn load_points(
    load: &dyn Fn(&[String]) -> Result<Loaded, Problems>,
    sweep: Option<&(String, Vec<String>)>,
    seed: Option<u64>,
) -> Result<Vec<Point>, Vec<Problem>> {
    let values = match sweep {
        None => vec![String::new()],
        Some((_, v)) => v.clone(),
    };
    if values.is_empty() || values.len() > MAX_POINTS {
        return Err(vec![Problem::new(
            "sweep",
            format!("{} values; allowed: 1 to {MAX_POINTS}", values.len()),
        )]);
    }
    let mut points = Vec::new();
    let mut problems: Vec<Problem> = Vec::new();
    let mut seen: Vec<Problem> = Vec::new();
    for value in values {
        let sets: Vec<String> = sweep
            .map(|(k, _)| format!("{k}={value}"))
            .into_iter()
            .collect();
        match load(&sets) {
            Ok(mut loaded) => {
                share_records(&mut loaded, &points);
                // The written scenario states the mix drawn from, defaults included.
                loaded.file.mix = loaded.file.mix.resolved(loaded.file.design.search.height);
                let seed = seed.unwrap_or_else(|| loaded.file.mix.seed());
                points.push(Point {
                    value,
                    loaded,
                    seed,
                })
            }
            Err(e) => {
                for p in e.0 {
                    if seen.contains(&p) {
                        continue;
                    }
                    seen.push(p.clone());
                    let mut p = p;
                    if sweep.is_some() {
                        p.message = format!("{} (at sweep point {value})", p.message);
                    }
                    problems.push(p);
                }
            }
        }
    }
    if problems.is_empty() {
        Ok(points)
    } else {
        Err(problems)
    }
}

/// A point's parcel records, if an earlier point holds the same ones, replaced by that
/// point's copy: a sweep over a 10⁷-record log holds it once, not once per point.
fn share_records(loaded: &mut Loaded, earlier: &[Point]) {
    use divertsim_core::analysis::population::mix::Sizes;
    let Sizes::Records(mine) = &loaded.mix.sizes else {
        return;
    };
    for p in earlier {
        if let Sizes::Records(theirs) = &p.loaded.mix.sizes {
            if std::sync::Arc::ptr_eq(mine, theirs) || **mine == **theirs {
                loaded.mix.sizes = Sizes::Records(theirs.clone());
                return;
            }
        }
    }
}

/// The trigger of a machine (`[machine]`, or a line's diverter): fixed, or its adaptive
/// table over `mix` on `setting` (the table's searches run here).
pub fn machine_trigger(
    machine: &MachineConfig,
    mix: &ParcelMix,
    setting: &Scenario,
    seed: u64,
    watch: &dyn Watch,
) -> Result<StartRule, Error> {
    match machine.trigger {
        TriggerConfig::Fixed => Ok(StartRule::Fixed),
        TriggerConfig::Adaptive => {
            let a = &machine.adaptive;
            let grid = a
                .nodes()
                .grid(mix, setting, seed)
                .map_err(|e| Error::Failed(e.to_string()))?;
            watch.table_started(grid.len() as u64);
            let tick = || watch.tick();
            let t = TriggerTable::build(setting, grid, &a.search(), &tick);
            watch.table_done(&t);
            Ok(StartRule::Adaptive(t))
        }
    }
}

/// Simulations of a machine's adaptive trigger table (0 for the fixed trigger).
pub fn table_simulations(machine: &MachineConfig) -> u64 {
    match machine.trigger {
        TriggerConfig::Fixed => 0,
        TriggerConfig::Adaptive => {
            let a = &machine.adaptive;
            (a.nodes().count() * a.search().estimated_simulations()) as u64
        }
    }
}

/// The points of a run on `scenario`: itself, or a variant per swept value (the swept key
/// set on its resolved file, turned into a table once, exactly as `--set` would).
pub fn variant_points(
    scenario: &Loaded,
    sweep: Option<&Sweep>,
    seed: Option<u64>,
) -> Result<Vec<Point>, Vec<Problem>> {
    let base = crate::config::ScenarioBuilder::resolved(scenario)
        .merged()
        .map_err(|p| p.0)?;
    let load = |extra: &[String]| match extra.is_empty() {
        true => Ok(scenario.clone()),
        false => base.clone().sets(extra).load(),
    };
    load_points(&load, sweep, seed)
}

/// The list grammar's warning on a sweep's values, keyed `sweep` (none for a bad sweep:
/// its check says what is wrong).
pub fn sweep_warning(spec: Option<&SweepSpec>) -> Vec<Problem> {
    spec.and_then(|s| s.resolve().ok())
        .and_then(|(_, warning)| warning)
        .map(|w| Problem::new("sweep", w))
        .into_iter()
        .collect()
}

/// The sweep of the options, its problem (keyed `sweep`) pushed onto `problems`.
pub fn checked_sweep(spec: Option<&SweepSpec>, problems: &mut Vec<Problem>) -> Option<Sweep> {
    match spec.map(SweepSpec::resolve) {
        None => None,
        Some(Ok((s, _))) => Some(s),
        Some(Err(p)) => {
            problems.push(p);
            None
        }
    }
}

/// Largest number of sweep points.
pub const MAX_POINTS: usize = 1000;

/// One point of the run (the only one without a sweep).
#[derive(Debug, Clone)]
pub struct Point {
    /// The swept value as given ("" without a sweep).
    pub value: String,
    pub loaded: Loaded,
    /// The seed of its streams: --seed, else its mix.seed (so `--sweep mix.seed=1,2,3`
    /// runs three sets of parcels).
    pub seed: u64,
}

pub fn proportion_json(p: &Proportion) -> Value {
    json!({
        "count": p.successes,
        "of": p.trials,
        "estimate": finite_or_null(p.estimate),
        "lower": p.lower,
        "upper": p.upper,
    })
}

pub fn finite_or_null(v: f64) -> Value {
    if v.is_finite() {
        json!(v)
    } else {
        Value::Null
    }
}

/// A study's arm loads as JSON (a summary's `load_spectrum`): the strokes, `note` on how
/// they were counted, both spectra and the `largest` stroke as its study describes it.
pub fn load_spectrum_json<R>(loads: &StrokeLoads<R>, note: &str, largest: Option<Value>) -> Value {
    json!({
        "strokes": loads.strokes,
        "note": note,
        "peak_drive_torque_n_m": spectrum_json(&loads.torque_spectrum, loads),
        "strike_angular_impulse_n_m_s": spectrum_json(&loads.strike_spectrum, loads),
        "largest_stroke": largest,
    })
}

/// A load spectrum as JSON: each non-empty bin with its count per 10⁶ strokes, and the loads
/// above the last edge.
fn spectrum_json<R>(sp: &Option<Spectrum>, loads: &StrokeLoads<R>) -> Value {
    let per_million = |n: u64| loads.per_million(n);
    let Some(sp) = sp else {
        return Value::Null;
    };
    let bins: Vec<Value> = (0..sp.count.len())
        .filter(|&k| sp.count[k] > 0)
        .map(|k| {
            json!({
                "lo": sp.lower(k),
                "hi": sp.upper[k],
                "count": sp.count[k],
                "per_million_strokes": per_million(sp.count[k]),
            })
        })
        .collect();
    json!({
        "bins": bins,
        "above": {
            "lo": sp.upper.last(),
            "count": sp.above,
            "per_million_strokes": per_million(sp.above),
        },
        "max": sp.max,
        "total": sp.total(),
    })
}

/// The scenario file of sample `s` of point `p`: `simulate` on it runs that sample again.
pub fn sample_file(p: &Point, s: &SampleRun) -> crate::config::ScenarioFile {
    let run = s.draw.scenario(&p.loaded.scenario, s.start_position);
    crate::config::scenario_file(&p.loaded.file, &run, s.draw.angle.to_degrees())
}

/// The file of point `i`'s largest stroke among `points`: largest_stroke.toml, or
/// pointK_largest_stroke.toml in a sweep (K from 1).
pub fn largest_stroke_name(points: usize, i: usize) -> String {
    match points {
        1 => "largest_stroke.toml".to_string(),
        _ => format!("point{}_largest_stroke.toml", i + 1),
    }
}

/// The columns of load_spectrum.csv.
pub const LOAD_SPECTRUM_COLUMNS: [&str; 7] = [
    "point",
    "sweep_value",
    "load",
    "bin_lo",
    "bin_hi",
    "count",
    "per_million_strokes",
];

/// load_spectrum.csv's rows of point `point` (swept value `value`): per load and bin, the
/// count and the count per 10⁶ strokes (the bin above the last edge has no upper edge).
pub fn load_spectrum_rows<R>(
    point: usize,
    value: &str,
    loads: &StrokeLoads<R>,
) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    for (load, sp) in [
        ("peak_drive_torque_n_m", &loads.torque_spectrum),
        ("strike_angular_impulse_n_m_s", &loads.strike_spectrum),
    ] {
        let Some(sp) = sp else { continue };
        let mut row = |lo: f64, hi: String, n: u64| {
            rows.push(vec![
                point.to_string(),
                value.to_string(),
                load.to_string(),
                lo.to_string(),
                hi,
                n.to_string(),
                loads.per_million(n).to_string(),
            ])
        };
        for k in 0..sp.count.len() {
            row(sp.lower(k), sp.upper[k].to_string(), sp.count[k]);
        }
        row(*sp.upper.last().unwrap_or(&0.0), String::new(), sp.above);
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config;

    #[test]
    fn sweep_grammar() {
        // A mapping of one key to its values, as Python gives it.
        let m = SweepSpec::Map(BTreeMap::from([(
            "machine.trigger".to_string(),
            json!(["fixed", 1.5]),
        )]));
        assert_eq!(m.resolve().unwrap().0 .1, ["fixed", "1.5"]);
        assert!(SweepSpec::Map(BTreeMap::new()).resolve().is_err());
        let (k, v) = parse_sweep("machine.belt_speed=1.5:2.3/9").unwrap().0;
        assert_eq!(k, "machine.belt_speed");
        assert_eq!(v.len(), 9);
        assert_eq!((v[0].as_str(), v[8].as_str()), ("1.5", "2.3"));
        assert_eq!(v[1], "1.6");
        let (_, v) = parse_sweep("k.x=0.65:2.3/5").unwrap().0;
        assert_eq!(v, ["0.65", "1.0625", "1.475", "1.8875", "2.3"]);
        let (_, v) = parse_sweep("machine.trigger = fixed, adaptive").unwrap().0;
        assert_eq!(v, ["fixed", "adaptive"]);
        for bad in [
            "belt_speed",
            "=1,2",
            "a.b=1:2",
            "a.b=x:2:3",
            "a.b=1,,2",
            "a.b=1:2/2000",
        ] {
            assert_eq!(parse_sweep(bad).unwrap_err().key, "sweep", "{bad}");
        }
    }

    /// Hostile input round three: a sweep held the parcel records once per point (a
    /// 10⁷-record log times 1,000 points). The points share one copy.
    #[test]
    fn sweep_points_share_one_copy_of_the_records() {
        use divertsim_core::analysis::population::mix::Sizes;
        let dir = tempfile::tempdir().unwrap();
        let records = dir.path().join("log.csv");
        std::fs::write(
            &records,
            "length,width,height,mass\n0.4,0.2,0.1,2\n0.3,0.2,0.15,1\n",
        )
        .unwrap();
        let scenario = dir.path().join("s.toml");
        std::fs::write(&scenario, "[mix]\nrecords = \"log.csv\"\n").unwrap();
        let load = |extra: &[String]| config::load(Some(&scenario), extra);
        let sweep = (
            "machine.belt_speed".to_string(),
            vec!["1.6".to_string(), "1.8".to_string(), "2.0".to_string()],
        );
        let points = load_points(&load, Some(&sweep), None).unwrap();
        let Sizes::Records(first) = &points[0].loaded.mix.sizes else {
            panic!("records");
        };
        for p in &points[1..] {
            let Sizes::Records(r) = &p.loaded.mix.sizes else {
                panic!("records");
            };
            assert!(std::sync::Arc::ptr_eq(first, r));
        }
    }
}
