//! Calibration: the unknown material and machine values that make the simulated marker paths
//! match measured tracks ([`crate::analysis::measurement::track`]), with an uncertainty for each value and a warning
//! where the tracks cannot pin a value down.
//!
//! **Residuals.** For each track (its own scenario: parcel, speed, R_s) the scenario with
//! the candidate values is simulated, the track aligned in time (its own offset t₀, fitted
//! inside every evaluation), and the residuals are the measured minus the simulated marker
//! positions, x and y of every point \[m].
//!
//! **Fit.** The loss is the Huber loss of all residuals (δ = `huber`, default 5 mm: squares
//! for errors of the order of the pixel and the model's smoothness, linear beyond, so the
//! points a model cannot follow — another engine's contact model, a tracking slip — pull
//! less). It jumps where a strike appears or vanishes (near the true values the loss has
//! narrow valleys a few thousandths wide in μ_b and e*), so global stages come first:
//! differential evolution over the box ([`crate::optimize::de`], no polish), then a compass
//! search from its best point ([`crate::optimize::pattern`], which steps over jumps), then a
//! robust Levenberg–Marquardt ([`crate::optimize::least_squares`]).
//!
//! **Uncertainty** by profile likelihood. With N residuals and p values, the noise scale is
//! s² = max(2 L̂/(N − p), σ̄²)·(1 + ρ)/(1 − ρ) (σ̄ the tracks' quantisation σ, ρ the lag-1
//! autocorrelation of the residuals along the tracks: correlated residuals carry less
//! information than their number says), and Δχ²(θ_k) = 2 (L_k(θ_k) − L̂)/s² where L_k is the
//! loss with θ_k fixed and the other values refitted. The 95 % interval is where
//! Δχ² ≤ 3.84, found on steps of 0.25, 0.5, 1, … 64 % of the box width either side and at
//! the box's ends. A value whose interval reaches both ends of its box is **not
//! identifiable** from these tracks: its profile is flat. The intervals assume the model is
//! right; on a rough loss they describe the valley the fit is in.
//!
//! **Intervals that admit model error** (issue 27): beside the profiles, a cluster-robust
//! sandwich over the tracks, cov = A⁻¹ B A⁻¹ · G/(G − 1) with A = Σ_t J_tᵀ W_t J_t (J_t the
//! Jacobian of track t's residuals at the fit, W_t the Huber weights) and B = Σ_t g_t g_tᵀ,
//! g_t = J_tᵀ W_t r_t: each track's pull on the values as it is, not as the noise model
//! says (Liang & Zeger 1986; docs/model.md §11). It needs G ≥ 2 tracks and is rough with
//! few. A fit whose noise scale is more than [`NOISE_WARNING_FACTOR`] times the tracks'
//! pixel is warned of: the model does not follow the tracks to their precision.
//!
//! **A bad track is found, not averaged in.** A track whose RMS at the fit is more than
//! [`OUTLIER_FACTOR`] times the median RMS of the other tracks (and than the pixel) is an
//! outlier: by default it is excluded and the fit is made again without it (so the values
//! are those of the other tracks alone), or only flagged ([`Outliers::Flag`]). Each
//! track's **influence** is the change of every value when the fit leaves it out (a local
//! refit from the fit).

use crate::analysis::measurement::track::{align_pinned, residuals, ArmStart, MarkerPath, Track};
use crate::model::belt_friction::FrictionCoefficient;
use crate::model::drive::{ArmDrive, DriveSpec};
use crate::model::params::Scenario;
use crate::optimize::de::{self, DeSettings};
use crate::optimize::least_squares::{self, huber_loss, LeastSquaresSettings};
use crate::optimize::pattern::{self, PatternSettings};
use crate::optimize::{Bounds, Evaluation, NoObserver, OptimizeError, Problem};
use crate::sim::simulate;
use glam::DVec2;
use rayon::prelude::*;

/// A value that can be fitted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FitParameter {
    /// μ_b (a constant).
    BeltFriction,
    /// μ_a.
    ArmFriction,
    /// e*.
    Restitution,
    /// R_z \[m].
    ArmLength,
    /// t_c \[s].
    CycleTime,
    /// α_max \[rad] of a cam law or the centred crank-rocker.
    MaxSwing,
}

impl FitParameter {
    pub const ALL: [FitParameter; 6] = [
        FitParameter::BeltFriction,
        FitParameter::ArmFriction,
        FitParameter::Restitution,
        FitParameter::ArmLength,
        FitParameter::CycleTime,
        FitParameter::MaxSwing,
    ];

    /// The scenario key.
    pub fn key(self) -> &'static str {
        match self {
            FitParameter::BeltFriction => "materials.belt_friction",
            FitParameter::ArmFriction => "materials.arm_friction",
            FitParameter::Restitution => "materials.restitution",
            FitParameter::ArmLength => "machine.arm_length",
            FitParameter::CycleTime => "machine.cycle_time",
            FitParameter::MaxSwing => "machine.drive.max_swing_deg",
        }
    }

    pub fn from_key(key: &str) -> Option<FitParameter> {
        FitParameter::ALL.into_iter().find(|p| p.key() == key)
    }

    /// The default search box (SI; the swing in radians).
    pub fn default_bounds(self) -> (f64, f64) {
        match self {
            FitParameter::BeltFriction => (0.05, 1.0),
            FitParameter::ArmFriction => (0.0, 1.0),
            FitParameter::Restitution => (0.0, 1.0),
            FitParameter::ArmLength => (0.5, 2.0),
            FitParameter::CycleTime => (0.5, 3.0),
            FitParameter::MaxSwing => (20f64.to_radians(), 80f64.to_radians()),
        }
    }

    /// Set the value in a scenario. `Err` if the scenario cannot take it (a drive without a
    /// swing parameter).
    pub fn apply(self, s: &mut Scenario, v: f64) -> Result<(), String> {
        match self {
            FitParameter::BeltFriction => {
                s.materials.belt_friction = FrictionCoefficient::Constant(v)
            }
            FitParameter::ArmFriction => s.materials.arm_friction = v,
            FitParameter::Restitution => s.materials.restitution = v,
            FitParameter::ArmLength => s.machine.arm_length = v,
            FitParameter::CycleTime => {
                s.machine.cycle_time = v;
                s.run.duration = s
                    .run
                    .duration
                    .max(crate::model::params::default_duration(v));
            }
            FitParameter::MaxSwing => match &mut s.machine.drive {
                DriveSpec::Cycloidal { max_swing }
                | DriveSpec::Harmonic { max_swing }
                | DriveSpec::Poly345 { max_swing } => *max_swing = v,
                DriveSpec::CrankRocker(links) => {
                    *links = crate::model::drive::FourBar::centred(v, links.coupler, links.rocker)
                }
                DriveSpec::Table { .. } => {
                    return Err("a drive table has no swing to fit".into());
                }
            },
        }
        Ok(())
    }

    /// The value in a scenario (NaN where it has none: a table μ_b, a table drive).
    pub fn value(self, s: &Scenario) -> f64 {
        match self {
            FitParameter::BeltFriction => match &s.materials.belt_friction {
                FrictionCoefficient::Constant(m) => *m,
                FrictionCoefficient::Table(_) => f64::NAN,
            },
            FitParameter::ArmFriction => s.materials.arm_friction,
            FitParameter::Restitution => s.materials.restitution,
            FitParameter::ArmLength => s.machine.arm_length,
            FitParameter::CycleTime => s.machine.cycle_time,
            FitParameter::MaxSwing => match &s.machine.drive {
                DriveSpec::Cycloidal { max_swing }
                | DriveSpec::Harmonic { max_swing }
                | DriveSpec::Poly345 { max_swing } => *max_swing,
                DriveSpec::CrankRocker(l) => l.swing().unwrap_or(f64::NAN),
                DriveSpec::Table { .. } => f64::NAN,
            },
        }
    }
}

/// One measured track with the scenario it was filmed in.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationCase {
    pub name: String,
    pub scenario: Scenario,
    pub track: Track,
    /// The marker's offset from the centre, in the parcel's axes \[m].
    pub marker_offset: DVec2,
    /// What is known of the arm start on the video (`None`: t₀ is searched freely).
    pub arm_start: Option<ArmStart>,
}

/// A track's RMS at the fit beyond this many times the other tracks' median makes it an
/// outlier (module notes).
pub const OUTLIER_FACTOR: f64 = 10.0;
/// A noise scale beyond this many times the tracks' pixel σ is warned of.
pub const NOISE_WARNING_FACTOR: f64 = 5.0;
/// z of a two-sided 95 % normal interval.
const Z_95: f64 = 1.959_963_984_540_054;

/// What to do with an outlier track.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Outliers {
    /// Fit again without it (its figures reported at the final values).
    #[default]
    Exclude,
    /// Keep it in the fit and flag it.
    Flag,
}

/// What to fit and how hard to search.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationSettings {
    pub parameters: Vec<FitParameter>,
    /// Search box per parameter (SI).
    pub bounds: Vec<(f64, f64)>,
    /// δ of the Huber loss \[m].
    pub huber: f64,
    /// Loss evaluations of the global stage (each runs every track once).
    pub global_evaluations: usize,
    pub seed: u64,
    /// Whether to profile each value (the uncertainty; p × about 14 local fits).
    pub profiles: bool,
    /// What to do with an outlier track.
    pub outliers: Outliers,
}

impl CalibrationSettings {
    /// `parameters` with their default boxes, δ = 5 mm, 1,200 global evaluations (fewer
    /// stall in a valley next to the true one: the paper's six runs need about 1,000).
    pub fn new(parameters: Vec<FitParameter>) -> CalibrationSettings {
        CalibrationSettings {
            bounds: parameters.iter().map(|p| p.default_bounds()).collect(),
            parameters,
            huber: 0.005,
            global_evaluations: 1200,
            seed: 1,
            profiles: true,
            outliers: Outliers::Exclude,
        }
    }
}

/// Δχ² of the 95 % profile interval (χ² with one degree of freedom).
pub const CHI2_95: f64 = 3.841_458_820_694_124;

/// The profile of one value.
#[derive(Debug, Clone, PartialEq)]
pub struct Profile {
    /// (value, Δχ²) at each profiled value, increasing.
    pub points: Vec<(f64, f64)>,
    /// The 95 % interval; an end at the box edge where the profile stays below 3.84 there.
    pub interval: (f64, f64),
    /// Whether the profile rises above 3.84 on both sides inside the box.
    pub identifiable: bool,
    /// Whether it rises on at least one side (bounded one way only).
    pub one_sided: bool,
}

/// One track's fit.
#[derive(Debug, Clone, PartialEq)]
pub struct CaseFit {
    pub name: String,
    /// t₀: the video time of the arm start \[s].
    pub offset: f64,
    /// RMS distance between measured and simulated marker \[m].
    pub rms: f64,
    /// Largest distance \[m].
    pub max: f64,
    pub points: usize,
    /// Whether the outlier rule flags it (module notes).
    pub outlier: bool,
    /// Whether the fit left it out (an outlier under [`Outliers::Exclude`]).
    pub excluded: bool,
    /// The change of each value when the fit leaves this track out (empty for a single
    /// track, or an excluded one).
    pub influence: Vec<f64>,
}

/// The calibration.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    pub parameters: Vec<FitParameter>,
    /// The fitted values (SI).
    pub values: Vec<f64>,
    /// The global stage's best values.
    pub global_values: Vec<f64>,
    /// L at the fit.
    pub loss: f64,
    /// s: the noise scale the intervals use, correlation included \[m].
    pub noise: f64,
    /// ρ: the lag-1 autocorrelation of the residuals within the tracks (in [0, 0.95]).
    pub correlation: f64,
    pub cases: Vec<CaseFit>,
    /// One per value (empty without profiles).
    pub profiles: Vec<Profile>,
    /// The model-robust (sandwich) 95 % interval of each value; `None` with fewer than two
    /// tracks in the fit (module notes).
    pub robust_intervals: Vec<Option<(f64, f64)>>,
    /// The tracks' pixel σ, pooled \[m].
    pub pixel: f64,
    /// What a user should know of this fit, in words.
    pub warnings: Vec<String>,
    /// Simulations run.
    pub simulations: usize,
}

/// Why a calibration cannot run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CalibrationError {
    #[error("no tracks")]
    NoTracks,
    #[error("no values to fit")]
    NoParameters,
    #[error("{0}")]
    Parameter(String),
    #[error(transparent)]
    Optimize(#[from] OptimizeError),
}

/// The scenario of a case with the values applied.
fn with_values(
    case: &CalibrationCase,
    params: &[FitParameter],
    x: &[f64],
) -> Result<Scenario, String> {
    let mut s = case.scenario.clone();
    for (p, v) in params.iter().zip(x) {
        p.apply(&mut s, *v)?;
    }
    if let Err(e) = ArmDrive::new(&s.machine.drive, s.machine.cycle_time) {
        return Err(e.to_string());
    }
    Ok(s)
}

/// Residuals of one case at values x (x then y of each point; a large constant if the
/// scenario cannot run, so that the fit avoids it), and its offset.
fn case_residuals(case: &CalibrationCase, params: &[FitParameter], x: &[f64]) -> (Vec<f64>, f64) {
    let n = case.track.points.len();
    let Ok(s) = with_values(case, params, x) else {
        return (vec![1.0; 2 * n], 0.0);
    };
    let r = simulate(&s);
    if matches!(r.outcome, crate::sim::Outcome::Failed(_)) {
        // A run that fails numerically is no fit: the same penalty as a scenario that
        // cannot run.
        return (vec![1.0; 2 * n], 0.0);
    }
    let path = MarkerPath::new(&s, &r, case.marker_offset);
    let t0 = align_pinned(&case.track, &path, case.arm_start);
    let res = residuals(&case.track, &path, t0);
    (res.iter().flat_map(|e| [e.x, e.y]).collect(), t0)
}

/// Every case's residuals, concatenated (cases in parallel, in order).
fn all_residuals(cases: &[CalibrationCase], params: &[FitParameter], x: &[f64]) -> Vec<f64> {
    cases
        .par_iter()
        .map(|c| case_residuals(c, params, x).0)
        .collect::<Vec<_>>()
        .concat()
}

/// The global stage's problem: the Huber loss over the box.
struct LossProblem<'a> {
    cases: &'a [CalibrationCase],
    params: &'a [FitParameter],
    bounds: Bounds,
    huber: f64,
}

impl Problem for LossProblem<'_> {
    fn bounds(&self) -> &Bounds {
        &self.bounds
    }
    fn constraint_count(&self) -> usize {
        0
    }
    fn evaluate(&self, x: &[f64]) -> Evaluation {
        let r = all_residuals(self.cases, self.params, x);
        let l = huber_loss(&r, self.huber);
        Evaluation {
            objectives: vec![if l.is_finite() { l } else { f64::MAX }],
            constraints: vec![],
        }
    }
}

/// Fit the values (module notes): the fit, the outlier rule (and a fit again without the
/// outliers it excludes), then each value's uncertainty and each track's influence.
pub fn calibrate(
    cases: &[CalibrationCase],
    settings: &CalibrationSettings,
) -> Result<Calibration, CalibrationError> {
    if cases.is_empty() {
        return Err(CalibrationError::NoTracks);
    }
    let params = &settings.parameters;
    if params.is_empty() {
        return Err(CalibrationError::NoParameters);
    }
    if settings.bounds.len() != params.len() {
        return Err(CalibrationError::Parameter(format!(
            "{} bounds for {} values",
            settings.bounds.len(),
            params.len()
        )));
    }
    let bounds = Bounds::new(
        settings.bounds.iter().map(|b| b.0).collect(),
        settings.bounds.iter().map(|b| b.1).collect(),
    )?;
    // Every case must take every value (e.g. a swing needs a swing parameter).
    let mid: Vec<f64> = settings.bounds.iter().map(|b| 0.5 * (b.0 + b.1)).collect();
    for c in cases {
        with_values(c, params, &mid)
            .map_err(|e| CalibrationError::Parameter(format!("{}: {e}", c.name)))?;
    }
    let first = fit_values(cases, settings, &bounds)?;
    let fits = case_fits(cases, params, &first.values);
    let pixel = pixel_sigma(cases);
    let flagged = outliers(&fits, pixel);
    let exclude = settings.outliers == Outliers::Exclude
        && flagged.iter().any(|&f| f)
        && flagged.iter().any(|&f| !f);
    let mut warnings = Vec::new();
    for ((c, f), out) in cases.iter().zip(&fits).zip(&flagged) {
        if *out {
            warnings.push(format!(
                "track {}: RMS {:.4} m at the fit of every track, more than {OUTLIER_FACTOR} times the other tracks' median: an outlier, {}",
                c.name,
                f.0.rms,
                if exclude {
                    "left out of the fit"
                } else {
                    "kept in the fit (flag only)"
                }
            ));
        }
    }
    let mut c = if exclude {
        let kept: Vec<CalibrationCase> = cases
            .iter()
            .zip(&flagged)
            .filter(|(_, f)| !**f)
            .map(|(c, _)| c.clone())
            .collect();
        let fitted = fit_values(&kept, settings, &bounds)?;
        let at_fit = case_fits(&kept, params, &fitted.values);
        let mut c = uncertainty(&kept, settings, &bounds, fitted, at_fit);
        // Every track in the order given, the excluded ones at the final values.
        let out: Vec<CalibrationCase> = cases
            .iter()
            .zip(&flagged)
            .filter(|(_, f)| **f)
            .map(|(c, _)| c.clone())
            .collect();
        let mut excluded = case_fits(&out, params, &c.values).into_iter();
        let mut kept_fits = std::mem::take(&mut c.cases).into_iter();
        c.cases = flagged
            .iter()
            .filter_map(|out| match out {
                true => excluded.next().map(|(f, _)| CaseFit {
                    outlier: true,
                    excluded: true,
                    ..f
                }),
                false => kept_fits.next(),
            })
            .collect();
        c.simulations += first.simulations + cases.len() + out.len();
        c
    } else {
        let mut c = uncertainty(cases, settings, &bounds, first, fits);
        for (f, out) in c.cases.iter_mut().zip(&flagged) {
            f.outlier = *out;
        }
        c
    };
    if c.noise > NOISE_WARNING_FACTOR * pixel {
        warnings.push(format!(
            "the fit's noise scale {:.2} mm is {:.0} times the tracks' pixel ({:.2} mm): the model does not follow the tracks to their precision; the profile intervals assume it does, the model-robust ones do not",
            1e3 * c.noise,
            c.noise / pixel.max(1e-300),
            1e3 * pixel
        ));
    }
    c.warnings = warnings;
    Ok(c)
}

/// The fit of the values alone: global search, compass search, local least squares.
struct Fitted {
    values: Vec<f64>,
    global_values: Vec<f64>,
    loss: f64,
    simulations: usize,
}

fn fit_values(
    cases: &[CalibrationCase],
    settings: &CalibrationSettings,
    bounds: &Bounds,
) -> Result<Fitted, CalibrationError> {
    let params = &settings.parameters;
    let mut sims = 0usize;
    let per_eval = cases.len();

    // Global stage.
    let p = params.len();
    let population = global_population(p);
    let budget = settings.global_evaluations.max(population);
    let problem = LossProblem {
        cases,
        params,
        bounds: bounds.clone(),
        huber: settings.huber,
    };
    let de_settings = DeSettings {
        population,
        generations: budget / population,
        polish: None,
        max_evaluations: Some(budget),
        seed: settings.seed,
        ..DeSettings::default()
    };
    let global = de::solve(&problem, &de_settings, &mut NoObserver)?;
    sims += global.evaluations * per_eval;
    // A compass search from there: it steps over the loss's jumps, which stall a gradient.
    let compass = pattern::solve(
        &problem,
        &PatternSettings {
            start: Some(global.best_x.clone()),
            initial_step: 0.02,
            min_step: 1e-4,
            max_evaluations: settings.global_evaluations.div_ceil(2).max(20),
        },
        &mut NoObserver,
    )?;
    sims += compass.evaluations * per_eval;
    let start = if compass.best.objectives[0] <= global.best.objectives[0] {
        compass
    } else {
        global
    };

    // Local stage.
    let ls = LeastSquaresSettings {
        huber: settings.huber,
        max_iterations: 40,
        difference_step: 1e-4,
        tolerance: 1e-9,
    };
    let fit = least_squares::solve(
        |x: &[f64]| all_residuals(cases, params, x),
        &start.best_x,
        bounds,
        &ls,
    );
    sims += fit.evaluations * per_eval;
    let (values, loss) = if fit.loss <= start.best.objectives[0] {
        (fit.x.clone(), fit.loss)
    } else {
        (start.best_x.clone(), start.best.objectives[0])
    };
    Ok(Fitted {
        values,
        global_values: start.best_x,
        loss,
        simulations: sims,
    })
}

/// The global search's population for `parameters` fitted parameters (its first
/// generation: the least a fit evaluates).
pub fn global_population(parameters: usize) -> usize {
    (8 * parameters).clamp(10, 40)
}

/// Each track's fit figures at `values`, with its residuals.
fn case_fits(
    cases: &[CalibrationCase],
    params: &[FitParameter],
    values: &[f64],
) -> Vec<(CaseFit, Vec<f64>)> {
    cases
        .par_iter()
        .map(|c| {
            let (r, t0) = case_residuals(c, params, values);
            let d: Vec<f64> = r.chunks(2).map(|e| e[0].hypot(e[1])).collect();
            let n = d.len().max(1) as f64;
            let fit = CaseFit {
                name: c.name.clone(),
                offset: t0,
                rms: (d.iter().map(|v| v * v).sum::<f64>() / n).sqrt(),
                max: d.iter().copied().fold(0.0, f64::max),
                points: d.len(),
                outlier: false,
                excluded: false,
                influence: Vec::new(),
            };
            (fit, r)
        })
        .collect()
}

/// The tracks' quantisation σ, pooled over every coordinate \[m].
fn pixel_sigma(cases: &[CalibrationCase]) -> f64 {
    let all: Vec<f64> = cases
        .iter()
        .flat_map(|c| c.track.sigma.iter().flat_map(|s| [s.x * s.x, s.y * s.y]))
        .collect();
    (all.iter().sum::<f64>() / all.len().max(1) as f64).sqrt()
}

/// The outlier rule (module notes): each track's RMS against the median of the others'.
fn outliers(fits: &[(CaseFit, Vec<f64>)], pixel: f64) -> Vec<bool> {
    (0..fits.len())
        .map(|i| {
            let mut others: Vec<f64> = fits
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|(_, f)| f.0.rms)
                .collect();
            if others.is_empty() {
                return false;
            }
            others.sort_by(f64::total_cmp);
            let m = others.len();
            let median = match m % 2 {
                1 => others[m / 2],
                _ => 0.5 * (others[m / 2 - 1] + others[m / 2]),
            };
            fits[i].0.rms > OUTLIER_FACTOR * median.max(pixel)
        })
        .collect()
}

/// The fit's uncertainty: noise scale, profiles, the sandwich intervals and each track's
/// influence; `at_fit`: each track's fit figures and residuals at the fitted values.
fn uncertainty(
    cases: &[CalibrationCase],
    settings: &CalibrationSettings,
    bounds: &Bounds,
    fitted: Fitted,
    at_fit: Vec<(CaseFit, Vec<f64>)>,
) -> Calibration {
    let params = &settings.parameters;
    let p = params.len();
    let per_eval = cases.len();
    let Fitted {
        values,
        global_values,
        loss,
        mut simulations,
    } = fitted;
    simulations += per_eval;

    // Noise scale: the fit's, not below the quantisation.
    let n_res: usize = cases.iter().map(|c| 2 * c.track.points.len()).sum();
    let pixel = pixel_sigma(cases);
    let dof = n_res.saturating_sub(p).max(1) as f64;
    // Correlated residuals: N points carry the information of N (1 − ρ)/(1 + ρ).
    let rho = lag1_correlation(at_fit.iter().map(|(_, r)| r.as_slice()));
    let inflation = (1.0 + rho) / (1.0 - rho);
    let s2 = (2.0 * loss / dof).max(pixel * pixel).max(1e-18) * inflation;

    let mut profiles = Vec::new();
    if settings.profiles {
        for k in 0..p {
            let (prof, used) = profile(cases, settings, bounds, &values, loss, s2, k);
            simulations += used * per_eval;
            profiles.push(prof);
        }
    }
    let residuals: Vec<&[f64]> = at_fit.iter().map(|(_, r)| r.as_slice()).collect();
    let (robust_intervals, used) = sandwich(cases, settings, bounds, &values, &residuals);
    simulations += used;
    let mut cases_out: Vec<CaseFit> = at_fit.into_iter().map(|(f, _)| f).collect();
    if cases.len() >= 2 {
        for (i, f) in cases_out.iter_mut().enumerate() {
            let others: Vec<CalibrationCase> = cases
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|(_, c)| c.clone())
                .collect();
            let refit = least_squares::solve(
                |x: &[f64]| all_residuals(&others, params, x),
                &values,
                bounds,
                &LeastSquaresSettings {
                    huber: settings.huber,
                    max_iterations: 20,
                    difference_step: 1e-4,
                    tolerance: 1e-9,
                },
            );
            simulations += refit.evaluations * others.len();
            f.influence = refit.x.iter().zip(&values).map(|(a, b)| a - b).collect();
        }
    }
    Calibration {
        correlation: rho,
        parameters: params.clone(),
        values,
        global_values,
        loss,
        noise: s2.sqrt(),
        cases: cases_out,
        profiles,
        robust_intervals,
        pixel,
        warnings: Vec::new(),
        simulations,
    }
}

/// The cluster-robust sandwich intervals over the tracks (module notes), and the
/// simulations they took.
fn sandwich(
    cases: &[CalibrationCase],
    settings: &CalibrationSettings,
    bounds: &Bounds,
    values: &[f64],
    residuals: &[&[f64]],
) -> (Vec<Option<(f64, f64)>>, usize) {
    let params = &settings.parameters;
    let p = params.len();
    let g = cases.len();
    if g < 2 {
        return (vec![None; p], 0);
    }
    // Forward differences into the box, each track's Jacobian column by column.
    let columns: Vec<(f64, Vec<Vec<f64>>)> = (0..p)
        .map(|j| {
            let width = bounds.upper[j] - bounds.lower[j];
            let mut h = 1e-4 * width.max(1e-12);
            if values[j] + h > bounds.upper[j] {
                h = -h;
            }
            let mut x = values.to_vec();
            x[j] += h;
            let r: Vec<Vec<f64>> = cases
                .par_iter()
                .map(|c| case_residuals(c, params, &x).0)
                .collect();
            (h, r)
        })
        .collect();
    let used = p * g;
    let weight = |v: f64| {
        let a = v.abs();
        if a <= settings.huber {
            1.0
        } else {
            settings.huber / a
        }
    };
    let mut a = vec![vec![0.0; p]; p];
    let mut b = vec![vec![0.0; p]; p];
    for (t, r0) in residuals.iter().enumerate() {
        let jac: Vec<Vec<f64>> = columns
            .iter()
            .map(|(h, r)| r[t].iter().zip(*r0).map(|(x, y)| (x - y) / h).collect())
            .collect();
        let w: Vec<f64> = r0.iter().map(|&v| weight(v)).collect();
        let score: Vec<f64> = (0..p)
            .map(|i| (0..r0.len()).map(|n| jac[i][n] * w[n] * r0[n]).sum())
            .collect();
        for i in 0..p {
            for k in 0..p {
                a[i][k] += (0..r0.len())
                    .map(|n| jac[i][n] * w[n] * jac[k][n])
                    .sum::<f64>();
                b[i][k] += score[i] * score[k];
            }
        }
    }
    let scale = g as f64 / (g as f64 - 1.0);
    // A⁻¹ column by column, then A⁻¹ B A⁻¹.
    let inverse: Option<Vec<Vec<f64>>> = (0..p)
        .map(|j| {
            let mut e = vec![0.0; p];
            e[j] = 1.0;
            least_squares::solve_dense(a.clone(), e)
        })
        .collect();
    let Some(inv) = inverse else {
        return (vec![None; p], used);
    };
    // inv[j] is column j of A⁻¹ (A symmetric, so also row j).
    let intervals = (0..p)
        .map(|k| {
            let var: f64 = (0..p)
                .flat_map(|i| (0..p).map(move |l| (i, l)))
                .map(|(i, l)| inv[k][i] * b[i][l] * inv[l][k])
                .sum::<f64>()
                * scale;
            (var.is_finite() && var >= 0.0).then(|| {
                let half = Z_95 * var.sqrt();
                (values[k] - half, values[k] + half)
            })
        })
        .collect();
    (intervals, used)
}

/// The lag-1 autocorrelation of each track's residuals (x, y interleaved; the x and y
/// series apart), pooled, clamped to [0, 0.95].
fn lag1_correlation<'a>(tracks: impl Iterator<Item = &'a [f64]>) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for r in tracks {
        for comp in 0..2 {
            let series: Vec<f64> = r.iter().skip(comp).step_by(2).copied().collect();
            let n = series.len().max(1) as f64;
            let mean = series.iter().sum::<f64>() / n;
            for w in series.windows(2) {
                num += (w[0] - mean) * (w[1] - mean);
            }
            den += series.iter().map(|v| (v - mean).powi(2)).sum::<f64>();
        }
    }
    if den > 0.0 {
        (num / den).clamp(0.0, 0.95)
    } else {
        0.0
    }
}

/// The profile of value k (module notes); returns it and the residual evaluations used.
fn profile(
    cases: &[CalibrationCase],
    settings: &CalibrationSettings,
    bounds: &Bounds,
    best: &[f64],
    best_loss: f64,
    s2: f64,
    k: usize,
) -> (Profile, usize) {
    let params = &settings.parameters;
    let (lo, hi) = (bounds.lower[k], bounds.upper[k]);
    let width = hi - lo;
    let others: Vec<usize> = (0..params.len()).filter(|&j| j != k).collect();
    let mut used = 0;
    // Δχ² with θ_k fixed at v and the others refitted, from `start` (the previous profile
    // point's refit: far from the optimum the others move, and a refit from the optimum
    // would overstate Δχ²). Returns Δχ² and the refitted others.
    let mut delta = |v: f64, start: &[f64]| -> (f64, Vec<f64>) {
        let point = |y: &[f64]| {
            let mut x = best.to_vec();
            x[k] = v;
            for (i, &j) in others.iter().enumerate() {
                x[j] = y[i];
            }
            x
        };
        let (loss, y) = if others.is_empty() {
            used += 1;
            (
                huber_loss(&all_residuals(cases, params, &point(&[])), settings.huber),
                Vec::new(),
            )
        } else {
            let sub = Bounds {
                lower: others.iter().map(|&j| bounds.lower[j]).collect(),
                upper: others.iter().map(|&j| bounds.upper[j]).collect(),
            };
            let fit = least_squares::solve(
                |y: &[f64]| all_residuals(cases, params, &point(y)),
                start,
                &sub,
                &LeastSquaresSettings {
                    huber: settings.huber,
                    max_iterations: 12,
                    difference_step: 1e-4,
                    tolerance: 1e-6,
                },
            );
            used += fit.evaluations;
            (fit.loss, fit.x)
        };
        ((2.0 * (loss - best_loss) / s2).max(0.0), y)
    };
    let best_others: Vec<f64> = others.iter().map(|&j| best[j]).collect();
    let mut points = vec![(best[k], 0.0)];
    // One side: steps of 0.25, 0.5, 1, … 64 % of the width, then the box's end, until Δχ² passes
    // the threshold. Returns the interval end (the crossing, interpolated) and whether the
    // profile crossed.
    let mut side = |sign: f64, points: &mut Vec<(f64, f64)>| -> (f64, bool) {
        let mut prev = (best[k], 0.0);
        let mut start = best_others.clone();
        for frac in [0.0025, 0.005, 0.01, 0.02, 0.04, 0.08, 0.16, 0.32, 0.64, 1.0] {
            let v = (best[k] + sign * frac * width).clamp(lo, hi);
            if v == prev.0 {
                break;
            }
            let (d, y) = delta(v, &start);
            start = y;
            points.push((v, d));
            if d > CHI2_95 {
                // The crossing: on the parabola Δχ² ∝ (θ − θ̂)² from the optimum, else
                // linear between the last point below and this one.
                let t = if prev.1 > 0.0 {
                    (CHI2_95 - prev.1) / (d - prev.1)
                } else {
                    (CHI2_95 / d).sqrt()
                };
                return (prev.0 + t * (v - prev.0), true);
            }
            prev = (v, d);
            if v == lo || v == hi {
                break;
            }
        }
        (if sign < 0.0 { lo } else { hi }, false)
    };
    let (low, closed_low) = side(-1.0, &mut points);
    let (high, closed_high) = side(1.0, &mut points);
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    (
        Profile {
            points,
            interval: (low, high),
            identifiable: closed_low && closed_high,
            one_sided: closed_low != closed_high,
        },
        used,
    )
}
