//! Worst-case overload of the design (paper §4.2 and Fig. 16; docs/model.md §5).
//!
//! The paper's limit: "the package highest allowable mass was scraped with its striking the
//! scraper in the longest distance from the scraper's arm rotation axis in the moment of its
//! reaching the maximal angular velocity". Here that is one closed-form strike, no
//! simulation:
//!
//! - the instant: the largest α̇ of the drive over the out-stroke, found numerically from the
//!   drive model ([`peak_arm_rate`]: a dense scan of [0, t_out] refined by golden-section
//!   search);
//! - the geometry: the worst-case parcel (e.g. 0.4 × 0.26 m, 15 kg) parallel to the belt
//!   (φ = 0), riding with it at (v, 0), not spinning; its front pivot-side corner
//!   (x_max, y_min) — the corner a parcel lying on the working face's side presents to the arm
//!   line, the geometry of the reference strikes P1/P2 of docs/model.md §5 — is struck by the
//!   arm tip, s_c = R_z, on the working face with normal n = (−sin α, cos α) (a corner on the
//!   face, model.md §5);
//! - the impact: Stronge's energetic law (or the scenario's law) with μ_a and e* by
//!   [`crate::model::impact::resolve`]: u_t0 = v cos α, u_n0 = −(v sin α + R_z α̇)
//!   (model.md §5);
//! - the comparison (model.md §5, "Overload"): S = |P| against S_fall = m(1 + e*)√(2 g H₀),
//!   the ratio S/S_fall, the margin S/S_fall − 1 (≤ 0 allowed) and the equivalent drop height
//!   H_eq = (S/(m(1 + e*)))²/(2g).
//!
//! The largest α̇ is not exactly the largest approach speed (v sin α grows after the peak of
//! α̇); the paper's wording is followed. The pose of `parcel` (offset, angle) is ignored: the
//! strike geometry is fixed as above.

use crate::geometry::Rect;
use crate::model::drive::{ArmDrive, DriveError};
use crate::model::impact::{
    equivalent_drop_height, free_fall_impulse, resolve, ImpactError, ImpactInput, Mobility,
};
use crate::model::params::{Parcel, Scenario};
use crate::GRAVITY;
use glam::DVec2;

/// Number of samples of the scan for the largest α̇ (then refined).
const PEAK_SCAN: usize = 400;
/// Golden-section iterations refining the largest α̇ (bracket shrinks by 0.618 each).
const PEAK_REFINE: usize = 60;

/// The instant of the largest arm angular velocity during the out-stroke.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PeakArmRate {
    /// t: time from the arm start \[s]
    pub time: f64,
    /// α at that instant \[rad]
    pub angle: f64,
    /// α̇_max: the largest arm angular velocity [rad/s]
    pub rate: f64,
}

/// The worst-case strike and its comparison with the free fall.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WorstCaseOverload {
    /// v: belt speed [m/s]
    pub belt_speed: f64,
    /// t_c: cycle time \[s]
    pub cycle_time: f64,
    /// The instant of the strike (largest α̇).
    pub peak: PeakArmRate,
    /// s_c = R_z: distance of the contact from the pivot \[m]
    pub reach: f64,
    /// −u_n0 = v sin α + R_z α̇: normal approach speed [m/s]
    pub approach_speed: f64,
    /// u_t0 = v cos α: initial tangential slip [m/s]
    pub slip_speed: f64,
    /// p_f: normal impulse [N·s]
    pub normal_impulse: f64,
    /// p_t: tangential impulse [N·s]
    pub tangential_impulse: f64,
    /// S = √(p_f² + p_t²) [N·s]
    pub impulse: f64,
    /// H₀: reference drop height \[m]
    pub drop_height: f64,
    /// S_fall = m(1 + e*)√(2 g H₀) [N·s]
    pub fall_impulse: f64,
    /// S/S_fall [-]
    pub ratio: f64,
    /// g = S/S_fall − 1: ≤ 0 allowed [-]
    pub margin: f64,
    /// H_eq = (S/(m(1 + e*)))²/(2g): the drop height with the same impulse \[m]
    pub equivalent_drop_height: f64,
    /// |W_c|/(m g H₀): the peak-force criterion of model.md §5 (≤ 1 allowed) [-]
    pub energy_ratio: f64,
}

/// Why the worst case cannot be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OverloadError {
    #[error("arm drive: {0}")]
    Drive(#[from] DriveError),
    #[error("impact: {0}")]
    Impact(#[from] ImpactError),
    #[error("{0}")]
    Invalid(String),
}

/// The largest α̇ over the out-stroke [0, t_out] of `drive`: a scan of `PEAK_SCAN` samples,
/// then golden-section search in the bracket around the best sample (α̇ is smooth and
/// single-peaked there for the four-bar and the cam laws).
pub fn peak_arm_rate(drive: &ArmDrive) -> PeakArmRate {
    let t_out = drive.out_stroke_time();
    let rate = |t: f64| drive.state(t).rate;
    let dt = t_out / PEAK_SCAN as f64;
    let mut best = 0;
    let mut best_rate = f64::NEG_INFINITY;
    for i in 0..=PEAK_SCAN {
        let r = rate(i as f64 * dt);
        if r > best_rate {
            best_rate = r;
            best = i;
        }
    }
    let (mut lo, mut hi) = (
        best.saturating_sub(1) as f64 * dt,
        ((best + 1).min(PEAK_SCAN)) as f64 * dt,
    );
    let phi = 0.5 * (5f64.sqrt() - 1.0);
    let (mut a, mut b) = (hi - phi * (hi - lo), lo + phi * (hi - lo));
    let (mut fa, mut fb) = (rate(a), rate(b));
    for _ in 0..PEAK_REFINE {
        if fa >= fb {
            hi = b;
            b = a;
            fb = fa;
            a = hi - phi * (hi - lo);
            fa = rate(a);
        } else {
            lo = a;
            a = b;
            fa = fb;
            b = lo + phi * (hi - lo);
            fb = rate(b);
        }
    }
    // Keep the scan's best if the refinement did not improve it (a kink, a table).
    let (mut t, mut r) = if fa >= fb { (a, fa) } else { (b, fb) };
    if best_rate > r {
        t = best as f64 * dt;
        r = best_rate;
    }
    PeakArmRate {
        time: t,
        angle: drive.state(t).angle,
        rate: r,
    }
}

/// The strike of a parcel's front pivot-side corner (body corner (a/2, −b/2), φ = 0) riding
/// at (v, 0) by the arm face at angle α \[rad], rate α̇ [rad/s], at distance s_c \[m] from the
/// pivot: returns (u_t0, u_n0, outcome) (model.md §5).
#[allow(clippy::too_many_arguments)]
pub fn corner_strike(
    length: f64,
    width: f64,
    mass: f64,
    angle: f64,
    rate: f64,
    reach: f64,
    belt_speed: f64,
    friction: f64,
    restitution: f64,
    law: crate::model::impact::ImpactLaw,
) -> Result<(f64, f64, crate::model::impact::ImpactOutcome), OverloadError> {
    let rect = Rect { length, width };
    let inertia = mass * rect.gyration_sq();
    let (s, c) = angle.sin_cos();
    let n = DVec2::new(-s, c);
    let r = rect.body_corners()[0];
    let u_t0 = belt_speed * c;
    let u_n0 = -(belt_speed * s + reach * rate);
    let input = ImpactInput {
        mobility: Mobility::at_contact(mass, inertia, r, n),
        u_t0,
        u_n0,
        friction,
        restitution,
        law,
    };
    Ok((u_t0, u_n0, resolve(&input)?))
}

/// The worst-case overload for a belt speed v [m/s] and an already found peak of α̇, using
/// the arm length, materials and H₀ of `base` and the size and mass of `parcel`.
pub fn worst_case_at(
    base: &Scenario,
    parcel: &Parcel,
    peak: &PeakArmRate,
    cycle_time: f64,
    belt_speed: f64,
    drop_height: f64,
) -> Result<WorstCaseOverload, OverloadError> {
    let ok = |v: f64| v.is_finite() && v > 0.0;
    if !(ok(parcel.length) && ok(parcel.width) && ok(parcel.mass)) {
        return Err(OverloadError::Invalid(
            "parcel length, width and mass must be finite and > 0".into(),
        ));
    }
    if !(belt_speed.is_finite() && belt_speed >= 0.0) {
        return Err(OverloadError::Invalid(format!(
            "belt speed {belt_speed} m/s must be finite and ≥ 0"
        )));
    }
    if !ok(drop_height) {
        return Err(OverloadError::Invalid(format!(
            "drop height {drop_height} m must be finite and > 0"
        )));
    }
    let mat = &base.materials;
    let reach = base.machine.arm_length;
    let (u_t0, u_n0, out) = corner_strike(
        parcel.length,
        parcel.width,
        parcel.mass,
        peak.angle,
        peak.rate,
        reach,
        belt_speed,
        mat.arm_friction,
        mat.restitution,
        mat.impact_law,
    )?;
    let (m, e) = (parcel.mass, mat.restitution);
    let fall = free_fall_impulse(m, e, drop_height);
    let ratio = out.total_impulse / fall;
    Ok(WorstCaseOverload {
        belt_speed,
        cycle_time,
        peak: *peak,
        reach,
        approach_speed: -u_n0,
        slip_speed: u_t0,
        normal_impulse: out.normal_impulse,
        tangential_impulse: out.tangential_impulse,
        impulse: out.total_impulse,
        drop_height,
        fall_impulse: fall,
        ratio,
        margin: ratio - 1.0,
        equivalent_drop_height: equivalent_drop_height(out.total_impulse, m, e),
        energy_ratio: out.compression_work.abs() / (m * GRAVITY * drop_height),
    })
}

/// The worst-case overload of `parcel` at cycle time t_c \[s] and belt speed v [m/s], with the
/// drive, arm length, materials and H₀ (`limits.drop_height`) of `base`.
pub fn worst_case_overload(
    base: &Scenario,
    parcel: &Parcel,
    cycle_time: f64,
    belt_speed: f64,
) -> Result<WorstCaseOverload, OverloadError> {
    let drive = ArmDrive::new(&base.machine.drive, cycle_time)?;
    let peak = peak_arm_rate(&drive);
    worst_case_at(
        base,
        parcel,
        &peak,
        cycle_time,
        belt_speed,
        base.limits.drop_height,
    )
}

/// One point of the impulse-against-belt-speed curve (paper Fig. 16).
#[derive(Debug, Clone, PartialEq)]
pub struct OverloadPoint {
    /// The worst case at this speed (H₀ of the scenario).
    pub worst: WorstCaseOverload,
    /// S/S_fall(H) for each requested reference height H, in order [-]
    pub ratios: Vec<f64>,
}

/// The worst-case impulse for each belt speed at the scenario's cycle time, with the ratios to
/// the free-fall impulses of `drop_heights` \[m] (paper Fig. 16). The peak of α̇ is found once.
pub fn overload_curve(
    base: &Scenario,
    parcel: &Parcel,
    speeds: &[f64],
    drop_heights: &[f64],
) -> Result<Vec<OverloadPoint>, OverloadError> {
    let t_c = base.machine.cycle_time;
    let drive = ArmDrive::new(&base.machine.drive, t_c)?;
    let peak = peak_arm_rate(&drive);
    speeds
        .iter()
        .map(|&v| {
            let worst = worst_case_at(base, parcel, &peak, t_c, v, base.limits.drop_height)?;
            let ratios = drop_heights
                .iter()
                .map(|&h| {
                    worst.impulse / free_fall_impulse(parcel.mass, base.materials.restitution, h)
                })
                .collect();
            Ok(OverloadPoint { worst, ratios })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::drive::DriveSpec;
    use crate::model::impact::ImpactLaw;
    use approx::assert_relative_eq;
    use proptest::prelude::*;

    fn worst_parcel() -> Parcel {
        Parcel::riding(0.4, 0.26, 0.15, 15.0, 0.0, 0.0)
    }

    /// model.md §2: max α̇ = 1.78249 rad/s at t = 0.319 s (α = 21.70°) for t_c = 1.36 s
    /// (half a unit of the last printed digit).
    #[test]
    fn peak_rate_of_the_default_crank_rocker() {
        let s = Scenario::paper_default();
        let drive = ArmDrive::new(&s.machine.drive, 1.36).unwrap();
        let p = peak_arm_rate(&drive);
        assert!((p.rate - 1.78249).abs() <= 5e-6, "{}", p.rate);
        assert!((p.time - 0.319).abs() <= 5e-4, "{}", p.time);
        assert!((p.angle.to_degrees() - 21.70).abs() <= 5e-3, "{}", p.angle);
    }

    /// Cam laws: the peak is at τ = 1/2 with the values of model.md §2 (T_r = 0.68 s, α_max = 45°).
    #[test]
    fn peak_rate_of_the_cam_laws() {
        let sw = 45f64.to_radians();
        for (spec, want) in [
            (DriveSpec::Cycloidal { max_swing: sw }, 2.309995),
            (DriveSpec::Poly345 { max_swing: sw }, 2.165620),
            (DriveSpec::Harmonic { max_swing: sw }, 1.814266),
        ] {
            let p = peak_arm_rate(&ArmDrive::new(&spec, 1.36).unwrap());
            assert!((p.rate - want).abs() <= 5e-7, "{spec:?}: {}", p.rate);
            assert_relative_eq!(p.time, 0.34, epsilon = 1e-6);
            assert_relative_eq!(p.angle, sw / 2.0, epsilon = 1e-6);
        }
    }

    /// The reference strike P1 of model.md §5: 0.4 × 0.26 m, 15 kg, α = 30°, α̇ = 1.5 rad/s,
    /// s_c = 0.6 m, v = 2 m/s, μ_a = e* = 0.3: S = 30.859298 N·s, p_f = 29.557847,
    /// p_t = −8.867354, and its overload: ratio 0.652, H_eq = 0.128 m.
    #[test]
    fn oracle_p1() {
        let (u_t0, u_n0, out) = corner_strike(
            0.4,
            0.26,
            15.0,
            30f64.to_radians(),
            1.5,
            0.6,
            2.0,
            0.3,
            0.3,
            ImpactLaw::Energetic,
        )
        .unwrap();
        assert!((u_t0 - 1.732051).abs() <= 5e-7);
        assert!((u_n0 + 1.9).abs() <= 1e-12);
        assert!((out.total_impulse - 30.859298).abs() <= 5e-7);
        assert!((out.normal_impulse - 29.557847).abs() <= 5e-7);
        assert!((out.tangential_impulse + 8.867354).abs() <= 5e-7);
        let fall = free_fall_impulse(15.0, 0.3, 0.3);
        assert!((fall - 47.309).abs() <= 5e-4);
        assert!((out.total_impulse / fall - 0.652).abs() <= 5e-4);
        let h = equivalent_drop_height(out.total_impulse, 15.0, 0.3);
        assert!((h - 0.128).abs() <= 5e-4);
    }

    /// Hand computation, central impact: a square a × a parcel struck at 45°, where r = P − G
    /// lies along −n, so r_t = 0, W_tn = 0, W_nn = 1/m, W_tt = 1/m + (a²/2)/(m a²/6) = 4/m:
    /// p_f = (1 + e) m v₀ and p_t = −min(μ p_f, u_t0 m/4) (the central case of model.md §5).
    #[test]
    fn central_impact_by_hand() {
        let (a, m, v, rate, reach, e) = (0.3, 7.0, 1.2, 1.6, 0.9, 0.4);
        let al = std::f64::consts::FRAC_PI_4;
        for mu in [0.05, 0.2, 0.9] {
            let (_, _, out) =
                corner_strike(a, a, m, al, rate, reach, v, mu, e, ImpactLaw::Energetic).unwrap();
            let v0 = v * al.sin() + reach * rate;
            let ut0 = v * al.cos();
            let p_f = (1.0 + e) * m * v0;
            let p_t = -(mu * p_f).min(ut0 * m / 4.0);
            assert_relative_eq!(out.normal_impulse, p_f, max_relative = 1e-12);
            assert_relative_eq!(out.tangential_impulse, p_t, max_relative = 1e-12);
            assert_relative_eq!(
                out.total_impulse,
                (p_f * p_f + p_t * p_t).sqrt(),
                max_relative = 1e-12
            );
        }
    }

    /// The assembled worst case on the default machine equals P1's computation redone at the
    /// peak of α̇ with s_c = R_z, and the free-fall numbers of model.md §5.
    #[test]
    fn worst_case_assembles_the_pieces() {
        let s = Scenario::paper_default();
        let w = worst_case_overload(&s, &worst_parcel(), 1.36, 2.0).unwrap();
        let (_, u_n0, out) = corner_strike(
            0.4,
            0.26,
            15.0,
            w.peak.angle,
            w.peak.rate,
            1.0,
            2.0,
            0.3,
            0.3,
            ImpactLaw::Energetic,
        )
        .unwrap();
        assert_eq!(w.impulse, out.total_impulse);
        assert_relative_eq!(
            w.approach_speed,
            2.0 * w.peak.angle.sin() + 1.0 * w.peak.rate,
            epsilon = 1e-14
        );
        assert_eq!(-u_n0, w.approach_speed);
        assert!((w.fall_impulse - 47.309).abs() <= 5e-4);
        assert_relative_eq!(w.ratio, w.impulse / w.fall_impulse, epsilon = 1e-15);
        assert_relative_eq!(w.margin, w.ratio - 1.0, epsilon = 1e-15);
        // S = m(1+e)√(2 g H_eq) by definition.
        assert_relative_eq!(
            free_fall_impulse(15.0, 0.3, w.equivalent_drop_height),
            w.impulse,
            max_relative = 1e-12
        );
    }

    #[test]
    fn curve_ratios_and_errors() {
        let s = Scenario::paper_default();
        let pts = overload_curve(&s, &worst_parcel(), &[0.5, 1.0, 2.0], &[0.2, 0.3]).unwrap();
        assert_eq!(pts.len(), 3);
        for p in &pts {
            assert_relative_eq!(p.ratios[1], p.worst.ratio, max_relative = 1e-14);
            // S_fall ∝ √H₀.
            assert_relative_eq!(
                p.ratios[0] / p.ratios[1],
                (0.3f64 / 0.2).sqrt(),
                max_relative = 1e-12
            );
        }
        let mut bad = worst_parcel();
        bad.mass = 0.0;
        assert!(worst_case_overload(&s, &bad, 1.36, 1.0).is_err());
        assert!(worst_case_overload(&s, &worst_parcel(), -1.0, 1.0).is_err());
        assert!(worst_case_overload(&s, &worst_parcel(), 1.36, f64::NAN).is_err());
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        /// The impulse grows with the belt speed and with a shorter cycle (faster arm), and the
        /// ratio and margin stay finite.
        #[test]
        fn impulse_is_monotone(v in 0.0f64..3.0, dv in 0.01f64..1.0, tc in 0.8f64..2.0) {
            let s = Scenario::paper_default();
            let p = worst_parcel();
            let a = worst_case_overload(&s, &p, tc, v).unwrap();
            let b = worst_case_overload(&s, &p, tc, v + dv).unwrap();
            let c = worst_case_overload(&s, &p, tc * 0.9, v).unwrap();
            prop_assert!(b.impulse > a.impulse);
            prop_assert!(c.impulse > a.impulse);
            prop_assert!(a.ratio.is_finite() && a.margin.is_finite());
        }
    }
}
