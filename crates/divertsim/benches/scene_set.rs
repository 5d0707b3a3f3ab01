//! The benchmark scenes (issue 16): five single runs that stand for the kinds of work, and a
//! fixed mix of 1,000 random scenarios.
//!
//! - `free_slide`: the default parcel sliding freely (1 m/s faster than the belt, spin
//!   3 rad/s), no arm: the belt-friction law alone.
//! - `default`: the built-in default scenario (strike, repeated strikes, F4, exit).
//! - `fig06`, `fig08`: the paper preset's figures 6 and 8 (the slender parcel at the
//!   pivot-side edge; F5/F6 contact work).
//! - `fig06` is the slender parcel lying on the retracted arm (F5 from the start); `fig08` the
//!   same parcel at R_s = 0, squeezed between the arm and the guide from the arm's start (F6).
//! - `flush_slender`: the paper's slender parcel (0.7 × 0.1 m, 1.5 kg) flush with the
//!   pivot-side guide (ΔP = 0) on the built-in default machine and setting: touching the arm
//!   and the guide as the arm starts from rest (F6), then struck, turned and pushed off. The
//!   start is stiff: the parcel's slip on the belt grows from zero.
//! - the mix: 1,000 scenarios on the built-in default machine drawn with a fixed seed from
//!   the ranges of the whole-run property test (`tests/scraping.rs`), by a SplitMix64
//!   generator written out here, so that the mix does not change with a crate's version.

#![allow(dead_code)] // each bench binary uses part of it

use divertsim_core::model::belt_friction::FrictionCoefficient;
use divertsim_core::model::params::Scenario;
use glam::DVec2;
use std::path::PathBuf;

/// The seed of the fixed mix.
pub const MIX_SEED: u64 = 16;
/// Scenarios in the fixed mix.
pub const MIX_SIZE: usize = 1000;

fn preset(file: &str, sets: &[&str]) -> Scenario {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../configs/paper")
        .join(file);
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    match divertsim_api::config::load(Some(&path), &sets) {
        Ok(l) => l.scenario,
        Err(e) => panic!("{}: {e}", path.display()),
    }
}

/// The named single-run scenes, in report order.
pub fn scenes() -> Vec<(&'static str, Scenario)> {
    let mut slide = Scenario::paper_default();
    slide.run.arm = false;
    slide.parcel.velocity = Some(DVec2::new(slide.machine.belt_speed + 1.0, 0.0));
    slide.parcel.spin = 3.0;
    vec![
        ("free_slide", slide),
        ("default", Scenario::paper_default()),
        ("fig06", preset("fig06.toml", &[])),
        ("fig08", preset("fig08.toml", &[])),
        ("flush_slender", {
            let mut s = Scenario::paper_default();
            s.parcel.length = 0.7;
            s.parcel.width = 0.1;
            s.parcel.height = 0.1;
            s.parcel.mass = 1.5;
            s.parcel.offset = 0.0;
            s
        }),
    ]
}

use divertsim_core::stats::splitmix::SplitMix64;

/// The fixed mix: parcel 0.15–0.7 × 0.08–0.4 m (length ≥ width), 0.3–15 kg, anywhere
/// across the belt, ±30°; v 0.3–2.5 m/s, R_s −0.3–0.9 m, t_c 0.8–1.6 s; μ_b 0.2–0.7,
/// μ_a 0–0.6, e* 0–0.8.
pub fn mix() -> Vec<Scenario> {
    let mut rng = SplitMix64(MIX_SEED);
    (0..MIX_SIZE)
        .map(|_| {
            let mut s = Scenario::paper_default();
            let (a, b) = (rng.uniform(0.15, 0.7), rng.uniform(0.08, 0.4));
            s.parcel.length = a.max(b);
            s.parcel.width = a.min(b);
            s.parcel.mass = rng.uniform(0.3, 15.0);
            s.parcel.angle = rng.uniform(-30.0, 30.0).to_radians();
            let across = s.footprint().half_extents(s.parcel.angle).y * 2.0;
            s.parcel.offset = (s.machine.belt_width - across).max(0.0) * rng.uniform(0.0, 1.0);
            s.machine.belt_speed = rng.uniform(0.3, 2.5);
            let rs = rng.uniform(-0.3, 0.9);
            s.machine.start_position = rs;
            s.machine.light_barrier = rs.min(0.0);
            s.machine.cycle_time = rng.uniform(0.8, 1.6);
            s.run.duration = s.machine.cycle_time + 2.0;
            s.materials.belt_friction = FrictionCoefficient::Constant(rng.uniform(0.2, 0.7));
            s.materials.arm_friction = rng.uniform(0.0, 0.6);
            s.materials.restitution = rng.uniform(0.0, 0.8);
            s
        })
        .collect()
}
