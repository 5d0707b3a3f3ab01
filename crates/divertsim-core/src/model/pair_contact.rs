//! Contact kinematics between two free parcels (docs/model.md §6a): a corner of parcel A on
//! an edge of parcel B, both moving. The gap, its rate, the slip, the contact frame, and the
//! acceleration-level rows over both bodies' coordinates q = (x_A, y_A, φ_A, x_B, y_B, φ_B):
//! g̈ = J q̈ − β (normal) and u̇_t = J_t q̈ − β_t (stick).
//!
//! A's side is a [`ContactFrame`], the frame of a contact with a moving obstacle (B's
//! material point at P): its geometry and rates read as any contact's. Its β and β_t are
//! the pair's: B's accelerations enter through B's columns (`jacobian_b`), not through β as
//! a driven arm's Ω̇ does, so a row over A alone would drop them.
//!
//! Conventions as for the arm and the guide ([`crate::model::contact`]): n is the unit
//! normal on A, from B into A (B's edge's outward normal m); t = (n_y, −n_x); u = v_A(P) −
//! v_B(P), the velocities of the two material points at the contact point P (A's corner);
//! u_n = u·n (approaching when < 0), u_t = u·t.
//!
//! # Derivation
//!
//! With r_A = P − G_A, r_B = P − G_B, h the half dimension of B to the edge and
//! g = r_B·m − h: m rotates with B (ṁ = ω_B ẑ×m) and P is A's material point, so
//! ṙ_B = v_A(P) − v_B and ġ = (v_A(P) − v_B − ω_B ẑ×r_B)·m = u·n = u_n, exact for every g.
//! Differentiating u = v_A + ω_A ẑ×r_A − v_B − ω_B ẑ×r_B once more, with
//! ṙ_A = ω_A ẑ×r_A, ṙ_B = u + ω_B ẑ×r_B and ṅ = ω_B ẑ×n, ṫ = ω_B n:
//! - g̈ = J q̈ − β with J = [n, r_A×n, −n, −r_B×n] and
//!   β = ω_A² (r_A·n) − ω_B² (r_B·n) + 2 ω_B u_t;
//! - u̇_t = J_t q̈ − β_t with J_t = [t, r_A×t, −t, −r_B×t] and
//!   β_t = ω_A² (r_A·t) − ω_B² (r_B·t) − 2 ω_B u_n.
//!
//! With B the arm (turning about O at Ω = α̇, its acceleration terms known), these are the
//! arm's rows of [`crate::model::contact`]: 2Ω u_t = 2Ω v_P·t + 2Ω² g gives its
//! β = φ̇²(r·n) + 2Ω v_P·t + Ω² g + Ω̇ s. The tests check every formula against central
//! finite differences of the bodies' own motion.

use glam::DVec2;

use crate::geometry::{cross, perp, rotate, Rect};
use crate::model::active_set::Row;
use crate::model::contact::ContactFrame;

/// A free parcel's pose and velocity in the plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoxState {
    /// G: centre \[m]
    pub centre: DVec2,
    /// φ: orientation, CCW from x to the body x' axis \[rad]
    pub angle: f64,
    /// v_G [m/s]
    pub velocity: DVec2,
    /// ω = φ̇ [rad/s]
    pub omega: f64,
    /// a × b: footprint
    pub rect: Rect,
}

impl BoxState {
    /// The velocity of its material point at p: v_G + ω ẑ×(p − G).
    pub fn velocity_at(&self, p: DVec2) -> DVec2 {
        self.velocity + self.omega * perp(p - self.centre)
    }
}

/// The frame and constraint rows of one corner–edge pair of two parcels at one instant: A's
/// side as the frame of a contact with a moving obstacle (B's material point at P, whose
/// velocity is `on_a.obstacle_velocity`), and B's columns of the rows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairFrame {
    /// The contact as A sees it: P (A's corner), r_A, n (B's edge's outward normal, on A
    /// from B into A), t, g, u_n = ġ, u_t, P's place along B's edge from its midpoint
    /// (r_B·t, within ±L/2; its rate is u_t), A's columns of the rows, and the pair's β, β_t
    /// (to be used with B's columns: g̈ = J q̈ − β over both bodies)
    pub on_a: ContactFrame,
    /// r_B = P − G_B \[m]
    pub r_b: DVec2,
    /// B's columns of J: [−n, −r_B×n]
    pub jacobian_b: [f64; 3],
    /// B's columns of J_t: [−t, −r_B×t]
    pub jacobian_t_b: [f64; 3],
}

impl PairFrame {
    /// J over q = (x_A, y_A, φ_A, x_B, y_B, φ_B): g̈ = J q̈ − β.
    pub fn jacobian(&self) -> [f64; 6] {
        let (a, b) = (self.on_a.jacobian, self.jacobian_b);
        [a[0], a[1], a[2], b[0], b[1], b[2]]
    }

    /// J_t over q: u̇_t = J_t q̈ − β_t.
    pub fn jacobian_t(&self) -> [f64; 6] {
        let (a, b) = (self.on_a.jacobian_t, self.jacobian_t_b);
        [a[0], a[1], a[2], b[0], b[1], b[2]]
    }

    /// The pair's row in a group of D / 3 bodies where A is body `a` and B body `b` (A's
    /// columns at 3a, B's at 3b, zero elsewhere), with Coulomb coefficient `friction`: what
    /// the active set of several parcels solves with ([`crate::model::active_set::Row`]).
    pub fn row<const D: usize>(&self, a: usize, b: usize, friction: f64) -> Row<D> {
        assert!(a != b, "a pair is two bodies");
        let mut normal = [0.0; D];
        let mut tangent = [0.0; D];
        normal[3 * a..3 * a + 3].copy_from_slice(&self.on_a.jacobian);
        normal[3 * b..3 * b + 3].copy_from_slice(&self.jacobian_b);
        tangent[3 * a..3 * a + 3].copy_from_slice(&self.on_a.jacobian_t);
        tangent[3 * b..3 * b + 3].copy_from_slice(&self.jacobian_t_b);
        Row {
            normal,
            beta: self.on_a.beta,
            tangent,
            beta_t: self.on_a.beta_t,
            friction,
            slip: self.on_a.slip,
        }
    }
}

/// The outward body normal m', the half dimension h to the edge and the half length L/2 of
/// edge `edge` (edge j joins corners j and j + 1: 0 the +a/2 side, 1 +b/2, 2 −a/2, 3 −b/2).
fn edge_geometry(rect: &Rect, edge: u8) -> (DVec2, f64, f64) {
    let (ha, hb) = (0.5 * rect.length, 0.5 * rect.width);
    match edge % 4 {
        0 => (DVec2::X, ha, hb),
        1 => (DVec2::Y, hb, ha),
        2 => (DVec2::NEG_X, ha, hb),
        _ => (DVec2::NEG_Y, hb, ha),
    }
}

/// Corner `corner` of A on edge `edge` of B (indices wrap modulo 4, as
/// [`crate::model::contact::ContactKind`]'s): defined for every pair whether or not it is
/// a real contact (check `gap` and `extent`).
pub fn corner_on_edge(a: &BoxState, corner: u8, b: &BoxState, edge: u8) -> PairFrame {
    let point = a.centre + rotate(a.rect.body_corners()[usize::from(corner % 4)], a.angle);
    let (m_body, h, half_len) = edge_geometry(&b.rect, edge);
    let normal = rotate(m_body, b.angle);
    let tangent = DVec2::new(normal.y, -normal.x);
    let (r_a, r_b) = (point - a.centre, point - b.centre);
    let u = a.velocity_at(point) - b.velocity_at(point);
    let (normal_speed, slip) = (u.dot(normal), u.dot(tangent));
    let (wa2, wb) = (a.omega * a.omega, b.omega);
    PairFrame {
        on_a: ContactFrame {
            point,
            r: r_a,
            normal,
            tangent,
            gap: r_b.dot(normal) - h,
            normal_speed,
            slip,
            along: r_b.dot(tangent),
            extent: (-half_len, half_len),
            along_rate: slip,
            jacobian: [normal.x, normal.y, cross(r_a, normal)],
            beta: wa2 * r_a.dot(normal) - wb * wb * r_b.dot(normal) + 2.0 * wb * slip,
            jacobian_t: [tangent.x, tangent.y, cross(r_a, tangent)],
            beta_t: wa2 * r_a.dot(tangent) - wb * wb * r_b.dot(tangent) - 2.0 * wb * normal_speed,
            obstacle_velocity: b.velocity_at(point),
        },
        r_b,
        jacobian_b: [-normal.x, -normal.y, -cross(r_b, normal)],
        jacobian_t_b: [-tangent.x, -tangent.y, -cross(r_b, tangent)],
    }
}

/// How far B's edge `edge` falls short of being the edge line nearest A's corner `corner`
/// \[m]: max_j g_j − g_edge over the corner's gaps g_j to B's four edge lines, 0 exactly
/// when that edge is the nearest. As for the arm's tip on a parcel's edge
/// ([`crate::model::contact::tip_edge_shortfall`], docs/model.md §6, "Nearest"): outside B,
/// in an edge's slab, that edge has the largest gap; inside, the nearest boundary does.
pub fn corner_edge_shortfall(a: &BoxState, corner: u8, b: &BoxState, edge: u8) -> f64 {
    let point = a.centre + rotate(a.rect.body_corners()[usize::from(corner % 4)], a.angle);
    let p = rotate(point - b.centre, -b.angle);
    let (ha, hb) = (0.5 * b.rect.length, 0.5 * b.rect.width);
    let gaps = [p.x - ha, p.y - hb, -p.x - ha, -p.y - hb];
    let max = gaps.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    max - gaps[usize::from(edge % 4)]
}

/// The smaller of d·m over A's two edges at its corner `corner` (d a unit vector from the
/// corner into A along the edge, m the outward normal of B's edge `edge`): negative when A's
/// body next to the corner lies inside that edge's half-plane, so that the corner cannot
/// touch the edge from outside; 0 for a side of A flush with the edge. As for the arm
/// behind its tip ([`crate::model::contact::arm_into_edge`], docs/model.md §6, "Touchable").
pub fn corner_into_edge(a: &BoxState, corner: u8, b: &BoxState, edge: u8) -> f64 {
    let corners = a.rect.body_corners();
    let k = usize::from(corner % 4);
    let (here, before, after) = (corners[k], corners[(k + 3) % 4], corners[(k + 1) % 4]);
    let (m_body, _, _) = edge_geometry(&b.rect, edge);
    // m in A's body axes: one rotation instead of two.
    let m = rotate(m_body, b.angle - a.angle);
    let d1 = (before - here).normalize();
    let d2 = (after - here).normalize();
    d1.dot(m).min(d2.dot(m))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box moving with constant accelerations (a_G, ω̇) from its state at t = 0.
    fn at(s: &BoxState, acc: DVec2, alpha: f64, t: f64) -> BoxState {
        BoxState {
            centre: s.centre + s.velocity * t + 0.5 * acc * t * t,
            angle: s.angle + s.omega * t + 0.5 * alpha * t * t,
            velocity: s.velocity + acc * t,
            omega: s.omega + alpha * t,
            rect: s.rect,
        }
    }

    /// ġ = u_n, the rate of P along the edge, g̈ = J q̈ − β and u̇_t = J_t q̈ − β_t, by
    /// central differences of the two bodies' own motion, over many poses, velocities and
    /// accelerations, every corner on every edge.
    #[test]
    fn pair_rows_match_finite_differences_of_the_motion() {
        let mut rng = crate::stats::splitmix::SplitMix64(6);
        let mut u = |lo: f64, hi: f64| lo + (hi - lo) * rng.next_f64();
        let mut checked = 0;
        for _ in 0..200 {
            let body = |u: &mut dyn FnMut(f64, f64) -> f64| BoxState {
                centre: DVec2::new(u(-1.0, 1.0), u(-1.0, 1.0)),
                angle: u(-3.0, 3.0),
                velocity: DVec2::new(u(-3.0, 3.0), u(-3.0, 3.0)),
                omega: u(-6.0, 6.0),
                rect: Rect {
                    length: u(0.1, 0.8),
                    width: u(0.05, 0.5),
                },
            };
            let (a, b) = (body(&mut u), body(&mut u));
            let (acc_a, alpha_a) = (DVec2::new(u(-20.0, 20.0), u(-20.0, 20.0)), u(-50.0, 50.0));
            let (acc_b, alpha_b) = (DVec2::new(u(-20.0, 20.0), u(-20.0, 20.0)), u(-50.0, 50.0));
            let q_dd = [acc_a.x, acc_a.y, alpha_a, acc_b.x, acc_b.y, alpha_b];
            // First derivatives over ±1e-5 s, the second over ±1e-4 s: truncation stays
            // below the tolerances at the largest rates drawn (ω 6 rad/s, ω̇ 50 rad/s²).
            let (h1, h) = (1e-5, 1e-4);
            for corner in 0..4 {
                for edge in 0..4 {
                    let f = |t: f64| {
                        corner_on_edge(
                            &at(&a, acc_a, alpha_a, t),
                            corner,
                            &at(&b, acc_b, alpha_b, t),
                            edge,
                        )
                    };
                    let (minus, zero, plus) = (f(-h), f(0.0), f(h));
                    let (near_minus, near_plus) = (f(-h1), f(h1));
                    let dot = |row: [f64; 6]| row.iter().zip(q_dd).map(|(j, q)| j * q).sum::<f64>();
                    let rate = (near_plus.on_a.gap - near_minus.on_a.gap) / (2.0 * h1);
                    assert!(
                        (rate - zero.on_a.normal_speed).abs() < 1e-6 * (1.0 + rate.abs()),
                        "{rate} vs {}",
                        zero.on_a.normal_speed
                    );
                    let along = (near_plus.on_a.along - near_minus.on_a.along) / (2.0 * h1);
                    let along_rate = zero.on_a.along_rate;
                    assert!((along - along_rate).abs() < 1e-6 * (1.0 + along.abs()));
                    let g_dd = (plus.on_a.gap - 2.0 * zero.on_a.gap + minus.on_a.gap) / (h * h);
                    let want = dot(zero.jacobian()) - zero.on_a.beta;
                    assert!(
                        (g_dd - want).abs() < 1e-4 * (1.0 + want.abs()),
                        "{g_dd} vs {want}"
                    );
                    let ut_d = (near_plus.on_a.slip - near_minus.on_a.slip) / (2.0 * h1);
                    let want_t = dot(zero.jacobian_t()) - zero.on_a.beta_t;
                    assert!(
                        (ut_d - want_t).abs() < 1e-5 * (1.0 + want_t.abs()),
                        "{ut_d} vs {want_t}"
                    );
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 200 * 16);
    }

    /// Each edge of a turned B: a corner of A placed on its midpoint has zero gap and sits
    /// mid-edge, the normal is that edge's outward one, the extent its half length, and a
    /// corner moved out along the normal has that distance as its gap.
    #[test]
    fn each_edge_has_its_own_normal_distance_and_length() {
        let b = BoxState {
            centre: DVec2::new(0.3, -0.2),
            angle: 0.7,
            velocity: DVec2::ZERO,
            omega: 0.0,
            rect: Rect {
                length: 0.5,
                width: 0.2,
            },
        };
        // (outward normal in B's axes, half distance to the edge, half its length)
        let edges = [
            (DVec2::X, 0.25, 0.1),
            (DVec2::Y, 0.1, 0.25),
            (DVec2::NEG_X, 0.25, 0.1),
            (DVec2::NEG_Y, 0.1, 0.25),
        ];
        for (edge, (m, h, half)) in edges.into_iter().enumerate() {
            let normal = rotate(m, b.angle);
            for out in [0.0, 0.05] {
                let mid = b.centre + normal * (h + out);
                // A: a small box whose corner 2 (−a/2, +b/2) is at `mid`.
                let rect = Rect {
                    length: 0.1,
                    width: 0.1,
                };
                let a = BoxState {
                    centre: mid + DVec2::new(0.05, -0.05),
                    angle: 0.0,
                    velocity: DVec2::ZERO,
                    omega: 0.0,
                    rect,
                };
                let f = corner_on_edge(&a, 2, &b, edge as u8).on_a;
                assert!((f.point - mid).length() < 1e-15);
                assert!((f.gap - out).abs() < 1e-15, "edge {edge}: {f:?}");
                assert!(f.along.abs() < 1e-15);
                assert!((f.normal - normal).length() < 1e-15);
                assert_eq!(f.extent, (-half, half));
            }
        }
    }

    /// A corner resting on the middle of an edge: zero gap, on the edge, and the normal is
    /// the edge's outward one, rotated with B.
    #[test]
    fn a_corner_on_the_middle_of_an_edge_touches_it() {
        let rect = Rect {
            length: 0.4,
            width: 0.2,
        };
        let b = BoxState {
            centre: DVec2::ZERO,
            angle: std::f64::consts::FRAC_PI_2,
            velocity: DVec2::ZERO,
            omega: 0.0,
            rect,
        };
        // B turned a quarter: its +a/2 edge (edge 0) faces +y, at y = 0.2.
        let a = BoxState {
            centre: DVec2::new(-0.2, 0.3),
            angle: 0.0,
            velocity: DVec2::new(0.0, -1.0),
            omega: 0.0,
            rect,
        };
        // A's corner 0 is (+0.2, −0.1) from its centre: (0, 0.2).
        let f = corner_on_edge(&a, 0, &b, 0).on_a;
        assert!(f.gap.abs() < 1e-15 && f.along.abs() < 1e-15, "{f:?}");
        assert!((f.normal - DVec2::Y).length() < 1e-15);
        assert_eq!(f.extent, (-0.1, 0.1));
        assert!((f.normal_speed + 1.0).abs() < 1e-15);
    }

    /// B's edge and a point inside its extent, and A with a corner there, turned so that the
    /// bisector of its corner's right angle lies `psi` off B's outward normal.
    fn corner_at_edge(
        rng: &mut crate::stats::splitmix::SplitMix64,
        psi: f64,
    ) -> (BoxState, u8, BoxState, u8) {
        let rect = |rng: &mut crate::stats::splitmix::SplitMix64| Rect {
            length: rng.uniform(0.1, 0.7),
            width: rng.uniform(0.08, 0.4),
        };
        let b = BoxState {
            centre: DVec2::new(rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0)),
            angle: rng.uniform(-3.2, 3.2),
            velocity: DVec2::ZERO,
            omega: 0.0,
            rect: rect(rng),
        };
        let edge = (rng.next_u64() % 4) as u8;
        let (m_body, h, half_len) = edge_geometry(&b.rect, edge);
        let along = rng.uniform(-0.95, 0.95) * half_len;
        let t_body = DVec2::new(m_body.y, -m_body.x);
        let point = b.centre + rotate(h * m_body + along * t_body, b.angle);
        let m = rotate(m_body, b.angle);
        let ra = rect(rng);
        let corner = (rng.next_u64() % 4) as u8;
        // The corner's bisector into A, in A's body axes, and the turn that lays it along m
        // turned by psi.
        let rho = ra.body_corners()[usize::from(corner)];
        let bisector = DVec2::new(-rho.x.signum(), -rho.y.signum()).normalize();
        let want = rotate(m, psi);
        let angle = want.y.atan2(want.x) - bisector.y.atan2(bisector.x);
        let a = BoxState {
            centre: point - rotate(rho, angle),
            angle,
            velocity: DVec2::ZERO,
            omega: 0.0,
            rect: ra,
        };
        (a, corner, b, edge)
    }

    /// A corner on an edge with A outside B: the edge is the corner's nearest (shortfall
    /// 0, no other edge ties) and touchable (d·m = cos(45° + |ψ|) over A's two sides at the
    /// corner), and the pair's gap is zero. Turned past 45°, A's body dips into B's
    /// half-plane beside the corner: not touchable. At 45° a side lies flush: d·m = 0.
    #[test]
    fn a_corner_on_an_edge_is_nearest_and_touchable_only_with_its_box_outside() {
        let mut rng = crate::stats::splitmix::SplitMix64(49);
        for _ in 0..2000 {
            let psi = rng.uniform(-40.0f64, 40.0).to_radians();
            let (a, corner, b, edge) = corner_at_edge(&mut rng, psi);
            let f = corner_on_edge(&a, corner, &b, edge).on_a;
            assert!(f.gap.abs() < 1e-12, "{f:?}");
            assert!(corner_edge_shortfall(&a, corner, &b, edge).abs() < 1e-12);
            for other in (0..4u8).filter(|&e| e != edge) {
                assert!(corner_edge_shortfall(&a, corner, &b, other) > 1e-3);
            }
            let into = corner_into_edge(&a, corner, &b, edge);
            let want = (std::f64::consts::FRAC_PI_4 + psi.abs()).cos();
            assert!((into - want).abs() < 1e-12, "{into} {want}");

            let psi = psi.signum() * rng.uniform(50.0f64, 130.0).to_radians();
            let (a, corner, b, edge) = corner_at_edge(&mut rng, psi);
            assert!(corner_into_edge(&a, corner, &b, edge) < -0.08);
        }
        let (a, corner, b, edge) = corner_at_edge(&mut rng, std::f64::consts::FRAC_PI_4);
        assert!(corner_into_edge(&a, corner, &b, edge).abs() < 1e-12);
    }

    /// Beyond B's corner, in neither edge's slab, the corner's nearest edge line is the one
    /// with the larger gap, and the other falls short by the difference.
    #[test]
    fn beyond_a_corner_the_nearest_edge_has_the_larger_gap() {
        let rect = Rect {
            length: 0.4,
            width: 0.2,
        };
        let b = BoxState {
            centre: DVec2::ZERO,
            angle: 0.0,
            velocity: DVec2::ZERO,
            omega: 0.0,
            rect,
        };
        // A's corner 2 (−a/2, +b/2) at (0.23, −0.11): 0.03 beyond B's +a/2 edge, 0.01
        // beyond its −b/2 edge.
        let a = BoxState {
            centre: DVec2::new(0.23, -0.11) + DVec2::new(0.2, -0.1),
            angle: 0.0,
            velocity: DVec2::ZERO,
            omega: 0.0,
            rect,
        };
        assert!(corner_edge_shortfall(&a, 2, &b, 0).abs() < 1e-15);
        assert!((corner_edge_shortfall(&a, 2, &b, 3) - 0.02).abs() < 1e-15);
    }
}
