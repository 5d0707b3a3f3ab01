//! Tipping of a tall parcel: the lift-off criterion, the strike's pivot, and the records
//! (issues 26 and 47; docs/model.md §12a derives every formula here).
//!
//! The plane model gives, at every instant, the horizontal forces on the parcel and its
//! acceleration, and at every strike its impulse. The third dimension enters here and in
//! [`crate::model::tilt`], which follows the tilt about an edge once it has started:
//! - **lift-off** (quasi-static): about a footprint edge at half side d, with outward normal
//!   n, the moment of the contact forces, the inertial force at h_c and the weight must stay
//!   below m g d. Each contact is a vertical line over the overlap [z_lo, z_hi] of the arm's
//!   face band and the parcel's side, and carries its resultant where it tips least: at
//!   z_lo for an edge it pushes towards. A contact on an edge's own side holds that side up
//!   (the face blocks a tilt towards it). The margin is m g d over the moment;
//! - **a strike** acts at the height of the overlap nearest h_c. Above h_c it presses the
//!   far edge into the belt and the box pivots forwards on it; below, it pivots backwards on
//!   the struck side's bottom edge ([`TipGeometry::strike_pivot`]). The pivot sticks if the
//!   belt's friction can hold it, else slides, by Coulomb's law for impulses. That rocking
//!   mode changes the struck point's mobility along the push ([`TipGeometry::rocking_mode`]),
//!   which the strike itself takes into its effective mass (`sim/settle.rs`).
//!
//! Assumptions: a rigid box with the inertia of a uniform one about its centre of mass; the
//! belt's friction acts in the footprint's plane; the arm and the guide share one face band.

use glam::DVec2;

use crate::GRAVITY;

/// The footprint edge a parcel tips over, in its own axes (x' along the length a).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TipEdge {
    /// The short side at x' = +a/2.
    FrontShort,
    /// The short side at x' = −a/2.
    RearShort,
    /// The long side at y' = +b/2.
    LeftLong,
    /// The long side at y' = −b/2.
    RightLong,
}

impl TipEdge {
    /// Every edge.
    pub const ALL: [TipEdge; 4] = [
        TipEdge::FrontShort,
        TipEdge::RearShort,
        TipEdge::LeftLong,
        TipEdge::RightLong,
    ];

    /// The edge's name in outputs.
    pub fn label(self) -> &'static str {
        match self {
            TipEdge::FrontShort => "short_side_plus_x",
            TipEdge::RearShort => "short_side_minus_x",
            TipEdge::LeftLong => "long_side_plus_y",
            TipEdge::RightLong => "long_side_minus_y",
        }
    }

    /// The edge in words.
    pub fn words(self) -> &'static str {
        match self {
            TipEdge::FrontShort => "a short side (x' = +a/2)",
            TipEdge::RearShort => "a short side (x' = −a/2)",
            TipEdge::LeftLong => "a long side (y' = +b/2)",
            TipEdge::RightLong => "a long side (y' = −b/2)",
        }
    }

    /// The edge of a label.
    pub fn from_label(label: &str) -> Option<TipEdge> {
        TipEdge::ALL.into_iter().find(|e| e.label() == label)
    }

    /// n: the edge's outward normal in the parcel's axes.
    pub fn normal(self) -> DVec2 {
        match self {
            TipEdge::FrontShort => DVec2::X,
            TipEdge::RearShort => DVec2::NEG_X,
            TipEdge::LeftLong => DVec2::Y,
            TipEdge::RightLong => DVec2::NEG_Y,
        }
    }

    /// The edge across the footprint.
    pub fn opposite(self) -> TipEdge {
        match self {
            TipEdge::FrontShort => TipEdge::RearShort,
            TipEdge::RearShort => TipEdge::FrontShort,
            TipEdge::LeftLong => TipEdge::RightLong,
            TipEdge::RightLong => TipEdge::LeftLong,
        }
    }

    /// Index in [`TipEdge::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }

    /// The edge a body-axes direction `dir` points to along its larger component.
    fn towards(dir: DVec2) -> TipEdge {
        if dir.x.abs() >= dir.y.abs() {
            if dir.x >= 0.0 {
                TipEdge::FrontShort
            } else {
                TipEdge::RearShort
            }
        } else if dir.y >= 0.0 {
            TipEdge::LeftLong
        } else {
            TipEdge::RightLong
        }
    }
}

/// What tipped or came closest to it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TipCause {
    /// The forces of a contact or of the belt (quasi-static).
    Forces,
    /// A strike's impulse.
    Strike,
}

impl TipCause {
    pub fn label(self) -> &'static str {
        match self {
            TipCause::Forces => "forces",
            TipCause::Strike => "strike",
        }
    }
}

/// One tipping check: the margin and the edge it concerns. For forces, below 1 the edge
/// lifts; for a strike, below 1 the strike alone gives the box the energy to go over.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tip {
    pub margin: f64,
    pub edge: TipEdge,
}

/// A run's tipping record: the smallest margin, where and how, the largest tilt, and the
/// verdict.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TipRecord {
    /// The smallest margin (infinite if nothing loaded the parcel sideways). Below 1 an
    /// edge lifted; whether the box went over is [`TipRecord::tipped`].
    pub margin: f64,
    /// t at which it occurred, or at which the box went over if it did \[s] (infinite if
    /// never loaded).
    pub t: f64,
    /// The edge (None if never loaded); the edge it went over if it did.
    pub edge: Option<TipEdge>,
    /// Forces or a strike (None if never loaded).
    pub cause: Option<TipCause>,
    /// θ_max: the largest tilt about a footprint edge \[rad] (0 if no edge lifted).
    pub max_tilt: f64,
    /// Whether the centre of mass passed over an edge: the box tipped over.
    pub over: bool,
}

impl Default for TipRecord {
    fn default() -> TipRecord {
        TipRecord {
            margin: f64::INFINITY,
            t: f64::INFINITY,
            edge: None,
            cause: None,
            max_tilt: 0.0,
            over: false,
        }
    }
}

impl TipRecord {
    /// Keep `tip` at `t` if it is the smallest margin so far (a box that went over keeps
    /// the time and edge of that).
    pub fn note(&mut self, t: f64, tip: Tip, cause: TipCause) {
        if tip.margin < self.margin {
            self.margin = tip.margin;
            self.cause = Some(cause);
            if !self.over {
                self.t = t;
                self.edge = Some(tip.edge);
            }
        }
    }

    /// Keep a tilt of `angle` \[rad].
    pub fn note_tilt(&mut self, angle: f64) {
        self.max_tilt = self.max_tilt.max(angle);
    }

    /// The box went over `edge` at `t`.
    pub fn note_over(&mut self, t: f64, edge: TipEdge, tilt: f64) {
        if !self.over {
            self.over = true;
            self.t = t;
            self.edge = Some(edge);
            self.cause.get_or_insert(TipCause::Forces);
        }
        self.note_tilt(tilt);
    }

    /// The two records of consecutive stretches of one run as one.
    pub fn merge(self, o: TipRecord) -> TipRecord {
        let mut m = if o.margin < self.margin { o } else { self };
        m.max_tilt = self.max_tilt.max(o.max_tilt);
        let over = if self.over {
            Some(self)
        } else if o.over {
            Some(o)
        } else {
            None
        };
        if let Some(w) = over {
            m.over = true;
            m.t = w.t;
            m.edge = w.edge;
            if m.cause.is_none() {
                m.cause = w.cause;
            }
        }
        m
    }

    /// Whether the parcel tipped over: its centre of mass passed over a footprint edge.
    pub fn tipped(&self) -> bool {
        self.over
    }
}

/// The overlap [z_lo, z_hi] of a face band \[`bottom`, `top`] with a parcel's side of
/// height `height` \[m]; `None` when the band misses the parcel (it is lower than the band's
/// bottom).
pub fn band_overlap(height: f64, bottom: f64, top: f64) -> Option<(f64, f64)> {
    let (lo, hi) = (bottom.max(0.0), top.min(height));
    (hi > lo).then_some((lo, hi))
}

/// z_c: the middle of the overlap of a face band \[`bottom`, `top`] with a parcel's side of
/// `height` \[m]; `None` when the band misses the parcel.
pub fn contact_height(height: f64, bottom: f64, top: f64) -> Option<f64> {
    band_overlap(height, bottom, top).map(|(lo, hi)| 0.5 * (lo + hi))
}

/// The geometry of a tilt about one edge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeGeometry {
    /// d: the edge's distance from the centre in the footprint \[m].
    pub half_side: f64,
    /// R = √(d² + h_c²): the edge's distance from the centre of mass \[m].
    pub radius: f64,
    /// α = atan(d/h_c): the tilt at which the centre of mass is over the edge \[rad].
    pub over_angle: f64,
    /// I_G: the moment of inertia about the axis through G along the edge [kg·m²].
    pub inertia_com: f64,
    /// I_O = I_G + m R²: about the edge [kg·m²].
    pub inertia_edge: f64,
}

/// The tipping geometry of one parcel against one machine.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TipGeometry {
    /// (a/2, b/2): the footprint's half sides \[m].
    pub half: DVec2,
    /// h: the parcel's height \[m].
    pub height: f64,
    /// h_c: its centre of mass above the belt \[m].
    pub com_height: f64,
    /// [z_lo, z_hi]: the overlap of the arm's (and the guide's) face band with the
    /// parcel's side \[m].
    pub band: (f64, f64),
    /// m \[kg].
    pub mass: f64,
    /// μ_b(0): the belt's friction under a pivot during a strike.
    pub belt_friction: f64,
}

/// The tilt rate a strike gives the box about its pivot edge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pivot {
    /// The edge the box turns about (forwards: the far edge; backwards: the struck side's).
    pub edge: TipEdge,
    /// θ̇: the tilt rate about it just after the strike [rad/s].
    pub rate: f64,
    /// Whether the belt's friction held the pivot (else it slid).
    pub stuck: bool,
}

/// The rocking mode of a strike on a standing box off h_c (docs/model.md §12a): what the
/// pivot adds to the plane model's strike along the far edge's normal e.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RockingMode {
    /// e: the far edge's outward normal, machine frame (unit) [-].
    pub direction: DVec2,
    /// ΔW: the struck point's mobility along e less the plane model's 1/m [1/kg]: z_s²/I_O
    /// − 1/m on a stuck pivot, (z_s − h_c)(z_s − h_c − σ μ_b p)/(I_G + m d² − σ μ_b m h_c p)
    /// on a sliding one.
    pub extra_mobility: f64,
    /// F̂/P_e: the pivot's friction impulse on the box along e per unit of the strike's
    /// impulse along e [-] (m h_c z_s/I_O − 1 stuck, −σ μ_b m p Δω/P_e sliding).
    pub pivot_friction: f64,
    /// σ: the pivot's slip direction, 0 when it sticks.
    pub slip_direction: f64,
}

impl RockingMode {
    /// Whether `other` is the same regime: the same far edge (so the same pivot edge), and
    /// the pivot stuck or sliding the same way.
    pub fn same_regime(&self, other: &RockingMode) -> bool {
        self.direction == other.direction && self.slip_direction == other.slip_direction
    }
}

/// [`TipGeometry::strike_answer`]'s result.
#[derive(Debug, Clone, Copy)]
struct StrikeAnswer {
    pivot: Pivot,
    /// σ, 0 when stuck.
    slip_direction: f64,
    far: TipEdge,
    /// Δv_x: the centre's velocity change along the far edge's normal [m/s].
    centre_speed: f64,
    /// The struck point's velocity change along the far edge's normal [m/s].
    point_speed: f64,
}

/// The loads that tilt the box about one edge at one instant, each along the edge's
/// outward normal n.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct EdgeLoad {
    /// Σ F·n over the contacts that push towards the edge \[N]: they act at z_lo.
    pub push: f64,
    /// m a·n: the centre's acceleration along n times the mass \[N] (its d'Alembert force
    /// acts at h_c).
    pub inertial: f64,
    /// k = F_b·n/(m g): the belt's friction along n per unit weight; on a lifted edge it
    /// scales with the edge's normal force N.
    pub friction: f64,
    /// u·n: the footprint's slip on the belt along n \[m/s]; a lifted edge slides while
    /// its own slip u·n − z_G θ̇ has this sign, else it sticks to the belt.
    pub slip: f64,
    /// m times the belt's acceleration along n \[N]: 0, the belt runs at constant speed
    /// (the rocking law holds for any).
    pub base: f64,
    /// A contact on the edge's own side holds that side: the box cannot tilt about it.
    pub held: bool,
}

impl TipGeometry {
    /// z_c: the middle of the band's overlap \[m].
    pub fn contact_height(&self) -> f64 {
        0.5 * (self.band.0 + self.band.1)
    }

    /// z_s: the height at which a strike acts, the overlap's height nearest h_c \[m].
    pub fn strike_height(&self) -> f64 {
        self.com_height.clamp(self.band.0, self.band.1)
    }

    /// d: `edge`'s distance from the centre in the footprint \[m].
    pub fn half_side(&self, edge: TipEdge) -> f64 {
        match edge {
            TipEdge::FrontShort | TipEdge::RearShort => self.half.x,
            TipEdge::LeftLong | TipEdge::RightLong => self.half.y,
        }
    }

    /// I_G = m ((2d)² + h²)/12: the moment of inertia about the axis through G along an
    /// edge at `half_side` d [kg·m²].
    pub fn inertia_com(&self, half_side: f64) -> f64 {
        let d = half_side;
        self.mass * (4.0 * d * d + self.height * self.height) / 12.0
    }

    /// The geometry of a tilt about `edge`.
    pub fn edge(&self, edge: TipEdge) -> EdgeGeometry {
        let d = self.half_side(edge);
        let (m, hc) = (self.mass, self.com_height);
        let inertia_com = self.inertia_com(d);
        let radius = d.hypot(hc);
        EdgeGeometry {
            half_side: d,
            radius,
            over_angle: d.atan2(hc),
            inertia_com,
            inertia_edge: inertia_com + m * radius * radius,
        }
    }

    /// The loads about every edge (in [`TipEdge::ALL`]'s order) of the contacts' forces
    /// `forces` on the parcel, its centre's acceleration `accel` and its slip on the belt
    /// `slip` (machine frame \[N], [m/s²], [m/s]), at orientation `angle` φ \[rad].
    pub fn loads(&self, angle: f64, forces: &[DVec2], accel: DVec2, slip: DVec2) -> [EdgeLoad; 4] {
        let to_body = DVec2::from_angle(-angle);
        let a = to_body.rotate(accel);
        let u = to_body.rotate(slip);
        let belt = self.mass * a - forces.iter().map(|f| to_body.rotate(*f)).sum::<DVec2>();
        let weight = self.mass * GRAVITY;
        let mut loads = TipEdge::ALL.map(|e| EdgeLoad {
            push: 0.0,
            inertial: self.mass * a.dot(e.normal()),
            friction: belt.dot(e.normal()) / weight,
            slip: u.dot(e.normal()),
            base: 0.0,
            held: false,
        });
        for &f in forces {
            let f = to_body.rotate(f);
            if f == DVec2::ZERO {
                continue;
            }
            loads[TipEdge::towards(-f).index()].held = true;
            for (e, load) in TipEdge::ALL.iter().zip(loads.iter_mut()) {
                load.push += f.dot(e.normal()).max(0.0);
            }
        }
        loads
    }

    /// The lift-off check at one instant: the margin m g d / (z_lo Σ F·n − h_c m a·n) of
    /// the edge nearest to lifting (infinite if no edge is loaded towards lifting, or only
    /// held ones).
    pub fn lift(&self, loads: &[EdgeLoad; 4]) -> Tip {
        let mut best = Tip {
            margin: f64::INFINITY,
            edge: TipEdge::FrontShort,
        };
        let mut loaded = false;
        for (e, load) in TipEdge::ALL.iter().zip(loads) {
            let d = self.half_side(*e);
            let over = self.band.0 * load.push - self.com_height * load.inertial;
            if load.held || over.is_nan() || over <= 0.0 {
                continue;
            }
            let margin = self.mass * GRAVITY * d / over;
            if !loaded || margin < best.margin {
                best = Tip { margin, edge: *e };
                loaded = true;
            }
        }
        best
    }

    /// The pivot of a strike of impulse `impulse` (machine frame \[N·s]) on the box at
    /// orientation `angle` \[rad], standing: `None` when it acts at h_c (no turn).
    ///
    /// Above h_c the strike turns the box forwards and presses the far edge into the belt;
    /// below, backwards onto the struck side's bottom edge. The pivot gets a normal impulse
    /// N̂ ≥ 0 and a friction impulse F̂: it sticks (Δω = z_s P/I_O) if |F̂| ≤ μ_b N̂, else
    /// slides with F̂ = −σ μ_b N̂, Δω = (z_s − h_c) P/(I_G + m d² − σ μ_b m h_c p), p = ±d
    /// the pivot's side (docs/model.md §12a).
    pub fn strike_pivot(&self, angle: f64, impulse: DVec2) -> Option<Pivot> {
        self.strike_answer(angle, impulse).map(|a| a.pivot)
    }

    /// The rocking mode a strike of impulse `impulse` (machine frame \[N·s]) engages on the
    /// standing box at orientation `angle` \[rad]: `None` when it acts at h_c. The mode is
    /// the pivot's regime (stuck, or sliding one way) for the impulse's direction; the
    /// struck point's mobility along the far edge's normal e is then linear in P_e = P·e.
    pub fn rocking_mode(&self, angle: f64, impulse: DVec2) -> Option<RockingMode> {
        let a = self.strike_answer(angle, impulse)?;
        let along = DVec2::from_angle(angle).rotate(a.far.normal());
        let p_e = impulse.dot(along);
        (p_e > 0.0).then(|| RockingMode {
            direction: along,
            extra_mobility: a.point_speed / p_e - 1.0 / self.mass,
            pivot_friction: self.mass * a.centre_speed / p_e - 1.0,
            slip_direction: a.slip_direction,
        })
    }

    /// The standing box's answer to a strike: the pivot, and the struck point's and the
    /// centre's velocity changes along the far edge's normal.
    fn strike_answer(&self, angle: f64, impulse: DVec2) -> Option<StrikeAnswer> {
        let body = DVec2::from_angle(-angle).rotate(impulse);
        let z = self.strike_height();
        let hc = self.com_height;
        if (z - hc).abs() <= 1e-12 * self.height || body == DVec2::ZERO {
            return None;
        }
        let far = TipEdge::towards(body);
        let forwards = z > hc;
        let edge = if forwards { far } else { far.opposite() };
        let g = self.edge(far);
        let (m, mu, d) = (self.mass, self.belt_friction, g.half_side);
        let p_imp = body.dot(far.normal());
        // x along the push, the struck side at x = −d, the pivot at x = p; Δω clockwise
        // (the top towards +x). The centre moves by Δv_x, the struck point by Δv_x +
        // (z − h_c) Δω.
        let p = if forwards { d } else { -d };
        if forwards {
            let domega = z * p_imp / g.inertia_edge;
            let normal = m * p * domega;
            let friction = m * hc * domega - p_imp;
            if normal >= 0.0 && friction.abs() <= mu * normal {
                return Some(StrikeAnswer {
                    pivot: Pivot {
                        edge,
                        rate: domega,
                        stuck: true,
                    },
                    slip_direction: 0.0,
                    far,
                    centre_speed: hc * domega,
                    point_speed: z * domega,
                });
            }
        }
        for sigma in [1.0, -1.0] {
            let den = g.inertia_com + m * p * p - sigma * mu * m * hc * p;
            if den <= 0.0 {
                continue;
            }
            let domega = (z - hc) * p_imp / den;
            let normal = m * p * domega;
            let slip = (p_imp - sigma * mu * normal) / m - hc * domega;
            if normal >= 0.0 && sigma * slip >= -1e-12 * p_imp.abs() / m {
                let rate = if forwards { domega } else { -domega };
                let centre_speed = (p_imp - sigma * mu * normal) / m;
                return Some(StrikeAnswer {
                    pivot: Pivot {
                        edge,
                        rate,
                        stuck: false,
                    },
                    slip_direction: sigma,
                    far,
                    centre_speed,
                    point_speed: centre_speed + (z - hc) * domega,
                });
            }
        }
        None
    }

    /// ω*: the tilt rate about `edge` that lifts the centre of mass over it from standing,
    /// ½ I_O ω*² = m g (R − h_c) [rad/s].
    pub fn over_rate(&self, edge: TipEdge) -> f64 {
        let g = self.edge(edge);
        (2.0 * self.mass * GRAVITY * (g.radius - self.com_height) / g.inertia_edge).sqrt()
    }

    /// The strike check: ω*/θ̇ for the pivot's tilt rate θ̇ (below 1 the strike alone
    /// carries the box over), or `None` when the strike does not turn it.
    pub fn strike(&self, angle: f64, impulse: DVec2) -> Option<(Tip, Pivot)> {
        let pivot = self.strike_pivot(angle, impulse)?;
        (pivot.rate > 0.0).then(|| {
            (
                Tip {
                    margin: self.over_rate(pivot.edge) / pivot.rate,
                    edge: pivot.edge,
                },
                pivot,
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 0.2 × 0.1 m footprint, 0.4 m tall, 4 kg, centre of mass at mid-height, the face band
    /// overlapping its side over [lo, hi].
    fn tall(lo: f64, hi: f64) -> TipGeometry {
        TipGeometry {
            half: DVec2::new(0.1, 0.05),
            height: 0.4,
            com_height: 0.2,
            band: (lo, hi),
            mass: 4.0,
            belt_friction: 0.4,
        }
    }

    fn lift_at(geo: &TipGeometry, force: DVec2, accel: DVec2) -> Tip {
        geo.lift(&geo.loads(0.0, &[force], accel, DVec2::ZERO))
    }

    /// A box held still (friction at its base balances the push, a = 0) and pushed across
    /// its width by a face whose overlap starts at z lifts exactly at F = m g d/(2 z), d = b.
    #[test]
    fn steady_push_lifts_at_m_g_d_over_2z() {
        for z in [0.1, 0.25, 0.39] {
            let box_ = tall(z, 0.4);
            let f_tip = box_.mass * GRAVITY * 0.1 / (2.0 * z);
            let at = |f: f64| lift_at(&box_, DVec2::new(0.0, f), DVec2::ZERO);
            let tip = at(f_tip);
            assert!((tip.margin - 1.0).abs() < 1e-12, "{z}: {tip:?}");
            assert_eq!(tip.edge, TipEdge::LeftLong);
            assert!(at(0.999 * f_tip).margin > 1.0 && at(1.001 * f_tip).margin < 1.0);
        }
    }

    /// The same push on a frictionless belt accelerates the box, a = F/m: the inertial
    /// force at h_c offsets it, and the box lifts at F = m g (d/2)/(z − h_c), only when
    /// pushed above its centre of mass.
    #[test]
    fn accelerating_push_lifts_with_the_inertial_term() {
        let box_ = tall(0.35, 0.4);
        let f_tip = box_.mass * GRAVITY * 0.05 / (0.35 - 0.2);
        let at = |f: f64| lift_at(&box_, DVec2::new(0.0, f), DVec2::new(0.0, f / 4.0));
        assert!((at(f_tip).margin - 1.0).abs() < 1e-12);
        // With a face reaching down to the centre of mass's height, never, however hard.
        let mid = tall(0.2, 0.4);
        let m = lift_at(&mid, DVec2::new(0.0, 1e6), DVec2::new(0.0, 1e6 / 4.0));
        assert!(m.margin > 1e9, "{m:?}");
    }

    /// The most favourable height: a face over [0.1, 0.35] carries its resultant at 0.1 m,
    /// where the box tips least, not at the band's middle (0.225 m), which would tip it.
    #[test]
    fn the_face_pushes_at_its_most_favourable_height() {
        let box_ = tall(0.1, 0.35);
        let f = box_.mass * GRAVITY * 0.1 / (2.0 * 0.2); // lifts at 0.2 m and above
        let tip = lift_at(&box_, DVec2::new(0.0, f), DVec2::ZERO);
        assert!((tip.margin - 2.0).abs() < 1e-12, "{tip:?}");
        // A strike acts at the overlap's height nearest h_c.
        assert_eq!(tall(0.1, 0.35).strike_height(), 0.2);
        assert_eq!(tall(0.25, 0.4).strike_height(), 0.25);
        assert_eq!(tall(0.0, 0.15).strike_height(), 0.15);
        assert!(tall(0.1, 0.35)
            .strike(0.0, DVec2::new(0.0, 100.0))
            .is_none());
    }

    /// A contact on a side holds that side: however the belt drags the box, it does not
    /// tilt towards the face that pushes it.
    #[test]
    fn a_pushing_face_holds_its_own_side() {
        let box_ = tall(0.0, 0.4);
        // Pushed +y and accelerated hard along +y by the belt too: the inertial force at h_c
        // would lift the pushed side's edge (−y), but the face holds that side.
        let loads = box_.loads(
            0.0,
            &[DVec2::new(0.0, 5.0)],
            DVec2::new(0.0, 20.0),
            DVec2::ZERO,
        );
        assert!(loads[TipEdge::RightLong.index()].held);
        assert_eq!(box_.lift(&loads).margin, f64::INFINITY);
        let free = box_.loads(0.0, &[], DVec2::new(0.0, 20.0), DVec2::ZERO);
        assert!(box_.lift(&free).margin < 1.0);
        assert_eq!(box_.lift(&free).edge, TipEdge::RightLong);
    }

    /// Lift-off under belt friction alone: a sliding box decelerated at μ_b g lifts an edge
    /// exactly when μ_b h_c > d (here d = b/2 = 0.05 m, h_c = 0.2 m: μ_b = 0.25).
    #[test]
    fn lift_off_under_belt_friction_alone_at_mu_hc_equal_half_width() {
        let box_ = tall(0.0, 0.4);
        for (mu, lifts) in [(0.249, false), (0.251, true)] {
            let tip = lift_at(&box_, DVec2::ZERO, DVec2::new(0.0, -mu * GRAVITY));
            assert_eq!(tip.margin < 1.0, lifts, "μ = {mu}: {tip:?}");
            assert!((tip.margin - 0.05 / (mu * 0.2)).abs() < 1e-12);
            assert_eq!(tip.edge, TipEdge::LeftLong);
        }
    }

    /// The margin is taken in the parcel's own axes: a push along the machine's y on a
    /// parcel turned by 90° loads its short side.
    #[test]
    fn margins_are_in_the_parcels_axes() {
        let box_ = tall(0.3, 0.4);
        let loads = box_.loads(
            std::f64::consts::FRAC_PI_2,
            &[DVec2::new(0.0, 10.0)],
            DVec2::ZERO,
            DVec2::ZERO,
        );
        let turned = box_.lift(&loads);
        assert_eq!(turned.edge, TipEdge::FrontShort);
        let expected = box_.mass * GRAVITY * 0.1 / (0.3 * 10.0);
        assert!((turned.margin - expected).abs() < 1e-9, "{turned:?}");
    }

    /// The pivot sticks where the belt's friction holds it: the strike's angular impulse
    /// about the far edge, z_s P, turns it at z_s P/I_O, and the impulse balance
    /// m Δv_G = P + F̂, m Δv_z = N̂ holds with |F̂| ≤ μ N̂.
    #[test]
    fn a_stuck_pivot_turns_at_the_angular_impulse_over_i_e() {
        let mut box_ = tall(0.3, 0.4);
        box_.belt_friction = 2.0;
        let p = 1.0;
        let pivot = box_.strike_pivot(0.0, DVec2::new(0.0, p)).unwrap();
        let g = box_.edge(TipEdge::LeftLong);
        assert_eq!(pivot.edge, TipEdge::LeftLong);
        assert!(pivot.stuck);
        assert!((pivot.rate - 0.3 * p / g.inertia_edge).abs() < 1e-12);
        // With little friction the pivot slides backwards (σ = −1): the friction impulse
        // μ N̂ it gets is less than sticking needs, and Δω = (z_s − h_c) P/(I_G + m d² +
        // μ m h_c d).
        let mut slippery = tall(0.3, 0.4);
        slippery.belt_friction = 0.1;
        let slid = slippery.strike_pivot(0.0, DVec2::new(0.0, p)).unwrap();
        let expected = 0.1 * p / (g.inertia_com + 4.0 * 0.05 * 0.05 + 0.1 * 4.0 * 0.2 * 0.05);
        assert!(
            !slid.stuck && (slid.rate - expected).abs() < 1e-12,
            "{slid:?}"
        );
        // Frictionless: Δω = (z_s − h_c) P/(I_G + m d²) exactly.
        let mut smooth = tall(0.3, 0.4);
        smooth.belt_friction = 0.0;
        let s = smooth.strike_pivot(0.0, DVec2::new(0.0, p)).unwrap();
        let expected = 0.1 * p / (g.inertia_com + 4.0 * 0.05 * 0.05);
        assert!((s.rate - expected).abs() < 1e-12, "{s:?}");
    }

    #[test]
    fn band_overlap_and_its_middle() {
        assert_eq!(contact_height(0.4, 0.0, f64::INFINITY), Some(0.2));
        assert_eq!(contact_height(0.4, 0.1, 0.3), Some(0.2));
        assert_eq!(contact_height(0.15, 0.05, 0.3), Some(0.1));
        assert_eq!(contact_height(0.04, 0.05, 0.3), None);
        assert_eq!(band_overlap(0.4, -1.0, 0.3), Some((0.0, 0.3)));
        for e in TipEdge::ALL {
            assert_eq!(TipEdge::from_label(e.label()), Some(e));
            assert_eq!(e.opposite().opposite(), e);
            assert_eq!(TipEdge::ALL[e.index()], e);
        }
    }

    /// Records merge by the smallest margin, the largest tilt, and the first tip-over.
    #[test]
    fn records_keep_the_smallest_margin_and_the_tip_over() {
        let mut a = TipRecord::default();
        a.note(
            1.0,
            Tip {
                margin: 0.8,
                edge: TipEdge::LeftLong,
            },
            TipCause::Forces,
        );
        a.note_tilt(0.05);
        let mut b = TipRecord::default();
        b.note(
            2.0,
            Tip {
                margin: 0.9,
                edge: TipEdge::RightLong,
            },
            TipCause::Strike,
        );
        b.note_over(2.5, TipEdge::RightLong, 0.24);
        let m = a.merge(b);
        assert_eq!(m.margin, 0.8);
        assert!(m.tipped());
        assert_eq!((m.t, m.edge), (2.5, Some(TipEdge::RightLong)));
        assert_eq!(m.max_tilt, 0.24);
        assert!(!a.tipped());
    }
}
