//! The loads on the arm's side of a run (issue 26; docs/model.md §12b): the torque the
//! drive must give the arm over its stroke, the input shaft's torque, the stroke's energy
//! and the strikes' angular impulses about the pivot.
//!
//! The arm follows its drive law exactly (a kinematic arm), so the drive supplies whatever
//! keeps it there: M_d = I_arm α̈ − M_c, with M_c the parcel's torque on the arm about the
//! pivot (from the contact forces at every accepted step) and I_arm the arm's inertia about
//! the pivot. At a strike the drive gives the angular impulse J_d = −J_c. The input shaft
//! turns at ω_in = 2π/t_c (one crank or cam turn per cycle) and, without losses, carries
//! M_in = M_d α̇/ω_in.

use crate::model::drive::ArmDrive;

/// Points of the uniform grid over the cycle, besides the contact samples.
const GRID: usize = 4000;

/// The arm's side of one stroke.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ArmLoads {
    /// The cycle evaluated: its start \[s].
    pub cycle_start: f64,
    /// max |M_d|: the drive's torque on the arm about the pivot \[N·m].
    pub peak_torque: f64,
    /// The root mean square of M_d over the cycle \[N·m].
    pub rms_torque: f64,
    /// max |M_in|, M_in = M_d α̇/ω_in: the input shaft's torque \[N·m].
    pub peak_input_torque: f64,
    /// W = ∫ M_d α̇ dt + Σ J_d α̇: the drive's work over the stroke \[J] (0 for a stroke
    /// that touches nothing: the arm starts and ends at rest).
    pub energy: f64,
    /// max |M_c|: the parcel's largest torque on the arm between strikes \[N·m].
    pub peak_contact_torque: f64,
    /// max |J_c|: the largest angular impulse of one strike on the arm about the pivot
    /// \[N·m·s].
    pub max_strike_angular_impulse: f64,
}

/// The parcel's torque on the arm at `t`, linear between the samples (`samples` in time
/// order, 0 outside them).
fn contact_at(samples: &[(f64, f64)], t: f64) -> f64 {
    let k = samples.partition_point(|&(ts, _)| ts <= t);
    if k == 0 || k == samples.len() {
        return if k > 0 && samples[k - 1].0 == t {
            samples[k - 1].1
        } else {
            0.0
        };
    }
    let ((t0, m0), (t1, m1)) = (samples[k - 1], samples[k]);
    if t1 > t0 {
        m0 + (m1 - m0) * (t - t0) / (t1 - t0)
    } else {
        m1
    }
}

/// The loads of the stroke starting at `cycle_start` \[s] of `drive`, for an arm of inertia
/// `inertia` about the pivot \[kg·m²], given the parcel's torque on the arm at the accepted
/// steps (`contact`: (t, M_c), time order) and each strike's angular impulse on the arm
/// (`strikes`: (t, J_c)). Trapezoids over a uniform grid of the cycle merged with the
/// contact samples.
pub fn arm_loads(
    drive: &ArmDrive,
    cycle_start: f64,
    inertia: f64,
    contact: &[(f64, f64)],
    strikes: &[(f64, f64)],
) -> ArmLoads {
    let tc = drive.cycle_time();
    let omega_in = std::f64::consts::TAU / tc;
    let end = cycle_start + tc;
    let mut times: Vec<f64> = (0..=GRID)
        .map(|k| cycle_start + tc * k as f64 / GRID as f64)
        .collect();
    times.extend(
        contact
            .iter()
            .map(|&(t, _)| t)
            .filter(|&t| t > cycle_start && t < end),
    );
    times.sort_by(f64::total_cmp);
    times.dedup();
    let mut out = ArmLoads {
        cycle_start,
        ..ArmLoads::default()
    };
    let (mut sq, mut work) = (0.0, 0.0);
    let mut last: Option<(f64, f64, f64)> = None;
    for &t in &times {
        let arm = drive.state(t - cycle_start);
        let mc = contact_at(contact, t);
        let md = inertia * arm.accel - mc;
        out.peak_torque = out.peak_torque.max(md.abs());
        out.peak_contact_torque = out.peak_contact_torque.max(mc.abs());
        out.peak_input_torque = out.peak_input_torque.max((md * arm.rate / omega_in).abs());
        if let Some((t0, md0, p0)) = last {
            let h = t - t0;
            sq += 0.5 * h * (md0 * md0 + md * md);
            work += 0.5 * h * (p0 + md * arm.rate);
        }
        last = Some((t, md, md * arm.rate));
    }
    for &(t, jc) in strikes
        .iter()
        .filter(|&&(t, _)| t >= cycle_start && t <= end)
    {
        work += -jc * drive.state(t - cycle_start).rate;
        out.max_strike_angular_impulse = out.max_strike_angular_impulse.max(jc.abs());
    }
    out.rms_torque = (sq / tc).sqrt();
    out.energy = work;
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::drive::{DriveSpec, FourBar};

    fn crank_rocker() -> ArmDrive {
        ArmDrive::new(&DriveSpec::CrankRocker(FourBar::paper_default()), 1.36).unwrap()
    }

    /// A stroke that touches nothing demands I_arm α̈ at the arm and I_arm α̈ α̇/ω_in at the
    /// input shaft; its work is ½ I (α̇_end² − α̇_0²) = 0, rest to rest.
    #[test]
    fn a_free_stroke_demands_the_arms_inertia_torque() {
        let d = crank_rocker();
        let inertia = 2.5;
        let loads = arm_loads(&d, 0.0, inertia, &[], &[]);
        let omega = std::f64::consts::TAU / 1.36;
        let (mut peak, mut peak_in, mut sq) = (0.0f64, 0.0f64, 0.0);
        let n = 200_000;
        for k in 0..=n {
            let s = d.state(1.36 * k as f64 / n as f64);
            peak = peak.max((inertia * s.accel).abs());
            peak_in = peak_in.max((inertia * s.accel * s.rate / omega).abs());
            let w = if k == 0 || k == n { 0.5 } else { 1.0 };
            sq += w * (inertia * s.accel).powi(2) * 1.36 / n as f64;
        }
        assert!(
            (loads.peak_torque - peak).abs() < 1e-3 * peak,
            "{loads:?} vs {peak}"
        );
        assert!((loads.peak_input_torque - peak_in).abs() < 1e-3 * peak_in);
        assert!((loads.rms_torque - (sq / 1.36).sqrt()).abs() < 1e-6 * loads.rms_torque);
        assert!(loads.energy.abs() < 1e-6 * peak, "{loads:?}");
        // Without inertia, nothing at all.
        let massless = arm_loads(&d, 0.0, 0.0, &[], &[]);
        assert_eq!((massless.peak_torque, massless.energy), (0.0, 0.0));
    }

    /// A constant resisting torque M_c = −M over the outward half of the stroke costs the
    /// drive M Δα (work against it), and the strikes' angular impulses add J_d α̇.
    #[test]
    fn a_resisting_torque_costs_its_work_and_strikes_their_impulse() {
        let d = crank_rocker();
        let half = 0.68;
        let m = 40.0;
        let contact: Vec<(f64, f64)> = (0..=2000)
            .map(|k| (half * k as f64 / 2000.0, -m))
            .chain([(half + 1e-9, 0.0)])
            .collect();
        let loads = arm_loads(&d, 0.0, 0.0, &contact, &[]);
        let swing = d.state(half).angle - d.state(0.0).angle;
        assert!(
            (loads.energy - m * swing).abs() < 1e-4 * m * swing,
            "{loads:?}"
        );
        assert!((loads.peak_torque - m).abs() < 1e-12);
        assert_eq!(loads.peak_contact_torque, m);
        let t = 0.3;
        let strike = arm_loads(&d, 0.0, 0.0, &[], &[(t, -0.5)]);
        assert!((strike.energy - 0.5 * d.state(t).rate).abs() < 1e-12);
        assert_eq!(strike.max_strike_angular_impulse, 0.5);
    }
}
