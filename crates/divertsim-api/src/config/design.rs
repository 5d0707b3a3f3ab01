//! The `[design]` section: the limiting parcels, the overload parcel and the search box, their
//! checks, and the core's design set built from them.

// The sibling files this one uses, named so that the import-cycle check sees them.
use super::bounds::{MASS, MASS_WHY, SIDE, SIDE_WHY};
#[allow(unused_imports)]
use super::*;
use divertsim_keys::Keys;

/// The design set of `divertsim capacity` and the optimiser (paper §4.2): the limiting
/// parcels every setting must divert, each in its worst pose, and the worst-case overload
/// parcel. Default: the paper's smallest 0.2×0.1×0.1 m (0.5 kg) at the far edge, slender
/// 0.7×0.1×0.1 m (1.5 kg) and compact 0.4×0.26×0.15 m (3 kg) at the near edge, and the
/// compact size at 15 kg for the overload.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct DesignConfig {
    /// The limiting parcels (`[[design.parcels]]` tables), 1 to 16; giving any replaces the
    /// whole default list.
    pub parcels: Vec<DesignParcelConfig>,
    /// The worst-case overload parcel, struck at the arm tip at the largest α̇ (the paper's
    /// definition, `--worst paper`).
    pub overload: OverloadParcelConfig,
    /// The parcel class and arrival scatter the worst-case search explores (`worst-case`,
    /// `overload`, `--worst search`).
    pub search: SearchBoxConfig,
}

/// The variables nobody controls, each as [lo, hi] (equal ends fix it). Every pose has
/// width ≤ length and lies anywhere across the belt.
#[allow(rustdoc::broken_intra_doc_links)]
// doc comments are schema descriptions: [m] is a unit
// Its ranges are checked by the core's PoseBox::problems against the same PoseBox::LIMITS.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, Keys)]
#[serde(deny_unknown_fields, default)]
#[keys(section = "design.search")]
pub struct SearchBoxConfig {
    /// a: parcel length [m].
    #[key(at = "[]", name = LENGTH, range = Bound::band(PoseBox::LIMITS.length, "m"))]
    pub length: [f64; 2],
    /// b: parcel width [m]; each pose has b ≤ a.
    #[key(at = "[]", name = WIDTH, range = Bound::band(PoseBox::LIMITS.width, "m"))]
    pub width: [f64; 2],
    /// m: mass [kg].
    #[key(at = "[]", name = MASS, range = Bound::band(PoseBox::LIMITS.mass, "kg"))]
    pub mass: [f64; 2],
    /// φ: angle to the belt direction [deg].
    #[key(at = "[]", name = ANGLE_DEG, range = Bound::band(PoseBox::LIMITS.angle_deg, "deg"))]
    pub angle_deg: [f64; 2],
    /// δt: arrival phase relative to the trigger (light-barrier timing error) [s]; + means
    /// the parcel is further downstream when the arm starts, by v·δt.
    #[key(at = "[]", name = PHASE, range = Bound::band(PoseBox::LIMITS.phase, "s"))]
    pub phase: [f64; 2],
    /// Factor on the belt speed [-].
    #[key(at = "[]", name = BELT_SPEED_SCALE,
        range = Bound::band(PoseBox::LIMITS.belt_speed_scale, ""))]
    pub belt_speed_scale: [f64; 2],
    /// Factor on μ_b (every point of a table) [-].
    #[key(at = "[]", name = BELT_FRICTION_SCALE,
        range = Bound::band(PoseBox::LIMITS.belt_friction_scale, ""))]
    pub belt_friction_scale: [f64; 2],
    /// μ_a band [-]. Default: materials.arm_friction.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[key(at = "[]", name = ARM_FRICTION, range = Bound::band(ARM_FRICTION_BAND, ""))]
    pub arm_friction: Option<[f64; 2]>,
    /// e* band [-]. Default: materials.restitution.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[key(at = "[]", name = RESTITUTION, range = Bound::band(RESTITUTION_BAND, ""))]
    pub restitution: Option<[f64; 2]>,
    /// Height band [m]: the height decides whether a tall parcel tips over, so a class with
    /// tall parcels states it. Default: parcel.height (one height; `check` takes the band of
    /// the mix it runs).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[key(at = "[]", name = HEIGHT, range = Bound::band(SIDE, "m").because(SIDE_WHY))]
    pub height: Option<[f64; 2]>,
}

/// The sides and mass of a design parcel and of the overload parcel.
pub const DESIGN_BOX: [Bound; 4] = [
    DesignParcelConfig::LENGTH,
    DesignParcelConfig::WIDTH,
    DesignParcelConfig::HEIGHT,
    DesignParcelConfig::MASS,
];
/// See [`DESIGN_BOX`].
pub const OVERLOAD_BOX: [Bound; 4] = [
    OverloadParcelConfig::LENGTH,
    OverloadParcelConfig::WIDTH,
    OverloadParcelConfig::HEIGHT,
    OverloadParcelConfig::MASS,
];

const ARM_FRICTION_BAND: (f64, f64) = match PoseBox::LIMITS.arm_friction {
    Some(b) => b,
    None => {
        let (lo, hi, _) = MaterialsConfig::ARM_FRICTION.ends();
        (lo, hi)
    }
};
const RESTITUTION_BAND: (f64, f64) = match PoseBox::LIMITS.restitution {
    Some(b) => b,
    None => {
        let (lo, hi, _) = MaterialsConfig::RESTITUTION.ends();
        (lo, hi)
    }
};

impl Default for SearchBoxConfig {
    fn default() -> Self {
        let p = PoseBox::paper();
        let b = |x: (f64, f64)| [x.0, x.1];
        SearchBoxConfig {
            length: b(p.length),
            width: b(p.width),
            mass: b(p.mass),
            angle_deg: b(p.angle_deg),
            phase: b(p.phase),
            belt_speed_scale: b(p.belt_speed_scale),
            belt_friction_scale: b(p.belt_friction_scale),
            arm_friction: None,
            restitution: None,
            height: None,
        }
    }
}

impl SearchBoxConfig {
    /// The core's pose box.
    pub fn pose_box(&self) -> PoseBox {
        let b = |x: [f64; 2]| (x[0], x[1]);
        PoseBox {
            length: b(self.length),
            width: b(self.width),
            mass: b(self.mass),
            angle_deg: b(self.angle_deg),
            phase: b(self.phase),
            belt_speed_scale: b(self.belt_speed_scale),
            belt_friction_scale: b(self.belt_friction_scale),
            arm_friction: self.arm_friction.map(b),
            restitution: self.restitution.map(b),
            height: self.height.map(b),
        }
    }
}

/// One limiting parcel in its pose, riding with the belt.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, Keys)]
#[serde(deny_unknown_fields)]
#[keys(section = "design.parcels[]")]
pub struct DesignParcelConfig {
    /// A short unique name for tables, e.g. "smallest".
    pub name: String,
    /// a: length along the parcel's own x axis [m].
    #[key(range = Bound::band(SIDE, "m").because(SIDE_WHY))]
    pub length: f64,
    /// b: width along the parcel's own y axis [m].
    #[key(range = Bound::band(SIDE, "m").because(SIDE_WHY))]
    pub width: f64,
    /// Height [m].
    #[serde(default = "default_design_height")]
    #[key(range = Bound::band(SIDE, "m").because(SIDE_WHY))]
    pub height: f64,
    /// m: mass [kg].
    #[key(range = Bound::band(MASS, "kg").because(MASS_WHY))]
    pub mass: f64,
    /// ΔP: gap to the pivot-side belt edge [m], or "near" (0) or "far" (against the far
    /// edge: belt_width minus the parcel's extent across the belt).
    pub offset: DesignOffset,
    /// φ: orientation, counter-clockwise from the belt direction [deg].
    #[serde(default)]
    #[key(range = Bound::closed(-180.0, 180.0, "deg"))]
    pub angle_deg: f64,
}

/// ΔP of a design parcel: metres, or an edge of the belt.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged, expecting = "a number [m], \"near\" or \"far\"")]
pub enum DesignOffset {
    Value(f64),
    Edge(BeltEdge),
}

/// A belt edge.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum BeltEdge {
    /// Against the pivot-side edge (ΔP = 0).
    Near,
    /// Against the far (discharge-side) edge.
    Far,
}

/// The worst-case overload parcel (its pose is fixed by the strike: parallel to the belt,
/// front pivot-side corner at the arm tip).
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, Keys)]
#[serde(deny_unknown_fields, default)]
#[keys(section = "design.overload", default)]
pub struct OverloadParcelConfig {
    /// a [m].
    #[key(default = 0.4, range = Bound::band(SIDE, "m").because(SIDE_WHY))]
    pub length: f64,
    /// b [m].
    #[key(default = 0.26, range = Bound::band(SIDE, "m").because(SIDE_WHY))]
    pub width: f64,
    /// Height [m].
    #[key(default = 0.15, range = Bound::band(SIDE, "m").because(SIDE_WHY))]
    pub height: f64,
    /// m: the largest allowed mass [kg].
    #[key(default = 15.0, range = Bound::band(MASS, "kg").because(MASS_WHY))]
    pub mass: f64,
}

pub(super) fn default_design_height() -> f64 {
    0.1
}

/// Largest number of design parcels.
pub const MAX_DESIGN_PARCELS: usize = 16;

impl Default for DesignConfig {
    fn default() -> Self {
        let parcel = |name: &str, length, width, height, mass, edge| DesignParcelConfig {
            name: name.into(),
            length,
            width,
            height,
            mass,
            offset: DesignOffset::Edge(edge),
            angle_deg: 0.0,
        };
        DesignConfig {
            parcels: vec![
                parcel("smallest", 0.2, 0.1, 0.1, 0.5, BeltEdge::Far),
                parcel("slender", 0.7, 0.1, 0.1, 1.5, BeltEdge::Near),
                parcel("compact", 0.4, 0.26, 0.15, 3.0, BeltEdge::Near),
            ],
            overload: OverloadParcelConfig::default(),
            search: SearchBoxConfig::default(),
        }
    }
}

/// Extent of a length × width footprint across the belt at angle φ [deg] [m].
pub(super) fn extent_across(length: f64, width: f64, angle_deg: f64) -> f64 {
    let (s, c) = angle_deg.to_radians().sin_cos();
    length * s.abs() + width * c.abs()
}

impl DesignParcelConfig {
    /// ΔP \[m] on a belt of width P_max.
    pub fn offset_on(&self, belt_width: f64) -> f64 {
        match self.offset {
            DesignOffset::Value(v) => v,
            DesignOffset::Edge(BeltEdge::Near) => 0.0,
            DesignOffset::Edge(BeltEdge::Far) => {
                (belt_width - extent_across(self.length, self.width, self.angle_deg)).max(0.0)
            }
        }
    }
}

/// The core design set of a validated `[design]` section on a belt of width P_max \[m].
pub fn design_set(d: &DesignConfig, belt_width: f64) -> DesignSet {
    DesignSet {
        cases: d
            .parcels
            .iter()
            .map(|p| DesignCase {
                name: p.name.clone(),
                parcel: Parcel::riding(
                    p.length,
                    p.width,
                    p.height,
                    p.mass,
                    p.offset_on(belt_width),
                    p.angle_deg.to_radians(),
                ),
            })
            .collect(),
        overload_parcel: Parcel::riding(
            d.overload.length,
            d.overload.width,
            d.overload.height,
            d.overload.mass,
            0.0,
            0.0,
        ),
        search: d.search.pose_box(),
        worst: WorstDefinition::Paper,
        worst_poses: Vec::new(),
        margins: Margins::default(),
    }
}
