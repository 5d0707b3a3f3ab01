//! The scenario file's types (the public TOML contract: every key, its default and its
//! description, from which `divertsim schema` and `divertsim example` are made).

// The sibling files this one uses, named so that the import-cycle check sees them.
use super::bounds::{MASS, MASS_WHY, NO_JAM, SIDE, SIDE_WHY};
use super::design::DesignConfig;
#[allow(unused_imports)]
use super::*;
use divertsim_keys::Keys;

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
    /// The sorter line of `divertsim line`.
    #[serde(skip_serializing_if = "LineConfig::is_default")]
    pub line: LineConfig,
}

/// The diverter and its belt. The frame has its origin at the arm pivot, x along the belt
/// motion and y across the belt towards the discharge side; the belt spans
/// 0 ≤ y ≤ belt_width.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, Keys)]
#[serde(deny_unknown_fields, default)]
#[keys(section = "machine", default)]
pub struct MachineConfig {
    /// P_max: belt width [m].
    #[key(default = 0.7, range = Bound::closed(0.01, 10.0, "m")
        .because("a belt narrower than 1 cm carries no parcel"))]
    pub belt_width: f64,
    /// v: belt speed [m/s].
    #[key(default = 2.0, range = Bound::closed(0.0, 20.0, "m/s"))]
    pub belt_speed: f64,
    /// R_z: arm length from the pivot [m].
    #[key(default = 1.0, range = Bound::closed(0.01, 10.0, "m")
        .because("an arm shorter than 1 cm reaches no parcel"))]
    pub arm_length: f64,
    /// t_c: the arm's working cycle, out and back [s].
    #[key(default = 1.36, range = Bound::closed(0.1, 60.0, "s")
        .because("a faster cycle is beyond any drive and strikes beyond the rigid-impact model"))]
    pub cycle_time: f64,
    /// R_s: x of the parcel's most downstream point when the arm starts (t = 0), measured
    /// from the pivot [m].
    #[key(default = 0.0, range = Bound::closed(-10.0, 10.0, "m"))]
    pub start_position: f64,
    /// S_d: x of the light barrier [m]; must not lie downstream of start_position.
    #[key(default = 0.0, range = Bound::closed(-10.0, 10.0, "m"))]
    pub light_barrier: f64,
    /// The arm's motion law.
    pub drive: DriveConfig,
    /// The pivot-side belt edge downstream of the pivot: "open" (default; docs/model.md §1 has
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
    /// The lowest height of the arm's face above the belt [m]: a parcel no taller than this
    /// passes under the arm (not_diverted, reason under_arm). Default 0.
    // (Worded here: a default left out of written files is not in the schema.)
    #[serde(skip_serializing_if = "is_zero")]
    #[key(default = 0.0, range = Bound::closed(0.0, 2.0, "m"))]
    pub arm_face_bottom: f64,
    /// The highest height of the arm's face above the belt [m]. The arm's (and the side
    /// guide's) force on a parcel acts in the middle of the part of its side between
    /// arm_face_bottom and arm_face_top: the height the tipping check uses. Default: above
    /// every parcel (the force at mid-height of a parcel standing on the belt).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[key(range = Bound::open_closed(0.0, 5.0, "m"))]
    pub arm_face_top: Option<f64>,
    /// The arm's mass [kg], for the drive torque of a stroke: its inertia about the pivot
    /// is that of a uniform bar, arm_mass · arm_length² / 3, unless arm_inertia is given.
    /// Default: not given (a massless arm: the torque is the parcel's alone).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[key(range = Bound::closed(0.0, 1000.0, "kg"))]
    pub arm_mass: Option<f64>,
    /// I_arm: the arm's moment of inertia about the pivot [kg·m²], the drive's rocker and
    /// everything that swings with it. Default: from arm_mass, else 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[key(range = Bound::closed(0.0, 10000.0, "kg·m²"))]
    pub arm_inertia: Option<f64>,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, Keys)]
#[serde(deny_unknown_fields, default)]
#[keys(section = "machine.drive", default)]
pub struct DriveConfig {
    /// "crank-rocker" (default; four-bar, crank at 2π/t_c), "cycloidal", "harmonic",
    /// "poly345" (cam laws: out in t_c/2 and back), or "table" (α(t) from `table` or
    /// `points`).
    pub kind: DriveKind,
    /// α_max: the largest arm angle [deg]. Default 45. For the crank-rocker it
    /// designs the centred linkage unless the four link lengths are all given.
    #[key(range = Bound::open_closed(0.0, 90.0, "deg"))]
    pub max_swing_deg: Option<f64>,
    /// Crank-rocker crank length a [m]. Default: c·sin(ψ/2).
    #[key(range = Bound::open_closed(0.0, 10.0, "m"))]
    pub crank: Option<f64>,
    /// Crank-rocker coupler length b [m]. Default 0.3.
    #[key(range = Bound::open_closed(0.0, 10.0, "m"))]
    pub coupler: Option<f64>,
    /// Crank-rocker rocker (arm lever) length c [m]. Default 0.15.
    #[key(range = Bound::open_closed(0.0, 10.0, "m"))]
    pub rocker: Option<f64>,
    /// Crank-rocker ground link d [m]. Default √(b² + c² cos²(ψ/2)).
    #[key(range = Bound::open_closed(0.0, 10.0, "m"))]
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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, Keys)]
#[serde(deny_unknown_fields, default)]
#[keys(section = "parcel", default)]
pub struct ParcelConfig {
    /// a: length along the parcel's own x axis [m].
    #[key(default = 0.4, range = Bound::band(SIDE, "m").because(SIDE_WHY))]
    pub length: f64,
    /// b: width along the parcel's own y axis [m].
    #[key(default = 0.26, range = Bound::band(SIDE, "m").because(SIDE_WHY))]
    pub width: f64,
    /// h: height [m] (the tipping check and the drop reference).
    #[key(default = 0.15, range = Bound::band(SIDE, "m").because(SIDE_WHY))]
    pub height: f64,
    /// h_c: height of the centre of mass above the belt [m], for the tipping check of an
    /// unevenly filled parcel; at most the height. Default: height / 2.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[key(range = Bound::open_closed(0.0, 5.0, "m"))]
    pub com_height: Option<f64>,
    /// m: mass [kg].
    #[key(default = 3.0, range = Bound::band(MASS, "kg").because(MASS_WHY))]
    pub mass: f64,
    /// ΔP: the smallest y of the parcel's corners at t = 0, its gap to the pivot-side belt
    /// edge [m].
    #[key(default = 0.22)]
    pub offset: f64,
    /// φ: the parcel's orientation, counter-clockwise from the belt direction [deg].
    #[key(default = 0.0, range = Bound::closed(-180.0, 180.0, "deg"))]
    pub angle_deg: f64,
    /// Initial velocity [vx, vy] of the centre in the machine frame [m/s]. Default: riding
    /// with the belt, [belt_speed, 0].
    #[key(at = "[]", name = VELOCITY, range = Bound::closed(-20.0, 20.0, "m/s"))]
    pub velocity: Option<[f64; 2]>,
    /// ω: initial spin, counter-clockwise [rad/s].
    #[key(default = 0.0, range = Bound::closed(-100.0, 100.0, "rad/s"))]
    pub spin: f64,
}

/// Friction and restitution.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, Keys)]
#[serde(deny_unknown_fields, default)]
#[keys(section = "materials", default)]
pub struct MaterialsConfig {
    /// μ_b: parcel–belt friction [-], a number, or a table of [relative speed m/s, μ] points
    /// for μ_1(v_o) (linear between points, constant beyond).
    #[key(default = BeltFrictionConfig::Constant(0.4), range = Bound::closed(0.0, 2.0, ""))]
    #[key(at = "[][0]", name = BELT_FRICTION_SPEED, range = Bound::closed(0.0, 100.0, "m/s"))]
    #[key(at = "[][1]", name = BELT_FRICTION_MU, range = Bound::closed(0.0, 2.0, ""))]
    pub belt_friction: BeltFrictionConfig,
    /// μ_a: parcel–arm friction, also used for the side guide.
    #[key(default = 0.3, range = Bound::closed(0.0, 1.3, "").because(NO_JAM))]
    pub arm_friction: f64,
    /// e*: Stronge's energetic coefficient of restitution.
    #[key(default = 0.3, range = Bound::closed(0.0, 1.0, ""))]
    pub restitution: f64,
    /// "exact" (default: Coulomb integrated over the footprint) or "seed" (the paper's
    /// tanh/exp law, corrected).
    pub friction_model: FrictionModelConfig,
    /// "energetic" (default, Stronge), "newton" or "poisson". Warning: with friction,
    /// "newton" can create energy when the slip reverses during a strike; only "energetic"
    /// never does.
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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, Keys)]
#[serde(deny_unknown_fields, default)]
#[keys(section = "run", default)]
pub struct RunConfig {
    /// The largest simulated time [s]. Default: cycle_time + 2 s (the arm cycle and the
    /// slide-out).
    #[key(range = Bound::closed(1e-3, 3600.0, "s")
        .because("the integrator's step budget grows with the duration up to an hour"))]
    pub duration: Option<f64>,
    /// Relative tolerance of the integrator.
    #[key(default = 1e-8, range = Bound::closed(1e-12, 1e-4, "")
        .because("tighter meets round-off in the event location, looser misses contacts"))]
    pub tolerance: f64,
    /// Whether the arm moves; false for free-motion studies.
    #[key(default = true)]
    pub arm: bool,
    /// When the arm starts each working cycle [s], from t = 0 (the parcel's front at
    /// start_position): increasing, each at least cycle_time after the one before. Default
    /// [0], the paper's one cycle. A parcel on a line meets several cycles, some under way
    /// before it arrives (negative times); `divertsim line` writes such files for its
    /// failures.
    #[serde(skip_serializing_if = "is_one_cycle")]
    #[key(default = vec![0.0])]
    #[key(at = "[]", name = CYCLE_STARTS, range = Bound::closed(-1e4, 1e4, "s"))]
    pub cycle_starts: Vec<f64>,
}

/// The paper's one cycle at t = 0 (the default, left out of written files).
fn is_one_cycle(starts: &[f64]) -> bool {
    starts == [0.0]
}

/// Allowable loads.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, Keys)]
#[serde(deny_unknown_fields, default)]
#[keys(section = "limits", default)]
pub struct LimitsConfig {
    /// H₀: reference free-fall height for the overload comparison [m].
    #[key(default = 0.3, range = Bound::closed(1e-3, 10.0, "m")
        .because("the reference fall must be finite and non-zero for the overload ratios"))]
    pub drop_height: f64,
    /// What a parcel that tips over does (a tall parcel toppled by the arm's push, a strike
    /// or the belt's friction: its tilt reached the angle that puts its centre of mass over
    /// an edge; docs/model.md §12a): "verdict" (default: the run ends there, not_diverted,
    /// reason tipped) or "flag" (the run goes on as the plane model has it and the tip-over
    /// is reported; for a line whose guard catches tipped parcels).
    #[serde(skip_serializing_if = "TippingConfig::is_default")]
    pub tipping: TippingConfig,
}

/// What a parcel that tips over does.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum TippingConfig {
    /// The run ends: not_diverted, reason tipped.
    #[default]
    Verdict,
    /// Reported only.
    Flag,
}

impl TippingConfig {
    fn is_default(&self) -> bool {
        *self == TippingConfig::Verdict
    }
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

/// The belt speeds of an analysis that needs a moving belt (trigger, capture, the
/// reference setting): `machine.belt_speed` without 0.
pub const MOVING_BELT_SPEED: Bound = {
    let b = MachineConfig::BELT_SPEED;
    Bound::open_closed(b.lo, b.hi, b.unit).at("speeds")
};

/// Default max swing \[deg].
pub const DEFAULT_SWING_DEG: f64 = 45.0;
/// Default crank-rocker coupler \[m] (docs/model.md §2).
pub const DEFAULT_COUPLER: f64 = 0.3;
/// Default crank-rocker rocker \[m] (docs/model.md §2).
pub const DEFAULT_ROCKER: f64 = 0.15;
