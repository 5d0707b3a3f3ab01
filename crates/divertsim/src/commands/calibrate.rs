//! `divertsim calibrate`: fit unknown material and machine values to filmed tracks
//! (`divertsim_core::analysis::measurement::calibration`), with a profile-likelihood interval for each
//! value, a warning for each value the tracks cannot pin down, and a scenario file of the
//! fitted values that `simulate` runs directly.

use divertsim_core::analysis::measurement::calibration::{calibrate, CalibrationSettings};

use super::common::{self, OutputArgs, ScenarioArgs};
use super::compare::draw_overlay;
use super::track::{load_tracks, TrackArgs};
use divertsim_api::analyses::calibration::{self, calibrated_toml, measured_points, report_json};
use divertsim_api::config::{self, Problem};

#[allow(rustdoc::broken_intra_doc_links)] // doc comments are --help text: [m] is a unit
#[derive(Debug, clap::Args)]
pub struct CalibrateArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub tracks: TrackArgs,
    /// The values to fit, comma-separated: materials.belt_friction, materials.arm_friction,
    /// materials.restitution, machine.arm_length, machine.cycle_time,
    /// machine.drive.max_swing_deg.
    #[arg(
        long,
        value_name = "KEYS",
        default_value = "materials.belt_friction,materials.arm_friction,materials.restitution"
    )]
    pub fit: String,
    /// The search box of a value, KEY=LO:HI (in the key's unit, degrees for the swing).
    /// Repeatable. Defaults: μ_b 0.05–1, μ_a 0–1, e* 0–1, R_z 0.5–2 m, t_c 0.5–3 s, swing
    /// 20–80°.
    #[arg(long = "bound", value_name = "KEY=LO:HI")]
    pub bounds: Vec<String>,
    /// δ of the Huber loss [m]: residuals beyond it count linearly (robust to points the
    /// model cannot follow).
    #[arg(long, value_name = "M", default_value_t = 0.005)]
    pub huber: f64,
    /// Loss evaluations of the global search (each simulates every track once; the compass
    /// search takes up to half as many more).
    #[arg(long, value_name = "N", default_value_t = 1200,
          value_parser = clap::value_parser!(u64).range(20..=1_000_000))]
    pub budget: u64,
    /// Seed of the global search.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Skip the profiles (no intervals, no identifiability verdicts; much faster).
    #[arg(long)]
    pub no_profiles: bool,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// The settings from the options; problems named by their flags.
fn settings(args: &CalibrateArgs, problems: &mut Vec<Problem>) -> Option<CalibrationSettings> {
    let fit: Vec<String> = args.fit.split(',').map(str::to_string).collect();
    let mut bounds = Vec::new();
    for b in &args.bounds {
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
                "--bound",
                format!("'{b}' is not KEY=LO:HI (e.g. materials.restitution=0.1:0.6)"),
            )),
        }
    }
    calibration::settings(
        &fit,
        &bounds,
        args.huber,
        args.budget,
        args.seed,
        !args.no_profiles,
    )
    .map_err(|p| problems.extend(common::flags(p)))
    .ok()
}

/// `divertsim calibrate`.
pub fn run(args: &CalibrateArgs) -> i32 {
    let mut problems = common::out_problems(&args.output);
    let settings = settings(args, &mut problems);
    let tracks = load_tracks(&args.scenario, &args.tracks, &mut problems);
    if let Some(settings) = &settings {
        problems.extend(common::flags(calibration::check_fit(&tracks, settings)));
    }
    if let Err(code) = common::check(problems) {
        return code;
    }
    let Some(settings) = settings else { return 2 };
    let (names, cases) = calibration::cases(&tracks);
    let evaluations = calibration::estimated_evaluations(&settings, cases.len());
    if let Err(code) = common::within_budget(
        "calibrate",
        evaluations,
        &args.output,
        "use a smaller --budget, or --no-profiles",
    ) {
        return code;
    }
    if !args.output.quiet {
        eprintln!(
            "calibrating {} value(s) on {} track(s): global search of {} evaluations, then a local fit{}",
            settings.parameters.len(),
            cases.len(),
            settings.global_evaluations,
            if settings.profiles { " and the profiles" } else { "" }
        );
    }
    let result = divertsim_api::threads::with_threads(args.output.threads.map(usize::from), || {
        calibrate(&cases, &settings)
    });
    let c = match result {
        Ok(c) => c,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let scenarios: Vec<(&str, &config::ScenarioFile)> = names
        .iter()
        .zip(&tracks)
        .map(|(n, t)| (n.as_str(), &t.loaded.file))
        .collect();
    let report =
        divertsim_api::output::describe_runs(report_json(&c, &names), "calibrate", &scenarios);
    if let Some(dir) = &args.output.out {
        let toml = match config::load_with(
            args.scenario.scenario.as_deref(),
            &args.scenario.sets,
            args.scenario.load_options(),
        )
        .map_err(|e| e.to_string())
        .and_then(|base| calibrated_toml(&base, &c).map_err(|e| e.to_string()))
        {
            Ok(t) => t,
            Err(e) => {
                eprintln!("error: cannot write calibrated.toml: {e}");
                return 1;
            }
        };
        let files = vec![
            ("calibration.json".to_string(), common::json_bytes(&report)),
            ("calibrated.toml".to_string(), toml.into_bytes()),
            (
                "profiles.csv".to_string(),
                calibration::profiles_csv(&c).unwrap_or_default(),
            ),
        ];
        let code = common::write_outputs(dir, files, |staging| {
            // Each track against the run at the fitted values.
            let mut fits = Vec::new();
            for ((fitted, r, cmp), n) in calibration::fitted_runs(&tracks, &c)
                .map_err(|e| e.to_string())?
                .into_iter()
                .zip(&names)
            {
                for ext in ["svg", "png"] {
                    draw_overlay(
                        &staging.join(format!("fit_{n}.{ext}")),
                        n,
                        &fitted,
                        &r,
                        &cmp,
                    )?;
                }
                let measured = measured_points(&fitted, &cmp);
                fits.push((n.clone(), fitted.loaded.scenario, r, measured));
            }
            let runs: Vec<crate::report::ReportRun<'_>> = fits
                .iter()
                .map(|(n, s, r, m)| crate::report::ReportRun {
                    label: n.clone(),
                    scenario: s,
                    result: r,
                    measured: m.clone(),
                })
                .collect();
            let page = crate::report::multi(
                "divertsim calibrate: the runs at the fitted values and the measured tracks (black dots)",
                &runs,
            );
            std::fs::write(staging.join("report.html"), page).map_err(|e| e.to_string())
        });
        if code != 0 {
            return code;
        }
    }
    if args.output.json {
        common::emit_json(&report);
    } else {
        let s = calibration::text(&c, &names);
        common::emit(&s);
    }
    0
}
