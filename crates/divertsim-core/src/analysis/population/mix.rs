//! A parcel mix: the distributions a population of parcels, their poses, arrivals and
//! materials is drawn from, and the draw of sample i of a seeded run.
//!
//! **Streams.** Sample i's random numbers come from ChaCha8 seeded with the run's seed, on
//! stream i: a sample depends on (seed, i) alone, never on which thread draws it or on what
//! was drawn before, so a run is the same for any thread count and can resume at any sample.
//! Each attempt takes [`DRAWS_PER_ATTEMPT`] numbers in a fixed order, one per quantity
//! (inversion sampling), so a change to one quantity's distribution leaves the others'
//! draws unchanged: the points of a sweep and the two trigger modes see the same parcels.
//!
//! **Construction.**
//! - length ≥ width: the two drawn sides are sorted (the length distribution is then that
//!   of the larger side);
//! - mass: drawn, or density × length × width × height, or the record's;
//! - the pose fits on the belt: with `RoomFraction`, ΔP = f·(P_max − extent across), valid
//!   whenever the parcel fits at all; with `Offset`, a ΔP that puts the parcel over an edge
//!   is rejected;
//! - values outside the model's ranges (sides 1 mm–5 m, mass 1 g–1000 kg, μ_b 0–2,
//!   μ_a 0–1.3, e* 0–1, |spin| ≤ 100 rad/s, |arrival speed| ≤ 20 m/s) are rejected.
//!
//! A rejected attempt is redrawn (from the same stream) and counted by reason; a sample that
//! needs more than [`MAX_ATTEMPTS`] attempts makes the draw an error (the mix puts almost no
//! parcel on this belt).
//!
//! **The run of a sample** ([`Draw::scenario`]): the setting with this parcel, pose and
//! materials; R_s from the trigger (fixed: the setting's; adaptive: the parcel's own, see
//! [`crate::analysis::population::adaptive_trigger`]) plus v·δt for the trigger phase error δt; the parcel arrives
//! with velocity (v + Δv, 0) and spin ω (riding with the belt when both are 0).

use crate::analysis::design::worst_case::extent_across;
use crate::model::params::{default_duration, Parcel, ParcelRun, Scenario};
use crate::stats::distribution::{open_unit, Distribution};
use glam::DVec2;
use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// One parcel of a dimensioner log: sides \[m] and, if logged, mass \[kg].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParcelRecord {
    pub length: f64,
    pub width: f64,
    pub height: f64,
    pub mass: Option<f64>,
}

/// Where the parcel sizes come from.
#[derive(Debug, Clone, PartialEq)]
pub enum Sizes {
    /// Each side drawn from its distribution \[m].
    Drawn {
        length: Distribution,
        width: Distribution,
        height: Distribution,
    },
    /// A record drawn uniformly from a list (an empirical distribution); shared, so that the
    /// points of a sweep hold one copy of a large log.
    Records(std::sync::Arc<[ParcelRecord]>),
}

/// Where the mass comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum MassLaw {
    /// m drawn \[kg].
    Mass(Distribution),
    /// ρ drawn [kg/m³]; m = ρ·a·b·h.
    Density(Distribution),
    /// The record's mass (every record has one).
    Recorded,
}

/// Where across the belt the parcel lies.
#[derive(Debug, Clone, PartialEq)]
pub enum Placement {
    /// ΔP drawn \[m]; a pose over an edge is rejected.
    Offset(Distribution),
    /// f drawn in [0, 1]; ΔP = f·(P_max − extent across).
    RoomFraction(Distribution),
}

/// A parcel mix (SI, angles in radians).
#[derive(Debug, Clone, PartialEq)]
pub struct ParcelMix {
    pub sizes: Sizes,
    pub mass: MassLaw,
    pub placement: Placement,
    /// φ \[rad]
    pub angle: Distribution,
    /// Δv: arrival speed relative to the belt, along the belt [m/s]
    pub speed: Distribution,
    /// ω: arrival spin [rad/s]
    pub spin: Distribution,
    /// δt: trigger phase error \[s]; R_s moves by v·δt
    pub phase: Distribution,
    /// μ_b per parcel (replaces the scenario's law by a constant); `None`: the scenario's.
    pub belt_friction: Option<Distribution>,
    /// μ_a per parcel; `None`: the scenario's.
    pub arm_friction: Option<Distribution>,
    /// e* per parcel; `None`: the scenario's.
    pub restitution: Option<Distribution>,
}

/// Random numbers one attempt takes, whatever the distributions.
pub const DRAWS_PER_ATTEMPT: usize = 12;
/// Attempts before a sample is given up.
pub const MAX_ATTEMPTS: u32 = 10_000;

/// Why an attempt was rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Rejection {
    /// Wider than the belt at its angle, or placed over an edge.
    OffBelt,
    /// A side outside 1 mm–5 m.
    Size,
    /// A mass outside 1 g–1000 kg.
    Mass,
    /// μ_b, μ_a or e* outside its range.
    Material,
    /// Arrival speed or spin outside its range.
    Arrival,
}

impl Rejection {
    /// Every reason, in report order.
    pub const ALL: [Rejection; 5] = [
        Rejection::OffBelt,
        Rejection::Size,
        Rejection::Mass,
        Rejection::Material,
        Rejection::Arrival,
    ];

    pub fn label(self) -> &'static str {
        match self {
            Rejection::OffBelt => "off_belt",
            Rejection::Size => "size",
            Rejection::Mass => "mass",
            Rejection::Material => "material",
            Rejection::Arrival => "arrival",
        }
    }
}

/// The mix gives almost no valid parcel.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "sample {index}: {attempts} draws in a row were rejected (last reason: {}); \
     the mix puts almost no parcel on this belt",
    last.label()
)]
pub struct MixError {
    pub index: u64,
    pub attempts: u32,
    pub last: Rejection,
}

/// One drawn sample: the parcel, its pose, arrival and materials.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Draw {
    /// i: the sample's index in the run
    pub index: u64,
    /// a ≥ b \[m]
    pub length: f64,
    /// b \[m]
    pub width: f64,
    /// h \[m]
    pub height: f64,
    /// m \[kg]
    pub mass: f64,
    /// ΔP \[m]
    pub offset: f64,
    /// φ \[rad]
    pub angle: f64,
    /// Δv [m/s]
    pub speed: f64,
    /// ω [rad/s]
    pub spin: f64,
    /// δt \[s]
    pub phase: f64,
    /// μ_b, if the mix scatters it
    pub belt_friction: Option<f64>,
    /// μ_a [-]
    pub arm_friction: f64,
    /// e* [-]
    pub restitution: f64,
    /// Attempts rejected before this one, per reason (in [`Rejection::ALL`] order).
    pub rejected: [u32; 5],
}

/// Two uniform numbers in (0, 1) from ChaCha8 seeded with `seed`, stream `index`: the
/// per-sample stream of a study's own quantities beside the mix's (e.g. a line's gap and
/// destination, with a salted seed).
pub fn open_unit_pair(seed: u64, index: u64) -> (f64, f64) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(index);
    (open_unit(rng.next_u64()), open_unit(rng.next_u64()))
}

impl ParcelMix {
    /// The heights the mix draws \[m]: its records' smallest and largest, or the support of
    /// its height law within the model's 1 mm–5 m (draws outside are redrawn), an unbounded
    /// tail cut at its 10⁻⁴ quantile. The class a worst-case search explores for this mix
    /// (issue 47: the height decides whether a parcel tips over).
    pub fn height_range(&self) -> (f64, f64) {
        const TAIL: f64 = 1e-4;
        match &self.sizes {
            Sizes::Records(r) => r
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), r| {
                    (lo.min(r.height), hi.max(r.height))
                }),
            Sizes::Drawn { height, .. } => {
                let (lo, hi) = height.support();
                let lo = if lo.is_finite() && lo > 0.0 {
                    lo
                } else {
                    height.quantile(TAIL)
                };
                let hi = if hi.is_finite() {
                    hi
                } else {
                    height.quantile(1.0 - TAIL)
                };
                (lo.max(1e-3), hi.min(5.0))
            }
        }
    }

    /// Sample `index` of the run with `seed` on a belt of width P_max, with the scenario's
    /// μ_a and e* where the mix does not scatter them.
    pub fn draw(&self, setting: &Scenario, seed: u64, index: u64) -> Result<Draw, MixError> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(index);
        let mut rejected = [0u32; 5];
        let mut last = Rejection::OffBelt;
        for _ in 0..MAX_ATTEMPTS {
            let mut u = [0.0; DRAWS_PER_ATTEMPT];
            for x in &mut u {
                *x = open_unit(rng.next_u64());
            }
            match self.attempt(setting, &u) {
                Ok(mut d) => {
                    d.index = index;
                    d.rejected = rejected;
                    return Ok(d);
                }
                Err(r) => {
                    rejected[r as usize] += 1;
                    last = r;
                }
            }
        }
        Err(MixError {
            index,
            attempts: MAX_ATTEMPTS,
            last,
        })
    }

    /// One attempt from its uniforms.
    fn attempt(&self, setting: &Scenario, u: &[f64; DRAWS_PER_ATTEMPT]) -> Result<Draw, Rejection> {
        let (a, b, height, recorded_mass) = match &self.sizes {
            Sizes::Drawn {
                length,
                width,
                height,
            } => (
                length.quantile(u[0]),
                width.quantile(u[1]),
                height.quantile(u[2]),
                None,
            ),
            Sizes::Records(r) => {
                let i = ((u[0] * r.len() as f64) as usize).min(r.len().saturating_sub(1));
                let rec = r.get(i).ok_or(Rejection::Size)?;
                (rec.length, rec.width, rec.height, rec.mass)
            }
        };
        let (length, width) = if b > a { (b, a) } else { (a, b) };
        let side_ok = |s: f64| (1e-3..=5.0).contains(&s);
        if !(side_ok(length) && side_ok(width) && side_ok(height)) {
            return Err(Rejection::Size);
        }
        let mass = match &self.mass {
            MassLaw::Mass(d) => d.quantile(u[3]),
            MassLaw::Density(d) => d.quantile(u[3]) * length * width * height,
            MassLaw::Recorded => recorded_mass.unwrap_or(f64::NAN),
        };
        if !(1e-3..=1000.0).contains(&mass) {
            return Err(Rejection::Mass);
        }
        let angle = self.angle.quantile(u[5]);
        let belt_width = setting.machine.belt_width;
        let across = extent_across(length, width, angle);
        if across.is_nan() || across > belt_width {
            return Err(Rejection::OffBelt);
        }
        let room = belt_width - across;
        let offset = match &self.placement {
            Placement::Offset(d) => d.quantile(u[4]),
            Placement::RoomFraction(d) => {
                let f = d.quantile(u[4]);
                if !(0.0..=1.0).contains(&f) {
                    return Err(Rejection::OffBelt);
                }
                f * room
            }
        };
        if !(0.0..=room).contains(&offset) {
            return Err(Rejection::OffBelt);
        }
        let speed = self.speed.quantile(u[6]);
        let spin = self.spin.quantile(u[7]);
        let v = setting.machine.belt_speed;
        if !((-20.0..=20.0).contains(&(v + speed)) && (-100.0..=100.0).contains(&spin)) {
            return Err(Rejection::Arrival);
        }
        let phase = self.phase.quantile(u[8]);
        if !phase.is_finite() {
            return Err(Rejection::Arrival);
        }
        let belt_friction = self.belt_friction.as_ref().map(|d| d.quantile(u[9]));
        let arm_friction = self
            .arm_friction
            .as_ref()
            .map_or(setting.materials.arm_friction, |d| d.quantile(u[10]));
        let restitution = self
            .restitution
            .as_ref()
            .map_or(setting.materials.restitution, |d| d.quantile(u[11]));
        if !(belt_friction.is_none_or(|m| (0.0..=2.0).contains(&m))
            && (0.0..=1.3).contains(&arm_friction)
            && (0.0..=1.0).contains(&restitution))
        {
            return Err(Rejection::Material);
        }
        Ok(Draw {
            index: 0,
            length,
            width,
            height,
            mass,
            offset,
            angle,
            speed,
            spin,
            phase,
            belt_friction,
            arm_friction,
            restitution,
            rejected: [0; 5],
        })
    }
}

impl Draw {
    /// The parcel as the core sees it (riding with the belt when Δv = ω = 0).
    pub fn parcel(&self, belt_speed: f64) -> Parcel {
        let moving = self.speed != 0.0 || self.spin != 0.0;
        Parcel::riding(
            self.length,
            self.width,
            self.height,
            self.mass,
            self.offset,
            self.angle,
        )
        .moving(
            moving.then(|| DVec2::new(belt_speed + self.speed, 0.0)),
            self.spin,
        )
    }

    /// The run of this sample at `setting` with the arm triggered for R_s = `start` (before
    /// the phase error): R_s ← start + v·δt, S_d ← min(S_d, R_s) (S_d does not change a run),
    /// the parcel and the scattered materials replaced, the run at least t_c + 2 s long.
    pub fn scenario(&self, setting: &Scenario, start: f64) -> Scenario {
        self.run_at(setting, start).scenario(setting)
    }

    /// The run of this sample at `setting` ([`Draw::scenario`]) as its record.
    pub fn run_at(&self, setting: &Scenario, start: f64) -> ParcelRun {
        let v = setting.machine.belt_speed;
        ParcelRun {
            parcel: self.parcel(v),
            belt_friction: self.belt_friction,
            arm_friction: self.arm_friction,
            restitution: self.restitution,
            // The trigger has chosen `start` (fixed, or from the adaptive table).
            start_position: start + v * self.phase,
            cycle_starts: None,
            duration: setting
                .run
                .duration
                .max(default_duration(setting.machine.cycle_time)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(crate) fn hub_mix() -> ParcelMix {
        ParcelMix {
            sizes: Sizes::Drawn {
                length: Distribution::LogNormal {
                    median: 0.35,
                    sigma: 0.35,
                },
                width: Distribution::LogNormal {
                    median: 0.22,
                    sigma: 0.35,
                },
                height: Distribution::Uniform {
                    min: 0.05,
                    max: 0.4,
                },
            },
            mass: MassLaw::Density(Distribution::LogNormal {
                median: 150.0,
                sigma: 0.5,
            }),
            placement: Placement::RoomFraction(Distribution::Uniform { min: 0.0, max: 1.0 }),
            angle: Distribution::Normal {
                mean: 0.0,
                sd: 10f64.to_radians(),
            },
            speed: Distribution::Fixed(0.0),
            spin: Distribution::Fixed(0.0),
            phase: Distribution::Normal {
                mean: 0.0,
                sd: 0.005,
            },
            belt_friction: None,
            arm_friction: Some(Distribution::Uniform {
                min: 0.25,
                max: 0.35,
            }),
            restitution: None,
        }
    }

    /// The height range a search takes from a mix: a bounded law's support, an unbounded
    /// tail's 10⁻⁴ quantile within the model's sides, the records' extremes; every draw of
    /// a bounded law falls inside.
    #[test]
    fn height_range_covers_the_mix_heights() {
        let s = Scenario::paper_default();
        let hub = hub_mix();
        assert_eq!(hub.height_range(), (0.05, 0.4));
        for i in 0..500 {
            let h = hub.draw(&s, 3, i).unwrap().height;
            assert!((0.05..=0.4).contains(&h), "{h}");
        }
        let log = ParcelMix {
            sizes: Sizes::Drawn {
                length: Distribution::Fixed(0.4),
                width: Distribution::Fixed(0.2),
                height: Distribution::LogNormal {
                    median: 0.2,
                    sigma: 0.3,
                },
            },
            ..hub.clone()
        };
        let (lo, hi) = log.height_range();
        // ln(h/0.2) = ±3.719 σ at the 10⁻⁴ tails.
        assert!((lo - 0.2 * (-3.719016 * 0.3f64).exp()).abs() < 1e-5, "{lo}");
        assert!((hi - 0.2 * (3.719016 * 0.3f64).exp()).abs() < 1e-5, "{hi}");
        let normal = ParcelMix {
            sizes: Sizes::Drawn {
                length: Distribution::Fixed(0.4),
                width: Distribution::Fixed(0.2),
                height: Distribution::Normal {
                    mean: 0.01,
                    sd: 0.5,
                },
            },
            ..hub.clone()
        };
        assert_eq!(normal.height_range().0, 1e-3);
        let records = ParcelMix {
            sizes: Sizes::Records(
                [0.12, 0.31, 0.2]
                    .iter()
                    .map(|&height| ParcelRecord {
                        length: 0.4,
                        width: 0.2,
                        height,
                        mass: None,
                    })
                    .collect(),
            ),
            ..hub
        };
        assert_eq!(records.height_range(), (0.12, 0.31));
    }

    #[test]
    fn draws_are_valid_by_construction_and_depend_only_on_seed_and_index() {
        let s = Scenario::paper_default();
        let mix = hub_mix();
        let mut rejected = 0;
        for i in 0..2000 {
            let d = mix.draw(&s, 7, i).unwrap();
            assert!(d.length >= d.width, "{d:?}");
            let across = extent_across(d.length, d.width, d.angle);
            assert!(d.offset >= 0.0 && d.offset + across <= s.machine.belt_width + 1e-12);
            let rho = d.mass / (d.length * d.width * d.height);
            assert!(rho > 0.0 && rho.is_finite());
            assert!((0.25..=0.35).contains(&d.arm_friction));
            assert_eq!(d.restitution, s.materials.restitution);
            rejected += d.rejected.iter().sum::<u32>();
            // Same (seed, index) → same draw, whatever was drawn before.
            assert_eq!(mix.draw(&s, 7, i).unwrap(), d);
        }
        // Wide parcels at an angle do not fit a 0.7 m belt: some are rejected.
        assert!(rejected > 0);
        assert_ne!(mix.draw(&s, 8, 0).unwrap(), mix.draw(&s, 7, 0).unwrap());
    }

    #[test]
    fn one_quantity_changed_leaves_the_others_drawn_alike() {
        let s = Scenario::paper_default();
        let a = hub_mix();
        let mut b = hub_mix();
        b.phase = Distribution::Fixed(0.0);
        for i in 0..200 {
            let (x, y) = (a.draw(&s, 1, i).unwrap(), b.draw(&s, 1, i).unwrap());
            assert_eq!(
                (x.length, x.width, x.angle, x.offset),
                (y.length, y.width, y.angle, y.offset)
            );
            assert_eq!(y.phase, 0.0);
        }
    }

    /// Regression (review of issue 11): μ_a = 1.3, allowed by the scenario, was rejected at
    /// every draw.
    #[test]
    fn arm_friction_at_its_upper_limit_is_drawn() {
        let mut s = Scenario::paper_default();
        s.materials.arm_friction = 1.3;
        let mut mix = hub_mix();
        mix.arm_friction = None;
        let d = mix.draw(&s, 1, 0).unwrap();
        assert_eq!(d.arm_friction, 1.3);
        assert_eq!(d.rejected[Rejection::Material as usize], 0);
    }

    #[test]
    fn hopeless_mix_is_an_error_not_a_hang() {
        let s = Scenario::paper_default();
        let mut mix = hub_mix();
        mix.sizes = Sizes::Drawn {
            length: Distribution::Fixed(2.0),
            width: Distribution::Fixed(1.0),
            height: Distribution::Fixed(0.1),
        };
        let e = mix.draw(&s, 1, 3).unwrap_err();
        assert_eq!((e.index, e.last), (3, Rejection::OffBelt));
    }

    #[test]
    fn scenario_applies_trigger_phase_and_arrival() {
        let s = Scenario::paper_default();
        let mut d = hub_mix().draw(&s, 2, 5).unwrap();
        d.phase = 0.01;
        d.speed = -0.5;
        let run = d.scenario(&s, 0.3);
        assert!((run.machine.start_position - (0.3 + 2.0 * 0.01)).abs() < 1e-15);
        assert!(run.machine.light_barrier <= run.machine.start_position);
        assert_eq!(run.parcel.velocity, Some(DVec2::new(1.5, 0.0)));
        d.speed = 0.0;
        assert_eq!(d.scenario(&s, 0.3).parcel.velocity, None);
    }
}
