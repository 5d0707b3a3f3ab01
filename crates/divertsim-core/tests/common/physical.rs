//! The physical invariants of a whole run (docs/model.md §5, §6): a verdict (no failure), no
//! NaN, no strike that creates energy, no penetration of the arm or the guide beyond 1e-6 m,
//! compressive contact forces, sticking friction inside its cone and sliding friction
//! against the slip.

#![allow(dead_code)] // each test program uses part of it

use divertsim_core::geometry::{rotate, Rect};
use divertsim_core::model::params::Scenario;
use divertsim_core::sim::{Outcome, SimResult};
use glam::DVec2;

/// Deepest intrusion of the arm segment into the parcel rectangle \[m] (0 when apart).
pub fn arm_intrusion(rect: Rect, centre: DVec2, phi: f64, alpha: f64, arm_length: f64) -> f64 {
    // Depth of a point inside the rectangle = min over the four sides of (h_j − |coordinate|)
    // pieces; along the segment it is the minimum of four linear functions, so its maximum is
    // at an end or where two of them cross.
    let (ha, hb) = (rect.length / 2.0, rect.width / 2.0);
    let to_body = |p: DVec2| rotate(p - centre, -phi);
    let p0 = to_body(DVec2::ZERO);
    let p1 = to_body(arm_length * DVec2::new(alpha.cos(), alpha.sin()));
    let depth = |u: f64| {
        let q = p0 + (p1 - p0) * u;
        (ha - q.x).min(ha + q.x).min(hb - q.y).min(hb + q.y)
    };
    let lin = |u: f64| {
        let q = p0 + (p1 - p0) * u;
        [ha - q.x, ha + q.x, hb - q.y, hb + q.y]
    };
    let (a0, a1) = (lin(0.0), lin(1.0));
    let mut best = depth(0.0).max(depth(1.0));
    for i in 0..4 {
        for j in i + 1..4 {
            let (d0, d1) = (a0[i] - a0[j], a1[i] - a1[j]);
            if d0 != d1 {
                let u = d0 / (d0 - d1);
                if (0.0..=1.0).contains(&u) {
                    best = best.max(depth(u));
                }
            }
        }
    }
    best.max(0.0)
}

/// The contact-force invariants of a run: compressive normal forces (the release guard
/// fires at −1e-9 m g; event location leaves a little more), sticking friction inside the
/// cone, sliding friction against the slip.
pub fn check_contact_forces(s: &Scenario, r: &SimResult) -> Result<(), String> {
    let c = r.contact_check;
    if c.min_normal_force < -1e-7 {
        return Err(format!(
            "a contact pulled: λ_n = {:e} m g",
            c.min_normal_force
        ));
    }
    if c.max_cone_excess > 1e-7 {
        return Err(format!(
            "sticking friction outside the cone by {:e} m g",
            c.max_cone_excess
        ));
    }
    if c.max_friction_power > 1e-7 * s.parcel.mass {
        return Err(format!("friction did work: {:e} W", c.max_friction_power));
    }
    Ok(())
}

pub fn check_run(s: &Scenario, r: &SimResult) -> Result<(), String> {
    if let Outcome::Failed(why) = &r.outcome {
        return Err(format!("failed: {why}"));
    }
    let rect = s.footprint();
    let drive = divertsim_core::model::drive::ArmDrive::new(&s.machine.drive, s.machine.cycle_time)
        .unwrap();
    for p in &r.trajectory {
        let st = p.state;
        if ![
            st.t,
            st.x,
            st.y,
            st.phi,
            st.vx,
            st.vy,
            st.omega,
            p.arm_angle,
        ]
        .iter()
        .all(|v| v.is_finite())
        {
            return Err(format!("non-finite state at t = {}", st.t));
        }
        let centre = DVec2::new(st.x, st.y);
        let alpha = drive.state(st.t).angle;
        let d = arm_intrusion(rect, centre, st.phi, alpha, s.machine.arm_length);
        if d > 1e-6 {
            return Err(format!("arm intrudes {d:e} m at t = {}", st.t));
        }
        for c in rect.corners(centre, st.phi) {
            if c.x <= 0.0 && c.y < -1e-6 {
                return Err(format!("guide penetrated by {:e} m at t = {}", -c.y, st.t));
            }
        }
    }
    for i in &r.impacts {
        let scale = 0.5 * s.parcel.mass * (i.approach_speed + s.machine.belt_speed + 3.0).powi(2);
        if i.dissipated < -1e-9 * scale {
            return Err(format!(
                "strike at t = {} created energy: {}",
                i.t, -i.dissipated
            ));
        }
        if !(i.impulse.is_finite() && i.impulse >= 0.0) {
            return Err(format!("bad impulse {}", i.impulse));
        }
    }
    Ok(())
}

/// Every invariant of a run, the first broken one as an error.
pub fn check(s: &Scenario, r: &SimResult) -> Result<(), String> {
    check_run(s, r).and_then(|()| check_contact_forces(s, r))
}
