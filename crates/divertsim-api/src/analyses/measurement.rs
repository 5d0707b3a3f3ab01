//! The measurement analyses on the contract ([`crate::contract`]): `compare` (each filmed
//! track against the simulation of its experiment) and `calibrate` (unknown values fitted
//! to the tracks, with profile intervals and a scenario file of the fitted values). Their
//! tracks, comparisons, fits and tables are [`super::calibration`]'s; this file is their
//! options and lifecycle.

use std::path::PathBuf;

use super::calibration::{
    self, calibrated_toml, compare_track, comparison_csv, comparison_json, comparison_text,
    fitted_runs, mismatches, profiles_csv, report_json, track_name, track_warnings, LoadedTrack,
};
use crate::config::{Loaded, Problem, ScenarioFile};
use crate::contract::{csv_table, Analysis, Error, Hooks, Work};
use divertsim_core::analysis::measurement::calibration::{
    calibrate, Calibration, CalibrationSettings, Outliers,
};
use divertsim_core::analysis::measurement::track::Comparison;
use divertsim_core::sim::SimResult;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

/// The filmed tracks of an analysis, an option group (compare, calibrate).
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are help text: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default)]
pub struct TrackOptions {
    /// A tracked marker path (CSV: t or frame, then u, v [px] or x, y [m]; `# set KEY=VALUE`
    /// comment lines give the experiment's own settings, applied after the scenario's: what
    /// was filmed wins; `# arm_start = T` or `T ± W`, in the time column's unit, pins the
    /// arm start on the video or bounds its search). Repeatable.
    #[schemars(extend("x-flag" = "track", "x-value" = "FILE"))]
    pub tracks: Vec<String>,
    /// Largest gap between consecutive points, in frame intervals, before the track is
    /// refused as broken; at least 1.
    #[schemars(extend("x-value" = "FRAMES"))]
    pub max_gap: f64,
}

impl Default for TrackOptions {
    fn default() -> TrackOptions {
        TrackOptions {
            tracks: Vec::new(),
            max_gap: 3.0,
        }
    }
}

impl TrackOptions {
    /// The tracks with their scenarios on `scenario`, or every problem.
    pub fn load(&self, scenario: &Loaded) -> Result<Vec<LoadedTrack>, Vec<Problem>> {
        let files: Vec<PathBuf> = self.tracks.iter().map(PathBuf::from).collect();
        let mut problems = Vec::new();
        let tracks = calibration::load_tracks_on(scenario, &files, self.max_gap, &mut problems);
        match problems.is_empty() {
            true => Ok(tracks),
            false => Err(problems),
        }
    }
}

/// Options of the comparison (`divertsim compare`).
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are help text: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default)]
pub struct CompareOptions {
    #[serde(flatten)]
    #[allow(missing_docs)]
    pub tracks: TrackOptions,
    /// A track matches its scenario when the RMS distance between the measured and
    /// simulated marker is at most this [m], the verdicts agree, and the belt speed on the
    /// track is within 5 % of the scenario's; > 0.
    #[schemars(extend("x-value" = "M"))]
    pub tolerance: f64,
    /// Leave the verdicts out of a match (a camera that never sees the far edge): the
    /// paths and the belt speed alone decide. A track that ends while its parcel still
    /// moves across is never taken as "not diverted" either way: its verdict is unknown.
    pub ignore_verdict: bool,
}

impl Default for CompareOptions {
    fn default() -> CompareOptions {
        CompareOptions {
            tracks: TrackOptions::default(),
            tolerance: 0.02,
            ignore_verdict: false,
        }
    }
}

/// A measurement's checked options with its tracks, bound to a scenario
/// ([`Analysis::bind`]): each track file read once.
#[derive(Debug, Clone)]
pub struct WithTracks<T> {
    pub options: T,
    pub tracks: Vec<LoadedTrack>,
}

/// A comparison's result: each track with its run, comparison and mismatch flags.
pub struct Compared {
    pub tracks: Vec<LoadedTrack>,
    /// (name, run, comparison, flags) per track, in the order given.
    pub runs: Vec<(String, SimResult, Comparison, Vec<String>)>,
    pub tolerance: f64,
}

impl Compared {
    /// (name, comparison, flags) per track.
    fn rows(&self) -> Vec<(&str, &Comparison, &[String])> {
        self.runs
            .iter()
            .map(|(n, _, c, f)| (n.as_str(), c, f.as_slice()))
            .collect()
    }
}

/// Each track's scenario, by the track's name.
fn described<'a>(
    names: impl Iterator<Item = &'a str>,
    tracks: &'a [LoadedTrack],
) -> Vec<(&'a str, &'a ScenarioFile)> {
    names
        .zip(tracks)
        .map(|(n, t)| (n, &t.loaded.file))
        .collect()
}

/// The comparison on the analysis contract.
pub struct Compare;

impl Analysis for Compare {
    const NAME: &'static str = "compare";
    const READS_FILES: bool = true;
    const ABOUT: &'static str = "Compare filmed tracks with simulations of their experiments (paper Figs 13–15): errors, Fréchet distance, verdicts; flags a track that does not match its scenario";
    type Options = CompareOptions;
    type Checked = CompareOptions;
    type Bound = WithTracks<CompareOptions>;
    type Output = Compared;

    fn validate(o: &CompareOptions) -> Result<CompareOptions, Vec<Problem>> {
        if o.tolerance > 0.0 && o.tolerance.is_finite() {
            Ok(o.clone())
        } else {
            Err(vec![Problem::new(
                "tolerance",
                format!("{} is out of range; allowed: > 0 m", o.tolerance),
            )])
        }
    }

    fn bind(
        options: CompareOptions,
        s: &Loaded,
    ) -> Result<WithTracks<CompareOptions>, Vec<Problem>> {
        let tracks = options.tracks.load(s)?;
        Ok(WithTracks { options, tracks })
    }

    fn work(c: &WithTracks<CompareOptions>, _: &Loaded) -> Work {
        let n = c.options.tracks.tracks.len() as u64;
        Work {
            at_most: Some(n),
            at_least: n,
            units: n,
            unit: "tracks",
            smaller: "give fewer `tracks`",
        }
    }

    fn run(_: &Loaded, c: &WithTracks<CompareOptions>, hooks: &Hooks) -> Result<Compared, Error> {
        use rayon::prelude::*;
        let tolerance = c.options.tolerance;
        let tracks = c.tracks.clone();
        let runs = tracks
            .par_iter()
            .map(|t| {
                let (r, cmp) = compare_track(t);
                let f = mismatches(
                    &cmp,
                    &t.loaded.scenario,
                    tolerance,
                    !c.options.ignore_verdict,
                );
                (hooks.progress)();
                (track_name(&t.path), r, cmp, f)
            })
            .collect();
        Ok(Compared {
            tracks,
            runs,
            tolerance,
        })
    }

    fn summary(r: &Compared, _: &WithTracks<CompareOptions>, _: &Loaded) -> Value {
        json!({
            "tolerance_m": r.tolerance,
            "warnings": track_warnings(&r.tracks),
            "tracks": r.runs.iter().map(|(n, _, c, f)| comparison_json(n, c, f)).collect::<Vec<_>>(),
        })
    }

    fn described_runs(r: &Compared) -> Option<Vec<(&str, &ScenarioFile)>> {
        Some(described(
            r.runs.iter().map(|(n, ..)| n.as_str()),
            &r.tracks,
        ))
    }

    fn tables(r: &Compared) -> Result<Vec<(String, Vec<u8>)>, Error> {
        Ok(vec![csv_table(
            "comparison.csv",
            comparison_csv(&r.rows()),
        )?])
    }

    fn text(r: &Compared, _: &WithTracks<CompareOptions>, _: &Loaded) -> String {
        let mut t = comparison_text(&r.rows(), r.tolerance);
        for w in track_warnings(&r.tracks) {
            t += &format!("! {w}\n");
        }
        t
    }
}

/// Options of the calibration (`divertsim calibrate`).
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are help text: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default)]
pub struct CalibrateOptions {
    #[serde(flatten)]
    #[allow(missing_docs)]
    pub tracks: TrackOptions,
    /// The values to fit, comma-separated: materials.belt_friction, materials.arm_friction,
    /// materials.restitution, machine.arm_length, machine.cycle_time,
    /// machine.drive.max_swing_deg.
    #[schemars(extend("x-value" = "KEYS"))]
    pub fit: String,
    /// The search box of a value, KEY=LO:HI (in the key's unit, degrees for the swing).
    /// Repeatable. Defaults: μ_b 0.05–1, μ_a 0–1, e* 0–1, R_z 0.5–2 m, t_c 0.5–3 s, swing
    /// 20–80°.
    #[schemars(extend("x-flag" = "bound", "x-value" = "KEY=LO:HI"))]
    pub bounds: Vec<String>,
    /// δ of the Huber loss [m]: residuals beyond it count linearly (robust to points the
    /// model cannot follow).
    #[schemars(extend("x-value" = "M"))]
    pub huber: f64,
    /// Loss evaluations of the global search (each simulates every track once; the compass
    /// search takes up to half as many more), 20 to 1000000.
    #[schemars(extend("x-value" = "N"))]
    pub budget: u64,
    /// Seed of the global search.
    pub seed: u64,
    /// The profiles (intervals and identifiability verdicts; much of the work).
    pub profiles: bool,
    /// A track whose RMS at the fit is more than 10 times the other tracks' median is an
    /// outlier: "exclude" fits again without it (the default), "flag" keeps it in the fit
    /// and says so.
    #[schemars(extend("enum" = ["exclude", "flag"]))]
    pub outliers: String,
}

impl Default for CalibrateOptions {
    fn default() -> CalibrateOptions {
        CalibrateOptions {
            tracks: TrackOptions::default(),
            fit: "materials.belt_friction,materials.arm_friction,materials.restitution".into(),
            bounds: Vec::new(),
            huber: 0.005,
            budget: 1200,
            seed: 1,
            profiles: true,
            outliers: "exclude".into(),
        }
    }
}

/// A calibration's checked inputs: the tracks to read and the settings of the fit.
#[derive(Debug, Clone)]
pub struct CalibrateInputs {
    pub tracks: TrackOptions,
    pub settings: CalibrationSettings,
}

/// A calibration's result: the fit, the tracks, each track's run at the fitted values and
/// the scenario file of the fitted values.
pub struct Calibrated {
    pub calibration: Calibration,
    pub names: Vec<String>,
    pub tracks: Vec<LoadedTrack>,
    /// Each track at the fitted values: its scenario, run and comparison.
    pub fits: Vec<(LoadedTrack, SimResult, Comparison)>,
    /// calibrated.toml: the scenario with the fitted values, standing alone.
    pub calibrated_toml: String,
}

/// The calibration on the analysis contract.
pub struct Calibrate;

impl Analysis for Calibrate {
    const NAME: &'static str = "calibrate";
    const READS_FILES: bool = true;
    const ABOUT: &'static str = "Fit μ_b, μ_a, e* (and machine values) to filmed tracks, with 95 % profile intervals, identifiability warnings and a calibrated scenario file";
    type Options = CalibrateOptions;
    type Checked = CalibrateInputs;
    type Bound = WithTracks<CalibrateInputs>;
    type Output = Calibrated;

    fn validate(o: &CalibrateOptions) -> Result<CalibrateInputs, Vec<Problem>> {
        let fit: Vec<String> = o.fit.split(',').map(str::to_string).collect();
        let mut problems = Vec::new();
        let mut bounds = Vec::new();
        for b in &o.bounds {
            let parsed = b.split_once('=').and_then(|(k, r)| {
                let (lo, hi) = r.split_once(':')?;
                Some((
                    k.trim().to_string(),
                    lo.trim().parse::<f64>().ok()?,
                    hi.trim().parse::<f64>().ok()?,
                ))
            });
            match parsed {
                Some(b) => bounds.push(b),
                None => problems.push(Problem::new(
                    "bounds",
                    format!("'{b}' is not KEY=LO:HI (e.g. materials.restitution=0.1:0.6)"),
                )),
            }
        }
        if !(20..=1_000_000).contains(&o.budget) {
            problems.push(Problem::new(
                "budget",
                format!("{} is out of range; allowed: 20 to 1000000", o.budget),
            ));
        }
        let outliers = match o.outliers.as_str() {
            "exclude" => Outliers::Exclude,
            "flag" => Outliers::Flag,
            other => {
                problems.push(Problem::new(
                    "outliers",
                    format!("'{other}' is not a rule; allowed: exclude, flag"),
                ));
                Outliers::Exclude
            }
        };
        let settings = calibration::settings(&fit, &bounds, o.huber, o.budget, o.seed, o.profiles)
            .map(|s| CalibrationSettings { outliers, ..s });
        match (settings, problems.is_empty()) {
            (Ok(settings), true) => Ok(CalibrateInputs {
                tracks: o.tracks.clone(),
                settings,
            }),
            (s, _) => Err(problems
                .into_iter()
                .chain(s.err().unwrap_or_default())
                .collect()),
        }
    }

    fn bind(
        options: CalibrateInputs,
        s: &Loaded,
    ) -> Result<WithTracks<CalibrateInputs>, Vec<Problem>> {
        let tracks = options.tracks.load(s)?;
        let problems = calibration::check_fit(&tracks, &options.settings);
        if !problems.is_empty() {
            return Err(problems);
        }
        Ok(WithTracks { options, tracks })
    }

    fn work(c: &WithTracks<CalibrateInputs>, _: &Loaded) -> Work {
        let c = &c.options;
        let tracks = c.tracks.tracks.len();
        let at_most = calibration::estimated_evaluations(&c.settings, tracks);
        Work {
            at_most: Some(at_most),
            // A fit has no piece of work to stop at (it ticks nothing): the limit holds only
            // if it is refused on the most it can run.
            at_least: at_most,
            units: 0,
            unit: "evaluations",
            smaller: "use a smaller `budget`, or skip the profiles (`profiles`)",
        }
    }

    fn run(s: &Loaded, c: &WithTracks<CalibrateInputs>, _: &Hooks) -> Result<Calibrated, Error> {
        let tracks = &c.tracks;
        let (names, cases) = calibration::cases(tracks);
        let mut fit = calibrate(&cases, &c.options.settings).map_err(Error::failed)?;
        fit.warnings.splice(0..0, track_warnings(tracks));
        let fits = fitted_runs(tracks, &fit)?;
        let calibrated_toml = calibrated_toml(s, &fit)?;
        Ok(Calibrated {
            calibration: fit,
            names,
            tracks: tracks.clone(),
            fits,
            calibrated_toml,
        })
    }

    fn summary(r: &Calibrated, _: &WithTracks<CalibrateInputs>, _: &Loaded) -> Value {
        report_json(&r.calibration, &r.names)
    }

    fn described_runs(r: &Calibrated) -> Option<Vec<(&str, &ScenarioFile)>> {
        Some(described(r.names.iter().map(String::as_str), &r.tracks))
    }

    fn tables(r: &Calibrated) -> Result<Vec<(String, Vec<u8>)>, Error> {
        Ok(vec![csv_table(
            "profiles.csv",
            profiles_csv(&r.calibration),
        )?])
    }

    fn text(r: &Calibrated, _: &WithTracks<CalibrateInputs>, _: &Loaded) -> String {
        calibration::text(&r.calibration, &r.names)
    }

    fn simulations(r: &Calibrated) -> Option<u64> {
        Some(r.calibration.simulations as u64)
    }
}
