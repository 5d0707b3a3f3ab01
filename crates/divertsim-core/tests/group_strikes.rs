//! Issue 49: the strikes of one instant among a group of free parcels (sim/group.rs,
//! docs/model.md §5a, §6c): sequential impulses by the impact law over each pair's mobility,
//! one plastic impact of the whole group on a repeat. Checked against the closed forms of a
//! row of three boxes with central contacts (e = 1: the motion passes down the row; e = 0:
//! all move together at a third), and over random groups of two and three for what every
//! strike keeps: momentum and angular momentum, no energy created (the energetic law: with
//! friction, Newton's and Poisson's coefficients can create energy, docs/model.md §5). Two
//! boxes lying flush, struck along their common side, settle through the group's plastic
//! impact.

use divertsim_core::geometry::{rotate, Rect};
use divertsim_core::model::impact::ImpactLaw;
use divertsim_core::model::pair_contact::BoxState;
use divertsim_core::sim::group::{closed_pairs, strike, Member, PairLaw};
use divertsim_core::stats::splitmix::SplitMix64;
use glam::DVec2;

fn member(centre: DVec2, angle: f64, velocity: DVec2, omega: f64, rect: Rect, mass: f64) -> Member {
    Member {
        state: BoxState {
            centre,
            angle,
            velocity,
            omega,
            rect,
        },
        mass,
        inertia: mass * (rect.length * rect.length + rect.width * rect.width) / 12.0,
    }
}

/// A row of three boxes of 2 kg along x, every contact central: a square of side 0.2 m
/// turned 45° with its corner on the middle of the left edge of a 0.3 × 0.2 m box, and
/// another so on its right edge. The left one moves into the row at `v`.
fn row_of_three(v: f64) -> Vec<Member> {
    let square = Rect {
        length: 0.2,
        width: 0.2,
    };
    let reach = 0.1 * std::f64::consts::SQRT_2; // centre to corner
    let quarter = std::f64::consts::FRAC_PI_4;
    vec![
        member(
            DVec2::new(-0.15 - reach, 0.0),
            quarter,
            DVec2::new(v, 0.0),
            0.0,
            square,
            2.0,
        ),
        member(
            DVec2::ZERO,
            0.0,
            DVec2::ZERO,
            0.0,
            Rect {
                length: 0.3,
                width: 0.2,
            },
            2.0,
        ),
        member(
            DVec2::new(0.15 + reach, 0.0),
            quarter + std::f64::consts::PI,
            DVec2::ZERO,
            0.0,
            square,
            2.0,
        ),
    ]
}

fn energy(ms: &[Member]) -> f64 {
    ms.iter()
        .map(|m| {
            0.5 * m.mass * m.state.velocity.length_squared()
                + 0.5 * m.inertia * m.state.omega.powi(2)
        })
        .sum()
}

fn momentum(ms: &[Member]) -> (DVec2, f64) {
    let p = ms.iter().map(|m| m.mass * m.state.velocity).sum::<DVec2>();
    // About the origin: the spin and the moment of each centre's momentum.
    let l = ms
        .iter()
        .map(|m| m.inertia * m.state.omega + m.state.centre.perp_dot(m.mass * m.state.velocity))
        .sum::<f64>();
    (p, l)
}

#[test]
fn an_elastic_strike_passes_down_a_row_of_three_boxes() {
    let mut ms = row_of_three(1.5);
    // Corner 0 of each square on the middle box's edges 2 and 0.
    let pairs: Vec<_> = closed_pairs(&ms)
        .into_iter()
        .map(|(k, _)| (k.a, k.corner, k.b, k.edge))
        .collect();
    assert_eq!(pairs, vec![(0, 0, 1, 2), (2, 0, 1, 0)]);
    let law = PairLaw {
        friction: 0.0,
        restitution: 1.0,
        law: ImpactLaw::Energetic,
    };
    let out = strike(&mut ms, &law).expect("settled");
    for (k, want) in [0.0, 0.0, 1.5].into_iter().enumerate() {
        assert!(
            (ms[k].state.velocity - DVec2::new(want, 0.0)).length() < 1e-12,
            "{k}: {ms:?}"
        );
        assert!(ms[k].state.omega.abs() < 1e-12);
    }
    assert!(out.persisting.is_empty(), "{out:?}");
    assert!(
        (out.impulse - 2.0 * 2.0 * 1.5).abs() < 1e-9,
        "{}",
        out.impulse
    );
}

#[test]
fn a_plastic_strike_on_a_row_of_three_boxes_moves_them_together_at_a_third() {
    let v = 1.5;
    let mut ms = row_of_three(v);
    let before = energy(&ms);
    let law = PairLaw {
        friction: 0.3,
        restitution: 0.0,
        law: ImpactLaw::Energetic,
    };
    let out = strike(&mut ms, &law).expect("settled");
    for m in &ms {
        assert!(
            (m.state.velocity - DVec2::new(v / 3.0, 0.0)).length() < 1e-9,
            "{ms:?}"
        );
        assert!(m.state.omega.abs() < 1e-9);
    }
    assert!((energy(&ms) - before / 3.0).abs() < 1e-9 * before);
    assert!(
        out.group_impacts >= 1 && !out.persisting.is_empty(),
        "{out:?}"
    );
}

/// Corner `corner` of a new box (sides, mass, turned `psi` off the edge's outward normal,
/// |ψ| < 45°: outside B) on edge `edge` of B, within 0.9 of its half length from the middle.
fn touching(rng: &mut SplitMix64, b: &Member, edge: u8) -> Member {
    let along = rng.uniform(-0.9, 0.9);
    let rect = Rect {
        length: rng.uniform(0.1, 0.6),
        width: rng.uniform(0.08, 0.4),
    };
    let (m_body, h, half): (DVec2, f64, f64) = match edge {
        0 => (
            DVec2::X,
            0.5 * b.state.rect.length,
            0.5 * b.state.rect.width,
        ),
        1 => (
            DVec2::Y,
            0.5 * b.state.rect.width,
            0.5 * b.state.rect.length,
        ),
        2 => (
            DVec2::NEG_X,
            0.5 * b.state.rect.length,
            0.5 * b.state.rect.width,
        ),
        _ => (
            DVec2::NEG_Y,
            0.5 * b.state.rect.width,
            0.5 * b.state.rect.length,
        ),
    };
    let t_body = DVec2::new(m_body.y, -m_body.x);
    let point = b.state.centre + rotate(h * m_body + along * half * t_body, b.state.angle);
    let m = rotate(m_body, b.state.angle);
    let corner = (rng.next_u64() % 4) as usize;
    let rho = rect.body_corners()[corner];
    let bisector = DVec2::new(-rho.x.signum(), -rho.y.signum()).normalize();
    let want = rotate(m, rng.uniform(-40.0f64, 40.0).to_radians());
    let angle = want.y.atan2(want.x) - bisector.y.atan2(bisector.x);
    member(
        point - rotate(rho, angle),
        angle,
        DVec2::new(rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0)),
        rng.uniform(-5.0, 5.0),
        rect,
        rng.uniform(0.3, 15.0),
    )
}

/// Random groups: B in the middle, A's corner on one of B's edges and, in half of them, C's
/// corner on the opposite edge; random velocities, masses, μ and e, every impact law
/// (chosen apart from μ). Each strike keeps the group's momentum and its angular momentum
/// (no outside impulse) and creates no energy (under the energetic law, or without
/// friction).
#[test]
fn strikes_among_random_groups_keep_momentum_and_create_no_energy() {
    let mut rng = SplitMix64(4949);
    let (mut struck, mut threes) = (0, 0);
    for case in 0..5000 {
        let b = member(
            DVec2::new(rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0)),
            rng.uniform(-3.2, 3.2),
            DVec2::new(rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0)),
            rng.uniform(-5.0, 5.0),
            Rect {
                length: rng.uniform(0.15, 0.7),
                width: rng.uniform(0.08, 0.4),
            },
            rng.uniform(0.3, 15.0),
        );
        let edge = (rng.next_u64() % 4) as u8;
        let a = touching(&mut rng, &b, edge);
        let mut ms = vec![a, b];
        if rng.next_u64().is_multiple_of(2) {
            ms.push(touching(&mut rng, &b, (edge + 2) % 4));
        }
        let law = PairLaw {
            friction: if case % 3 == 0 {
                0.0
            } else {
                rng.uniform(0.0, 0.8)
            },
            restitution: rng.uniform(0.0, 1.0),
            law: [ImpactLaw::Energetic, ImpactLaw::Newton, ImpactLaw::Poisson][(case / 3) % 3],
        };
        let (e0, (p0, l0)) = (energy(&ms), momentum(&ms));
        let out = match strike(&mut ms, &law) {
            Ok(out) => out,
            Err(e) => panic!("case {case}: {e}"),
        };
        if out.struck.is_empty() {
            continue;
        }
        struck += 1;
        threes += usize::from(ms.len() == 3);
        let (e1, (p1, l1)) = (energy(&ms), momentum(&ms));
        if law.law == ImpactLaw::Energetic {
            assert!(
                e1 <= e0 + 1e-9 * (1.0 + e0),
                "case {case}: energy {e0} → {e1}"
            );
        }
        let ps = 1.0 + ms.iter().map(|m| m.mass * 2.0).sum::<f64>();
        assert!(
            (p1 - p0).length() <= 1e-9 * ps,
            "case {case}: momentum {p0} → {p1}"
        );
        assert!(
            (l1 - l0).abs() <= 1e-9 * ps,
            "case {case}: angular momentum {l0} → {l1}"
        );
    }
    // docs/model.md §6c quotes these.
    assert_eq!((struck, threes), (3311, 2022));
}

/// Two boxes of 3 kg lying flush, A's long side (0.4 m) on B's, corner to corner: two
/// contacts, one at each end of the common side (A's corner on B's edge and B's on A's, at
/// the same point, are one). A, 0.1 m deep, moves into B at (1.2, 0.3) m/s, e* = 0, μ = 0.3:
/// the first corner's strike turns A onto the second, whose strike turns it back onto the
/// first, and that repeat settles both contacts in the group's plastic impact, where they
/// persist. Momentum and angular momentum are kept, energy is lost, and both contacts end
/// with u_n = 0.
#[test]
fn two_boxes_lying_flush_settle_through_the_groups_plastic_impact() {
    let (ra, rb) = (
        Rect {
            length: 0.1,
            width: 0.4,
        },
        Rect {
            length: 0.3,
            width: 0.4,
        },
    );
    let mut ms = vec![
        member(
            DVec2::new(-0.05, 0.0),
            0.0,
            DVec2::new(1.2, 0.3),
            0.0,
            ra,
            3.0,
        ),
        member(DVec2::new(0.15, 0.0), 0.0, DVec2::ZERO, 0.0, rb, 3.0),
    ];
    // One contact at each end of the common side, whichever box's corner names it.
    let mut points: Vec<[f64; 2]> = closed_pairs(&ms)
        .into_iter()
        .map(|(_, f)| f.on_a.point.to_array())
        .collect();
    points.sort_by(|p, q| p[1].total_cmp(&q[1]));
    assert_eq!(points.len(), 2, "{points:?}");
    assert!((DVec2::from(points[0]) - DVec2::new(0.0, -0.2)).length() < 1e-12);
    assert!((DVec2::from(points[1]) - DVec2::new(0.0, 0.2)).length() < 1e-12);
    let (e0, (p0, l0)) = (energy(&ms), momentum(&ms));
    let law = PairLaw {
        friction: 0.3,
        restitution: 0.0,
        law: ImpactLaw::Energetic,
    };
    let out = strike(&mut ms, &law).expect("settled");
    assert_eq!(out.group_impacts, 1, "{out:?}");
    assert!(out.persisting.len() >= 2, "{out:?}");
    let (e1, (p1, l1)) = (energy(&ms), momentum(&ms));
    assert!(e1 < e0);
    assert!((p1 - p0).length() < 1e-12 && (l1 - l0).abs() < 1e-12);
    for (_, f) in closed_pairs(&ms) {
        assert!(f.on_a.normal_speed.abs() < 1e-9, "{f:?}");
    }
}
