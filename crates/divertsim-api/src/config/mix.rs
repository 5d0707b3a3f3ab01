//! The `[mix]` section (a parcel population for `divertsim reliability`) and
//! `[machine.adaptive]` (the per-parcel trigger table): schema, defaults, checks and
//! conversion into the core's [`ParcelMix`] and table settings.
//!
//! A distribution is an inline table with a `kind`:
//! `{ kind = "fixed", value = 0.4 }`, `{ kind = "uniform", min = 0.2, max = 0.7 }`,
//! `{ kind = "normal", mean = 0, sd = 10 }`,
//! `{ kind = "truncated-normal", mean = 0, sd = 10, min = -30, max = 30 }`,
//! `{ kind = "lognormal", median = 0.35, sigma = 0.3 }` (σ of ln x),
//! `{ kind = "discrete", values = [0.2, 0.4], weights = [3, 1] }` (weights optional).
//! Parameters are in the unit of the quantity (degrees for `angle_deg`).

use super::bounds::Bound;
use super::Problem;
use divertsim_core::analysis::population::adaptive_trigger::{
    StartSearch, TableNodes, MIN_TOLERANCE,
};
use divertsim_core::analysis::population::mix::{
    MassLaw, ParcelMix, ParcelRecord, Placement, Sizes,
};
use divertsim_core::stats::distribution::Distribution;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A distribution of one quantity, in that quantity's unit.
#[allow(rustdoc::broken_intra_doc_links)]
// doc comments are schema descriptions: [m] is a unit
// Its ranges are checked by the core's Distribution::problems (a test ties the two); `sd`
// is one key path (mix.*.sd) for the normal and the truncated normal, declared on the first.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, divertsim_keys::Keys)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
#[keys(section = "mix.*")]
pub enum DistConfig {
    /// Always `value`.
    Fixed { value: f64 },
    /// Uniform on [min, max].
    Uniform { min: f64, max: f64 },
    /// Normal with `mean` and standard deviation `sd` > 0.
    Normal {
        mean: f64,
        #[key(range = Bound::above(0.0, ""))]
        sd: f64,
    },
    /// Normal(mean, sd) restricted to [min, max].
    TruncatedNormal {
        mean: f64,
        sd: f64,
        min: f64,
        max: f64,
    },
    /// ln x normal: `median` > 0, `sigma` > 0 the standard deviation of ln x.
    Lognormal {
        #[key(range = Bound::above(0.0, ""))]
        median: f64,
        #[key(range = Bound::above(0.0, ""))]
        sigma: f64,
    },
    /// One of `values`, with probabilities proportional to `weights` (default: equal).
    Discrete {
        values: Vec<f64>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        #[key(at = "[]", name = WEIGHTS, range = Bound::at_least(0.0, ""))]
        weights: Option<Vec<f64>>,
    },
}

impl DistConfig {
    /// The largest value it can give (infinite for the unbounded kinds).
    pub fn largest(&self) -> f64 {
        match self {
            DistConfig::Fixed { value } => *value,
            DistConfig::Uniform { max, .. } | DistConfig::TruncatedNormal { max, .. } => *max,
            DistConfig::Normal { .. } | DistConfig::Lognormal { .. } => f64::INFINITY,
            DistConfig::Discrete { values, .. } => {
                values.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            }
        }
    }

    /// The core distribution (same unit).
    pub fn distribution(&self) -> Distribution {
        match self {
            DistConfig::Fixed { value } => Distribution::Fixed(*value),
            DistConfig::Uniform { min, max } => Distribution::Uniform {
                min: *min,
                max: *max,
            },
            DistConfig::Normal { mean, sd } => Distribution::Normal {
                mean: *mean,
                sd: *sd,
            },
            DistConfig::TruncatedNormal { mean, sd, min, max } => Distribution::TruncatedNormal {
                mean: *mean,
                sd: *sd,
                min: *min,
                max: *max,
            },
            DistConfig::Lognormal { median, sigma } => Distribution::LogNormal {
                median: *median,
                sigma: *sigma,
            },
            DistConfig::Discrete { values, weights } => Distribution::Discrete {
                values: values.clone(),
                weights: weights.clone().unwrap_or_else(|| vec![1.0; values.len()]),
            },
        }
    }
}

fn uniform(min: f64, max: f64) -> DistConfig {
    DistConfig::Uniform { min, max }
}

fn fixed(value: f64) -> DistConfig {
    DistConfig::Fixed { value }
}

/// A parcel population for `divertsim reliability`: each quantity a distribution (see
/// `kind`), in SI units (angles in degrees). Sides are sorted so that length ≥ width; a
/// draw that does not fit on the belt or leaves the model's ranges is redrawn and counted.
/// Every key is optional; the defaults are the paper's parcel class, anywhere across the
/// belt, ±10° skew and ±5 ms trigger scatter.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct MixConfig {
    /// CSV of parcel records (e.g. a day's dimensioner log), relative to this file and in its
    /// directory or below (see --allow-outside-paths): a header
    /// naming the columns `length`, `width`, `height` [m] and optionally `mass` [kg] (other
    /// columns are ignored); each sample takes a record uniformly at random. Replaces
    /// length, width and height (and mass, unless mass or density is given).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub records: Option<String>,
    /// a: the longer side [m]. Default uniform 0.2–0.7.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub length: Option<DistConfig>,
    /// b: the shorter side [m] (swapped with length if drawn longer). Default uniform
    /// 0.1–0.26.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub width: Option<DistConfig>,
    /// Height [m]. Default uniform 0.1–0.3.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub height: Option<DistConfig>,
    /// m [kg]. Default uniform 0.5–15 (unless density or records give the mass).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mass: Option<DistConfig>,
    /// ρ [kg/m³]: the mass is ρ × length × width × height (instead of `mass`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub density: Option<DistConfig>,
    /// ΔP: gap to the pivot-side edge [m] (instead of offset_fraction); a parcel placed
    /// over an edge is redrawn.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub offset: Option<DistConfig>,
    /// ΔP as a fraction of the room beside the parcel, in [0, 1]: 0 against the pivot-side
    /// edge, 1 against the far edge. Default uniform 0–1.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub offset_fraction: Option<DistConfig>,
    /// φ: angle to the belt direction [deg]. Default truncated normal, mean 0, sd 10,
    /// within ±30.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub angle_deg: Option<DistConfig>,
    /// Δv: arrival speed relative to the belt, along it [m/s]. Default fixed 0 (riding).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub speed: Option<DistConfig>,
    /// ω: arrival spin [rad/s]. Default fixed 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spin: Option<DistConfig>,
    /// δt: trigger phase error [s]; the parcel is v·δt further downstream when the arm
    /// starts. Default truncated normal, mean 0, sd 0.005, within ±0.01.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub phase: Option<DistConfig>,
    /// μ_b per parcel (replaces materials.belt_friction). Default: no scatter.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub belt_friction: Option<DistConfig>,
    /// μ_a per parcel. Default: no scatter (materials.arm_friction).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub arm_friction: Option<DistConfig>,
    /// e* per parcel. Default: no scatter (materials.restitution).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub restitution: Option<DistConfig>,
    /// Seed of the random streams (sample i uses stream i). Default 1.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
}

/// The defaults of `[mix]`, one place for the loader and for [`MixConfig::resolved`].
mod defaults {
    use super::{fixed, uniform, DistConfig};
    pub fn length() -> DistConfig {
        uniform(0.2, 0.7)
    }
    pub fn width() -> DistConfig {
        uniform(0.1, 0.26)
    }
    pub fn height() -> DistConfig {
        uniform(0.1, 0.3)
    }
    /// The heights a mix without its own draws: the class's band where `[design.search]
    /// height` states one (one class for `check`, `reliability` and the optimisers: issue 50),
    /// else [`height`].
    pub fn class_height(class: Option<[f64; 2]>) -> DistConfig {
        match class {
            Some([lo, hi]) if lo == hi => DistConfig::Fixed { value: lo },
            Some([lo, hi]) => uniform(lo, hi),
            None => height(),
        }
    }
    pub fn mass() -> DistConfig {
        uniform(0.5, 15.0)
    }
    pub fn offset_fraction() -> DistConfig {
        uniform(0.0, 1.0)
    }
    fn truncated(sd: f64, lim: f64) -> DistConfig {
        DistConfig::TruncatedNormal {
            mean: 0.0,
            sd,
            min: -lim,
            max: lim,
        }
    }
    pub fn angle_deg() -> DistConfig {
        truncated(10.0, 30.0)
    }
    pub fn speed() -> DistConfig {
        fixed(0.0)
    }
    pub fn spin() -> DistConfig {
        fixed(0.0)
    }
    pub fn phase() -> DistConfig {
        truncated(0.005, 0.01)
    }
}

impl MixConfig {
    pub fn is_default(&self) -> bool {
        *self == MixConfig::default()
    }

    /// The mix with every default that a draw uses stated (issue 50: a written scenario
    /// records every distribution its run drew from, the built-in mix's included). The seed
    /// stays as given: a run's --seed may replace it. `class`: `[design.search] height`,
    /// which the heights follow when the mix draws none of its own.
    pub fn resolved(&self, class: Option<[f64; 2]>) -> MixConfig {
        let mut m = self.clone();
        let fill = |d: &mut Option<DistConfig>, default: fn() -> DistConfig| {
            if d.is_none() {
                *d = Some(default());
            }
        };
        if m.records.is_none() {
            fill(&mut m.length, defaults::length);
            fill(&mut m.width, defaults::width);
            if m.height.is_none() {
                m.height = Some(defaults::class_height(class));
            }
            if m.density.is_none() {
                fill(&mut m.mass, defaults::mass);
            }
        }
        if m.offset.is_none() {
            fill(&mut m.offset_fraction, defaults::offset_fraction);
        }
        fill(&mut m.angle_deg, defaults::angle_deg);
        fill(&mut m.speed, defaults::speed);
        fill(&mut m.spin, defaults::spin);
        fill(&mut m.phase, defaults::phase);
        m
    }

    /// Every distribution given, with its key name.
    fn given(&self) -> Vec<(&'static str, &DistConfig)> {
        [
            ("length", &self.length),
            ("width", &self.width),
            ("height", &self.height),
            ("mass", &self.mass),
            ("density", &self.density),
            ("offset", &self.offset),
            ("offset_fraction", &self.offset_fraction),
            ("angle_deg", &self.angle_deg),
            ("speed", &self.speed),
            ("spin", &self.spin),
            ("phase", &self.phase),
            ("belt_friction", &self.belt_friction),
            ("arm_friction", &self.arm_friction),
            ("restitution", &self.restitution),
        ]
        .into_iter()
        .filter_map(|(k, d)| d.as_ref().map(|d| (k, d)))
        .collect()
    }

    /// The seed.
    pub fn seed(&self) -> u64 {
        self.seed.unwrap_or(1)
    }
}

/// Range and consistency checks of `[mix]` (the records file is read in [`parcel_mix`]).
pub fn validate(m: &MixConfig, problems: &mut Vec<Problem>) {
    for (key, d) in m.given() {
        for (param, message) in d.distribution().problems() {
            problems.push(Problem::new(format!("mix.{key}.{param}"), message));
        }
    }
    if m.records.is_some() {
        for (key, d) in [
            ("length", &m.length),
            ("width", &m.width),
            ("height", &m.height),
        ] {
            if d.is_some() {
                problems.push(Problem::new(
                    format!("mix.{key}"),
                    "cannot be given with mix.records (the records give the sizes); remove one",
                ));
            }
        }
    }
    if m.mass.is_some() && m.density.is_some() {
        problems.push(Problem::new(
            "mix.density",
            "cannot be given with mix.mass; give the mass or the density",
        ));
    }
    if m.offset.is_some() && m.offset_fraction.is_some() {
        problems.push(Problem::new(
            "mix.offset_fraction",
            "cannot be given with mix.offset; give ΔP in metres or as a fraction of the room",
        ));
    }
}

/// The core mix: the distributions (defaults filled in, degrees to radians) and the records
/// file read (its path as resolved by the loader: relative to the working directory).
pub fn parcel_mix(m: &MixConfig, class: Option<[f64; 2]>) -> Result<ParcelMix, Vec<Problem>> {
    let d =
        |c: &Option<DistConfig>, default: DistConfig| c.clone().unwrap_or(default).distribution();
    let (sizes, recorded_mass) = match &m.records {
        Some(path) => {
            let records = read_records(Path::new(path))
                .map_err(|e| vec![Problem::new("mix.records", format!("{path}: {e}"))])?;
            let with_mass = records.iter().all(|r| r.mass.is_some());
            (Sizes::Records(records.into()), with_mass)
        }
        None => (
            Sizes::Drawn {
                length: d(&m.length, defaults::length()),
                width: d(&m.width, defaults::width()),
                height: d(&m.height, defaults::class_height(class)),
            },
            false,
        ),
    };
    let mass = match (&m.mass, &m.density) {
        (_, Some(rho)) => MassLaw::Density(rho.distribution()),
        (Some(mass), None) => MassLaw::Mass(mass.distribution()),
        (None, None) if recorded_mass => MassLaw::Recorded,
        (None, None) => {
            if matches!(sizes, Sizes::Records(_)) {
                return Err(vec![Problem::new(
                    "mix.mass",
                    "the records have no mass column: give mix.mass or mix.density",
                )]);
            }
            MassLaw::Mass(defaults::mass().distribution())
        }
    };
    let placement = match &m.offset {
        Some(o) => Placement::Offset(o.distribution()),
        None => Placement::RoomFraction(d(&m.offset_fraction, defaults::offset_fraction())),
    };
    Ok(ParcelMix {
        sizes,
        mass,
        placement,
        angle: d(&m.angle_deg, defaults::angle_deg()).scaled(std::f64::consts::PI / 180.0),
        speed: d(&m.speed, defaults::speed()),
        spin: d(&m.spin, defaults::spin()),
        phase: d(&m.phase, defaults::phase()),
        belt_friction: m.belt_friction.as_ref().map(DistConfig::distribution),
        arm_friction: m.arm_friction.as_ref().map(DistConfig::distribution),
        restitution: m.restitution.as_ref().map(DistConfig::distribution),
    })
}

/// Largest number of records read.
pub const MAX_RECORDS: usize = 10_000_000;

/// Largest records file read [bytes]: 10⁷ records of a few numbers each; checked before
/// anything is read, so an endless or giant file is an error, not an abort.
pub const MAX_RECORDS_BYTES: u64 = 512 << 20;

/// Read a records CSV: a header naming length, width, height (and optionally mass); other
/// columns ignored. Errors name the line and column, never echo a cell.
pub(crate) fn read_records(path: &Path) -> Result<Vec<ParcelRecord>, String> {
    let file = super::files::open_regular(path, MAX_RECORDS_BYTES, "a records file")
        .map_err(|e| format!("cannot read: {e}"))?;
    let mut r = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .flexible(false)
        .from_reader(std::io::Read::take(file, MAX_RECORDS_BYTES));
    let headers = r
        .headers()
        .map_err(|_| "the first line must be a CSV header".to_string())?
        .clone();
    let column = |name: &str| headers.iter().position(|h| h.eq_ignore_ascii_case(name));
    let cols: Vec<Option<usize>> = ["length", "width", "height", "mass"]
        .iter()
        .map(|n| column(n))
        .collect();
    let missing: Vec<&str> = ["length", "width", "height"]
        .iter()
        .zip(&cols)
        .filter(|(_, c)| c.is_none())
        .map(|(n, _)| *n)
        .collect();
    if !missing.is_empty() {
        return Err(format!(
            "the header has no column {} (needed: length, width, height [m], optional mass [kg])",
            missing.join(", ")
        ));
    }
    let mut out = Vec::new();
    for (i, row) in r.records().enumerate() {
        let line = i + 2;
        let row = row.map_err(|e| match e.kind() {
            csv::ErrorKind::UnequalLengths { .. } => {
                format!("line {line}: the number of fields differs from the header")
            }
            _ => format!("line {line}: not valid CSV"),
        })?;
        let cell = |k: usize, name: &str| -> Result<f64, String> {
            let text = cols[k].and_then(|c| row.get(c)).unwrap_or("");
            let v: f64 = text
                .parse()
                .map_err(|_| format!("line {line}, column {name}: not a number"))?;
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                Err(format!(
                    "line {line}, column {name}: allowed: a finite number > 0"
                ))
            }
        };
        out.push(ParcelRecord {
            length: cell(0, "length")?,
            width: cell(1, "width")?,
            height: cell(2, "height")?,
            mass: match cols[3] {
                Some(_) => Some(cell(3, "mass")?),
                None => None,
            },
        });
        if out.len() > MAX_RECORDS {
            return Err(format!("more than {MAX_RECORDS} records"));
        }
    }
    if out.is_empty() {
        return Err("has no records below the header".into());
    }
    Ok(out)
}

/// How the arm is started for each parcel.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum TriggerConfig {
    /// Every parcel at machine.start_position.
    #[default]
    Fixed,
    /// Each parcel at its own R_s, from a table over its length, width, offset and angle
    /// (`simulate`: the parcel's own best R_s; `reliability`: the table).
    Adaptive,
}

/// The per-parcel trigger's table: its grid (ranges from the mix) and the R_s search at
/// each node.
#[allow(rustdoc::broken_intra_doc_links)]
// doc comments are schema descriptions: [m] is a unit
// Its defaults are the core's (TableNodes, StartSearch); the step and tolerance are
// checked by the core's StartSearch::problems (a test ties the two).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, divertsim_keys::Keys)]
#[serde(deny_unknown_fields, default)]
#[keys(section = "machine.adaptive")]
pub struct AdaptiveConfig {
    /// Nodes along the parcel length.
    #[key(range = Bound::band(NODES, ""))]
    pub length_nodes: usize,
    /// Nodes along the aspect width/length.
    #[key(range = Bound::band(NODES, ""))]
    pub aspect_nodes: usize,
    /// Nodes across the room beside the parcel (offset fraction 0–1).
    #[key(range = Bound::band(NODES, ""))]
    pub offset_nodes: usize,
    /// Nodes along the angle.
    #[key(range = Bound::band(NODES, ""))]
    pub angle_nodes: usize,
    /// R_s interval searched at each node [m].
    pub search: [f64; 2],
    /// R_s scan step [m].
    #[key(range = Bound::above(0.0, "m"))]
    pub step: f64,
    /// Bisection tolerance on the ends of the passing R_s interval [m].
    #[key(range = Bound::at_least(MIN_TOLERANCE, "m"))]
    pub tolerance: f64,
}

/// The range of a table's node count along one axis.
const NODES: (f64, f64) = (1.0, 50.0);

impl Default for AdaptiveConfig {
    fn default() -> Self {
        let s = StartSearch::default();
        let n = TableNodes::default();
        AdaptiveConfig {
            length_nodes: n.length,
            aspect_nodes: n.aspect,
            offset_nodes: n.offset,
            angle_nodes: n.angle,
            search: [s.range.0, s.range.1],
            step: s.step,
            tolerance: s.tolerance,
        }
    }
}

/// Largest number of table nodes.
pub const MAX_NODES: usize = 20_000;

impl AdaptiveConfig {
    pub fn is_default(&self) -> bool {
        *self == AdaptiveConfig::default()
    }

    /// The R_s search at a node.
    pub fn search(&self) -> StartSearch {
        StartSearch {
            range: (self.search[0], self.search[1]),
            step: self.step,
            tolerance: self.tolerance,
            ..StartSearch::default()
        }
    }

    /// The table's nodes along each axis.
    pub fn nodes(&self) -> TableNodes {
        TableNodes {
            length: self.length_nodes,
            aspect: self.aspect_nodes,
            offset: self.offset_nodes,
            angle: self.angle_nodes,
        }
    }
}

/// Checks of `[machine.adaptive]`.
pub fn validate_adaptive(a: &AdaptiveConfig, problems: &mut Vec<Problem>) {
    for (b, n) in [
        (&AdaptiveConfig::LENGTH_NODES, a.length_nodes),
        (&AdaptiveConfig::ASPECT_NODES, a.aspect_nodes),
        (&AdaptiveConfig::OFFSET_NODES, a.offset_nodes),
        (&AdaptiveConfig::ANGLE_NODES, a.angle_nodes),
    ] {
        // Counts far beyond the bound lose precision as f64, but stay out of range.
        problems.extend(b.problem(b.key, n as f64));
    }
    let nodes = a
        .length_nodes
        .saturating_mul(a.aspect_nodes)
        .saturating_mul(a.offset_nodes)
        .saturating_mul(a.angle_nodes);
    if nodes > MAX_NODES {
        problems.push(Problem::new(
            "machine.adaptive",
            format!("{nodes} table nodes; allowed: at most {MAX_NODES}"),
        ));
    }
    for (name, message) in a.search().problems() {
        problems.push(Problem::new(format!("machine.adaptive.{name}"), message));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 50, item 2: a mix that draws no heights of its own follows a stated
    /// `[design.search] height` (one class for `check`, `reliability` and the optimisers),
    /// in the run and in the written scenario; without one it keeps the default 0.1–0.3 m;
    /// its own heights or records win.
    #[test]
    fn a_mix_without_heights_follows_the_stated_class_band() {
        let plain = MixConfig::default();
        let drawn = |m: &MixConfig, class| parcel_mix(m, class).unwrap().height_range();
        assert_eq!(drawn(&plain, Some([0.12, 0.18])), (0.12, 0.18));
        assert_eq!(drawn(&plain, Some([0.15, 0.15])), (0.15, 0.15));
        assert_eq!(drawn(&plain, None), (0.1, 0.3));
        assert_eq!(
            plain.resolved(Some([0.15, 0.15])).height,
            Some(DistConfig::Fixed { value: 0.15 })
        );
        assert_eq!(plain.resolved(None).height, Some(uniform(0.1, 0.3)));
        let own = MixConfig {
            height: Some(uniform(0.2, 0.4)),
            ..MixConfig::default()
        };
        assert_eq!(drawn(&own, Some([0.12, 0.18])), (0.2, 0.4));
        assert_eq!(own.resolved(Some([0.12, 0.18])).height, own.height);
    }

    /// Hostile input round three: a huge `mix.records` aborted (SIGABRT) instead of exit 2.
    /// A file beyond the cap is refused by its size; so is a drive table beyond its own.
    #[test]
    fn huge_records_and_drive_table_are_refused_by_size() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("r.csv");
        std::fs::File::create(&p)
            .unwrap()
            .set_len(MAX_RECORDS_BYTES + 1)
            .unwrap();
        let e = read_records(&p).unwrap_err();
        assert!(e.contains("larger than 512 MiB"), "{e}");
        let t = dir.path().join("alpha.csv");
        std::fs::File::create(&t)
            .unwrap()
            .set_len(crate::config::files::MAX_SCENARIO_BYTES + 1)
            .unwrap();
        let e = crate::config::read_alpha_table(&t).unwrap_err();
        assert!(e.contains("larger than 16 MiB"), "{e}");
    }

    #[test]
    fn records_errors_name_line_and_column_without_echoing() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("r.csv");
        std::fs::write(
            &p,
            "id,length,width,height\n1,0.4,0.2,0.1\n2,0.3,secret,0.1\n",
        )
        .unwrap();
        let e = read_records(&p).unwrap_err();
        assert!(e.contains("line 3, column width"), "{e}");
        assert!(!e.contains("secret"));
        std::fs::write(&p, "length,width\n0.4,0.2\n").unwrap();
        assert!(read_records(&p).unwrap_err().contains("no column height"));
        std::fs::write(&p, "Length,Width,Height,Mass,label\n0.4,0.2,0.1,2.5,x\n").unwrap();
        let r = read_records(&p).unwrap();
        assert_eq!(r[0].mass, Some(2.5));
    }
}
