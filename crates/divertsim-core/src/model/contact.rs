//! Contact kinematics between the parcel and the obstacles (docs/model.md §1, §5, §6, §7): a
//! parcel corner on the arm face (either side), a parcel corner on the side guide, and
//! the arm tip on a parcel edge. For each pair: the gap, its rate, the slip, the contact frame,
//! and the acceleration-level constraint rows J q̈ = β (normal) and J_t q̈ = β_t (stick).
//!
//! Conventions (docs/model.md §1): pivot O = (0, 0); arm direction t(α) = (cos α, sin α), working
//! face normal n(α) = (−sin α, cos α); the arm's material point at P moves with α̇ ẑ×(P − O).
//! The side guide is the ray y = 0, x ≤ 0, normal (0, 1), fixed. For every contact n is the unit
//! normal on the parcel pointing from the obstacle into the parcel, t = (n_y, −n_x) (t × n = +ẑ),
//! u = v_parcel point − v_obstacle point, u_n = u·n (approaching when < 0), u_t = u·t.
//! State q = (x, y, φ), q̇ = (ẋ, ẏ, ω).
//!
//! # Derivations
//!
//! **Vertex on a moving line** (arm with Ω = α̇, or guide with Ω = 0). The line passes through
//! O with contact normal n (n = σ n(α) for arm side σ) and t = (n_y, −n_x). Because n and t are
//! rigidly attached to the line, ṅ = Ω ẑ×n = −Ω t and ṫ = Ω ẑ×t = Ω n, whichever the side σ.
//! With d = P − O, s = d·t (position along the line *measured along this contact's t*; for the
//! back face σ = −1, t = −t(α) so s = −(P − O)·t(α)) and g = d·n:
//! - ġ = v_P·n + d·ṅ = v_P·n − Ω s = (v_P − Ω ẑ×d)·n = u_n  (exact for every g);
//! - u_t = (v_P − Ω ẑ×d)·t = v_P·t + Ω g;
//! - g̈ = a_P·n − 2Ω v_P·t − Ω̇ s − Ω² g with a_P = a_G + φ̈ ẑ×r − φ̇² r, so
//!   g̈ = J q̈ − β, J = [n_x, n_y, r×n], β = φ̇²(r·n) + 2Ω(v_P·t) + Ω̇ s + Ω² g (model.md §6,
//!   shown valid for both arm faces with s taken along the contact's own t);
//! - u̇_t = a_P·t + Ω v_P·n + Ω̇ g + Ω ġ, so u̇_t = J_t q̈ − β_t with J_t = [t_x, t_y, r×t] and
//!   β_t = φ̇²(r·t) − Ω(v_P·n) − Ω̇ g − Ω ġ. This is exact for every g and ġ; for a persistent
//!   contact (g = ġ = 0) it reduces to the stick row φ̇²(r·t) − Ω(v_P·n) (model.md §6).
//!
//! **Arm tip T on a parcel edge.** T = R_z t(α), Ṫ = R_z α̇ n(α), T̈ = R_z(α̈ n(α) − α̇² t(α)).
//! The edge has outward normal m = R(φ) m' (rotating with the parcel, ṁ = ω ẑ×m), n = −m,
//! t = (n_y, −n_x) = ẑ×m (the counter-clockwise direction along the edge), h = the half
//! dimension to that edge, r = T − G, ṙ = Ṫ − v_G and g = r·m − h. The parcel material point at
//! T moves with v_G + ω ẑ×r, so u = v_G + ω ẑ×r − Ṫ = −ṙ + ω ẑ×r. For e ∈ {n, t} (both rotate
//! with ω, ė = ω ẑ×e):
//! - ġ = ṙ·m + ω r·(ẑ×m) = −ṙ·n + ω (r×n) = u·n = u_n  (exact for every g);
//! - d/dt(u·e) = a_G·e + ω̇ (r×e) − T̈·e + 2ω (ṙ×e) + ω²(r·e), using (ẑ×e)·w = e×w and
//!   a×(ẑ×b) = a·b. Hence g̈ = J q̈ − β with J = [n_x, n_y, r×n] and
//!   β = T̈·n − 2ω(ṙ×n) − ω²(r·n), and u̇_t = J_t q̈ − β_t with J_t = [t_x, t_y, r×t] and
//!   β_t = T̈·t − 2ω(ṙ×t) − ω²(r·t), both exact for every g.
//!
//! Every formula above is checked against central finite differences in the tests.

use glam::DVec2;

use crate::geometry::{cross, perp, rotate, Rect};
use crate::model::drive::ArmState;

/// Which parcel feature touches which obstacle.
///
/// Indices wrap modulo 4 (an out-of-range index never panics); corners follow
/// [`Rect::body_corners`]; edge j joins corner j and corner (j + 1) mod 4, so edge 0 is the
/// +a/2 side, edge 1 the +b/2 side, edge 2 the −a/2 side and edge 3 the −b/2 side.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ContactKind {
    /// Parcel corner `corner` against the arm; `side` = +1 the working face (normal n(α)),
    /// −1 the back face (normal −n(α)). Any `side` < 0 means the back face, otherwise the
    /// working face.
    CornerArm {
        /// k: corner index (0..3)
        corner: u8,
        /// σ: arm face, +1 working face, −1 back face
        side: i8,
    },
    /// Parcel corner `corner` on the side guide (normal (0, 1)).
    CornerGuide {
        /// k: corner index (0..3)
        corner: u8,
    },
    /// The arm tip T = R_z t(α) on parcel edge `edge` (normal: the edge's inward normal).
    TipEdge {
        /// j: edge index (0..3)
        edge: u8,
    },
}

impl ContactKind {
    /// Whether the arm carries this contact (a corner on either face, or the tip on an
    /// edge); the guide's contacts load the guide.
    pub fn is_arm(self) -> bool {
        !matches!(self, ContactKind::CornerGuide { .. })
    }
}

/// The parcel's state and the arm's, at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kinematics {
    /// G = (x, y): parcel centre \[m]
    pub centre: DVec2,
    /// φ: parcel orientation, CCW from x to the body x' axis \[rad]
    pub angle: f64,
    /// v_G = (ẋ, ẏ): centre velocity [m/s]
    pub velocity: DVec2,
    /// ω = φ̇: parcel angular velocity [rad/s]
    pub omega: f64,
    /// α, α̇, α̈ of the arm
    pub arm: ArmState,
    /// R_z: arm length \[m]
    pub arm_length: f64,
    /// a × b: parcel footprint
    pub rect: Rect,
    /// x where the pivot-side guide ends \[m]: 0 for the upstream guide alone (the side is
    /// open downstream of the pivot), +∞ for a guide along the whole pivot-side edge.
    pub guide_end: f64,
}

/// The frame and constraint rows of one contact pair at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactFrame {
    /// P: the contact point (the parcel corner, or the arm tip T) \[m]
    pub point: DVec2,
    /// r = P − G \[m]
    pub r: DVec2,
    /// n: unit normal on the parcel, from the obstacle into the parcel
    pub normal: DVec2,
    /// t = (n_y, −n_x), so that t × n = +ẑ
    pub tangent: DVec2,
    /// g: signed distance, ≥ 0 when apart \[m]
    pub gap: f64,
    /// u_n = ġ: normal relative velocity, exactly the time derivative of `gap` [m/s]
    pub normal_speed: f64,
    /// u_t: relative sliding velocity of the material points along t [m/s]
    pub slip: f64,
    /// Position of P along the obstacle \[m]: arm s = (P − O)·t(α); guide P_x; tip-edge
    /// (T − G)·t, T's position along the edge from its midpoint (−L/2 at corner j, +L/2 at
    /// corner j + 1)
    pub along: f64,
    /// Allowed range of `along` for a real contact \[m]: arm [0, R_z]; guide (−∞, 0];
    /// tip-edge [−L/2, L/2] with L the edge length
    pub extent: (f64, f64),
    /// d(along)/dt: how fast P moves along its obstacle [m/s], exact for every gap (arm:
    /// v_P·t(α) + α̇ (P − O)·n(α); guide: v_P,x; tip-edge: ṙ·t + ω r·(ẑ×t)). Where P sits at
    /// an end of the extent, its sign tells whether P stays on the obstacle or moves off it.
    pub along_rate: f64,
    /// J = [n_x, n_y, r×n]: normal row, ġ = J q̇ + (obstacle terms)
    pub jacobian: [f64; 3],
    /// β with g̈ = J·q̈ − β [m/s²] (a persistent contact has J·q̈ = β)
    pub beta: f64,
    /// J_t = [t_x, t_y, r×t]: tangential row
    pub jacobian_t: [f64; 3],
    /// β_t with u̇_t = J_t·q̈ − β_t [m/s²], exact for every g (stick row J_t q̈ = β_t)
    pub beta_t: f64,
    /// Velocity of the obstacle's material point at P [m/s] (arm: α̇ ẑ×P; guide: 0; tip: Ṫ)
    pub obstacle_velocity: DVec2,
}

impl ContactFrame {
    /// r_t = r·t \[m] (for the mobility matrix W, model.md §5).
    #[inline]
    pub fn r_t(&self) -> f64 {
        self.r.dot(self.tangent)
    }

    /// r_n = r·n \[m] (for the mobility matrix W, model.md §5).
    #[inline]
    pub fn r_n(&self) -> f64 {
        self.r.dot(self.normal)
    }
}

/// t = (n_y, −n_x): the contact tangent with t × n = +ẑ.
#[inline]
fn tangent_of(n: DVec2) -> DVec2 {
    DVec2::new(n.y, -n.x)
}

/// Corner k of the parcel in the frame (index modulo 4).
#[inline]
fn corner_point(k: &Kinematics, corner: u8, (sp, cp): (f64, f64)) -> DVec2 {
    let rho = k.rect.body_corners()[usize::from(corner % 4)];
    k.centre + DVec2::new(cp * rho.x - sp * rho.y, sp * rho.x + cp * rho.y)
}

/// A parcel vertex P against a line through O with contact normal `normal`, rotating at
/// Ω = `rate` with Ω̇ = `accel` (see the module docs for the derivation).
/// `along` is measured along the unit vector `along_dir`, which turns with the line.
#[allow(clippy::too_many_arguments)] // the line's normal, motion and extent, all needed
fn vertex_on_line(
    k: &Kinematics,
    point: DVec2,
    normal: DVec2,
    rate: f64,
    accel: f64,
    along_dir: DVec2,
    along: f64,
    extent: (f64, f64),
) -> ContactFrame {
    let tangent = tangent_of(normal);
    let r = point - k.centre;
    let v_p = k.velocity + k.omega * perp(r);
    // d = P − O with O = (0, 0).
    let d = point;
    let gap = d.dot(normal);
    let s = d.dot(tangent);
    let obstacle_velocity = rate * perp(d);
    let u = v_p - obstacle_velocity;
    let normal_speed = u.dot(normal);
    let slip = u.dot(tangent);
    let w2 = k.omega * k.omega;
    let beta = w2 * r.dot(normal) + 2.0 * rate * v_p.dot(tangent) + accel * s + rate * rate * gap;
    let beta_t = w2 * r.dot(tangent) - rate * v_p.dot(normal) - accel * gap - rate * normal_speed;
    ContactFrame {
        point,
        r,
        normal,
        tangent,
        gap,
        normal_speed,
        slip,
        along,
        extent,
        along_rate: v_p.dot(along_dir) + rate * d.dot(perp(along_dir)),
        jacobian: [normal.x, normal.y, cross(r, normal)],
        beta,
        jacobian_t: [tangent.x, tangent.y, cross(r, tangent)],
        beta_t,
        obstacle_velocity,
    }
}

/// The arm tip T on parcel edge `edge` (see the module docs for the derivation).
fn tip_on_edge(
    k: &Kinematics,
    edge: u8,
    (sp, cp): (f64, f64),
    (sa, ca): (f64, f64),
) -> ContactFrame {
    let t_arm = DVec2::new(ca, sa);
    let n_arm = DVec2::new(-sa, ca);
    let (rz, rate, accel) = (k.arm_length, k.arm.rate, k.arm.accel);
    let tip = rz * t_arm;
    let tip_vel = rz * rate * n_arm;
    let tip_acc = rz * (accel * n_arm - rate * rate * t_arm);

    let (ha, hb) = (0.5 * k.rect.length, 0.5 * k.rect.width);
    // (outward body normal m', half dimension h to the edge, half edge length L/2)
    let (m_body, h, half_len) = match edge % 4 {
        0 => (DVec2::X, ha, hb),
        1 => (DVec2::Y, hb, ha),
        2 => (DVec2::NEG_X, ha, hb),
        _ => (DVec2::NEG_Y, hb, ha),
    };
    let m = DVec2::new(cp * m_body.x - sp * m_body.y, sp * m_body.x + cp * m_body.y);
    let normal = -m;
    let tangent = tangent_of(normal);
    let r = tip - k.centre;
    let r_dot = tip_vel - k.velocity;
    let gap = r.dot(m) - h;
    let u = k.velocity + k.omega * perp(r) - tip_vel;
    let w = k.omega;
    let beta = tip_acc.dot(normal) - 2.0 * w * cross(r_dot, normal) - w * w * r.dot(normal);
    let beta_t = tip_acc.dot(tangent) - 2.0 * w * cross(r_dot, tangent) - w * w * r.dot(tangent);
    ContactFrame {
        point: tip,
        r,
        normal,
        tangent,
        gap,
        normal_speed: u.dot(normal),
        slip: u.dot(tangent),
        along: r.dot(tangent),
        extent: (-half_len, half_len),
        along_rate: r_dot.dot(tangent) + w * r.dot(perp(tangent)),
        jacobian: [normal.x, normal.y, cross(r, normal)],
        beta,
        jacobian_t: [tangent.x, tangent.y, cross(r, tangent)],
        beta_t,
        obstacle_velocity: tip_vel,
    }
}

/// The contact frame, gap, rates and constraint rows of pair `kind` at state `k`.
///
/// Pure and allocation-free; defined for every pair whether or not it is a real contact
/// (check `gap` and [`in_range`]).
pub fn frame(kind: ContactKind, k: &Kinematics) -> ContactFrame {
    frame_with(kind, k, k.angle.sin_cos(), k.arm.angle.sin_cos())
}

/// [`frame`] with (sin φ, cos φ) and (sin α, cos α) given, for callers that have them.
pub fn frame_with(
    kind: ContactKind,
    k: &Kinematics,
    phi_sc: (f64, f64),
    (sa, ca): (f64, f64),
) -> ContactFrame {
    match kind {
        ContactKind::CornerArm { corner, side } => {
            let point = corner_point(k, corner, phi_sc);
            let t_arm = DVec2::new(ca, sa);
            let n_arm = DVec2::new(-sa, ca);
            let normal = if side < 0 { -n_arm } else { n_arm };
            vertex_on_line(
                k,
                point,
                normal,
                k.arm.rate,
                k.arm.accel,
                t_arm,
                point.dot(t_arm),
                (0.0, k.arm_length),
            )
        }
        ContactKind::CornerGuide { corner } => {
            let point = corner_point(k, corner, phi_sc);
            vertex_on_line(
                k,
                point,
                DVec2::Y,
                0.0,
                0.0,
                DVec2::X,
                point.x,
                (f64::NEG_INFINITY, k.guide_end),
            )
        }
        ContactKind::TipEdge { edge } => tip_on_edge(k, edge, phi_sc, (sa, ca)),
    }
}

/// The geometric part of [`frame`] only — (gap, along, extent) — for guards evaluated many
/// times per step.
pub fn gap_and_range(kind: ContactKind, k: &Kinematics) -> (f64, f64, (f64, f64)) {
    gap_and_range_with(kind, k, k.angle.sin_cos(), k.arm.angle.sin_cos())
}

/// [`gap_and_range`] with (sin φ, cos φ) and (sin α, cos α) given, so that a caller
/// evaluating all pairs at one instant computes the trigonometry once.
pub fn gap_and_range_with(
    kind: ContactKind,
    k: &Kinematics,
    (sp, cp): (f64, f64),
    (sa, ca): (f64, f64),
) -> (f64, f64, (f64, f64)) {
    let (ha, hb) = (0.5 * k.rect.length, 0.5 * k.rect.width);
    let corner = |c: u8| {
        let rho = k.rect.body_corners()[(c % 4) as usize];
        k.centre + DVec2::new(cp * rho.x - sp * rho.y, sp * rho.x + cp * rho.y)
    };
    match kind {
        ContactKind::CornerArm { corner: c, side } => {
            let point = corner(c);
            let g = -sa * point.x + ca * point.y;
            let along = ca * point.x + sa * point.y;
            (if side < 0 { -g } else { g }, along, (0.0, k.arm_length))
        }
        ContactKind::CornerGuide { corner: c } => {
            let point = corner(c);
            (point.y, point.x, (f64::NEG_INFINITY, k.guide_end))
        }
        ContactKind::TipEdge { edge } => {
            let b = tip_in_body(k, (sp, cp), (sa, ca));
            match edge % 4 {
                0 => (b.x - ha, b.y, (-hb, hb)),
                1 => (b.y - hb, -b.x, (-ha, ha)),
                2 => (-b.x - ha, -b.y, (-hb, hb)),
                _ => (-b.y - hb, b.x, (-ha, ha)),
            }
        }
    }
}

/// The arm tip in the parcel's body axes (origin G, axes x', y').
#[inline]
fn tip_in_body(k: &Kinematics, (sp, cp): (f64, f64), (sa, ca): (f64, f64)) -> DVec2 {
    let d = k.arm_length * DVec2::new(ca, sa) - k.centre;
    DVec2::new(cp * d.x + sp * d.y, -sp * d.x + cp * d.y)
}

/// Nearest-feature rule for the arm tip (model.md §6, "Nearest"): how far the
/// gap of the tip to edge `edge`'s line falls short of the largest of its four edge gaps
/// \[m]; 0 exactly when that edge's line is the one nearest the tip.
///
/// A tip–edge pair is a contact only between nearest features. Outside the parcel, in an
/// edge's slab, that edge has the largest gap; inside (penetration, or a tip resting on a
/// corner that has just slid past it) the nearest boundary is the edge with the largest gap
/// too. Without this rule a tip sitting on the face that lies along the arm, a hair behind
/// the leading face's line, was taken to touch the *leading* face and struck it with the
/// whole sliding speed (issue "Contacts that hold", fault 1).
pub fn tip_edge_shortfall(edge: u8, k: &Kinematics) -> f64 {
    tip_edge_shortfall_with(edge, k, k.angle.sin_cos(), k.arm.angle.sin_cos())
}

/// [`tip_edge_shortfall`] with the trigonometry given.
pub fn tip_edge_shortfall_with(
    edge: u8,
    k: &Kinematics,
    phi_sc: (f64, f64),
    arm_sc: (f64, f64),
) -> f64 {
    let b = tip_in_body(k, phi_sc, arm_sc);
    let (ha, hb) = (0.5 * k.rect.length, 0.5 * k.rect.width);
    let gaps = [b.x - ha, b.y - hb, -b.x - ha, -b.y - hb];
    let max = gaps.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    max - gaps[usize::from(edge % 4)]
}

/// Whether `along` lies within `extent` (inclusive); false for NaN.
#[inline]
pub fn in_range(f: &ContactFrame) -> bool {
    f.along >= f.extent.0 && f.along <= f.extent.1
}

/// Whether the contact point sits at an end of its obstacle (within `tol` of it, on either
/// side) and moves off it faster than `speed` (model.md §6, "Ends"): a parcel corner passing
/// the arm's tip or its pivot, a corner passing the guide's end, the tip passing round a
/// parcel corner. Such a point is no contact, however fast it approaches the obstacle's
/// line: the line ends where it crosses it. One rule for every pair and both ends.
#[inline]
pub fn leaves_end(f: &ContactFrame, tol: f64, speed: f64) -> bool {
    (f.along >= f.extent.1 - tol && f.along_rate > speed)
        || (f.along <= f.extent.0 + tol && f.along_rate < -speed)
}

/// t(α)·n for a tip–edge frame (n the edge's inward normal): negative when the arm just
/// behind its tip lies inside that edge's half-plane.
///
/// The arm's points T − s t(α) (s ≥ 0) have the edge gap g(T) + s t(α)·n. With the tip on
/// the edge, a negative product puts the arm behind the tip inside the edge's half-plane:
/// the arm cannot touch that edge from outside, it passes the parcel's corner on the other
/// edge's side. At a parcel corner this decides between the corner's two edges where their
/// gaps tie: as the leading corner of a side lying on the arm passes the tip, the arm runs
/// along that side (t·n = 0) and into the leading face's half-plane (t·n = −1), so the tip
/// takes the side and never strikes the leading face.
#[inline]
pub fn arm_into_edge(tip_edge: &ContactFrame) -> f64 {
    // The frame's point is the tip T = R_z t(α).
    tip_edge.point.normalize_or_zero().dot(tip_edge.normal)
}

/// Whether the arm tip is inside the parcel's closed rectangle (all four edge gaps ≤ 0).
pub fn tip_inside(k: &Kinematics) -> bool {
    let tip = k.arm_length * DVec2::new(k.arm.angle.cos(), k.arm.angle.sin());
    // Body coordinates of the tip: one rotation instead of four edge frames.
    let b = rotate(tip - k.centre, -k.angle);
    b.x.abs() <= 0.5 * k.rect.length && b.y.abs() <= 0.5 * k.rect.width
}

/// All candidate pairs: corners 0..3 × arm (face `sides[k]` for corner k), corners 0..3 ×
/// guide, edges 0..3 × tip, in that order.
pub fn candidates(sides: [i8; 4]) -> [ContactKind; 12] {
    use ContactKind::{CornerArm, CornerGuide, TipEdge};
    [
        CornerArm {
            corner: 0,
            side: sides[0],
        },
        CornerArm {
            corner: 1,
            side: sides[1],
        },
        CornerArm {
            corner: 2,
            side: sides[2],
        },
        CornerArm {
            corner: 3,
            side: sides[3],
        },
        CornerGuide { corner: 0 },
        CornerGuide { corner: 1 },
        CornerGuide { corner: 2 },
        CornerGuide { corner: 3 },
        TipEdge { edge: 0 },
        TipEdge { edge: 1 },
        TipEdge { edge: 2 },
        TipEdge { edge: 3 },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use proptest::prelude::*;
    use std::f64::consts::PI;

    /// A parcel in uniformly accelerated motion and an arm with constant α̈, as functions of
    /// time, for finite-difference checks.
    #[derive(Debug, Clone, Copy)]
    struct Motion {
        q0: [f64; 3],
        qd0: [f64; 3],
        qdd: [f64; 3],
        alpha: [f64; 3],
        arm_length: f64,
        rect: Rect,
    }

    impl Motion {
        fn at(&self, t: f64) -> Kinematics {
            let q = |i: usize| self.q0[i] + self.qd0[i] * t + 0.5 * self.qdd[i] * t * t;
            let qd = |i: usize| self.qd0[i] + self.qdd[i] * t;
            let [a0, ad0, add] = self.alpha;
            Kinematics {
                centre: DVec2::new(q(0), q(1)),
                angle: q(2),
                velocity: DVec2::new(qd(0), qd(1)),
                omega: qd(2),
                arm: ArmState {
                    angle: a0 + ad0 * t + 0.5 * add * t * t,
                    rate: ad0 + add * t,
                    accel: add,
                },
                arm_length: self.arm_length,
                rect: self.rect,
                guide_end: 0.0,
            }
        }
    }

    const H: f64 = 1e-4;

    /// Five-point central difference (error O(H⁴)) of a frame quantity at t = 0: the plain
    /// two-point rule's O(H²) error reaches 1e-7 for fast arms and spins, where third
    /// derivatives are ~10³.
    fn fd(m: &Motion, kind: ContactKind, get: fn(&ContactFrame) -> f64) -> f64 {
        let at = |t: f64| get(&frame(kind, &m.at(t)));
        (8.0 * (at(H) - at(-H)) - (at(2.0 * H) - at(-2.0 * H))) / (12.0 * H)
    }

    fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }

    /// |fd − analytic| ≤ 1e-7 × the size of the terms involved (at least 1).
    fn close(fd: f64, analytic: f64, scale: f64) -> Result<(), TestCaseError> {
        let tol = 1e-7 * scale.abs().max(analytic.abs()).max(1.0);
        prop_assert!(
            (fd - analytic).abs() <= tol,
            "fd {fd} vs analytic {analytic} (tol {tol})"
        );
        Ok(())
    }

    /// Checks ġ = normal_speed, d(along)/dt = along_rate, d(normal_speed)/dt = J q̈ − β and
    /// du_t/dt = J_t q̈ − β_t.
    fn check_rates(m: &Motion, kind: ContactKind) -> Result<(), TestCaseError> {
        let f = frame(kind, &m.at(0.0));
        close(fd(m, kind, |f| f.gap), f.normal_speed, f.normal_speed)?;
        close(fd(m, kind, |f| f.along), f.along_rate, f.along_rate)?;
        let jq = dot3(f.jacobian, m.qdd);
        close(
            fd(m, kind, |f| f.normal_speed),
            jq - f.beta,
            jq.abs() + f.beta.abs(),
        )?;
        let jq_t = dot3(f.jacobian_t, m.qdd);
        close(
            fd(m, kind, |f| f.slip),
            jq_t - f.beta_t,
            jq_t.abs() + f.beta_t.abs(),
        )?;
        Ok(())
    }

    /// Independent restatement of the definitions: u from the material point velocities,
    /// a unit normal, t × n = +ẑ, J and J_t from r.
    fn check_definitions(k: &Kinematics, kind: ContactKind) -> Result<(), TestCaseError> {
        let f = frame(kind, k);
        let v_parcel = k.velocity + k.omega * perp(f.point - k.centre);
        let u = v_parcel - f.obstacle_velocity;
        prop_assert!((f.r - (f.point - k.centre)).length() < 1e-12);
        prop_assert!((f.normal.length() - 1.0).abs() < 1e-12);
        prop_assert!((cross(f.tangent, f.normal) - 1.0).abs() < 1e-12);
        prop_assert!((u.dot(f.normal) - f.normal_speed).abs() < 1e-12 * (1.0 + u.length()));
        prop_assert!((u.dot(f.tangent) - f.slip).abs() < 1e-12 * (1.0 + u.length()));
        let j = [f.normal.x, f.normal.y, cross(f.r, f.normal)];
        let jt = [f.tangent.x, f.tangent.y, cross(f.r, f.tangent)];
        for i in 0..3 {
            prop_assert_eq!(f.jacobian[i], j[i]);
            prop_assert_eq!(f.jacobian_t[i], jt[i]);
        }
        Ok(())
    }

    fn all_kinds() -> [ContactKind; 16] {
        let a = candidates([1, 1, 1, 1]);
        let b = candidates([-1, -1, -1, -1]);
        [
            a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3], a[4], a[5], a[6], a[7], a[8], a[9],
            a[10], a[11],
        ]
    }

    prop_compose! {
        fn arb_motion()(
            x in -1.0..1.5f64, y in -1.0..1.5f64, phi in -PI..PI,
            vx in -3.0..3.0f64, vy in -3.0..3.0f64, w in -6.0..6.0f64,
            ax in -20.0..20.0f64, ay in -20.0..20.0f64, aw in -50.0..50.0f64,
            a0 in -0.5..1.8f64, ad0 in -4.0..4.0f64, add in -30.0..30.0f64,
            rz in 0.3..1.5f64, la in 0.05..0.8f64, lb in 0.05..0.8f64,
        ) -> Motion {
            Motion {
                q0: [x, y, phi],
                qd0: [vx, vy, w],
                qdd: [ax, ay, aw],
                alpha: [a0, ad0, add],
                arm_length: rz,
                rect: Rect { length: la, width: lb },
            }
        }
    }

    /// Place the parcel so that the pair `kind` touches (g = 0) at position `frac` ∈ [0, 1]
    /// of its extent (the guide at x = −2·frac).
    fn touching(m: &Motion, kind: ContactKind, frac: f64) -> Motion {
        let k = m.at(0.0);
        let (sa, ca) = k.arm.angle.sin_cos();
        let t_arm = DVec2::new(ca, sa);
        let rho_world = |c: u8| rotate(k.rect.body_corners()[usize::from(c)], k.angle);
        let g = match kind {
            ContactKind::CornerArm { corner, .. } => {
                frac * k.arm_length * t_arm - rho_world(corner)
            }
            ContactKind::CornerGuide { corner } => DVec2::new(-2.0 * frac, 0.0) - rho_world(corner),
            ContactKind::TipEdge { edge } => {
                let f = frame(kind, &k);
                let (lo, hi) = f.extent;
                let along = lo + frac * (hi - lo);
                let h = if edge % 2 == 0 {
                    0.5 * k.rect.length
                } else {
                    0.5 * k.rect.width
                };
                // T = G + h m + along t, with m = −n.
                f.point + h * f.normal - along * f.tangent
            }
        };
        Motion {
            q0: [g.x, g.y, m.q0[2]],
            ..*m
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        /// Every pair, random states: ġ, g̈ and u̇_t match finite differences; u, n, t, J are
        /// the stated definitions.
        #[test]
        fn rates_match_finite_differences(m in arb_motion()) {
            for kind in all_kinds() {
                check_rates(&m, kind)?;
                check_definitions(&m.at(0.0), kind)?;
            }
        }

        /// Pairs placed in contact (g = 0, in range): the same rate checks, `along` is where
        /// the pair was placed, and the gap is zero.
        #[test]
        fn touching_pairs(m in arb_motion(), frac in 0.0..1.0f64) {
            for kind in all_kinds() {
                let mt = touching(&m, kind, frac);
                let k = mt.at(0.0);
                let f = frame(kind, &k);
                prop_assert!(f.gap.abs() < 1e-12, "{kind:?}: gap {}", f.gap);
                prop_assert!(in_range(&f), "{kind:?}: along {} extent {:?}", f.along, f.extent);
                let expect = match kind {
                    ContactKind::CornerArm { .. } => frac * k.arm_length,
                    ContactKind::CornerGuide { .. } => -2.0 * frac,
                    ContactKind::TipEdge { .. } => f.extent.0 + frac * (f.extent.1 - f.extent.0),
                };
                prop_assert!((f.along - expect).abs() < 1e-12);
                check_rates(&mt, kind)?;
            }
        }

        /// Persistent contact (g = 0 and ġ = 0): β_t reduces to the closed-form stick row
        /// φ̇²(r·t) − Ω(v_P·n) for vertex–line pairs (model.md §6).
        #[test]
        fn persistent_vertex_stick_row_matches_the_closed_form(m in arb_motion(), frac in 0.0..1.0f64) {
            for kind in &all_kinds()[..12] {
                let mut mt = touching(&m, *kind, frac);
                let f0 = frame(*kind, &mt.at(0.0));
                // Cancel the approach speed by moving G along n.
                mt.qd0[0] -= f0.normal_speed * f0.normal.x;
                mt.qd0[1] -= f0.normal_speed * f0.normal.y;
                let k = mt.at(0.0);
                let f = frame(*kind, &k);
                prop_assert!(f.normal_speed.abs() < 1e-12);
                let big_omega = match kind {
                    ContactKind::CornerArm { .. } => k.arm.rate,
                    _ => 0.0,
                };
                let v_p = k.velocity + k.omega * perp(f.r);
                let beta_t = k.omega * k.omega * f.r.dot(f.tangent) - big_omega * v_p.dot(f.normal);
                prop_assert!((f.beta_t - beta_t).abs() < 1e-10 * (1.0 + beta_t.abs()));
                // And u_t = v_P·t on contact.
                prop_assert!((f.slip - v_p.dot(f.tangent)).abs() < 1e-11 * (1.0 + v_p.length()));
            }
        }

        /// The tip is inside exactly when all four tip–edge gaps are ≤ 0; gaps are signed
        /// distances (the foot point T + g n lies on the edge line).
        #[test]
        fn tip_inside_matches_edge_gaps(m in arb_motion()) {
            let k = m.at(0.0);
            let mut all_le0 = true;
            for edge in 0..4u8 {
                let f = frame(ContactKind::TipEdge { edge }, &k);
                all_le0 &= f.gap <= 0.0;
                let h = if edge % 2 == 0 { 0.5 * k.rect.length } else { 0.5 * k.rect.width };
                let foot = f.point + f.gap * f.normal;
                prop_assert!(((foot - k.centre).dot(-f.normal) - h).abs() < 1e-12);
            }
            prop_assert_eq!(tip_inside(&k), all_le0);
        }

        /// The two arm faces are the same line seen from opposite sides.
        #[test]
        fn arm_faces_are_mirror_images(m in arb_motion()) {
            let k = m.at(0.0);
            for corner in 0..4u8 {
                let p = frame(ContactKind::CornerArm { corner, side: 1 }, &k);
                let b = frame(ContactKind::CornerArm { corner, side: -1 }, &k);
                prop_assert!((p.gap + b.gap).abs() < 1e-14);
                prop_assert!((p.normal_speed + b.normal_speed).abs() < 1e-12);
                prop_assert!((p.slip + b.slip).abs() < 1e-12);
                prop_assert!((p.beta + b.beta).abs() < 1e-9 * (1.0 + p.beta.abs()));
                prop_assert_eq!(p.along, b.along);
                prop_assert_eq!(p.obstacle_velocity, b.obstacle_velocity);
            }
        }
    }

    fn still(centre: DVec2, rect: Rect, alpha: f64) -> Kinematics {
        Kinematics {
            centre,
            angle: 0.0,
            velocity: DVec2::ZERO,
            omega: 0.0,
            arm: ArmState {
                angle: alpha,
                rate: 0.0,
                accel: 0.0,
            },
            arm_length: 1.0,
            rect,
            guide_end: 0.0,
        }
    }

    /// Parcel flush on the retracted arm: bottom side on y = 0, x ∈ [0.2, 0.6].
    #[test]
    fn flush_on_retracted_arm() {
        let rect = Rect {
            length: 0.4,
            width: 0.3,
        };
        let k = still(DVec2::new(0.4, 0.15), rect, 0.0);
        for (corner, gap, along) in [(0u8, 0.0, 0.6), (1, 0.3, 0.6), (2, 0.3, 0.2), (3, 0.0, 0.2)] {
            let f = frame(ContactKind::CornerArm { corner, side: 1 }, &k);
            assert_relative_eq!(f.gap, gap, epsilon = 1e-15);
            assert_relative_eq!(f.along, along, epsilon = 1e-15);
            assert!(in_range(&f));
            assert_eq!(f.normal, DVec2::Y);
            assert_eq!(f.tangent, DVec2::X);
            // The same corners are on the guide's line, but downstream of the pivot.
            let g = frame(ContactKind::CornerGuide { corner }, &k);
            assert_relative_eq!(g.gap, gap, epsilon = 1e-15);
            assert!(!in_range(&g));
        }
        // Seen from the back face the parcel is on the wrong side.
        let b = frame(
            ContactKind::CornerArm {
                corner: 1,
                side: -1,
            },
            &k,
        );
        assert_relative_eq!(b.gap, -0.3, epsilon = 1e-15);
        assert_eq!(b.normal, DVec2::NEG_Y);
    }

    /// Parcel under the retracted arm touches it with its top corners on the back face.
    #[test]
    fn back_face_contact() {
        let rect = Rect {
            length: 0.4,
            width: 0.2,
        };
        let mut k = still(DVec2::new(0.5, -0.1), rect, 0.0);
        k.velocity = DVec2::new(0.7, 0.4);
        k.arm.rate = 2.0;
        for corner in [1u8, 2] {
            let f = frame(ContactKind::CornerArm { corner, side: -1 }, &k);
            assert_relative_eq!(f.gap, 0.0, epsilon = 1e-15);
            assert!(in_range(&f));
            let x = f.point.x;
            // Arm point velocity α̇ x ŷ, parcel (0.7, 0.4); n = −ŷ, t = (−1, 0).
            assert_relative_eq!(f.normal_speed, -(0.4 - 2.0 * x), epsilon = 1e-15);
            assert_relative_eq!(f.slip, -0.7, epsilon = 1e-15);
            assert_eq!(f.obstacle_velocity, DVec2::new(0.0, 2.0 * x));
        }
    }

    fn oracle_case(
        rect: Rect,
        alpha_deg: f64,
        rate: f64,
        s_c: f64,
        v: f64,
    ) -> (ContactFrame, Kinematics) {
        let alpha = alpha_deg.to_radians();
        let p = s_c * DVec2::new(alpha.cos(), alpha.sin());
        // Corner 0 = (x_max, y_min) at φ = 0.
        let centre = p - rect.body_corners()[0];
        let k = Kinematics {
            centre,
            angle: 0.0,
            velocity: DVec2::new(v, 0.0),
            omega: 0.0,
            arm: ArmState {
                angle: alpha,
                rate,
                accel: 0.0,
            },
            arm_length: 1.0,
            rect,
            guide_end: 0.0,
        };
        (frame(ContactKind::CornerArm { corner: 0, side: 1 }, &k), k)
    }

    /// The reference strikes P1 and P2 of a parcel on the arm, model.md §5 (6 decimals:
    /// tolerance 5e-7).
    #[test]
    fn oracle_p1_p2_package_on_arm() {
        let cases = [
            (
                Rect {
                    length: 0.4,
                    width: 0.26,
                },
                30.0,
                1.5,
                0.6,
                2.0,
                [0.108205, -0.212583, 1.732051, -1.9],
            ),
            (
                Rect {
                    length: 0.7,
                    width: 0.1,
                },
                20.0,
                1.7,
                0.8,
                0.65,
                [0.311791, -0.166692, 0.610800, -1.582313],
            ),
        ];
        for (rect, a, rate, s_c, v, [rt, rn, ut, un]) in cases {
            let (f, k) = oracle_case(rect, a, rate, s_c, v);
            assert_relative_eq!(f.gap, 0.0, epsilon = 1e-15);
            assert_relative_eq!(f.along, s_c, epsilon = 1e-15);
            assert!(in_range(&f));
            assert_relative_eq!(f.r_t(), rt, epsilon = 5e-7);
            assert_relative_eq!(f.r_n(), rn, epsilon = 5e-7);
            assert_relative_eq!(f.slip, ut, epsilon = 5e-7);
            assert_relative_eq!(f.normal_speed, un, epsilon = 5e-7);
            // Closed forms of the first strike (model.md §5).
            let al = a.to_radians();
            assert_relative_eq!(f.slip, v * al.cos(), epsilon = 1e-14);
            assert_relative_eq!(
                f.normal_speed,
                -(v * al.sin() + s_c * rate),
                epsilon = 1e-14
            );
            // The struck corner is the only one touching; the others are on the parcel side.
            for corner in 1..4u8 {
                assert!(frame(ContactKind::CornerArm { corner, side: 1 }, &k).gap > 0.0);
            }
        }
    }

    /// Corner on the guide at x ≤ 0: n = (0, 1), t = (1, 0), obstacle at rest.
    #[test]
    fn guide_frame() {
        let rect = Rect {
            length: 0.4,
            width: 0.2,
        };
        let mut k = still(DVec2::new(-0.5, 0.1 + 0.01), rect, 0.7);
        k.velocity = DVec2::new(1.2, -0.3);
        k.omega = 2.0;
        k.arm.rate = 3.0;
        let f = frame(ContactKind::CornerGuide { corner: 3 }, &k);
        // Corner 3 = (−0.7, 0.01); r = (−0.2, −0.1).
        assert_relative_eq!(f.point.x, -0.7, epsilon = 1e-15);
        assert_relative_eq!(f.gap, 0.01, epsilon = 1e-15);
        assert_relative_eq!(f.along, -0.7, epsilon = 1e-15);
        assert!(in_range(&f));
        assert_eq!(f.extent, (f64::NEG_INFINITY, 0.0));
        assert_eq!(f.normal, DVec2::Y);
        assert_eq!(f.tangent, DVec2::X);
        assert_eq!(f.obstacle_velocity, DVec2::ZERO);
        // v_P = v_G + ω ẑ×r = (1.2 + 0.2, −0.3 − 0.4).
        assert_relative_eq!(f.normal_speed, -0.7, epsilon = 1e-14);
        assert_relative_eq!(f.slip, 1.4, epsilon = 1e-14);
        // β = ω² r_y, β_t = ω² r_x (no guide rotation).
        assert_relative_eq!(f.beta, 4.0 * -0.1, epsilon = 1e-14);
        assert_relative_eq!(f.beta_t, 4.0 * -0.2, epsilon = 1e-14);
        assert_eq!(f.jacobian, [0.0, 1.0, cross(f.r, DVec2::Y)]);
        // A corner downstream of the pivot is out of the guide's range.
        k.centre.x = 0.5;
        assert!(!in_range(&frame(
            ContactKind::CornerGuide { corner: 3 },
            &k
        )));
    }

    #[test]
    fn tip_inside_and_outside() {
        let rect = Rect {
            length: 0.4,
            width: 0.3,
        };
        // Tip at (1, 0) with α = 0 and R_z = 1.
        assert!(tip_inside(&still(DVec2::new(1.0, 0.1), rect, 0.0)));
        // On the bottom edge: the closed rectangle contains it.
        assert!(tip_inside(&still(DVec2::new(1.0, 0.15), rect, 0.0)));
        assert!(!tip_inside(&still(DVec2::new(1.0, 0.16), rect, 0.0)));
        assert!(!tip_inside(&still(DVec2::new(1.21, 0.0), rect, 0.0)));
        // Rotated parcel: tip near a long edge; inside at φ = 0, outside at φ = 90°.
        let mut k = still(DVec2::new(1.18, 0.0), rect, 0.0);
        assert!(tip_inside(&k));
        k.angle = 0.5 * PI;
        assert!(!tip_inside(&k));
    }

    /// Tip on edge 1 (+b/2 side) of a parcel below the arm tip, at φ = 0.
    #[test]
    fn tip_edge_frame() {
        let rect = Rect {
            length: 0.4,
            width: 0.3,
        };
        let mut k = still(DVec2::new(1.1, -0.15), rect, 0.0);
        k.arm.rate = 2.0;
        k.velocity = DVec2::new(0.5, 0.0);
        let f = frame(ContactKind::TipEdge { edge: 1 }, &k);
        assert_eq!(f.point, DVec2::new(1.0, 0.0));
        assert_relative_eq!(f.gap, 0.0, epsilon = 1e-15);
        assert_eq!(f.normal, DVec2::NEG_Y);
        assert_eq!(f.tangent, DVec2::NEG_X);
        // T is 0.1 to the left of the edge midpoint; t points to −x (CCW along the top edge).
        assert_relative_eq!(f.along, 0.1, epsilon = 1e-15);
        assert_eq!(f.extent, (-0.2, 0.2));
        assert!(in_range(&f));
        // Ṫ = R_z α̇ n(0) = (0, 2): the tip lifts off the parcel below it, u_n = +2.
        assert_eq!(f.obstacle_velocity, DVec2::new(0.0, 2.0));
        assert_relative_eq!(f.normal_speed, 2.0, epsilon = 1e-15);
        assert_relative_eq!(f.slip, -0.5, epsilon = 1e-15);
        // T̈ = −R_z α̇² t(0) = (−4, 0): β = T̈·n = 0, β_t = T̈·t = 4.
        assert_relative_eq!(f.beta, 0.0, epsilon = 1e-15);
        assert_relative_eq!(f.beta_t, 4.0, epsilon = 1e-15);
        // The other edges are apart (gap ≥ 0 means apart, signed).
        assert_relative_eq!(
            frame(ContactKind::TipEdge { edge: 3 }, &k).gap,
            -0.3,
            epsilon = 1e-15
        );
        assert_relative_eq!(
            frame(ContactKind::TipEdge { edge: 0 }, &k).gap,
            -0.3,
            epsilon = 1e-15
        );
        assert_relative_eq!(
            frame(ContactKind::TipEdge { edge: 2 }, &k).gap,
            -0.1,
            epsilon = 1e-15
        );
    }

    #[test]
    fn in_range_is_inclusive_and_rejects_nan() {
        let rect = Rect {
            length: 0.4,
            width: 0.3,
        };
        let k = still(DVec2::new(0.4, 0.15), rect, 0.0);
        let mut f = frame(ContactKind::CornerArm { corner: 0, side: 1 }, &k);
        for (along, ok) in [
            (0.0, true),
            (1.0, true),
            (-1e-12, false),
            (1.0 + 1e-12, false),
            (f64::NAN, false),
        ] {
            f.along = along;
            assert_eq!(in_range(&f), ok, "along {along}");
        }
    }

    #[test]
    fn candidates_order_and_wrapping_indices() {
        let c = candidates([1, -1, 1, -1]);
        assert_eq!(
            c[1],
            ContactKind::CornerArm {
                corner: 1,
                side: -1
            }
        );
        assert_eq!(c[6], ContactKind::CornerGuide { corner: 2 });
        assert_eq!(c[11], ContactKind::TipEdge { edge: 3 });
        // Out-of-range indices wrap instead of panicking.
        let k = still(
            DVec2::new(0.4, 0.15),
            Rect {
                length: 0.4,
                width: 0.3,
            },
            0.3,
        );
        assert_eq!(
            frame(ContactKind::CornerArm { corner: 5, side: 0 }, &k),
            frame(ContactKind::CornerArm { corner: 1, side: 1 }, &k)
        );
        assert_eq!(
            frame(ContactKind::TipEdge { edge: 6 }, &k),
            frame(ContactKind::TipEdge { edge: 2 }, &k)
        );
    }

    /// The cheap geometric evaluation agrees with the full frame.
    #[test]
    fn gap_and_range_matches_frame() {
        let rect = Rect {
            length: 0.43,
            width: 0.17,
        };
        for i in 0..400 {
            let f = i as f64;
            let k = Kinematics {
                centre: DVec2::new((f * 0.37).sin() * 0.8, 0.3 + (f * 0.11).cos() * 0.3),
                angle: (f * 0.7).sin() * 3.0,
                velocity: DVec2::new(1.0, 0.2),
                omega: 0.4,
                arm: ArmState {
                    angle: (f * 0.23).sin().abs() * 0.9,
                    rate: 1.1,
                    accel: 2.0,
                },
                arm_length: 1.0,
                rect,
                guide_end: 0.0,
            };
            for kind in candidates([1, -1, 1, -1]) {
                let fr = frame(kind, &k);
                let (g, along, extent) = gap_and_range(kind, &k);
                assert!((g - fr.gap).abs() < 1e-12, "{kind:?} gap {g} vs {}", fr.gap);
                assert!(
                    (along - fr.along).abs() < 1e-12,
                    "{kind:?} along {along} vs {}",
                    fr.along
                );
                assert_eq!(extent, fr.extent, "{kind:?}");
            }
        }
    }
}
