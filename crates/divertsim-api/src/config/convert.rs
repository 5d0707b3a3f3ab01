//! Conversion of a validated scenario file into the core's SI scenario (the drive, the
//! materials, the near side), and the drive table file.

// The sibling files this one uses, named so that the import-cycle check sees them.
use super::problems::Problem;
use super::schema::{
    BeltFrictionConfig, DriveConfig, DriveKind, FrictionModelConfig, ImpactLawConfig,
    NearSideConfig, ScenarioFile, TippingConfig, DEFAULT_COUPLER, DEFAULT_ROCKER,
    DEFAULT_SWING_DEG,
};
#[allow(unused_imports)]
use super::*;
use divertsim_core::model::params::{run_length, TippingRule};
use divertsim_core::model::trigger::Trigger;

/// The rows of a drive table: \[t \[s], α \[deg]].
pub type AlphaRows = Vec<[f64; 2]>;

/// Build the core scenario, and the rows of a drive table file it read; drive problems (a
/// linkage that cannot reach its swing, a bad table) are reported against the drive keys.
pub(super) fn to_scenario(f: &ScenarioFile) -> Result<(Scenario, Option<AlphaRows>), Vec<Problem>> {
    let d = &f.machine.drive;
    let (drive, rows) = drive_spec(d)?;
    if let Err(e) = ArmDrive::new(&drive, f.machine.cycle_time) {
        let message = match (&d.table, d.kind) {
            (Some(path), DriveKind::Table) => format!("{path}: {e}"),
            _ => e.to_string(),
        };
        return Err(vec![Problem::new(drive_key(d), message)]);
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
            trigger: match m.trigger {
                TriggerConfig::Fixed => Trigger::Fixed,
                TriggerConfig::Adaptive => Trigger::Adaptive(m.adaptive.search()),
            },
            arm_face_bottom: m.arm_face_bottom,
            arm_face_top: m.arm_face_top.unwrap_or(f64::INFINITY),
            arm_inertia: m
                .arm_inertia
                .or(m
                    .arm_mass
                    .map(|mass| mass * m.arm_length * m.arm_length / 3.0))
                .unwrap_or(0.0),
        },
        parcel: Parcel::riding(
            p.length,
            p.width,
            p.height,
            p.mass,
            p.offset,
            p.angle_deg.to_radians(),
        )
        .moving(p.velocity.map(|[x, y]| DVec2::new(x, y)), p.spin)
        .with_com_height(p.com_height),
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
                .unwrap_or_else(|| run_length(&f.run.cycle_starts, m.cycle_time)),
            tolerance: f.run.tolerance,
            arm: f.run.arm,
            cycle_starts: f.run.cycle_starts.clone(),
        },
        limits: Limits {
            drop_height: f.limits.drop_height,
            tipping: match f.limits.tipping {
                TippingConfig::Verdict => TippingRule::Verdict,
                TippingConfig::Flag => TippingRule::Flag,
            },
        },
    };
    Ok((scenario, rows))
}

pub(super) fn drive_key(d: &DriveConfig) -> &'static str {
    match d.kind {
        DriveKind::Table if d.table.is_none() => "machine.drive.points",
        DriveKind::Table => "machine.drive.table",
        DriveKind::CrankRocker if d.crank.is_some() => "machine.drive",
        _ => "machine.drive.max_swing_deg",
    }
}

/// The core's drive, and the rows of a drive table file it read.
pub(super) fn drive_spec(d: &DriveConfig) -> Result<(DriveSpec, Option<AlphaRows>), Vec<Problem>> {
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
                                return Err(vec![Problem::new(
                                    "machine.drive.max_swing_deg",
                                    format!(
                                        "the links give a swing of {:.6}°, not the {want}° asked; leave max_swing_deg out or adjust the links",
                                        got.to_degrees()
                                    ),
                                )])
                            }
                            Err(e) => return Err(vec![Problem::new("machine.drive", e.to_string())]),
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
                        vec![Problem::new("machine.drive.table", format!("{path}: {m}"))]
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
pub(crate) fn read_alpha_table(path: &Path) -> Result<AlphaRows, String> {
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
