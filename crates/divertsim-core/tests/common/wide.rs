//! Wide random scenarios for whole-run audits: every drive kind (the crank-rocker, the three
//! cam laws and random spline tables with ramps as short as 5 ms), arm lengths 0.9–1.2 m,
//! parcels 0.15–0.7 × 0.08–0.4 m of 0.3–15 kg anywhere across the belt at ±45°, belt
//! speeds 0.3–2.5 m/s, R_s −0.3–1.0 m, t_c 0.8–1.6 s, μ_b 0.2–0.7, μ_a 0–0.6 (a third
//! frictionless), e* 0–0.8 with some at 0 and 1.
//!
//! Case i of seed s depends on (s, i) only: ChaCha8 seeded with s, stream i.

#![allow(dead_code)] // each test program uses part of it

use divertsim_core::model::belt_friction::FrictionCoefficient;
use divertsim_core::model::drive::{ArmDrive, DriveSpec, FourBar};
use divertsim_core::model::params::Scenario;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The random case `index` of `seed`.
pub fn scenario(seed: u64, index: u64) -> Scenario {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(index);
    let mut s = Scenario::paper_default();
    s.machine.arm_length = if rng.random_bool(0.5) {
        [1.0, 1.15][rng.random_range(0..2)]
    } else {
        rng.random_range(0.9..1.2)
    };
    s.machine.cycle_time = rng.random_range(0.8..1.6);
    s.machine.drive = drive(&mut rng, s.machine.cycle_time);
    s.parcel.length = rng.random_range(0.15..0.7);
    s.parcel.width = rng.random_range(0.08..0.4);
    s.parcel.mass = rng.random_range(0.3..15.0);
    s.parcel.angle = rng.random_range(-45.0f64..45.0).to_radians();
    let across = s.footprint().half_extents(s.parcel.angle).y * 2.0;
    s.parcel.offset = (s.machine.belt_width - across).max(0.0) * rng.random_range(0.0..1.0);
    s.machine.belt_speed = rng.random_range(0.3..2.5);
    s.machine.start_position = rng.random_range(-0.3..1.0);
    s.machine.light_barrier = s.machine.start_position.min(0.0);
    s.materials.belt_friction = FrictionCoefficient::Constant(rng.random_range(0.2..0.7));
    s.materials.arm_friction = if rng.random_range(0..3) == 0 {
        0.0
    } else {
        rng.random_range(0.0..0.6)
    };
    s.materials.restitution = match rng.random_range(0..6) {
        0 => 0.0,
        1 => 1.0,
        _ => rng.random_range(0.0..0.8),
    };
    s.run.duration = s.machine.cycle_time + 2.0;
    s
}

/// One of the five drive kinds: the paper's crank-rocker (2 in 6), each cam law (1 in 6
/// each; swing 35–50°) and random tables (1 in 6).
fn drive(rng: &mut ChaCha8Rng, cycle_time: f64) -> DriveSpec {
    let swing = rng.random_range(35.0f64..50.0).to_radians();
    match rng.random_range(0..6) {
        0 => DriveSpec::Harmonic { max_swing: swing },
        1 => DriveSpec::Cycloidal { max_swing: swing },
        2 => DriveSpec::Poly345 { max_swing: swing },
        3 => table(rng, cycle_time, swing),
        4 => DriveSpec::CrankRocker(FourBar::centred(swing, 0.3, 0.15)),
        _ => DriveSpec::CrankRocker(FourBar::paper_default()),
    }
}

/// A random table: a slow lead-in to a shoulder, a fast ramp (5–150 ms, sampled on a cosine
/// at 3–8 points) to the swing, a dwell, and the mirror of it back, scaled to t_c, with points
/// every 50 ms along the lead-in and the dwell (as a user would give a measured motion; a
/// clamped spline through a ramp followed by a long stretch without points bulges and is
/// refused). Tables whose spline still leaves [0, 90°] are drawn again.
fn table(rng: &mut ChaCha8Rng, cycle_time: f64, swing: f64) -> DriveSpec {
    // Points every ≤ 50 ms on a straight stretch from (t0, a0) to (t1, a1), t1 excluded.
    fn stretch(t: &mut Vec<f64>, a: &mut Vec<f64>, (t0, a0): (f64, f64), (t1, a1): (f64, f64)) {
        let n = ((t1 - t0) / 0.05).ceil().max(1.0) as usize;
        for k in 1..n {
            let f = k as f64 / n as f64;
            t.push(t0 + f * (t1 - t0));
            a.push(a0 + f * (a1 - a0));
        }
    }
    for _ in 0..64 {
        let half = 0.5 * cycle_time;
        let shoulder = rng.random_range(0.0..0.2) * swing;
        let lead = rng.random_range(0.02..0.4) * half;
        let ramp = rng.random_range(0.005f64..0.15).min(0.5 * half);
        let dwell = rng.random_range(0.0..0.3) * half;
        let points = rng.random_range(3..=8);
        let mut t = vec![0.0];
        let mut a = vec![0.0];
        let start = if shoulder > 0.0 {
            stretch(&mut t, &mut a, (0.0, 0.0), (lead, shoulder));
            t.push(lead);
            a.push(shoulder);
            lead
        } else {
            0.0
        };
        for k in 1..=points {
            let f = k as f64 / points as f64;
            t.push(start + ramp * f);
            a.push(shoulder + (swing - shoulder) * 0.5 * (1.0 - (std::f64::consts::PI * f).cos()));
        }
        let top = *t.last().unwrap();
        if top + dwell >= half {
            continue;
        }
        // The dwell runs to its mirror image: points along the whole top.
        stretch(&mut t, &mut a, (top, swing), (cycle_time - top, swing));
        // Mirror the rise about the half cycle.
        let rise = t.iter().position(|&x| x > top).unwrap_or(t.len());
        let mut tail: Vec<(f64, f64)> =
            (0..rise).rev().map(|k| (cycle_time - t[k], a[k])).collect();
        tail.retain(|&(x, _)| x > *t.last().unwrap());
        for (x, y) in tail {
            t.push(x);
            a.push(y);
        }
        let spec = DriveSpec::Table {
            times: t,
            angles: a,
        };
        if ArmDrive::new(&spec, cycle_time).is_ok() {
            return spec;
        }
    }
    DriveSpec::CrankRocker(FourBar::paper_default())
}

/// The scenario as `divertsim simulate` flags, to reproduce a case from the command line.
pub fn as_flags(s: &Scenario) -> String {
    let mut f = vec![
        format!("--set machine.belt_speed={}", s.machine.belt_speed),
        format!("--set machine.start_position={}", s.machine.start_position),
        format!("--set machine.light_barrier={}", s.machine.light_barrier),
        format!("--set machine.cycle_time={}", s.machine.cycle_time),
        format!("--set machine.arm_length={}", s.machine.arm_length),
        format!("--set parcel.length={}", s.parcel.length),
        format!("--set parcel.width={}", s.parcel.width),
        format!("--set parcel.mass={}", s.parcel.mass),
        format!("--set parcel.offset={}", s.parcel.offset),
        format!("--set parcel.angle_deg={}", s.parcel.angle.to_degrees()),
        format!("--set materials.arm_friction={}", s.materials.arm_friction),
        format!("--set materials.restitution={}", s.materials.restitution),
        format!(
            "--set materials.belt_friction={}",
            s.materials.belt_friction.max_value()
        ),
        format!("--set run.duration={}", s.run.duration),
    ];
    match &s.machine.drive {
        DriveSpec::CrankRocker(fb) => {
            f.push(format!(
                "--set machine.drive.max_swing_deg={}",
                fb.swing().unwrap_or(0.0).to_degrees()
            ));
        }
        DriveSpec::Harmonic { max_swing }
        | DriveSpec::Cycloidal { max_swing }
        | DriveSpec::Poly345 { max_swing } => {
            let kind = match s.machine.drive {
                DriveSpec::Harmonic { .. } => "harmonic",
                DriveSpec::Cycloidal { .. } => "cycloidal",
                _ => "poly345",
            };
            f.push(format!("--set 'machine.drive.kind=\"{kind}\"'"));
            f.push(format!(
                "--set machine.drive.max_swing_deg={}",
                max_swing.to_degrees()
            ));
        }
        DriveSpec::Table { times, angles } => {
            f.push("--set 'machine.drive.kind=\"table\"'".into());
            let pts: Vec<String> = times
                .iter()
                .zip(angles)
                .map(|(t, a)| format!("[{t}, {}]", a.to_degrees()))
                .collect();
            f.push(format!("--set 'machine.drive.points=[{}]'", pts.join(", ")));
        }
    }
    f.join(" ")
}
