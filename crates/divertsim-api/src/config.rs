//! The scenario file (TOML): its schema, `--set` overrides, validation and conversion into
//! the core's SI scenario.
//!
//! The keys are a public contract. Every key is optional: a key left out takes the value of
//! the built-in default scenario (the paper's compact parcel at v = 2 m/s, t_c = 1.36 s,
//! R_s = 0). Angles are in degrees and carry `_deg` in their names; everything else is SI.
//! Every problem is reported at once, each naming its key path and the allowed range.

use divertsim_core::analysis::design::design_set::{
    DesignCase, DesignSet, Margins, WorstDefinition,
};
use divertsim_core::analysis::design::worst_case::{Pose, PoseBox};
use divertsim_core::model::belt_friction::{FrictionCoefficient, FrictionModel};
use divertsim_core::model::drive::{ArmDrive, DriveSpec, FourBar};
use divertsim_core::model::impact::ImpactLaw;
use divertsim_core::model::params::{
    default_duration, Limits, Machine, Materials, NearSide, Parcel, RunSettings, Scenario,
};
use glam::DVec2;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::{Path, PathBuf};

pub mod bounds;
pub mod camera;
pub mod example;
pub mod files;
pub mod mix;
pub mod values;
use bounds::Bound;
use camera::CameraConfig;
pub use files::LoadOptions;
use files::Origin;
use mix::{AdaptiveConfig, MixConfig, TriggerConfig};

/// A divertsim scenario: the machine, the parcel, the materials, the run and the limits.
/// Any key left out takes the built-in default. SI units; angles in degrees (`_deg`).
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct ScenarioFile {
    /// Path of a scenario file this one builds on, relative to this file and in its
    /// directory or below (e.g. `base = "machine.toml"`; see --allow-outside-paths): its
    /// keys are read first and this file's keys override them. Bases may chain, up to 8
    /// deep.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub base: Option<String>,
    pub machine: MachineConfig,
    pub parcel: ParcelConfig,
    pub materials: MaterialsConfig,
    pub run: RunConfig,
    pub limits: LimitsConfig,
    pub design: DesignConfig,
    #[serde(skip_serializing_if = "OptimizeConfig::is_default")]
    pub optimize: OptimizeConfig,
    /// The parcel population of `divertsim reliability`.
    #[serde(skip_serializing_if = "MixConfig::is_default")]
    pub mix: MixConfig,
    /// The camera of filmed tracks (`divertsim track`, `compare`, `calibrate`).
    #[serde(skip_serializing_if = "CameraConfig::is_default")]
    pub camera: CameraConfig,
}

/// The diverter and its belt. The frame has its origin at the arm pivot, x along the belt
/// motion and y across the belt towards the discharge side; the belt spans
/// 0 ≤ y ≤ belt_width.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct MachineConfig {
    /// P_max: belt width [m]. Default 0.7.
    pub belt_width: f64,
    /// v: belt speed [m/s]. Default 2.
    pub belt_speed: f64,
    /// R_z: arm length from the pivot [m]. Default 1.0.
    pub arm_length: f64,
    /// t_c: the arm's working cycle, out and back [s]. Default 1.36.
    pub cycle_time: f64,
    /// R_s: x of the parcel's most downstream point when the arm starts (t = 0), measured
    /// from the pivot [m]. Default 0.
    pub start_position: f64,
    /// S_d: x of the light barrier [m]; must not lie downstream of start_position.
    /// Default 0.
    pub light_barrier: f64,
    /// The arm's motion law.
    pub drive: DriveConfig,
    /// The pivot-side belt edge downstream of the pivot: "open" (default; physics.md §0 has
    /// a side guide only upstream of the pivot, and a parcel whose centre crosses the edge
    /// downstream falls off: not_diverted, reason off_near_side) or "guide" (the side guide
    /// continues along the whole edge and holds the parcel).
    pub near_side: NearSideConfig,
    /// How the arm is started: "fixed" (default: every parcel at start_position) or
    /// "adaptive" (each parcel at its own R_s, from what a dimensioner sees: `simulate` runs
    /// the parcel's own best R_s, `reliability` reads a table; other commands refuse it).
    pub trigger: TriggerConfig,
    /// The adaptive trigger's table.
    pub adaptive: AdaptiveConfig,
}

/// The pivot-side belt edge downstream of the pivot.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum NearSideConfig {
    /// No guide downstream of the pivot: a parcel can fall off there.
    #[default]
    Open,
    /// A side guide along the whole pivot-side edge.
    Guide,
}

/// The arm's motion law over one cycle, starting and ending at rest at α = 0.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct DriveConfig {
    /// "crank-rocker" (default; four-bar, crank at 2π/t_c), "cycloidal", "harmonic",
    /// "poly345" (cam laws: out in t_c/2 and back), or "table" (α(t) from `table` or
    /// `points`).
    pub kind: DriveKind,
    /// α_max: the largest arm angle [deg]. Default 45. For the crank-rocker it
    /// designs the centred linkage unless the four link lengths are all given.
    pub max_swing_deg: Option<f64>,
    /// Crank-rocker crank length a [m]. Default: c·sin(ψ/2).
    pub crank: Option<f64>,
    /// Crank-rocker coupler length b [m]. Default 0.3.
    pub coupler: Option<f64>,
    /// Crank-rocker rocker (arm lever) length c [m]. Default 0.15.
    pub rocker: Option<f64>,
    /// Crank-rocker ground link d [m]. Default √(b² + c² cos²(ψ/2)).
    pub ground: Option<f64>,
    /// For kind = "table": CSV file of `t, alpha_deg` rows [s, deg] (a header line is
    /// allowed), relative to the scenario file and in its directory or below (see
    /// --allow-outside-paths). Times start at 0 and increase; the time axis is scaled to
    /// cycle_time; the angle starts and ends at 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub table: Option<String>,
    /// For kind = "table", instead of `table`: the same rows inline, [[t, alpha_deg], ...]
    /// [s, deg]. Files divertsim writes use this form, so that they stand alone.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub points: Option<Vec<[f64; 2]>>,
}

/// The rows of a drive table: \[t \[s], α \[deg]].
pub type AlphaRows = Vec<[f64; 2]>;

/// The kinds of arm drive.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum DriveKind {
    #[default]
    CrankRocker,
    Cycloidal,
    Harmonic,
    Poly345,
    Table,
}

/// The parcel: a homogeneous box on the belt.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct ParcelConfig {
    /// a: length along the parcel's own x axis [m]. Default 0.4.
    pub length: f64,
    /// b: width along the parcel's own y axis [m]. Default 0.26.
    pub width: f64,
    /// Height [m] (for the drop reference only). Default 0.15.
    pub height: f64,
    /// m: mass [kg]. Default 3.
    pub mass: f64,
    /// ΔP: the smallest y of the parcel's corners at t = 0, its gap to the pivot-side belt
    /// edge [m]. Default 0.22.
    pub offset: f64,
    /// φ: the parcel's orientation, counter-clockwise from the belt direction [deg].
    /// Default 0.
    pub angle_deg: f64,
    /// Initial velocity [vx, vy] of the centre in the machine frame [m/s]. Default: riding
    /// with the belt, [belt_speed, 0].
    pub velocity: Option<[f64; 2]>,
    /// ω: initial spin, counter-clockwise [rad/s]. Default 0.
    pub spin: f64,
}

/// Friction and restitution.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct MaterialsConfig {
    /// μ_b: parcel–belt friction [-], a number, or a table of [relative speed m/s, μ] points
    /// for μ_1(v_o) (linear between points, constant beyond). Default 0.4.
    pub belt_friction: BeltFrictionConfig,
    /// μ_a: parcel–arm friction, also used for the side guide. Default 0.3.
    pub arm_friction: f64,
    /// e*: Stronge's energetic coefficient of restitution. Default 0.3.
    pub restitution: f64,
    /// "exact" (default: Coulomb integrated over the footprint) or "seed" (the paper's
    /// tanh/exp law, corrected).
    pub friction_model: FrictionModelConfig,
    /// "energetic" (default, Stronge), "newton" or "poisson".
    pub impact_law: ImpactLawConfig,
}

/// μ_b: a constant, or μ_1(v_o) as [relative speed, μ] points.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(
    untagged,
    expecting = "a number, or a list of [relative speed m/s, μ] pairs"
)]
pub enum BeltFrictionConfig {
    Constant(f64),
    Table(Vec<[f64; 2]>),
}

/// Footprint friction law.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum FrictionModelConfig {
    #[default]
    Exact,
    Seed,
}

/// Restitution law at impacts.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum ImpactLawConfig {
    #[default]
    Energetic,
    Newton,
    Poisson,
}

/// How long and how precisely to run.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct RunConfig {
    /// The largest simulated time [s]. Default: cycle_time + 2 s (the arm cycle and the
    /// slide-out).
    pub duration: Option<f64>,
    /// Relative tolerance of the integrator. Default 1e-8.
    pub tolerance: f64,
    /// Whether the arm moves; false for free-motion studies. Default true.
    pub arm: bool,
}

/// Allowable loads.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct LimitsConfig {
    /// H₀: reference free-fall height for the overload comparison [m]. Default 0.3.
    pub drop_height: f64,
}

/// The search box of `divertsim optimize` over the decision variables (v, t_c, R_s, S_d).
/// Each key is `[low, high]` or one number, which fixes the variable; a key left out keeps the
/// command's default (v 1.0–2.3 m/s, t_c 1.0–1.5 s, R_s 0–0.9 m, S_d fixed at
/// `machine.light_barrier`). The command line's `--bound` and `--fix` override these.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct OptimizeConfig {
    /// v: belt speed range [m/s], within [0.05, 10].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub belt_speed: Option<SearchRange>,
    /// t_c: cycle time range [s], within [0.2, 10].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cycle_time: Option<SearchRange>,
    /// R_s: start position range [m], within [−5, 5].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub start_position: Option<SearchRange>,
    /// S_d: light barrier range [m], within [−5, 5].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light_barrier: Option<SearchRange>,
}

impl OptimizeConfig {
    fn is_default(&self) -> bool {
        *self == OptimizeConfig::default()
    }
}

/// A decision variable's search range: `[low, high]`, or one value that fixes it.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum SearchRange {
    Fixed(f64),
    Range([f64; 2]),
}

/// The design set of `divertsim capacity` and the optimiser (paper §4.2): the limiting
/// parcels every setting must divert, each in its worst pose, and the worst-case overload
/// parcel. Default: the paper's smallest 0.2×0.1×0.1 m (0.5 kg) at the far edge, slender
/// 0.7×0.1×0.1 m (1.5 kg) and compact 0.4×0.26×0.15 m (3 kg) at the near edge, and the
/// compact size at 15 kg for the overload.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct DesignConfig {
    /// The limiting parcels (`[[design.parcels]]` tables), 1 to 16; giving any replaces the
    /// whole default list.
    pub parcels: Vec<DesignParcelConfig>,
    /// The worst-case overload parcel, struck at the arm tip at the largest α̇ (the paper's
    /// definition, `--worst paper`).
    pub overload: OverloadParcelConfig,
    /// The parcel class and arrival scatter the worst-case search explores (`worst-case`,
    /// `overload --search`, `--worst search`).
    pub search: SearchBoxConfig,
}

/// The variables nobody controls, each as [lo, hi] (equal ends fix it). Every pose has
/// width ≤ length and lies anywhere across the belt.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct SearchBoxConfig {
    /// a: parcel length [m]. Default [0.2, 0.7] (the paper's class).
    pub length: [f64; 2],
    /// b: parcel width [m]; each pose has b ≤ a. Default [0.1, 0.26].
    pub width: [f64; 2],
    /// m: mass [kg]. Default [0.5, 15].
    pub mass: [f64; 2],
    /// φ: angle to the belt direction [deg]. Default [-30, 30].
    pub angle_deg: [f64; 2],
    /// δt: arrival phase relative to the trigger (light-barrier timing error) [s]; + means
    /// the parcel is further downstream when the arm starts, by v·δt. Default [-0.01, 0.01].
    pub phase: [f64; 2],
    /// Factor on the belt speed [-]. Default [1, 1].
    pub belt_speed_scale: [f64; 2],
    /// Factor on μ_b (every point of a table) [-]. Default [1, 1].
    pub belt_friction_scale: [f64; 2],
    /// μ_a band [-]. Default: materials.arm_friction.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub arm_friction: Option<[f64; 2]>,
    /// e* band [-]. Default: materials.restitution.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub restitution: Option<[f64; 2]>,
}

impl Default for SearchBoxConfig {
    fn default() -> Self {
        let p = PoseBox::paper();
        let b = |x: (f64, f64)| [x.0, x.1];
        SearchBoxConfig {
            length: b(p.length),
            width: b(p.width),
            mass: b(p.mass),
            angle_deg: b(p.angle_deg),
            phase: b(p.phase),
            belt_speed_scale: b(p.belt_speed_scale),
            belt_friction_scale: b(p.belt_friction_scale),
            arm_friction: None,
            restitution: None,
        }
    }
}

impl SearchBoxConfig {
    /// The core's pose box.
    pub fn pose_box(&self) -> PoseBox {
        let b = |x: [f64; 2]| (x[0], x[1]);
        PoseBox {
            length: b(self.length),
            width: b(self.width),
            mass: b(self.mass),
            angle_deg: b(self.angle_deg),
            phase: b(self.phase),
            belt_speed_scale: b(self.belt_speed_scale),
            belt_friction_scale: b(self.belt_friction_scale),
            arm_friction: self.arm_friction.map(b),
            restitution: self.restitution.map(b),
        }
    }
}

/// One limiting parcel in its pose, riding with the belt.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DesignParcelConfig {
    /// A short unique name for tables, e.g. "smallest".
    pub name: String,
    /// a: length along the parcel's own x axis [m].
    pub length: f64,
    /// b: width along the parcel's own y axis [m].
    pub width: f64,
    /// Height [m]. Default 0.1.
    #[serde(default = "default_design_height")]
    pub height: f64,
    /// m: mass [kg].
    pub mass: f64,
    /// ΔP: gap to the pivot-side belt edge [m], or "near" (0) or "far" (against the far
    /// edge: belt_width minus the parcel's extent across the belt).
    pub offset: DesignOffset,
    /// φ: orientation, counter-clockwise from the belt direction [deg]. Default 0.
    #[serde(default)]
    pub angle_deg: f64,
}

/// ΔP of a design parcel: metres, or an edge of the belt.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged, expecting = "a number [m], \"near\" or \"far\"")]
pub enum DesignOffset {
    Value(f64),
    Edge(BeltEdge),
}

/// A belt edge.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum BeltEdge {
    /// Against the pivot-side edge (ΔP = 0).
    Near,
    /// Against the far (discharge-side) edge.
    Far,
}

/// The worst-case overload parcel (its pose is fixed by the strike: parallel to the belt,
/// front pivot-side corner at the arm tip).
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct OverloadParcelConfig {
    /// a [m]. Default 0.4.
    pub length: f64,
    /// b [m]. Default 0.26.
    pub width: f64,
    /// Height [m]. Default 0.15.
    pub height: f64,
    /// m: the largest allowed mass [kg]. Default 15.
    pub mass: f64,
}

fn default_design_height() -> f64 {
    0.1
}

/// Largest number of design parcels.
pub const MAX_DESIGN_PARCELS: usize = 16;

impl Default for DesignConfig {
    fn default() -> Self {
        let parcel = |name: &str, length, width, height, mass, edge| DesignParcelConfig {
            name: name.into(),
            length,
            width,
            height,
            mass,
            offset: DesignOffset::Edge(edge),
            angle_deg: 0.0,
        };
        DesignConfig {
            parcels: vec![
                parcel("smallest", 0.2, 0.1, 0.1, 0.5, BeltEdge::Far),
                parcel("slender", 0.7, 0.1, 0.1, 1.5, BeltEdge::Near),
                parcel("compact", 0.4, 0.26, 0.15, 3.0, BeltEdge::Near),
            ],
            overload: OverloadParcelConfig::default(),
            search: SearchBoxConfig::default(),
        }
    }
}

impl Default for OverloadParcelConfig {
    fn default() -> Self {
        OverloadParcelConfig {
            length: 0.4,
            width: 0.26,
            height: 0.15,
            mass: 15.0,
        }
    }
}

/// Extent of a length × width footprint across the belt at angle φ [deg] [m].
fn extent_across(length: f64, width: f64, angle_deg: f64) -> f64 {
    let (s, c) = angle_deg.to_radians().sin_cos();
    length * s.abs() + width * c.abs()
}

impl DesignParcelConfig {
    /// ΔP \[m] on a belt of width P_max.
    pub fn offset_on(&self, belt_width: f64) -> f64 {
        match self.offset {
            DesignOffset::Value(v) => v,
            DesignOffset::Edge(BeltEdge::Near) => 0.0,
            DesignOffset::Edge(BeltEdge::Far) => {
                (belt_width - extent_across(self.length, self.width, self.angle_deg)).max(0.0)
            }
        }
    }
}

/// The `[design]` checks (ranges, names, parcels on the belt), with key paths.
fn validate_design(d: &DesignConfig, belt_width: f64, c: &mut Checks<'_>) {
    if d.parcels.is_empty() || d.parcels.len() > MAX_DESIGN_PARCELS {
        c.0.push(problem(
            "design.parcels",
            format!(
                "{} parcels; allowed: 1 to {MAX_DESIGN_PARCELS}",
                d.parcels.len()
            ),
        ));
    }
    for (i, p) in d.parcels.iter().enumerate() {
        let k = |f: &str| format!("design.parcels[{i}].{f}");
        if p.name.trim().is_empty() {
            c.0.push(problem(k("name"), "must not be empty"));
        } else if d.parcels[..i].iter().any(|q| q.name == p.name) {
            c.0.push(problem(
                k("name"),
                format!("\"{}\" is used twice; names must be unique", p.name),
            ));
        }
        c.box_size(
            k,
            &bounds::DESIGN_BOX,
            [p.length, p.width, p.height],
            p.mass,
        );
        c.bound_at(&k("angle_deg"), &bounds::DESIGN_ANGLE, p.angle_deg);
        let sizes_ok = [p.length, p.width, p.angle_deg, belt_width]
            .iter()
            .all(|v| v.is_finite())
            && p.length > 0.0
            && p.width > 0.0
            && belt_width > 0.0;
        let offset_ok = match p.offset {
            DesignOffset::Value(v) => c.finite(&k("offset"), v),
            DesignOffset::Edge(_) => true,
        };
        if sizes_ok && offset_ok {
            let across = extent_across(p.length, p.width, p.angle_deg);
            let offset = p.offset_on(belt_width);
            if across > belt_width {
                c.0.push(problem(
                    k("width"),
                    format!(
                        "the parcel spans {across:.4} m across the belt at angle_deg = {}, wider than machine.belt_width = {belt_width}",
                        p.angle_deg
                    ),
                ));
            } else if offset < 0.0 || offset + across > belt_width + 1e-12 {
                c.0.push(problem(
                    k("offset"),
                    format!(
                        "{offset} puts the parcel off the belt; allowed: [0, {:.6}] m (belt_width − the parcel's extent across the belt), \"near\" or \"far\"",
                        belt_width - across
                    ),
                ));
            }
        }
    }
    let o = &d.overload;
    c.box_size(
        |f| format!("design.overload.{f}"),
        &bounds::OVERLOAD_BOX,
        [o.length, o.width, o.height],
        o.mass,
    );
    let search = d.search.pose_box();
    let problems = search.problems();
    for (key, message) in &problems {
        c.0.push(problem(format!("design.search.{key}"), message.clone()));
    }
    if problems.is_empty() && belt_width.is_finite() {
        // The narrowest parcel of the class at its best angle must fit on the belt (the
        // extent a|sin φ| + b|cos φ| is smallest at an end of the band or at 0).
        let (a, b) = (search.length.0, search.width.0);
        let (lo, hi) = search.angle_deg;
        let narrowest = [lo, hi, 0.0f64.clamp(lo, hi)]
            .iter()
            .map(|&phi| extent_across(a, b, phi))
            .fold(f64::INFINITY, f64::min);
        if narrowest > belt_width {
            c.0.push(problem(
                "design.search.width",
                format!(
                    "the narrowest parcel of the class ({a} × {b} m) spans {narrowest:.4} m across the belt at its best angle, wider than machine.belt_width = {belt_width}"
                ),
            ));
        }
    }
}

/// The core design set of a validated `[design]` section on a belt of width P_max \[m].
pub fn design_set(d: &DesignConfig, belt_width: f64) -> DesignSet {
    DesignSet {
        cases: d
            .parcels
            .iter()
            .map(|p| DesignCase {
                name: p.name.clone(),
                parcel: Parcel::riding(
                    p.length,
                    p.width,
                    p.height,
                    p.mass,
                    p.offset_on(belt_width),
                    p.angle_deg.to_radians(),
                ),
            })
            .collect(),
        overload_parcel: Parcel::riding(
            d.overload.length,
            d.overload.width,
            d.overload.height,
            d.overload.mass,
            0.0,
            0.0,
        ),
        search: d.search.pose_box(),
        worst: WorstDefinition::Paper,
        worst_poses: Vec::new(),
        margins: Margins::default(),
    }
}

impl Default for MachineConfig {
    fn default() -> Self {
        MachineConfig {
            belt_width: 0.7,
            belt_speed: 2.0,
            arm_length: 1.0,
            cycle_time: 1.36,
            start_position: 0.0,
            light_barrier: 0.0,
            drive: DriveConfig::default(),
            near_side: NearSideConfig::Open,
            trigger: TriggerConfig::Fixed,
            adaptive: AdaptiveConfig::default(),
        }
    }
}

impl Default for DriveConfig {
    fn default() -> Self {
        DriveConfig {
            kind: DriveKind::CrankRocker,
            max_swing_deg: None,
            crank: None,
            coupler: None,
            rocker: None,
            ground: None,
            table: None,
            points: None,
        }
    }
}

impl Default for ParcelConfig {
    fn default() -> Self {
        ParcelConfig {
            length: 0.4,
            width: 0.26,
            height: 0.15,
            mass: 3.0,
            offset: 0.22,
            angle_deg: 0.0,
            velocity: None,
            spin: 0.0,
        }
    }
}

impl Default for MaterialsConfig {
    fn default() -> Self {
        MaterialsConfig {
            belt_friction: BeltFrictionConfig::Constant(0.4),
            arm_friction: 0.3,
            restitution: 0.3,
            friction_model: FrictionModelConfig::Exact,
            impact_law: ImpactLawConfig::Energetic,
        }
    }
}

impl Default for RunConfig {
    fn default() -> Self {
        RunConfig {
            duration: None,
            tolerance: 1e-8,
            arm: true,
        }
    }
}

impl Default for LimitsConfig {
    fn default() -> Self {
        LimitsConfig { drop_height: 0.3 }
    }
}

/// Default max swing \[deg].
pub const DEFAULT_SWING_DEG: f64 = 45.0;
/// Default crank-rocker coupler \[m] (physics.md §6.2).
pub const DEFAULT_COUPLER: f64 = 0.3;
/// Default crank-rocker rocker \[m] (physics.md §6.2).
pub const DEFAULT_ROCKER: f64 = 0.15;

/// One problem with the input, tied to a key.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Problem {
    /// Dotted key path (`machine.belt_speed`), or the file / option concerned.
    pub key: String,
    pub message: String,
}

impl Problem {
    /// A problem with the value at `key`.
    pub fn new(key: impl Into<String>, message: impl Into<String>) -> Problem {
        Problem {
            key: key.into(),
            message: message.into(),
        }
    }
}

/// Every problem found in the input.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Problems(pub Vec<Problem>);

impl fmt::Display for Problems {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = self.0.len();
        writeln!(
            f,
            "invalid input: {n} problem{}",
            if n == 1 { "" } else { "s" }
        )?;
        for p in self.0.iter().take(MAX_LISTED) {
            writeln!(f, "  - {}: {}", p.key, p.message)?;
        }
        if n > MAX_LISTED {
            writeln!(f, "  ... and {} more problems", n - MAX_LISTED)?;
        }
        Ok(())
    }
}

impl std::error::Error for Problems {}

/// Problems listed one by one before "and N more".
pub const MAX_LISTED: usize = 64;

fn problem(key: impl Into<String>, message: impl Into<String>) -> Problem {
    Problem {
        key: key.into(),
        message: message.into(),
    }
}

/// A validated scenario: what the file said (after defaults and overrides) and the core's
/// SI scenario built from it.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// The file, resolved: no `base` (its keys merged in), a drive table read into
    /// `machine.drive.points`, and `mix.records` relative to the working directory.
    pub file: ScenarioFile,
    pub scenario: Scenario,
    /// The `[design]` section as the core's design set.
    pub design: DesignSet,
    /// The `[mix]` section as the core's parcel mix (defaults filled in).
    pub mix: divertsim_core::analysis::population::mix::ParcelMix,
}

/// [`load_with`] under the default rule: files outside the scenario's directory refused.
pub fn load(path: Option<&Path>, sets: &[String]) -> Result<Loaded, Problems> {
    load_with(path, sets, LoadOptions::default())
}

/// Read, override, validate and convert. `path = None` starts from the built-in default.
/// The files a scenario names follow the rule of [`files`].
pub fn load_with(
    path: Option<&Path>,
    sets: &[String],
    options: LoadOptions,
) -> Result<Loaded, Problems> {
    let table = scenario_table(path, options)?;
    resolve(table, sets.iter().map(|s| parse_set(s)), options)
}

/// [`load_with`] for a scenario given as a table instead of a file (what an edge builds from
/// its own data, e.g. a Python dict), with overrides as (dotted key, value) pairs applied
/// exactly as `--set` applies them. The paths the table names (`base`,
/// `machine.drive.table`, `mix.records`) are relative to `base_dir` and follow the rule of
/// [`files`] as if the table were a file in `base_dir`; `name` stands for the table in
/// messages. An empty table is the built-in default scenario.
pub fn load_table(
    table: toml::Table,
    name: &str,
    base_dir: &Path,
    overrides: &[(String, toml::Value)],
    options: LoadOptions,
) -> Result<Loaded, Problems> {
    load_merged(
        merged_table(table, name, base_dir, options)?,
        overrides,
        options,
    )
}

/// The scenario table of a file with its `base` chain merged underneath and its paths made
/// relative to the working directory (`None`: the empty table, the built-in default): what
/// [`load_merged`] takes, for edges that load many variants of one file.
pub fn scenario_table(path: Option<&Path>, options: LoadOptions) -> Result<toml::Table, Problems> {
    match path {
        None => Ok(toml::Table::new()),
        Some(p) => read_layered(p, 0, options),
    }
}

/// A scenario table given in memory (see [`load_table`]) with its `base` chain merged
/// underneath and its paths made relative to the working directory: what [`load_merged`]
/// takes.
pub fn merged_table(
    table: toml::Table,
    name: &str,
    base_dir: &Path,
    options: LoadOptions,
) -> Result<toml::Table, Problems> {
    layered(table, name, base_dir, 0, options)
}

/// Override, validate and convert a table from [`scenario_table`] or [`merged_table`]; the
/// overrides are applied exactly as `--set` applies them.
pub fn load_merged(
    table: toml::Table,
    overrides: &[(String, toml::Value)],
    options: LoadOptions,
) -> Result<Loaded, Problems> {
    resolve(
        table,
        overrides.iter().map(|(k, v)| Ok((k.clone(), v.clone()))),
        options,
    )
}

/// Override, validate and convert a scenario table whose `base` chain is merged in already.
fn resolve(
    mut table: toml::Table,
    sets: impl Iterator<Item = Result<(String, toml::Value), Problem>>,
    options: LoadOptions,
) -> Result<Loaded, Problems> {
    let mut problems = Vec::new();
    // The paths the files named are checked and resolved already; one a --set replaces is
    // relative to the working directory.
    let from_files: Vec<Option<toml::Value>> = files::PATH_KEYS
        .iter()
        .map(|k| lookup_mut(&mut table, k).cloned())
        .collect();
    for set in sets {
        if let Err(p) = set.and_then(|(key, value)| set_value(&mut table, &key, value)) {
            problems.push(p);
        }
    }
    for (k, before) in files::PATH_KEYS.iter().zip(from_files) {
        if let Some(toml::Value::String(raw)) = lookup_mut(&mut table, k) {
            if before.as_ref().and_then(toml::Value::as_str) != Some(raw.as_str()) {
                problems.extend(files::outside_problem(
                    &k.join("."),
                    raw,
                    Path::new("."),
                    Origin::Set,
                    options,
                ));
            }
        }
    }
    let mut file = deserialize_collecting(table, &mut problems);
    validate(&file, &mut problems);
    if !problems.is_empty() {
        return Err(Problems(problems));
    }
    let (scenario, rows) = to_scenario(&file).map_err(Problems)?;
    // The table travels with the file from here on: a file written from it stands alone.
    if let Some(rows) = rows {
        file.machine.drive.table = None;
        file.machine.drive.points = Some(rows);
    }
    let design = design_set(&file.design, file.machine.belt_width);
    let mix = mix::parcel_mix(&file.mix).map_err(Problems)?;
    Ok(Loaded {
        file,
        scenario,
        design,
        mix,
    })
}

/// The scenario file of one searched pose: `file` with the setting of `setting` (v, t_c,
/// R_s, S_d, the run length) and the parcel and materials of `pose`, resolved exactly as
/// [`Pose::scenario`] resolves them, so that loading the file gives that scenario bit for
/// bit. The file stands alone ([`standalone`]).
pub fn pose_file(file: &ScenarioFile, setting: &Scenario, pose: &Pose) -> ScenarioFile {
    let s = pose.scenario(setting);
    let mut f = standalone(file);
    f.machine.belt_speed = s.machine.belt_speed;
    f.machine.cycle_time = s.machine.cycle_time;
    f.machine.start_position = s.machine.start_position;
    // An early arrival can put R_s upstream of S_d, which a file may not state; S_d does not
    // change a run (only the capacity), so it moves with R_s.
    f.machine.light_barrier = s.machine.light_barrier.min(s.machine.start_position);
    f.parcel = ParcelConfig {
        length: s.parcel.length,
        width: s.parcel.width,
        height: s.parcel.height,
        mass: s.parcel.mass,
        offset: s.parcel.offset,
        angle_deg: pose.angle_deg,
        velocity: None,
        spin: 0.0,
    };
    f.materials.belt_friction = match &s.materials.belt_friction {
        FrictionCoefficient::Constant(m) => BeltFrictionConfig::Constant(*m),
        FrictionCoefficient::Table(t) => {
            BeltFrictionConfig::Table(t.iter().map(|&(v, m)| [v, m]).collect())
        }
    };
    f.materials.arm_friction = s.materials.arm_friction;
    f.materials.restitution = s.materials.restitution;
    f.run.duration = Some(s.run.duration);
    f
}

/// A resolved scenario file (as [`load`] gives it) that stands alone, so that a file
/// written from it reloads wherever it is put: no `base`, the drive table inline (`load`
/// reads it into `machine.drive.points`), and `mix.records`, a file too large to inline,
/// made absolute; reloading a file with records therefore needs `--allow-outside-paths`.
pub fn standalone(file: &ScenarioFile) -> ScenarioFile {
    let mut f = file.clone();
    f.base = None;
    let absolute = |t: &mut Option<String>| {
        if let Some(rel) = t.as_ref().filter(|t| Path::new(t.as_str()).is_relative()) {
            let p = PathBuf::from(rel);
            let p = p
                .canonicalize()
                .or_else(|_| std::path::absolute(&p))
                .unwrap_or(p);
            *t = Some(p.display().to_string());
        }
    };
    absolute(&mut f.machine.drive.table);
    absolute(&mut f.mix.records);
    f
}

/// A scenario file as TOML text, with a comment heading it; the file stands alone
/// ([`standalone`]).
pub fn to_toml(file: &ScenarioFile, heading: &str) -> Result<String, String> {
    let body = toml::to_string(&standalone(file)).map_err(|e| e.to_string())?;
    let head: String = heading.lines().map(|l| format!("# {l}\n")).collect();
    Ok(format!("{head}\n{body}"))
}

/// Largest chain of `base` files.
const MAX_BASE_DEPTH: usize = 8;

/// Read a scenario file as a TOML table with its `base` chain merged underneath (the file's
/// own keys win). Every path a file names is checked against the rule of [`files`] and made
/// relative to the working directory, so that it still names the same file once merged.
fn read_layered(p: &Path, depth: usize, options: LoadOptions) -> Result<toml::Table, Problems> {
    let key = p.display().to_string();
    let text = if depth == 0 && p == Path::new("-") {
        stdin_text().map_err(|e| {
            Problems(vec![problem(
                "-",
                format!("cannot read the scenario from standard input: {e}"),
            )])
        })?
    } else {
        files::scenario_text(p, depth > 0).map_err(|e| {
            Problems(vec![problem(
                &key,
                format!("cannot read the scenario file: {e}"),
            )])
        })?
    };
    let table = files::parse_toml(&text).map_err(|e| Problems(vec![problem(&key, e)]))?;
    layered(
        table,
        &key,
        p.parent().unwrap_or(Path::new("")),
        depth,
        options,
    )
}

/// The scenario table `table`, read from `key` in directory `dir`, with its `base` chain
/// merged underneath and its paths checked and made relative to the working directory.
fn layered(
    mut table: toml::Table,
    key: &str,
    dir: &Path,
    depth: usize,
    options: LoadOptions,
) -> Result<toml::Table, Problems> {
    let mut problems = Vec::new();
    for k in files::PATH_KEYS {
        if let Some(toml::Value::String(raw)) = lookup_mut(&mut table, k) {
            match files::outside_problem(&k.join("."), raw, dir, Origin::File(key), options) {
                Some(pr) => problems.push(pr),
                None => *raw = dir.join(raw.as_str()).display().to_string(),
            }
        }
    }
    if !problems.is_empty() {
        return Err(Problems(problems));
    }
    let Some(base) = table.remove("base") else {
        return Ok(table);
    };
    let toml::Value::String(base) = base else {
        return Err(Problems(vec![problem(
            "base",
            format!("in {key}: must be a string, the path of another scenario file"),
        )]));
    };
    if depth + 1 >= MAX_BASE_DEPTH {
        return Err(Problems(vec![problem(
            "base",
            format!("in {key}: more than {MAX_BASE_DEPTH} files chained by `base` (a cycle?)"),
        )]));
    }
    let base_path = PathBuf::from(base);
    let mut merged = read_layered(&base_path, depth + 1, options).map_err(|mut e| {
        for pr in &mut e.0 {
            if pr.key == base_path.display().to_string() {
                pr.key = "base".into();
                pr.message = format!("in {key}: {}: {}", base_path.display(), pr.message);
            }
        }
        e
    })?;
    merge_tables(&mut merged, table);
    Ok(merged)
}

/// A scenario given as `-`: standard input, read once (a command may load it several
/// times: per sweep point, per track); relative paths in it are relative to the working
/// directory.
fn stdin_text() -> Result<String, String> {
    static TEXT: std::sync::OnceLock<Result<String, String>> = std::sync::OnceLock::new();
    TEXT.get_or_init(|| files::capped_text(std::io::stdin()))
        .clone()
}

/// The value at a key path of nested tables.
fn lookup_mut<'a>(table: &'a mut toml::Table, path: &[&str]) -> Option<&'a mut toml::Value> {
    let (last, sections) = path.split_last()?;
    let mut cur = table;
    for s in sections {
        match cur.get_mut(*s) {
            Some(toml::Value::Table(t)) => cur = t,
            _ => return None,
        }
    }
    cur.get_mut(*last)
}

/// Deep merge: keys of `top` override those of `bottom`; sections merge key by key.
fn merge_tables(bottom: &mut toml::Table, top: toml::Table) {
    for (k, v) in top {
        match (bottom.get_mut(&k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(t)) => merge_tables(b, t),
            (_, v) => {
                bottom.insert(k, v);
            }
        }
    }
}

/// Apply one `--set KEY=VALUE`; VALUE is a TOML value (`1.5`, `[3.0, 0.0]`, `"seed"`); a bare
/// word is taken as a string.
pub fn apply_set(table: &mut toml::Table, set: &str) -> Result<(), Problem> {
    let (key, value) = parse_set(set)?;
    set_value(table, &key, value)
}

/// Split one `--set KEY=VALUE` into its key and its TOML value (see [`apply_set`]).
pub fn parse_set(set: &str) -> Result<(String, toml::Value), Problem> {
    let Some((key, raw)) = set.split_once('=') else {
        return Err(problem(
            "--set",
            format!("'{set}' is not KEY=VALUE (e.g. machine.belt_speed=1.5)"),
        ));
    };
    let key = key.trim();
    let raw = raw.trim();
    if raw.contains('\n') || raw.contains('\r') {
        return Err(problem(
            key,
            "--set value spans several lines; allowed: one TOML value on one line",
        ));
    }
    check_key(key, &format!("'{set}'"))?;
    let value = match toml::from_str::<toml::Table>(&format!("v = {raw}")) {
        Ok(mut t) => t
            .remove("v")
            .unwrap_or(toml::Value::String(raw.to_string())),
        Err(_)
            if !raw.is_empty() && raw.chars().all(|c| c.is_alphanumeric() || "-_".contains(c)) =>
        {
            toml::Value::String(raw.to_string())
        }
        Err(e) => {
            return Err(problem(
                key,
                format!(
                    "--set value '{raw}' is not a TOML value: {}",
                    first_line(&e.to_string())
                ),
            ));
        }
    };
    Ok((key.to_string(), value))
}

/// A dotted key has no empty part; `what` names the override in the message.
fn check_key(key: &str, what: &str) -> Result<(), Problem> {
    if key.is_empty() || key.split('.').any(str::is_empty) {
        return Err(problem(
            "--set",
            format!("{what}: the key must be a dotted path such as machine.belt_speed"),
        ));
    }
    Ok(())
}

/// Set the value at a dotted key path (`machine.belt_speed`), creating the sections on the
/// way: the override of [`apply_set`] once its value is parsed.
pub fn set_value(table: &mut toml::Table, key: &str, value: toml::Value) -> Result<(), Problem> {
    check_key(key, &format!("'{key}'"))?;
    let parts: Vec<&str> = key.split('.').collect();
    let mut cur = table;
    for (i, part) in parts[..parts.len() - 1].iter().enumerate() {
        let entry = cur
            .entry(part.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        cur = match entry {
            toml::Value::Table(t) => t,
            _ => {
                return Err(problem(
                    parts[..=i].join("."),
                    "is a value, not a section, so it has no sub-keys",
                ))
            }
        };
    }
    cur.insert(parts[parts.len() - 1].to_string(), value);
    Ok(())
}

fn first_line(s: &str) -> String {
    s.lines()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("")
        .trim()
        .to_string()
}

/// Deserialize, collecting every structural problem (unknown key, wrong type): each one is
/// recorded with its path, the offending key removed, and deserialization retried.
fn deserialize_collecting(mut table: toml::Table, problems: &mut Vec<Problem>) -> ScenarioFile {
    for _ in 0..MAX_STRUCTURAL {
        match serde_path_to_error::deserialize::<_, ScenarioFile>(table.clone()) {
            Ok(file) => return file,
            Err(err) => {
                let mut path: Vec<String> = err.path().iter().map(|s| s.to_string()).collect();
                let message = err.inner().to_string();
                // An unknown key's path ends at its section; the key is named in the message.
                if let Some(unknown) = unknown_field(&message) {
                    if path.last().map(String::as_str) != Some(unknown.as_str()) {
                        path.push(unknown);
                    }
                }
                let key = path
                    .iter()
                    .filter(|s| s.as_str() != "?")
                    .cloned()
                    .collect::<Vec<_>>()
                    .join(".")
                    .replace(".[", "[");
                problems.push(problem(
                    if key.is_empty() {
                        "scenario".to_string()
                    } else {
                        key
                    },
                    tidy(&message),
                ));
                if !remove_path(&mut table, &path) {
                    return ScenarioFile::default();
                }
            }
        }
    }
    ScenarioFile::default()
}

/// A deserializer's message without the values it quotes from the file (`invalid type:
/// string "…"`, `unknown variant `…``, `unknown field `…``): the key path says where, the expected type or the
/// allowed variants say what; the file's text is never echoed (it may be anything).
fn without_quoted_values(message: &str) -> String {
    let mut out = String::new();
    let mut rest = message;
    loop {
        // (pattern, what stays, closing quote); the earliest in the message first.
        let patterns = [
            ("string \"", "a string", '"'),
            ("unknown variant `", "unknown variant", '`'),
            ("unknown field `", "unknown field", '`'),
        ];
        let Some((at, (open, keep, close))) = patterns
            .iter()
            .filter_map(|p| rest.find(p.0).map(|at| (at, *p)))
            .min_by_key(|(at, _)| *at)
        else {
            break;
        };
        let open = open.len();
        out.push_str(&rest[..at]);
        out.push_str(keep);
        // Skip the quoted value (a string's Debug form escapes its quotes).
        let body = &rest[at + open..];
        let mut escaped = false;
        let mut end = body.len();
        for (i, c) in body.char_indices() {
            if escaped {
                escaped = false;
            } else if c == '\\' && close == '"' {
                escaped = true;
            } else if c == close {
                end = i + c.len_utf8();
                break;
            }
        }
        rest = &body[end..];
    }
    out.push_str(rest);
    out
}

/// Structural problems (unknown keys, wrong types) collected before giving up.
const MAX_STRUCTURAL: usize = 256;

fn unknown_field(message: &str) -> Option<String> {
    let rest = message.strip_prefix("unknown field `")?;
    Some(rest.split('`').next()?.to_string())
}

fn tidy(message: &str) -> String {
    let mut m = without_quoted_values(message)
        .replace("unknown field", "unknown key")
        .replace("f64", "a number");
    for section in [
        "machine",
        "drive",
        "parcel",
        "materials",
        "run",
        "limits",
        "design",
    ] {
        let name = format!(
            "struct {}{}Config",
            section[..1].to_uppercase(),
            &section[1..]
        );
        m = m.replace(&name, &format!("a [{section}] section (a table of keys)"));
    }
    m = m
        .replace(
            "struct DesignParcelConfig",
            "a [[design.parcels]] entry (a table of keys)",
        )
        .replace(
            "struct OverloadParcelConfig",
            "a [design.overload] section (a table of keys)",
        )
        .replace(
            "data did not match any variant of untagged enum SearchRange",
            "expected a number (a fixed value) or [low, high]",
        )
        .replace("struct MixConfig", "a [mix] section (a table of keys)")
        .replace("struct CameraConfig", "a [camera] section (a table of keys)")
        .replace(
            "struct AdaptiveConfig",
            "a [machine.adaptive] section (a table of keys)",
        )
        .replace(
            "internally tagged enum DistConfig",
            "a distribution: a table with kind = \"fixed\", \"uniform\", \"normal\", \"truncated-normal\", \"lognormal\" or \"discrete\" and its parameters",
        );
    first_line(&m)
}

fn remove_path(table: &mut toml::Table, path: &[String]) -> bool {
    match path {
        [] => false,
        [last] => table.remove(last).is_some(),
        [head, rest @ ..] => match table.get_mut(head) {
            Some(toml::Value::Table(t)) => {
                if remove_path(t, rest) {
                    true
                } else {
                    // The problem is with the section itself (e.g. wrong type inside an
                    // array): drop the whole value.
                    table.remove(head).is_some()
                }
            }
            Some(_) => table.remove(head).is_some(),
            None => false,
        },
    }
}

/// A number for a message: at most 6 significant digits, in the shortest form
/// (`0.65`, `1.23457`, `1e300`, `-2.5e-7`).
pub fn num(v: f64) -> String {
    if !v.is_finite() {
        return v.to_string();
    }
    let rounded: f64 = format!("{v:.5e}").parse().unwrap_or(v);
    let plain = rounded.to_string();
    let sci = format!("{rounded:e}");
    if plain.len() <= sci.len() + 2 {
        plain
    } else {
        sci
    }
}

/// Range checks that collect a message per bad key.
struct Checks<'a>(&'a mut Vec<Problem>);

impl Checks<'_> {
    /// v is finite; else a problem (for keys whose range depends on other keys).
    fn finite(&mut self, key: &str, v: f64) -> bool {
        if v.is_finite() {
            true
        } else {
            self.0.push(problem(
                key,
                format!("{v} is not a finite number; allowed: a finite number"),
            ));
            false
        }
    }

    /// v lies within `b` (reported at the bound's own key).
    fn bound(&mut self, b: &Bound, v: f64) {
        self.bound_at(b.key, b, v);
    }

    /// v lies within `b`, reported at `key` (the bound's key with its indices filled in).
    fn bound_at(&mut self, key: &str, b: &Bound, v: f64) {
        if let Some(p) = b.problem(key, v) {
            self.0.push(p);
        }
    }

    /// A parcel's sides (length, width, height) and mass, with the keys `key("length")` …
    /// `key("mass")`, against `bounds` in that order.
    fn box_size(
        &mut self,
        key: impl Fn(&str) -> String,
        bounds: &[Bound; 4],
        sides: [f64; 3],
        mass: f64,
    ) {
        let values = [sides[0], sides[1], sides[2], mass];
        for ((name, b), v) in ["length", "width", "height", "mass"]
            .into_iter()
            .zip(bounds)
            .zip(values)
        {
            self.bound_at(&key(name), b, v);
        }
    }
}

/// Every range and consistency check of the contract.
fn validate(f: &ScenarioFile, problems: &mut Vec<Problem>) {
    if f.base.is_some() {
        problems.push(problem(
            "base",
            "can only be given in a scenario file, not with --set",
        ));
    }
    let mut c = Checks(problems);
    let m = &f.machine;
    c.bound(&bounds::BELT_WIDTH, m.belt_width);
    c.bound(&bounds::BELT_SPEED, m.belt_speed);
    c.bound(&bounds::ARM_LENGTH, m.arm_length);
    c.bound(&bounds::CYCLE_TIME, m.cycle_time);
    c.bound(&bounds::START_POSITION, m.start_position);
    c.bound(&bounds::LIGHT_BARRIER, m.light_barrier);
    if m.light_barrier.is_finite()
        && m.start_position.is_finite()
        && m.light_barrier > m.start_position
    {
        c.0.push(problem(
            "machine.light_barrier",
            format!(
                "{} lies downstream of machine.start_position = {}; allowed: light_barrier ≤ start_position",
                m.light_barrier, m.start_position
            ),
        ));
    }
    validate_drive(&m.drive, &mut c);

    let p = &f.parcel;
    c.box_size(
        |f| format!("parcel.{f}"),
        &bounds::PARCEL_BOX,
        [p.length, p.width, p.height],
        p.mass,
    );
    c.bound(&bounds::PARCEL_ANGLE, p.angle_deg);
    c.bound(&bounds::PARCEL_SPIN, p.spin);
    for (i, v) in p.velocity.iter().flatten().enumerate() {
        c.bound_at(
            &format!("parcel.velocity[{i}]"),
            &bounds::PARCEL_VELOCITY,
            *v,
        );
    }
    if c.finite("parcel.offset", p.offset) {
        let sizes_ok = [p.length, p.width, p.angle_deg, m.belt_width]
            .iter()
            .all(|v| v.is_finite())
            && p.length > 0.0
            && p.width > 0.0
            && m.belt_width > 0.0;
        if sizes_ok {
            let (s, co) = p.angle_deg.to_radians().sin_cos();
            let across = p.length * s.abs() + p.width * co.abs();
            if across > m.belt_width {
                c.0.push(problem(
                    "parcel.width",
                    format!(
                        "the parcel spans {across:.4} m across the belt at angle_deg = {}, wider than machine.belt_width = {}",
                        p.angle_deg, m.belt_width
                    ),
                ));
            } else if p.offset < 0.0 || p.offset + across > m.belt_width + 1e-12 {
                c.0.push(problem(
                    "parcel.offset",
                    format!(
                        "{} puts the parcel off the belt; allowed: [0, {:.6}] m (belt_width − the parcel's extent across the belt)",
                        p.offset,
                        m.belt_width - across
                    ),
                ));
            }
        }
    }

    let mat = &f.materials;
    match &mat.belt_friction {
        BeltFrictionConfig::Constant(mu) => c.bound(&bounds::BELT_FRICTION, *mu),
        BeltFrictionConfig::Table(points) => {
            if points.is_empty() {
                c.0.push(problem(
                    "materials.belt_friction",
                    "the table is empty; give at least one [speed, μ] point",
                ));
            }
            for (i, [v, mu]) in points.iter().enumerate() {
                c.bound_at(
                    &format!("materials.belt_friction[{i}][0]"),
                    &bounds::BELT_FRICTION_SPEED,
                    *v,
                );
                c.bound_at(
                    &format!("materials.belt_friction[{i}][1]"),
                    &bounds::BELT_FRICTION_MU,
                    *mu,
                );
                let increasing = i == 0 || *v > points[i - 1][0];
                if !increasing {
                    c.0.push(problem(
                        format!("materials.belt_friction[{i}][0]"),
                        format!(
                            "speeds must increase strictly; {v} follows {}",
                            points[i - 1][0]
                        ),
                    ));
                }
            }
        }
    }
    c.bound(&bounds::ARM_FRICTION, mat.arm_friction);
    c.bound(&bounds::RESTITUTION, mat.restitution);

    if let Some(d) = f.run.duration {
        c.bound(&bounds::DURATION, d);
    }
    c.bound(&bounds::TOLERANCE, f.run.tolerance);
    c.bound(&bounds::DROP_HEIGHT, f.limits.drop_height);
    validate_design(&f.design, m.belt_width, &mut c);
    mix::validate(&f.mix, c.0);
    camera::validate(&f.camera, c.0);
    mix::validate_adaptive(&f.machine.adaptive, c.0);
}

fn validate_drive(d: &DriveConfig, c: &mut Checks<'_>) {
    if let Some(s) = d.max_swing_deg {
        c.bound(&bounds::MAX_SWING, s);
    }
    let links = [
        (&bounds::CRANK, d.crank),
        (&bounds::COUPLER, d.coupler),
        (&bounds::ROCKER, d.rocker),
        (&bounds::GROUND, d.ground),
    ];
    for (b, v) in links {
        if let Some(v) = v {
            if d.kind != DriveKind::CrankRocker {
                c.0.push(problem(b.key, "applies only to kind = \"crank-rocker\""));
            } else {
                c.bound(b, v);
            }
        }
    }
    let table = d.kind == DriveKind::Table;
    for (key, given) in [
        ("machine.drive.table", d.table.is_some()),
        ("machine.drive.points", d.points.is_some()),
    ] {
        if given && !table {
            c.0.push(problem(key, "applies only to kind = \"table\""));
        }
    }
    if table {
        match (&d.table, &d.points) {
            (None, None) => c.0.push(problem(
                "machine.drive.table",
                "kind = \"table\" needs table = \"FILE.csv\" (rows of t, alpha_deg) or points = [[t, alpha_deg], ...]",
            )),
            (Some(_), Some(_)) => c.0.push(problem(
                "machine.drive.points",
                "cannot be given with machine.drive.table; give the rows in one of them",
            )),
            _ => {}
        }
        if d.max_swing_deg.is_some() {
            c.0.push(problem(
                "machine.drive.max_swing_deg",
                "does not apply to kind = \"table\" (the table sets the swing)",
            ));
        }
    }
    if d.kind == DriveKind::CrankRocker {
        let given = [d.crank, d.ground].iter().filter(|v| v.is_some()).count();
        if given == 1 {
            c.0.push(problem(
                if d.crank.is_some() { "machine.drive.ground" } else { "machine.drive.crank" },
                "give crank and ground together (with coupler and rocker), or neither to design the linkage from max_swing_deg",
            ));
        }
    }
}

/// Build the core scenario, and the rows of a drive table file it read; drive problems (a
/// linkage that cannot reach its swing, a bad table) are reported against the drive keys.
fn to_scenario(f: &ScenarioFile) -> Result<(Scenario, Option<AlphaRows>), Vec<Problem>> {
    let d = &f.machine.drive;
    let (drive, rows) = drive_spec(d)?;
    if let Err(e) = ArmDrive::new(&drive, f.machine.cycle_time) {
        let message = match (&d.table, d.kind) {
            (Some(path), DriveKind::Table) => format!("{path}: {e}"),
            _ => e.to_string(),
        };
        return Err(vec![problem(drive_key(d), message)]);
    }
    let m = &f.machine;
    let p = &f.parcel;
    let mat = &f.materials;
    let scenario = Scenario {
        machine: Machine {
            belt_width: m.belt_width,
            belt_speed: m.belt_speed,
            arm_length: m.arm_length,
            cycle_time: m.cycle_time,
            start_position: m.start_position,
            light_barrier: m.light_barrier,
            drive,
            near_side: match m.near_side {
                NearSideConfig::Open => NearSide::Open,
                NearSideConfig::Guide => NearSide::Guide,
            },
        },
        parcel: Parcel::riding(
            p.length,
            p.width,
            p.height,
            p.mass,
            p.offset,
            p.angle_deg.to_radians(),
        )
        .moving(p.velocity.map(|[x, y]| DVec2::new(x, y)), p.spin),
        materials: Materials {
            belt_friction: match &mat.belt_friction {
                BeltFrictionConfig::Constant(mu) => FrictionCoefficient::Constant(*mu),
                BeltFrictionConfig::Table(points) => {
                    FrictionCoefficient::Table(points.iter().map(|[v, mu]| (*v, *mu)).collect())
                }
            },
            arm_friction: mat.arm_friction,
            restitution: mat.restitution,
            friction_model: match mat.friction_model {
                FrictionModelConfig::Exact => FrictionModel::Exact,
                FrictionModelConfig::Seed => FrictionModel::Seed,
            },
            impact_law: match mat.impact_law {
                ImpactLawConfig::Energetic => ImpactLaw::Energetic,
                ImpactLawConfig::Newton => ImpactLaw::Newton,
                ImpactLawConfig::Poisson => ImpactLaw::Poisson,
            },
        },
        run: RunSettings {
            duration: f
                .run
                .duration
                .unwrap_or_else(|| default_duration(m.cycle_time)),
            tolerance: f.run.tolerance,
            arm: f.run.arm,
        },
        limits: Limits {
            drop_height: f.limits.drop_height,
        },
    };
    Ok((scenario, rows))
}

fn drive_key(d: &DriveConfig) -> &'static str {
    match d.kind {
        DriveKind::Table if d.table.is_none() => "machine.drive.points",
        DriveKind::Table => "machine.drive.table",
        DriveKind::CrankRocker if d.crank.is_some() => "machine.drive",
        _ => "machine.drive.max_swing_deg",
    }
}

/// The core's drive, and the rows of a drive table file it read.
fn drive_spec(d: &DriveConfig) -> Result<(DriveSpec, Option<AlphaRows>), Vec<Problem>> {
    let swing = d.max_swing_deg.unwrap_or(DEFAULT_SWING_DEG).to_radians();
    let mut read = None;
    let spec = match d.kind {
        DriveKind::CrankRocker => {
            let coupler = d.coupler.unwrap_or(DEFAULT_COUPLER);
            let rocker = d.rocker.unwrap_or(DEFAULT_ROCKER);
            match (d.crank, d.ground) {
                (Some(crank), Some(ground)) => {
                    let links = FourBar {
                        crank,
                        coupler,
                        rocker,
                        ground,
                    };
                    if let Some(want) = d.max_swing_deg {
                        match links.swing() {
                            Ok(got) if (got.to_degrees() - want).abs() > 1e-6 => {
                                return Err(vec![problem(
                                    "machine.drive.max_swing_deg",
                                    format!(
                                        "the links give a swing of {:.6}°, not the {want}° asked; leave max_swing_deg out or adjust the links",
                                        got.to_degrees()
                                    ),
                                )])
                            }
                            Err(e) => return Err(vec![problem("machine.drive", e.to_string())]),
                            _ => {}
                        }
                    }
                    DriveSpec::CrankRocker(links)
                }
                _ => DriveSpec::CrankRocker(FourBar::centred(swing, coupler, rocker)),
            }
        }
        DriveKind::Cycloidal => DriveSpec::Cycloidal { max_swing: swing },
        DriveKind::Harmonic => DriveSpec::Harmonic { max_swing: swing },
        DriveKind::Poly345 => DriveSpec::Poly345 { max_swing: swing },
        DriveKind::Table => {
            let rows = match (&d.table, &d.points) {
                (Some(path), _) => {
                    let rows = read_alpha_table(Path::new(path)).map_err(|m| {
                        vec![problem("machine.drive.table", format!("{path}: {m}"))]
                    })?;
                    read.insert(rows).clone()
                }
                (None, points) => points.clone().unwrap_or_default(),
            };
            // One conversion for the file's rows and the inline ones: a file written with
            // the rows inline gives the same drive bit for bit.
            DriveSpec::Table {
                times: rows.iter().map(|r| r[0]).collect(),
                angles: rows.iter().map(|r| r[1].to_radians()).collect(),
            }
        }
    };
    Ok((spec, read))
}

/// Read a `t, alpha_deg` CSV (header line optional) into rows [s, deg]. It must be a
/// regular file; errors name the line, never echo it.
pub fn read_alpha_table(path: &Path) -> Result<AlphaRows, String> {
    files::regular_file(path).map_err(|e| format!("cannot read: {e}"))?;
    let text = files::capped_file_text(path, files::MAX_SCENARIO_BYTES, "a drive table")
        .map_err(|e| format!("cannot read: {e}"))?;
    let mut rows: AlphaRows = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let parsed: Option<Vec<f64>> = cells.iter().map(|c| c.parse::<f64>().ok()).collect();
        match parsed {
            Some(v) if v.len() == 2 => rows.push([v[0], v[1]]),
            None if rows.is_empty() && i == 0 => continue, // header
            _ => {
                // The line itself is not echoed: the file may be anything.
                return Err(format!(
                    "line {}: expected two numbers 't, alpha_deg' [s, deg]",
                    i + 1
                ));
            }
        }
    }
    Ok(rows)
}

/// The JSON Schema of the scenario file, with the ranges of [`bounds::ALL`] (so an editor
/// flags `belt_speed = -3` as validation does).
pub fn json_schema() -> serde_json::Value {
    let mut schema = serde_json::to_value(schemars::schema_for!(ScenarioFile)).unwrap_or_default();
    bounds::annotate(&mut schema);
    schema
}
