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
    contact_between(samples, samples.partition_point(|&(ts, _)| ts <= t), t)
}

/// [`contact_at`] given k, the number of samples at or before `t`.
fn contact_between(samples: &[(f64, f64)], k: usize, t: f64) -> f64 {
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

/// The part of a stroke's loads that does not depend on the parcel: the drive's α̇ and α̈
/// on a uniform grid of the cycle, and the arm's inertia torque I_arm α̈ summed over every
/// stretch of it (running peaks from either end, running integrals of M_d² and M_d α̇).
/// Built once per machine; a run then only walks the stretch its parcel loads the arm, so a
/// batch of 10⁶ parcels pays for the drive's 4000 grid points once.
#[derive(Debug, Clone)]
pub struct StrokeProfile {
    drive: ArmDrive,
    /// I_arm: the arm's inertia about the pivot \[kg·m²].
    inertia: f64,
    /// t_c \[s] and ω_in = 2π/t_c \[rad/s].
    cycle_time: f64,
    omega_in: f64,
    /// α̇ and α̈ at t_k = t_c k/GRID.
    rate: Vec<f64>,
    accel: Vec<f64>,
    /// max |I α̈| and max |I α̈ α̇/ω_in| over the grid points before k (exclusive) …
    peak_before: Vec<(f64, f64)>,
    /// … and after k (exclusive).
    peak_after: Vec<(f64, f64)>,
    /// ∫ (I α̈)² and ∫ I α̈ α̇ from 0 to t_k, trapezoids on the grid.
    integral_to: Vec<(f64, f64)>,
}

impl StrokeProfile {
    /// The profile of `drive` for an arm of inertia `inertia` about the pivot \[kg·m²].
    pub fn new(drive: &ArmDrive, inertia: f64) -> StrokeProfile {
        let tc = drive.cycle_time();
        let omega_in = std::f64::consts::TAU / tc;
        let (mut rate, mut accel) = (Vec::with_capacity(GRID + 1), Vec::with_capacity(GRID + 1));
        for k in 0..=GRID {
            let s = drive.state(Self::grid_time(tc, k));
            rate.push(s.rate);
            accel.push(s.accel);
        }
        let point = |k: usize| {
            let md = inertia * accel[k];
            (
                md.abs(),
                (md * rate[k] / omega_in).abs(),
                md * md,
                md * rate[k],
            )
        };
        let mut peak_before = vec![(0.0, 0.0); GRID + 1];
        for k in 1..=GRID {
            let (a, b, _, _) = point(k - 1);
            let (pa, pb) = peak_before[k - 1];
            peak_before[k] = (f64::max(pa, a), f64::max(pb, b));
        }
        let mut peak_after = vec![(0.0, 0.0); GRID + 1];
        for k in (0..GRID).rev() {
            let (a, b, _, _) = point(k + 1);
            let (pa, pb) = peak_after[k + 1];
            peak_after[k] = (f64::max(pa, a), f64::max(pb, b));
        }
        let mut integral_to = vec![(0.0, 0.0); GRID + 1];
        for k in 1..=GRID {
            let h = Self::grid_time(tc, k) - Self::grid_time(tc, k - 1);
            let ((_, _, q0, p0), (_, _, q1, p1)) = (point(k - 1), point(k));
            let (sq, w) = integral_to[k - 1];
            integral_to[k] = (sq + 0.5 * h * (q0 + q1), w + 0.5 * h * (p0 + p1));
        }
        StrokeProfile {
            drive: drive.clone(),
            inertia,
            cycle_time: tc,
            omega_in,
            rate,
            accel,
            peak_before,
            peak_after,
            integral_to,
        }
    }

    /// The profile of `scenario`'s arm and drive; `None` without an arm (or with a drive
    /// that does not build, which validation has already refused).
    pub fn of(scenario: &crate::model::params::Scenario) -> Option<StrokeProfile> {
        if !scenario.run.arm {
            return None;
        }
        let drive = ArmDrive::new(&scenario.machine.drive, scenario.machine.cycle_time).ok()?;
        Some(StrokeProfile::new(&drive, scenario.machine.arm_inertia))
    }

    fn grid_time(tc: f64, k: usize) -> f64 {
        tc * k as f64 / GRID as f64
    }

    /// α̇ and α̈ at `t` in the cycle \[s], linear between the grid points.
    fn drive_at(&self, t: f64) -> (f64, f64) {
        let x = (t / self.cycle_time * GRID as f64).clamp(0.0, GRID as f64);
        let k = (x.floor() as usize).min(GRID - 1);
        let f = x - k as f64;
        (
            self.rate[k] + f * (self.rate[k + 1] - self.rate[k]),
            self.accel[k] + f * (self.accel[k + 1] - self.accel[k]),
        )
    }

    /// M_d = I_arm α̈ − M_c: the drive's torque on the arm at `t` of the stroke starting at
    /// `cycle_start` \[s], given the parcel's torque on the arm at the accepted steps
    /// (`contact`, time order) \[N·m]; 0 outside the cycle.
    pub fn drive_torque(&self, cycle_start: f64, contact: &[(f64, f64)], t: f64) -> f64 {
        let rel = t - cycle_start;
        if !(0.0..=self.cycle_time).contains(&rel) {
            return 0.0;
        }
        self.inertia * self.drive_at(rel).1 - contact_at(contact, t)
    }

    /// The loads of the stroke starting at `cycle_start` \[s], given the parcel's torque on
    /// the arm at the accepted steps (`contact`: (t, M_c), time order) and each strike's
    /// angular impulse on the arm (`strikes`: (t, J_c)). Trapezoids over the uniform grid
    /// merged with the contact samples; only the stretch where M_c ≠ 0 is walked, the rest
    /// comes from the profile's running sums.
    pub fn loads(
        &self,
        cycle_start: f64,
        contact: &[(f64, f64)],
        strikes: &[(f64, f64)],
    ) -> ArmLoads {
        self.loads_scaled(cycle_start, contact, strikes, 1.0)
    }

    /// [`StrokeProfile::loads`] with the parcel's torques and strikes scaled by `scale`:
    /// the same run with the parcel's mass times `scale`, where every force scales with the
    /// mass and the path does not (the worst-case search's mass, docs/model.md §12c).
    pub fn loads_scaled(
        &self,
        cycle_start: f64,
        contact: &[(f64, f64)],
        strikes: &[(f64, f64)],
        scale: f64,
    ) -> ArmLoads {
        let tc = self.cycle_time;
        let mut out = ArmLoads {
            cycle_start,
            ..ArmLoads::default()
        };
        let loaded = |&&(_, m): &&(f64, f64)| m != 0.0;
        let first = contact.iter().position(|s| loaded(&s));
        let last = contact.iter().rposition(|s| loaded(&s));
        // The stretch [ta, tb] (cycle time) outside which M_c = 0, and the grid points kl <
        // ta, kr > tb that bound it (or the cycle's ends).
        let (kl, kr) = match (first, last) {
            (Some(a), Some(b)) => {
                let ta = contact[a.saturating_sub(1)].0 - cycle_start;
                let tb = contact[(b + 1).min(contact.len() - 1)].0 - cycle_start;
                let mut kl = 0;
                while kl < GRID && Self::grid_time(tc, kl + 1) < ta {
                    kl += 1;
                }
                let mut kr = GRID;
                while kr > kl && Self::grid_time(tc, kr - 1) > tb {
                    kr -= 1;
                }
                (kl, kr)
            }
            _ => (0, 0),
        };
        let (left_peak, left_in) = self.peak_before[kl];
        let (right_peak, right_in) = self.peak_after[kr];
        out.peak_torque = left_peak.max(right_peak);
        out.peak_input_torque = left_in.max(right_in);
        let (sq_l, w_l) = self.integral_to[kl];
        let (sq_end, w_end) = self.integral_to[GRID];
        let (sq_r, w_r) = self.integral_to[kr];
        let (mut sq, mut work) = (sq_l + (sq_end - sq_r), w_l + (w_end - w_r));
        // Walk [t_kl, t_kr]: the grid points and the contact samples between them.
        let (t_lo, t_hi) = (Self::grid_time(tc, kl), Self::grid_time(tc, kr));
        // Each sample keeps its own time t for M_c: cycle_start + (t − cycle_start) need not
        // give t back, and M_c jumps to 0 past the last sample.
        let mut samples = contact
            .iter()
            .map(|&(t, _)| (t - cycle_start, t))
            .filter(|&(r, _)| r > t_lo && r < t_hi)
            .peekable();
        let mut last: Option<(f64, f64, f64)> = None;
        // The walk's times increase: the samples at or before each are counted on the way.
        let mut seen = 0;
        let mut visit = |(rel, t): (f64, f64), rate: f64, accel: f64, out: &mut ArmLoads| {
            while seen < contact.len() && contact[seen].0 <= t {
                seen += 1;
            }
            let mc = scale * contact_between(contact, seen, t);
            let md = self.inertia * accel - mc;
            out.peak_torque = out.peak_torque.max(md.abs());
            out.peak_contact_torque = out.peak_contact_torque.max(mc.abs());
            out.peak_input_torque = out.peak_input_torque.max((md * rate / self.omega_in).abs());
            if let Some((t0, md0, p0)) = last {
                let h = rel - t0;
                sq += 0.5 * h * (md0 * md0 + md * md);
                work += 0.5 * h * (p0 + md * rate);
            }
            last = Some((rel, md, md * rate));
        };
        for k in kl..=kr {
            let tk = Self::grid_time(tc, k);
            while let Some((r, t)) = samples.next_if(|&(r, _)| r < tk) {
                let (rate, accel) = self.drive_at(r);
                visit((r, t), rate, accel, &mut out);
            }
            // A sample on the grid point lends it its own time.
            let t = samples
                .next_if(|&(r, _)| r == tk)
                .map_or(cycle_start + tk, |(_, t)| t);
            visit((tk, t), self.rate[k], self.accel[k], &mut out);
        }
        // [start, start + t_c): a strike at a cycle's end belongs to the next.
        for &(t, jc) in strikes
            .iter()
            .filter(|&&(t, _)| t >= cycle_start && t < cycle_start + tc)
        {
            let jc = scale * jc;
            work += -jc * self.drive.state(t - cycle_start).rate;
            out.max_strike_angular_impulse = out.max_strike_angular_impulse.max(jc.abs());
        }
        out.rms_torque = (sq / tc).sqrt();
        out.energy = work;
        out
    }
}

/// The loads of the stroke starting at `cycle_start` \[s] of `drive`, for an arm of inertia
/// `inertia` about the pivot \[kg·m²] ([`StrokeProfile::loads`]; build the profile once
/// where many runs share a machine).
pub fn arm_loads(
    drive: &ArmDrive,
    cycle_start: f64,
    inertia: f64,
    contact: &[(f64, f64)],
    strikes: &[(f64, f64)],
) -> ArmLoads {
    StrokeProfile::new(drive, inertia).loads(cycle_start, contact, strikes)
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

    /// The profile's running sums plus the walk over the loaded stretch give the plain
    /// trapezoid sum over every grid point and contact sample (drive evaluated exactly):
    /// a load bump inside the cycle, one at its start and one running past its end.
    #[test]
    fn the_profile_walk_matches_the_plain_sum_over_the_cycle() {
        let d = crank_rocker();
        let inertia = 1.7;
        let plain = |start: f64, contact: &[(f64, f64)]| {
            let tc = d.cycle_time();
            let omega = std::f64::consts::TAU / tc;
            let mut times: Vec<f64> = (0..=GRID)
                .map(|k| start + tc * k as f64 / GRID as f64)
                .chain(contact.iter().map(|c| c.0))
                .filter(|&t| t >= start && t <= start + tc)
                .collect();
            times.sort_by(f64::total_cmp);
            times.dedup();
            let (mut peak, mut peak_in, mut sq, mut w) = (0.0f64, 0.0f64, 0.0, 0.0);
            let mut last: Option<(f64, f64, f64)> = None;
            for &t in &times {
                let s = d.state(t - start);
                let md = inertia * s.accel - contact_at(contact, t);
                peak = peak.max(md.abs());
                peak_in = peak_in.max((md * s.rate / omega).abs());
                if let Some((t0, m0, p0)) = last {
                    sq += 0.5 * (t - t0) * (m0 * m0 + md * md);
                    w += 0.5 * (t - t0) * (p0 + md * s.rate);
                }
                last = Some((t, md, md * s.rate));
            }
            (peak, peak_in, (sq / tc).sqrt(), w)
        };
        let bump = |from: f64, to: f64| -> Vec<(f64, f64)> {
            // Zero before and after, a half sine of 60 N·m between, on uneven steps.
            let mut v = vec![(from - 0.01, 0.0)];
            let n = 137;
            for k in 0..=n {
                let x = (k as f64 / n as f64).powf(1.3);
                v.push((
                    from + (to - from) * x,
                    -60.0 * (std::f64::consts::PI * x).sin() - 1.0,
                ));
            }
            v.push((to + 0.013, 0.0));
            v
        };
        let profile = StrokeProfile::new(&d, inertia);
        for (start, contact) in [
            (0.5, bump(0.7, 1.0)),
            (0.0, bump(0.0, 0.2)),
            (0.2, bump(1.3, 1.7)),
        ] {
            let got = profile.loads(start, &contact, &[]);
            let (peak, peak_in, rms, w) = plain(start, &contact);
            let close = |a: f64, b: f64, what: &str| {
                assert!(
                    (a - b).abs() <= 1e-4 * b.abs().max(1.0),
                    "{what}: {a} vs {b}"
                );
            };
            close(got.peak_torque, peak, "peak");
            close(got.peak_input_torque, peak_in, "input");
            close(got.rms_torque, rms, "rms");
            close(got.energy, w, "energy");
        }
    }

    /// Regression (review of issue 26): the walk rebuilt a sample's time as
    /// cycle_start + (t − cycle_start), which need not give t back; where the load ends at
    /// the last sample (M_c jumps to 0 past it) the rebuilt time fell past it and lost the
    /// sample's value. Every sample now keeps its own time: the peak is the sample's, at any
    /// cycle start, and so is the mass-scaled peak.
    #[test]
    fn a_load_ending_at_the_last_sample_keeps_its_value_at_any_cycle_start() {
        let d = crank_rocker();
        let profile = StrokeProfile::new(&d, 0.0);
        for k in 0..200 {
            let start = -0.9 + 0.0173 * k as f64;
            let contact: Vec<(f64, f64)> = (0..=37)
                .map(|j| (start + 0.31 + 0.00731 * j as f64, -149.0 + 0.01 * j as f64))
                .collect();
            let l = profile.loads(start, &contact, &[]);
            assert_eq!(l.peak_contact_torque, 149.0, "cycle start {start}");
            assert_eq!(l.peak_torque, 149.0, "cycle start {start}");
            let half = profile.loads_scaled(start, &contact, &[], 0.5);
            assert_eq!(half.peak_contact_torque, 74.5, "cycle start {start}");
        }
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
