//! Issue 49: the active set over several parcels (docs/model.md §6c). A group of N bodies
//! solves for 3N accelerations with its contacts' forces, by the same rules as one body
//! (model/active_set.rs): one body's contacts with the arm or the guide on its own
//! columns, a pair's on both bodies' columns (model/pair_contact.rs).

use approx::assert_relative_eq;
use divertsim_core::geometry::Rect;
use divertsim_core::model::active_set::{
    select_group, solve, solve_group, Body, ContactRow, Group, Row, Tangential, Tolerances,
};
use divertsim_core::model::belt_friction::{BeltFriction, FrictionCoefficient, FrictionModel};
use divertsim_core::model::pair_contact::{corner_on_edge, BoxState};
use divertsim_core::stats::splitmix::SplitMix64;
use divertsim_core::GRAVITY;
use glam::DVec2;

const TOL: Tolerances = Tolerances {
    slip: 1e-9,
    force: 1e-9,
    accel: 1e-9,
};

/// A corner at r from its body's centre on a straight face with inward normal n that moves
/// without turning (β = β_t = 0), frictionless: a pusher's face, or the guide.
fn on_flat_face(r: DVec2, n: DVec2) -> ContactRow {
    let t = DVec2::new(n.y, -n.x);
    ContactRow {
        normal: [n.x, n.y, r.perp_dot(n)],
        beta: 0.0,
        tangent: [t.x, t.y, r.perp_dot(t)],
        beta_t: 0.0,
        friction: 0.0,
        slip: 0.0,
    }
}

/// The exact footprint law's wrench on a box sliding without spin at `slip` over the belt.
fn belt_wrench(rect: Rect, mass: f64, mu: f64, slip: DVec2) -> [f64; 3] {
    let law = BeltFriction::new(
        rect.length,
        rect.width,
        mass * GRAVITY,
        FrictionCoefficient::Constant(mu),
        FrictionModel::Exact,
    );
    let (f, m) = law.wrench(slip, 0.0, 0.0);
    [f.x, f.y, m]
}

/// A box A pushed across the belt by a flat pusher pushes a shorter box B ahead of it, B
/// off A's middle by δ along the face. Everything moves with the pusher, so each box slides
/// over the belt at the pusher's speed across it, and at a steady state (no acceleration)
/// the pusher carries both belt frictions: its two contacts on A give
/// P₁ + P₂ = μ g (m_A + m_B), and about A's centre they balance B's push, whose line of
/// action runs through B's centre: (P₂ − P₁) a/2 = μ m_B g δ.
#[test]
fn a_pusher_pushing_two_boxes_at_a_steady_state_carries_both_belt_frictions_with_their_torque() {
    let (mu, w) = (0.45, 0.8);
    let (ra, rb) = (
        Rect {
            length: 0.5,
            width: 0.3,
        },
        Rect {
            length: 0.3,
            width: 0.2,
        },
    );
    let (ma, mb) = (4.0, 2.5);
    for delta in [0.0, 0.04, -0.07] {
        // In the belt's frame: both boxes and the pusher move across it at w.
        let v = DVec2::new(0.0, w);
        let a = BoxState {
            centre: DVec2::new(1.0, 0.3),
            angle: 0.0,
            velocity: v,
            omega: 0.0,
            rect: ra,
        };
        let b = BoxState {
            centre: a.centre + DVec2::new(delta, 0.5 * (ra.width + rb.width)),
            angle: 0.0,
            velocity: v,
            omega: 0.0,
            rect: rb,
        };
        // The pusher's face y = 0.15 under A's corners 3 and 0; B's corners 3 and 0 on A's
        // edge 1 (its +b/2 side).
        let mut rows: Vec<Row<6>> = [3u8, 0]
            .iter()
            .map(|&k| {
                let r = ra.body_corners()[usize::from(k)];
                on_flat_face(r, DVec2::Y).on_body::<6>(0)
            })
            .collect();
        for k in [3u8, 0] {
            let f = corner_on_edge(&b, k, &a, 1);
            assert!(f.on_a.gap.abs() < 1e-12 && f.on_a.normal_speed.abs() < 1e-12);
            assert!(f.on_a.along.abs() <= f.on_a.extent.1, "{f:?}");
            rows.push(f.row(1, 0, 0.0));
        }
        let external: Vec<f64> = [belt_wrench(ra, ma, mu, v), belt_wrench(rb, mb, mu, v)].concat();
        let group = Group::<6> {
            external: external.try_into().unwrap(),
            ..Group::of(&[
                Body {
                    mass: ma,
                    inertia: ma * (0.25 + 0.09) / 12.0,
                    external: [0.0; 3],
                },
                Body {
                    mass: mb,
                    inertia: mb * (0.09 + 0.04) / 12.0,
                    external: [0.0; 3],
                },
            ])
        };
        let sel =
            select_group::<6, 8>(&group, group.external, &rows, &TOL, 0).expect("an active set");
        assert!(sel.modes[..4].iter().all(|m| m.is_some()), "{sel:?}");
        let sol = sel.solution;
        for (d, acc) in sol.accel.iter().enumerate() {
            assert!(acc.abs() < 1e-12, "q̈[{d}] = {acc}");
        }
        let (p1, p2) = (sol.normal_force[0], sol.normal_force[1]);
        assert_relative_eq!(p1 + p2, mu * GRAVITY * (ma + mb), max_relative = 1e-12);
        // Corner 3 is at −a/2, corner 0 at +a/2.
        assert_relative_eq!(
            (p2 - p1) * 0.5 * ra.length,
            mu * mb * GRAVITY * delta,
            epsilon = 1e-12
        );
        // B's two corners carry B's friction, their moment about B's centre zero.
        let (n1, n2) = (sol.normal_force[2], sol.normal_force[3]);
        assert_relative_eq!(n1 + n2, mu * GRAVITY * mb, max_relative = 1e-12);
        assert_relative_eq!(n2 - n1, 0.0, epsilon = 1e-12);
    }
}

/// Two bodies that share no contact solve in a group exactly as each does alone (every
/// mode of one or two contacts each, random rows), within rounding: the group adds zeros,
/// never couples them.
#[test]
fn a_group_of_two_unlinked_bodies_solves_as_each_body_alone() {
    let mut rng = SplitMix64(49);
    let mut u = |lo: f64, hi: f64| rng.uniform(lo, hi);
    let modes = [
        Tangential::Slide(1.0),
        Tangential::Slide(-1.0),
        Tangential::Stick,
    ];
    let mut compared = 0;
    for _ in 0..2000 {
        let body = |u: &mut dyn FnMut(f64, f64) -> f64| Body {
            mass: u(0.3, 15.0),
            inertia: u(0.005, 0.5),
            external: [u(-20.0, 20.0), u(-20.0, 20.0), u(-2.0, 2.0)],
        };
        let bodies = [body(&mut u), body(&mut u)];
        let row = |u: &mut dyn FnMut(f64, f64) -> f64| {
            let r = DVec2::new(u(-0.3, 0.3), u(-0.2, 0.2));
            let n = DVec2::from_angle(u(-3.2, 3.2));
            let t = DVec2::new(n.y, -n.x);
            ContactRow {
                normal: [n.x, n.y, r.perp_dot(n)],
                beta: u(-5.0, 5.0),
                tangent: [t.x, t.y, r.perp_dot(t)],
                beta_t: u(-5.0, 5.0),
                friction: u(0.0, 0.8),
                slip: u(-1.0, 1.0),
            }
        };
        let counts = [1 + (u(0.0, 2.0) as usize), 1 + (u(0.0, 2.0) as usize)];
        let mut own: [Vec<ContactRow>; 2] = [Vec::new(), Vec::new()];
        let mut own_modes: [Vec<Option<Tangential>>; 2] = [Vec::new(), Vec::new()];
        let mut rows: Vec<Row<6>> = Vec::new();
        let mut group_modes = Vec::new();
        for k in 0..2 {
            for _ in 0..counts[k] {
                let r = row(&mut u);
                let m = modes[u(0.0, 3.0) as usize % 3];
                own[k].push(r);
                own_modes[k].push(Some(m));
                rows.push(r.on_body::<6>(k));
                group_modes.push(Some(m));
            }
        }
        let alone: Vec<_> = (0..2)
            .map(|k| solve(&bodies[k], &own[k], &own_modes[k]))
            .collect();
        let group = Group::<6>::of(&bodies);
        let together = solve_group::<6, 8>(&group, &rows, &group_modes);
        // The group adds exact zeros: singular (or over-constrained) exactly when a body
        // alone is.
        assert_eq!(
            together.is_none(),
            alone.iter().any(Option::is_none),
            "{rows:?}"
        );
        let (Some(a), Some(b), Some(g)) = (alone[0], alone[1], together) else {
            continue;
        };
        compared += 1;
        let scale = 1.0 + g.accel.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for d in 0..3 {
            assert!((g.accel[d] - a.accel[d]).abs() <= 1e-9 * scale);
            assert!((g.accel[3 + d] - b.accel[d]).abs() <= 1e-9 * scale);
        }
        let forces = |s: &[f64]| s.iter().fold(1.0f64, |m, x| m.max(x.abs()));
        let fs = forces(&g.normal_force).max(forces(&g.tangential_force));
        for i in 0..counts[0] {
            assert!((g.normal_force[i] - a.normal_force[i]).abs() <= 1e-9 * fs);
            assert!((g.tangential_force[i] - a.tangential_force[i]).abs() <= 1e-9 * fs);
        }
        for i in 0..counts[1] {
            let j = counts[0] + i;
            assert!((g.normal_force[j] - b.normal_force[i]).abs() <= 1e-9 * fs);
            assert!((g.tangential_force[j] - b.tangential_force[i]).abs() <= 1e-9 * fs);
        }
    }
    assert!(compared > 500, "{compared} compared");
}

/// A group of N bodies solves for at most 3N unknowns, and a body's own contacts (with the
/// arm or the guide) for at most its three: two sticking contacts on one body (four
/// unknowns) are refused in a group of two (six coordinates) as they are alone, and four
/// over two bodies (eight) are refused; one on each is solved as each alone.
#[test]
fn a_group_takes_at_most_three_unknowns_per_body() {
    let body = Body {
        mass: 2.0,
        inertia: 0.05,
        external: [0.3, -5.0, 0.1],
    };
    let group = Group::<6>::of(&[body, body]);
    let stick = Some(Tangential::Stick);
    // A corner on a floor and another on a wall: independent rows.
    let (r, s) = (
        on_flat_face(DVec2::new(0.1, -0.1), DVec2::Y),
        on_flat_face(DVec2::new(-0.2, 0.05), DVec2::X),
    );
    assert!(solve(&body, &[r, s], &[stick, stick]).is_none());
    let own: Vec<Row<6>> = vec![r.on_body(0), s.on_body(0)];
    assert!(solve_group::<6, 8>(&group, &own, &[stick, stick]).is_none());
    let rows: Vec<Row<6>> = vec![r.on_body(0), r.on_body(1), s.on_body(0), s.on_body(1)];
    assert!(solve_group::<6, 8>(&group, &rows, &[stick; 4]).is_none());
    let two = solve_group::<6, 8>(&group, &rows[..2], &[stick, stick]).expect("solved");
    let one = solve(&body, &[r], &[stick]).expect("solved");
    for d in 0..3 {
        assert_relative_eq!(two.accel[d], one.accel[d], epsilon = 1e-12);
        assert_relative_eq!(two.accel[3 + d], one.accel[d], epsilon = 1e-12);
    }
}

/// A body that none of a candidate set's contacts touches is judged by its free belt law:
/// box B slides free beside box A held on the guide, so B's acceleration is its free law's
/// whatever A's contact does.
#[test]
fn a_body_without_an_active_contact_moves_under_its_free_law() {
    let body = |external| Body {
        mass: 2.0,
        inertia: 0.05,
        external,
    };
    // Under contacts the belt friction is regularised: a different force.
    let (contact_a, contact_b) = ([0.0, -8.0, 0.0], [1.0, -2.0, 0.0]);
    let (free_a, free_b) = ([0.0, -9.0, 0.0], [1.5, -3.0, 0.2]);
    let group = Group::<6>::of(&[body(contact_a), body(contact_b)]);
    let free: [f64; 6] = [free_a, free_b].concat().try_into().unwrap();
    // A pressed on the guide y = 0 (normal +y) by its belt friction.
    let rows: Vec<Row<6>> = vec![on_flat_face(DVec2::new(0.0, -0.1), DVec2::Y).on_body(0)];
    let sel = select_group::<6, 8>(&group, free, &rows, &TOL, 0).expect("an active set");
    assert!(sel.modes[0].is_some());
    let acc = sel.solution.accel;
    assert_relative_eq!(acc[1], 0.0, epsilon = 1e-12);
    assert_relative_eq!(acc[3], free_b[0] / 2.0, epsilon = 1e-12);
    assert_relative_eq!(acc[4], free_b[1] / 2.0, epsilon = 1e-12);
    assert_relative_eq!(acc[5], free_b[2] / 0.05, epsilon = 1e-12);
}
