//! The variables nobody controls, for the worst-case search and the design set: the pose
//! box (parcel class, pose, arrival phase, optional scatter of belt speed and friction), a
//! pose within it, the search vector's mapping onto it, and the exact scenario of a pose
//! (angles in degrees, converted as the file loader does, so a file written from a pose
//! reproduces its run bit for bit). The search itself is [`crate::analysis::design::worst_case`].

use crate::model::belt_friction::FrictionCoefficient;
use crate::model::params::{Parcel, Scenario};
use crate::optimize::{Bounds, OptimizeError};

/// A closed interval [lo, hi] of an uncontrolled variable (lo = hi fixes it).
pub type Band = (f64, f64);

/// The variables nobody controls and their ranges (module notes).
#[derive(Debug, Clone, PartialEq)]
pub struct PoseBox {
    /// a: parcel length \[m]
    pub length: Band,
    /// b: parcel width \[m]; each pose has b ≤ a
    pub width: Band,
    /// m: mass \[kg]
    pub mass: Band,
    /// φ: angle to the belt direction \[deg]
    pub angle_deg: Band,
    /// δt: arrival phase relative to the trigger \[s] (+: the parcel is late, the arm early)
    pub phase: Band,
    /// Factor on the belt speed v [-]
    pub belt_speed_scale: Band,
    /// Factor on μ_b (every point of a μ_1(v_o) table) [-]
    pub belt_friction_scale: Band,
    /// μ_a band; `None`: the scenario's value
    pub arm_friction: Option<Band>,
    /// e* band; `None`: the scenario's value
    pub restitution: Option<Band>,
    /// Height band \[m] (issue 47: the height decides whether a parcel tips over); `None`:
    /// the scenario's parcel height, and the search keeps its ten variables.
    pub height: Option<Band>,
}

impl PoseBox {
    /// The widest box the model supports: every band of a box must lie within the band of
    /// the same name here (sizes above 1 mm for the contact tolerances, masses above 1 g,
    /// the angle a half turn, the phase a minute). The scenario file's schema reads its
    /// ranges from here.
    pub const LIMITS: PoseBox = PoseBox {
        length: (0.001, 5.0),
        width: (0.001, 5.0),
        mass: (0.001, 1000.0),
        angle_deg: (-90.0, 90.0),
        phase: (-60.0, 60.0),
        belt_speed_scale: (0.5, 1.5),
        belt_friction_scale: (0.1, 3.0),
        arm_friction: Some((0.0, 1.3)),
        restitution: Some((0.0, 1.0)),
        height: Some((0.001, 5.0)),
    };

    /// The paper's parcel class (§4.1: 0.2 × 0.1 m up to 0.7 m long, the compact
    /// 0.26 m wide; up to the 15 kg of §4.2, down to the smallest parcel's 0.5 kg), turned up
    /// to ±30° to the belt, anywhere across it, with a ±10 ms light-barrier timing error,
    /// nominal belt speed and materials.
    pub fn paper() -> PoseBox {
        PoseBox {
            length: (0.2, 0.7),
            width: (0.1, 0.26),
            mass: (0.5, 15.0),
            angle_deg: (-30.0, 30.0),
            phase: (-0.01, 0.01),
            belt_speed_scale: (1.0, 1.0),
            belt_friction_scale: (1.0, 1.0),
            arm_friction: None,
            restitution: None,
            height: None,
        }
    }

    /// Every problem with the box: (key, message), keys as the scenario file spells them
    /// under `design.search`.
    pub fn problems(&self) -> Vec<(&'static str, String)> {
        let mut out = Vec::new();
        let mut band = |key: &'static str, b: Band, (lo, hi): Band, unit: &str| {
            if !(b.0.is_finite() && b.1.is_finite()) || b.0 > b.1 {
                out.push((
                    key,
                    format!(
                        "[{}, {}] is not an interval [lo, hi] with lo ≤ hi",
                        b.0, b.1
                    ),
                ));
            } else if b.0 < lo || b.1 > hi {
                out.push((
                    key,
                    format!(
                        "[{}, {}] leaves the allowed range [{lo}, {hi}] {unit}",
                        b.0, b.1
                    ),
                ));
            }
        };
        let l = Self::LIMITS;
        band("length", self.length, l.length, "m");
        band("width", self.width, l.width, "m");
        band("mass", self.mass, l.mass, "kg");
        band("angle_deg", self.angle_deg, l.angle_deg, "deg");
        band("phase", self.phase, l.phase, "s");
        band(
            "belt_speed_scale",
            self.belt_speed_scale,
            l.belt_speed_scale,
            "",
        );
        band(
            "belt_friction_scale",
            self.belt_friction_scale,
            l.belt_friction_scale,
            "",
        );
        if let (Some(b), Some(limit)) = (self.arm_friction, l.arm_friction) {
            band("arm_friction", b, limit, "");
        }
        if let (Some(b), Some(limit)) = (self.restitution, l.restitution) {
            band("restitution", b, limit, "");
        }
        if let (Some(b), Some(limit)) = (self.height, l.height) {
            band("height", b, limit, "m");
        }
        if out.is_empty() && self.width.0 > self.length.1 {
            out.push((
                "width",
                format!(
                    "the smallest width {} m exceeds the largest length {} m (each pose has width ≤ length)",
                    self.width.0, self.length.1
                ),
            ));
        }
        out
    }

    /// The box with each band widened by a scatter (module notes of [`Scatter`]).
    pub fn with_scatter(&self, s: &Scatter) -> PoseBox {
        let widen = |b: Band, d: f64| (b.0 - d, b.1 + d);
        PoseBox {
            phase: widen(self.phase, s.phase),
            belt_speed_scale: widen(self.belt_speed_scale, s.belt_speed),
            belt_friction_scale: widen(self.belt_friction_scale, s.belt_friction),
            ..self.clone()
        }
    }
}

/// Scatter a setting must stay feasible under (issue 10 "robustness"), each a half-width
/// added to the pose box: the belt speed and μ_b as relative deviations (0.02 = ±2 %), the
/// trigger phase in seconds.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Scatter {
    /// Relative belt speed deviation [-]
    pub belt_speed: f64,
    /// Trigger timing deviation \[s]
    pub phase: f64,
    /// Relative μ_b deviation [-]
    pub belt_friction: f64,
}

/// One parcel's uncontrolled variables, resolved to the values a scenario file states.
#[derive(Debug, Clone, PartialEq)]
pub struct Pose {
    /// a \[m]
    pub length: f64,
    /// b \[m]
    pub width: f64,
    /// m \[kg]
    pub mass: f64,
    /// φ \[deg]
    pub angle_deg: f64,
    /// ΔP \[m]
    pub offset: f64,
    /// δt: arrival phase \[s]
    pub phase: f64,
    /// Factor on v [-]
    pub belt_speed_scale: f64,
    /// Factor on μ_b [-]
    pub belt_friction_scale: f64,
    /// μ_a [-]
    pub arm_friction: f64,
    /// e* [-]
    pub restitution: f64,
    /// Height \[m]; `None`: the setting's parcel height.
    pub height: Option<f64>,
}

/// Number of search variables of a box without a height band; a height band is an eleventh,
/// appended, so that a search without one keeps its random stream and results.
pub const DIM: usize = 10;
/// Names of the search variables, in order (the fractions are of the width range left by the
/// length, and of the room beside the parcel).
pub const VARIABLES: [&str; DIM] = [
    "length",
    "width_fraction",
    "mass",
    "angle_deg",
    "offset_fraction",
    "phase",
    "belt_speed_scale",
    "belt_friction_scale",
    "arm_friction",
    "restitution",
];

impl Pose {
    /// The run of this pose at a setting: `setting` (a scenario with the machine setting,
    /// materials and run length) with the parcel, its arrival and the material values
    /// replaced. v ← v·scale, R_s ← R_s + v δt, μ_b ← μ_b·scale.
    pub fn scenario(&self, setting: &Scenario) -> Scenario {
        let mut s = setting.clone();
        let v = setting.machine.belt_speed * self.belt_speed_scale;
        s.machine.belt_speed = v;
        s.machine
            .start_at(setting.machine.start_position + v * self.phase);
        s.parcel = Parcel::riding(
            self.length,
            self.width,
            self.height.unwrap_or(setting.parcel.height),
            self.mass,
            self.offset,
            self.angle_deg.to_radians(),
        );
        s.materials.belt_friction =
            scale_friction(&setting.materials.belt_friction, self.belt_friction_scale);
        s.materials.arm_friction = self.arm_friction;
        s.materials.restitution = self.restitution;
        s
    }
}

/// μ_b scaled by k (a table point by point).
pub fn scale_friction(mu: &FrictionCoefficient, k: f64) -> FrictionCoefficient {
    match mu {
        FrictionCoefficient::Constant(m) => FrictionCoefficient::Constant(m * k),
        FrictionCoefficient::Table(t) => {
            FrictionCoefficient::Table(t.iter().map(|&(v, m)| (v, m * k)).collect())
        }
    }
}

/// Extent of an a × b footprint across the belt at φ \[m] (as the simulator computes it).
pub fn extent_across(length: f64, width: f64, angle: f64) -> f64 {
    crate::geometry::Rect { length, width }
        .half_extents(angle)
        .y
        * 2.0
}

/// The search box of a pose box on a setting: bounds of the [`VARIABLES`].
pub fn search_bounds(pose_box: &PoseBox, setting: &Scenario) -> Result<Bounds, OptimizeError> {
    let m = &setting.materials;
    let arm = pose_box
        .arm_friction
        .unwrap_or((m.arm_friction, m.arm_friction));
    let e = pose_box
        .restitution
        .unwrap_or((m.restitution, m.restitution));
    let b = [
        pose_box.length,
        (0.0, 1.0),
        // Fixed at the largest mass: the ratio and reserve do not depend on m (module notes).
        (pose_box.mass.1, pose_box.mass.1),
        pose_box.angle_deg,
        (0.0, 1.0),
        pose_box.phase,
        pose_box.belt_speed_scale,
        pose_box.belt_friction_scale,
        arm,
        e,
    ];
    let b = b.iter().chain(pose_box.height.as_ref());
    Bounds::new(b.clone().map(|b| b.0).collect(), b.map(|b| b.1).collect())
}

/// The pose of a search vector, and how far the parcel is too wide for the belt (≤ 0: fits).
pub fn pose_of(x: &[f64], pose_box: &PoseBox, belt_width: f64) -> (Pose, f64) {
    // b ≤ a: a length below the smallest width is taken as that width.
    let length = x[0].max(pose_box.width.0);
    let w_hi = pose_box.width.1.min(length).max(pose_box.width.0);
    let width = pose_box.width.0 + x[1] * (w_hi - pose_box.width.0);
    let angle_deg = x[3];
    let extent = extent_across(length, width, angle_deg.to_radians());
    let room = belt_width - extent;
    let pose = Pose {
        length,
        width,
        mass: x[2],
        angle_deg,
        offset: x[4] * room.max(0.0),
        phase: x[5],
        belt_speed_scale: x[6],
        belt_friction_scale: x[7],
        arm_friction: x[8],
        restitution: x[9],
        height: pose_box.height.map(|_| x[DIM]),
    };
    (pose, -room)
}
