//! Strikes between two free parcels (docs/model.md §5a): §5's impact law with the pair's
//! mobility W_A + W_B, checked against the closed form of a head-on strike, against an
//! independent integration of the two bodies in impulse space, and over random strikes for
//! what no strike may do (create energy, momentum or angular momentum).

use divertsim_core::model::impact::{
    contact_basis, pair_mobility, pair_velocity_changes, resolve, BodyAtContact, ImpactInput,
    ImpactLaw, ImpactOutcome,
};
use divertsim_core::stats::splitmix::SplitMix64;
use glam::DVec2;

/// A free box in the plane.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Body {
    mass: f64,
    inertia: f64,
    centre: DVec2,
    velocity: DVec2,
    spin: f64,
}

impl Body {
    /// A uniform a × b box of mass m: I = m (a² + b²)/12.
    fn boxed(mass: f64, a: f64, b: f64, centre: DVec2, velocity: DVec2, spin: f64) -> Body {
        Body {
            mass,
            inertia: mass * (a * a + b * b) / 12.0,
            centre,
            velocity,
            spin,
        }
    }

    /// The velocity of its material point at p: v_G + ω ẑ × (p − G).
    fn at(&self, p: DVec2) -> DVec2 {
        self.velocity + self.spin * (p - self.centre).perp()
    }

    fn energy(&self) -> f64 {
        0.5 * self.mass * self.velocity.length_squared() + 0.5 * self.inertia * self.spin.powi(2)
    }

    fn momentum(&self) -> DVec2 {
        self.mass * self.velocity
    }

    /// Angular momentum about the origin.
    fn angular_momentum(&self) -> f64 {
        self.centre.perp_dot(self.momentum()) + self.inertia * self.spin
    }

    /// Take the impulse `j` at p.
    fn take(&mut self, j: DVec2, p: DVec2) {
        self.velocity += j / self.mass;
        self.spin += (p - self.centre).perp_dot(j) / self.inertia;
    }

    fn contact(&self, p: DVec2) -> BodyAtContact {
        BodyAtContact {
            mass: self.mass,
            inertia: self.inertia,
            r: p - self.centre,
        }
    }
}

/// Two bodies meeting at p, with the normal n on A (from B into A), μ and e*.
#[derive(Debug, Clone, Copy)]
struct Meeting {
    a: Body,
    b: Body,
    p: DVec2,
    n: DVec2,
    friction: f64,
    restitution: f64,
}

/// The strike by the library: §5's law on the pair's mobility, then both bodies' jumps.
fn strike(m: Meeting) -> (Body, Body, ImpactOutcome) {
    let Meeting {
        a,
        b,
        p,
        n,
        friction,
        restitution,
    } = m;
    let (t, n) = contact_basis(n);
    let u = a.at(p) - b.at(p);
    let (ca, cb) = (a.contact(p), b.contact(p));
    let out = resolve(&ImpactInput {
        mobility: pair_mobility(&ca, &cb, n),
        u_t0: u.dot(t),
        u_n0: u.dot(n),
        friction,
        restitution,
        law: ImpactLaw::Energetic,
    })
    .unwrap();
    let (ja, jb) = pair_velocity_changes(&ca, &cb, n, out.normal_impulse, out.tangential_impulse);
    let (mut a2, mut b2) = (a, b);
    a2.velocity += ja.dv;
    a2.spin += ja.domega;
    b2.velocity += jb.dv;
    b2.spin += jb.domega;
    (a2, b2, out)
}

/// The same strike integrated in small steps of normal impulse on the two bodies
/// themselves, sharing no code with the library's law: each step's tangential impulse is the
/// one that brings the slip nearest to zero within the friction cone (Coulomb's law:
/// opposing the slip, at most μ dp, sticking where it can), the response to it measured by
/// applying it; compression ends at u_n = 0 and the strike at W_n = (1 − e*²) W_c.
/// Returns the bodies after and (p_n, p_t).
fn integrated(m: Meeting, steps_per_compression: f64) -> (Body, Body, f64, f64) {
    let Meeting {
        a,
        b,
        p,
        n,
        friction,
        restitution,
    } = m;
    let n = n.normalize();
    let t = DVec2::new(n.y, -n.x);
    let (mut a, mut b) = (a, b);
    let relative = |a: &Body, b: &Body| a.at(p) - b.at(p);
    // The change of u for a unit impulse along d on A (and −d on B), by applying it.
    let response = |a: &Body, b: &Body, d: DVec2| {
        let (mut a2, mut b2) = (*a, *b);
        a2.take(d, p);
        b2.take(-d, p);
        relative(&a2, &b2) - relative(a, b)
    };
    let u0 = relative(&a, &b);
    let dp = (-u0.dot(n)) / response(&a, &b, n).dot(n) / steps_per_compression;
    let (mut p_n, mut p_t) = (0.0, 0.0);
    let (mut work, mut compression_work) = (0.0, None);
    for _ in 0..100 * steps_per_compression as usize {
        let u = relative(&a, &b);
        let k_tn = response(&a, &b, n * dp).dot(t);
        let k_tt = response(&a, &b, t).dot(t);
        let needed = -(u.dot(t) + k_tn) / k_tt;
        let dpt = needed.clamp(-friction * dp, friction * dp);
        let j = n * dp + t * dpt;
        a.take(j, p);
        b.take(-j, p);
        p_n += dp;
        p_t += dpt;
        let u_after = relative(&a, &b);
        work += 0.5 * (u.dot(n) + u_after.dot(n)) * dp;
        if compression_work.is_none() && u_after.dot(n) >= 0.0 {
            compression_work = Some(work);
        }
        if let Some(wc) = compression_work {
            if work >= (1.0 - restitution * restitution) * wc {
                return (a, b, p_n, p_t);
            }
        }
    }
    panic!("the integrated strike did not end");
}

/// Head-on and collinear: the contact on the line through both centres, no tangential
/// motion. Momentum is conserved, the relative speed leaves at e* times its arrival, and the
/// energy lost is (1 − e*²) · ½ μ_r v₀² with μ_r = m_A m_B/(m_A + m_B), the reduced mass: for a
/// central strike the energetic coefficient is Newton's.
#[test]
fn a_head_on_strike_of_two_free_boxes_keeps_momentum_and_loses_the_energetic_share() {
    for (e, friction) in [(0.3, 0.4), (0.0, 0.0), (1.0, 0.8), (0.6, 0.2)] {
        // A (0.4 × 0.26 m, 3 kg) at 2 m/s runs into B (0.3 × 0.3 m, 5 kg) at 0.5 m/s.
        let a = Body::boxed(3.0, 0.4, 0.26, DVec2::ZERO, DVec2::new(2.0, 0.0), 0.0);
        let b = Body::boxed(
            5.0,
            0.3,
            0.3,
            DVec2::new(0.35, 0.0),
            DVec2::new(0.5, 0.0),
            0.0,
        );
        let p = DVec2::new(0.2, 0.0);
        let (a2, b2, out) = strike(Meeting {
            a,
            b,
            p,
            n: DVec2::new(-1.0, 0.0),
            friction,
            restitution: e,
        });
        let reduced = a.mass * b.mass / (a.mass + b.mass);
        let v0 = 1.5;
        let momentum = a.momentum() + b.momentum() - a2.momentum() - b2.momentum();
        assert!(momentum.length() < 1e-12, "{momentum}");
        let leaving = b2.velocity.x - a2.velocity.x;
        assert!((leaving - e * v0).abs() < 1e-12, "{leaving}");
        let lost = a.energy() + b.energy() - a2.energy() - b2.energy();
        let want = (1.0 - e * e) * 0.5 * reduced * v0 * v0;
        assert!(
            (lost - want).abs() < 1e-12,
            "e* = {e}: lost {lost}, want {want}"
        );
        assert!((out.normal_impulse - (1.0 + e) * reduced * v0).abs() < 1e-12);
        assert_eq!(out.tangential_impulse, 0.0);
        assert!(a2.spin.abs() < 1e-15 && b2.spin.abs() < 1e-15);
    }
}

/// An oblique strike of a corner of A on an edge of B, both moving and spinning, with
/// friction: the library's exact solution against the independent integration, in a case
/// that slips throughout, one that sticks, and one whose slip reverses.
#[test]
fn an_oblique_strike_of_two_boxes_matches_an_independent_integration_in_impulse_space() {
    // A's corner (0.2, −0.13) of a 0.4 × 0.26 m box, turned by −0.3 rad (its lowest
    // corner), meets B's upper edge (normal +y into A). A approaches from above.
    let corner = |angle: f64| DVec2::from_angle(angle).rotate(DVec2::new(0.2, -0.13));
    #[rustfmt::skip]
    let cases = [
        // (μ, A's velocity, A's spin, B's velocity, B's spin, what it does)
        (0.2, DVec2::new(1.5, -1.0), 0.0, DVec2::ZERO, 0.0, "slips"),
        (0.9, DVec2::new(0.05, -1.0), 0.0, DVec2::ZERO, 0.0, "sticks"),
        (0.1, DVec2::new(0.15, -1.2), -2.0, DVec2::new(0.3, 0.1), 1.0, "reverses"),
    ];
    let mut seen = Vec::new();
    for (friction, va, wa, vb, wb, what) in cases {
        let angle = -0.3;
        let a_centre = DVec2::new(0.0, 0.5);
        let p = a_centre + corner(angle);
        let a = Body::boxed(3.0, 0.4, 0.26, a_centre, va, wa);
        let b = Body::boxed(8.0, 0.6, 0.4, DVec2::new(p.x + 0.1, p.y - 0.2), vb, wb);
        let n = DVec2::new(0.0, 1.0);
        let meeting = Meeting {
            a,
            b,
            p,
            n,
            friction,
            restitution: 0.5,
        };
        let (a1, b1, out) = strike(meeting);
        let (a2, b2, p_n, p_t) = integrated(meeting, 2e5);
        let close = |x: f64, y: f64, tol: f64| (x - y).abs() <= tol * (1.0 + y.abs());
        assert!(
            close(out.normal_impulse, p_n, 1e-4),
            "{what}: p_f {} vs {p_n}",
            out.normal_impulse
        );
        assert!(
            close(out.tangential_impulse, p_t, 1e-4),
            "{what}: p_t {} vs {p_t}",
            out.tangential_impulse
        );
        for (x, y) in [
            (a1.velocity.x, a2.velocity.x),
            (a1.velocity.y, a2.velocity.y),
            (a1.spin, a2.spin),
            (b1.velocity.x, b2.velocity.x),
            (b1.velocity.y, b2.velocity.y),
            (b1.spin, b2.spin),
        ] {
            assert!(close(x, y, 1e-4), "{what}: {x} vs {y}");
        }
        seen.push(format!("{:?}", out.modes.as_slice()));
    }
    // The three cases are the three courses named.
    assert_eq!(seen[0], "[Slip(1)]", "{seen:?}");
    assert!(seen[1].contains("Stick"), "{seen:?}");
    assert!(
        seen[2].contains("Slip(1), Slip(-1)") || seen[2].contains("Slip(-1), Slip(1)"),
        "{seen:?}"
    );
}

/// Over random strikes of a corner of one box on an edge of another (μ < 4/3, so no jam:
/// docs/model.md §5a), the energetic law never creates energy, and the pair keeps its
/// momentum and its angular momentum: the kinetic energy lost is the strike's own
/// dissipation, −(∫u_n dp + ∫u_t dp_t) ≥ 0.
#[test]
fn no_strike_between_two_free_boxes_creates_energy_or_momentum() {
    let mut rng = SplitMix64(49);
    let mut u = |lo: f64, hi: f64| lo + (hi - lo) * rng.next_f64();
    let mut strikes = 0;
    for _ in 0..20_000 {
        let (la, wa) = (u(0.1, 0.8), u(0.05, 0.5));
        let a_angle = u(-3.1, 3.1);
        let a_centre = DVec2::new(u(-1.0, 1.0), u(-1.0, 1.0));
        let sx = if u(0.0, 1.0) < 0.5 { 0.5 } else { -0.5 };
        let sy = if u(0.0, 1.0) < 0.5 { 0.5 } else { -0.5 };
        let p = a_centre + DVec2::from_angle(a_angle).rotate(DVec2::new(sx * la, sy * wa));
        // p on an edge of B whose outward normal is n: B's centre half its thickness
        // behind the edge, anywhere along it.
        let n = DVec2::from_angle(u(-3.1, 3.1));
        let (lb, wb) = (u(0.1, 0.8), u(0.05, 0.5));
        let b_centre = p - n * (0.5 * wb) + n.perp() * (u(-0.5, 0.5) * lb);
        let mut moving = |l: f64, w: f64, centre: DVec2| {
            let (mass, vx, vy, spin) = (u(0.2, 30.0), u(-3.0, 3.0), u(-3.0, 3.0), u(-5.0, 5.0));
            Body::boxed(mass, l, w, centre, DVec2::new(vx, vy), spin)
        };
        let (a, b) = (moving(la, wa, a_centre), moving(lb, wb, b_centre));
        let (friction, e) = (u(0.0, 1.3), u(0.0, 1.0));
        if (a.at(p) - b.at(p)).dot(n) >= 0.0 {
            continue; // not approaching: no strike
        }
        let (a2, b2, out) = strike(Meeting {
            a,
            b,
            p,
            n,
            friction,
            restitution: e,
        });
        strikes += 1;
        let before = a.energy() + b.energy();
        let lost = before - a2.energy() - b2.energy();
        let scale = 1e-10 * (1.0 + before);
        assert!(lost >= -scale, "energy created: {lost} J");
        assert!(
            (lost - out.dissipated).abs() <= scale,
            "lost {lost}, dissipated {}",
            out.dissipated
        );
        let dm = a.momentum() + b.momentum() - a2.momentum() - b2.momentum();
        assert!(dm.length() <= 1e-10 * (1.0 + a.momentum().length() + b.momentum().length()));
        let dl = a.angular_momentum() + b.angular_momentum()
            - a2.angular_momentum()
            - b2.angular_momentum();
        assert!(
            dl.abs() <= 1e-10 * (1.0 + a.angular_momentum().abs() + b.angular_momentum().abs())
        );
        // Compressive: the normal impulse pushes the bodies apart.
        assert!(out.normal_impulse > 0.0);
    }
    assert!(strikes > 5_000, "{strikes}");
}
