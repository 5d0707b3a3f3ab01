//! The scenario: machine, parcel, materials, run settings and limits, in SI units and radians.
//!
//! These mirror the sections of the scenario file (the app crate converts degrees and checks
//! ranges, naming the keys); the core assumes a validated scenario and reports numerical
//! trouble as an outcome rather than panicking.

use super::belt_friction::{FrictionCoefficient, FrictionModel};
use super::drive::{DriveSpec, FourBar};
use super::impact::ImpactLaw;
use super::trigger::Trigger;
use crate::geometry::Rect;
use glam::DVec2;
use serde::{Deserialize, Serialize};

/// The diverter and its belt.
#[derive(Debug, Clone, PartialEq)]
pub struct Machine {
    /// P_max: belt width \[m]; the belt occupies 0 ≤ y ≤ P_max.
    pub belt_width: f64,
    /// v: belt speed [m/s], along +x.
    pub belt_speed: f64,
    /// R_z: arm length \[m], from the pivot O.
    pub arm_length: f64,
    /// t_c: arm working cycle (out and back) \[s].
    pub cycle_time: f64,
    /// R_s: x of the parcel's most downstream point when the arm starts (t = 0) \[m].
    pub start_position: f64,
    /// S_d: x of the light barrier \[m]; S_d ≤ R_s.
    pub light_barrier: f64,
    /// The arm's motion law.
    pub drive: DriveSpec,
    /// What bounds the pivot-side belt edge downstream of the pivot.
    pub near_side: NearSide,
    /// When the arm starts: at R_s for every parcel, or at each parcel's own best R_s.
    pub trigger: Trigger,
    /// The lowest height of the arm's face above the belt \[m]: a parcel no taller passes
    /// under the arm.
    pub arm_face_bottom: f64,
    /// The highest height of the arm's face above the belt \[m] (infinite: above every
    /// parcel). The arm's force acts in the middle of the parcel's side within the band.
    pub arm_face_top: f64,
    /// I_arm: the arm's moment of inertia about the pivot \[kg·m²] (0: massless), for the
    /// drive torque of a stroke ([`crate::sim::arm_loads`]).
    pub arm_inertia: f64,
}

/// The pivot-side belt edge (y = 0) downstream of the pivot. Upstream (x ≤ 0) it always
/// has the side guide (docs/model.md §1); downstream the retracted arm lies along it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NearSide {
    /// No guide downstream of the pivot (docs/model.md §1): a parcel whose centre crosses the
    /// edge there falls off the belt and the run ends (`off_near_side`).
    #[default]
    Open,
    /// The side guide continues along the whole pivot-side edge, modelled like the upstream
    /// guide (a fixed line y = 0 with the arm's friction μ_a).
    Guide,
}

/// The parcel: a homogeneous box, its initial pose and velocity.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Parcel {
    /// a: side along the parcel's own x' axis \[m]
    pub length: f64,
    /// b: side along the parcel's own y' axis \[m]
    pub width: f64,
    /// h: height \[m] (the tipping check and the drop reference use it).
    pub height: f64,
    /// h_c: height of the centre of mass above the belt \[m]; `None`: h/2.
    pub com_height: Option<f64>,
    /// m: mass \[kg]
    pub mass: f64,
    /// ΔP: smallest y of the corners at t = 0, the gap to the pivot-side belt edge \[m].
    pub offset: f64,
    /// φ: orientation at t = 0, counter-clockwise from x to x' \[rad].
    pub angle: f64,
    /// Initial centre velocity in the machine frame [m/s]; `None`: riding with the belt.
    pub velocity: Option<DVec2>,
    /// ω: initial spin [rad/s].
    pub spin: f64,
}

impl Parcel {
    /// h_c: the centre of mass's height above the belt \[m] (h/2 unless given).
    pub fn com_height(&self) -> f64 {
        self.com_height.unwrap_or(0.5 * self.height)
    }

    /// A box of sides a = `length`, b = `width` and `height` \[m] and mass `mass` \[kg],
    /// ΔP = `offset` \[m] from the pivot-side edge at φ = `angle` \[rad], riding with the
    /// belt.
    pub fn riding(
        length: f64,
        width: f64,
        height: f64,
        mass: f64,
        offset: f64,
        angle: f64,
    ) -> Parcel {
        Parcel {
            length,
            width,
            height,
            com_height: None,
            mass,
            offset,
            angle,
            velocity: None,
            spin: 0.0,
        }
    }

    /// This parcel with an initial centre velocity (`None`: riding with the belt) \[m/s] and
    /// spin ω \[rad/s].
    pub fn moving(self, velocity: Option<DVec2>, spin: f64) -> Parcel {
        Parcel {
            velocity,
            spin,
            ..self
        }
    }

    /// This parcel with its centre of mass at `com_height` above the belt \[m] (`None`:
    /// mid-height).
    pub fn with_com_height(self, com_height: Option<f64>) -> Parcel {
        Parcel { com_height, ..self }
    }
}

/// Friction and restitution.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Materials {
    /// μ_b (μ_1(v_o) in the paper): parcel–belt friction.
    pub belt_friction: FrictionCoefficient,
    /// μ_a (μ_2 in the paper): parcel–arm friction, also used for the side guide.
    pub arm_friction: f64,
    /// e*: Stronge's energetic coefficient of restitution (the paper's k).
    pub restitution: f64,
    /// Footprint friction law.
    pub friction_model: FrictionModel,
    /// Restitution law at impacts.
    pub impact_law: ImpactLaw,
}

impl Materials {
    /// A parcel's own values: μ_b as a constant when it has one (else the law stays), μ_a and
    /// e*.
    pub fn set_parcel_values(
        &mut self,
        belt_friction: Option<f64>,
        arm_friction: f64,
        restitution: f64,
    ) {
        if let Some(mu) = belt_friction {
            self.belt_friction = FrictionCoefficient::Constant(mu);
        }
        self.arm_friction = arm_friction;
        self.restitution = restitution;
    }
}

/// One parcel's run at a machine setting: the parcel, the material values a mix scatters,
/// where the arm is triggered, and the run's cycles and length. What every study that runs
/// parcels keeps of a run (a mix's sample, a line's passage), and the one way such a run
/// becomes a scenario ([`ParcelRun::scenario`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParcelRun {
    /// The parcel (sides, mass, pose ΔP and φ at t = 0, velocity, spin).
    pub parcel: Parcel,
    /// μ_b, when the parcel has its own (else the setting's law).
    pub belt_friction: Option<f64>,
    /// μ_a [-]
    pub arm_friction: f64,
    /// e* [-]
    pub restitution: f64,
    /// R_s: the parcel front's x at t = 0 in the diverter's frame \[m] (the arm triggered
    /// for it: the trigger becomes fixed).
    pub start_position: f64,
    /// The arm's cycles from t = 0 \[s]; `None`: the setting's.
    pub cycle_starts: Option<Vec<f64>>,
    /// The run's length \[s].
    pub duration: f64,
}

impl ParcelRun {
    /// The run as a scenario of `setting`: R_s set (S_d moved with it where it would lie
    /// downstream: S_d does not change a run), the parcel and its material values put in,
    /// the cycles and the length.
    pub fn scenario(&self, setting: &Scenario) -> Scenario {
        let mut s = setting.clone();
        s.machine.start_at(self.start_position);
        s.machine.light_barrier = s.machine.light_barrier.min(self.start_position);
        s.parcel = self.parcel.clone();
        s.materials
            .set_parcel_values(self.belt_friction, self.arm_friction, self.restitution);
        if let Some(c) = &self.cycle_starts {
            s.run.cycle_starts = c.clone();
        }
        s.run.duration = self.duration;
        s
    }
}

/// How long and how precisely to run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSettings {
    /// Largest simulated time \[s].
    pub duration: f64,
    /// Relative tolerance of the integrator.
    pub tolerance: f64,
    /// Whether the arm moves; `false` for free-motion studies.
    pub arm: bool,
    /// When the arm starts each working cycle \[s], from t = 0 (the parcel's front at R_s):
    /// increasing, each cycle ending before the next starts. The paper's one cycle is `[0]`;
    /// a parcel on a line meets every cycle started near it, some before t = 0 (a negative
    /// time: a cycle under way when the run begins).
    pub cycle_starts: Vec<f64>,
}

/// Allowable loads.
#[derive(Debug, Clone, PartialEq)]
pub struct Limits {
    /// H₀: reference free-fall height \[m] (docs/model.md §5).
    pub drop_height: f64,
    /// What a tip-over does ([`crate::model::tilt`]).
    pub tipping: TippingRule,
}

/// What a tip-over (the tilt reaching the angle that puts the centre of mass over an edge)
/// does to a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TippingRule {
    /// The run ends there: not diverted, reason `tipped`.
    #[default]
    Verdict,
    /// The run goes on as in the plane model; the tip-over is only reported (a guard
    /// catches tipped parcels).
    Flag,
}

/// One complete simulation input.
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    pub machine: Machine,
    pub parcel: Parcel,
    pub materials: Materials,
    pub run: RunSettings,
    pub limits: Limits,
}

impl Machine {
    /// Start the arm when the parcel's front is at `start` (R_s) \[m], whatever the parcel:
    /// the trigger becomes fixed there. Every analysis that chooses R_s itself sets it so,
    /// so that no run of an adaptive scenario is left unresolved.
    pub fn start_at(&mut self, start: f64) {
        self.start_position = start;
        self.trigger = Trigger::Fixed;
    }

    /// The paper's optimised machine (v = 2 m/s, t_c = 1.36 s, R_s = 0, S_d = 0) with the
    /// defaults of docs/model.md §1 (P_max 0.7 m, R_z 1 m, 45° crank-rocker).
    pub fn paper_default() -> Machine {
        Machine {
            belt_width: 0.7,
            belt_speed: 2.0,
            arm_length: 1.0,
            cycle_time: 1.36,
            start_position: 0.0,
            light_barrier: 0.0,
            drive: DriveSpec::CrankRocker(FourBar::paper_default()),
            near_side: NearSide::Open,
            trigger: Trigger::Fixed,
            arm_face_bottom: 0.0,
            arm_face_top: f64::INFINITY,
            arm_inertia: 0.0,
        }
    }
}

impl Materials {
    /// The defaults of docs/model.md §1: μ_b 0.4, μ_a 0.3, e* 0.3, exact friction, energetic
    /// impacts.
    pub fn paper_default() -> Materials {
        Materials {
            belt_friction: FrictionCoefficient::Constant(0.4),
            arm_friction: 0.3,
            restitution: 0.3,
            friction_model: FrictionModel::Exact,
            impact_law: ImpactLaw::Energetic,
        }
    }
}

impl Scenario {
    /// The built-in default: the paper's compact parcel 0.4 × 0.26 × 0.15 m (3 kg) at
    /// ΔP = 0.22 m, φ = 0, riding with the belt; v = 2 m/s, t_c = 1.36 s, R_s = 0.
    pub fn paper_default() -> Scenario {
        let machine = Machine::paper_default();
        Scenario {
            run: RunSettings {
                duration: default_duration(machine.cycle_time),
                tolerance: 1e-8,
                arm: true,
                cycle_starts: vec![0.0],
            },
            machine,
            parcel: Parcel::riding(0.4, 0.26, 0.15, 3.0, 0.22, 0.0),
            materials: Materials::paper_default(),
            limits: Limits {
                drop_height: 0.3,
                tipping: TippingRule::Verdict,
            },
        }
    }

    /// The paper preset's machine (configs/paper/machine.toml) on the built-in scenario:
    /// [`Scenario::paper_default`] with R_z = 1.15 m, μ_b = 0.5 and μ_a = 0.38; the fixture
    /// of the tests that reproduce the paper's findings.
    pub fn paper_machine() -> Scenario {
        let mut s = Scenario::paper_default();
        s.machine.arm_length = 1.15;
        s.materials.belt_friction = FrictionCoefficient::Constant(0.5);
        s.materials.arm_friction = 0.38;
        s
    }

    /// z_c: the height at which the arm's face pushes this parcel \[m], the middle of the
    /// part of its side within the face band; `None` when the parcel is no taller than the
    /// band's bottom and the arm passes over it ([`crate::model::tipping::contact_height`]).
    pub fn arm_contact_height(&self) -> Option<f64> {
        crate::model::tipping::contact_height(
            self.parcel.height,
            self.machine.arm_face_bottom,
            self.machine.arm_face_top,
        )
    }

    /// The parcel footprint.
    pub fn footprint(&self) -> Rect {
        Rect {
            length: self.parcel.length,
            width: self.parcel.width,
        }
    }

    /// I: moment of inertia about the vertical axis through G, m(a² + b²)/12 [kg·m²].
    pub fn inertia(&self) -> f64 {
        self.parcel.mass * self.footprint().gyration_sq()
    }

    /// Centre G at t = 0 from R_s (most downstream x) and ΔP (smallest y).
    pub fn initial_centre(&self) -> DVec2 {
        let e = self.footprint().half_extents(self.parcel.angle);
        DVec2::new(self.machine.start_position - e.x, self.parcel.offset + e.y)
    }

    /// Initial centre velocity: the given one, or the belt's.
    pub fn initial_velocity(&self) -> DVec2 {
        self.parcel
            .velocity
            .unwrap_or(DVec2::new(self.machine.belt_speed, 0.0))
    }
}

/// Default run length: the arm cycle plus 2 s for the slide-out.
pub fn default_duration(cycle_time: f64) -> f64 {
    cycle_time + 2.0
}

/// The run's length when none is stated: past the start of the last cycle (when after
/// t = 0), [`default_duration`] \[s].
pub fn run_length(cycle_starts: &[f64], cycle_time: f64) -> f64 {
    let last = cycle_starts.last().copied().unwrap_or(0.0).max(0.0);
    last + default_duration(cycle_time)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn initial_pose_touches_start_position_and_offset() {
        let mut s = Scenario::paper_default();
        s.parcel.angle = 0.3;
        s.machine.start_position = 0.5;
        let g = s.initial_centre();
        let cs = s.footprint().corners(g, s.parcel.angle);
        let max_x = cs.iter().map(|c| c.x).fold(f64::MIN, f64::max);
        let min_y = cs.iter().map(|c| c.y).fold(f64::MAX, f64::min);
        assert_relative_eq!(max_x, 0.5, epsilon = 1e-14);
        assert_relative_eq!(min_y, s.parcel.offset, epsilon = 1e-14);
    }

    /// A run record keeps the parcel and its materials exactly: written and read back in the
    /// memo's encoding, every value is the same to the bit, and its scenario is
    /// the setting with the parcel, its own values, R_s (S_d moved with it), the cycles
    /// and the length put in.
    #[test]
    fn a_parcel_run_round_trips_and_makes_its_scenario() {
        let setting = Scenario::paper_default();
        let run = ParcelRun {
            parcel: Parcel::riding(0.41, 0.27, 0.19, 3.3, 0.123_456_789, 0.1 + 0.2)
                .moving(Some(DVec2::new(1.0 / 3.0, -0.07)), 0.9)
                .with_com_height(Some(0.05)),
            belt_friction: Some(0.456),
            arm_friction: 0.31,
            restitution: 0.2,
            start_position: -0.25,
            cycle_starts: Some(vec![0.1, 1.7]),
            duration: 4.5,
        };
        let bytes = postcard::to_allocvec(&run).unwrap();
        let back: ParcelRun = postcard::from_bytes(&bytes).unwrap();
        assert_eq!(back, run);
        let bytes = postcard::to_allocvec(&setting.materials).unwrap();
        let m: Materials = postcard::from_bytes(&bytes).unwrap();
        assert_eq!(m, setting.materials);

        let s = run.scenario(&setting);
        assert_eq!(s.parcel, run.parcel);
        assert_eq!(s.machine.start_position, -0.25);
        assert_eq!(s.machine.light_barrier, -0.25);
        assert_eq!(s.machine.trigger, Trigger::Fixed);
        assert_eq!(
            s.materials.belt_friction,
            FrictionCoefficient::Constant(0.456)
        );
        assert_eq!(
            (s.materials.arm_friction, s.materials.restitution),
            (0.31, 0.2)
        );
        assert_eq!(s.run.cycle_starts, vec![0.1, 1.7]);
        assert_eq!(s.run.duration, 4.5);
        assert_eq!(s.machine.cycle_time, setting.machine.cycle_time);
        // Without cycles of its own, the setting's stay.
        let own = ParcelRun {
            cycle_starts: None,
            ..run
        };
        assert_eq!(
            own.scenario(&setting).run.cycle_starts,
            setting.run.cycle_starts
        );
    }
}
