//! Tipping of a tall parcel: a check on the plane model, not a 3-D simulation (issue 26;
//! docs/model.md, "Tipping", derives both criteria).
//!
//! The plane model gives, at every instant, the horizontal forces on the parcel and its
//! acceleration, and at every strike its impulse. The third dimension enters only here:
//! - **quasi-static** (a contact or a slide): the zero-moment point of the forces,
//!   p = p_G + (z_c F_c − h_c m a)/(m g), must stay inside the footprint; the margin is
//!   min((a/2)/|δx'|, (b/2)/|δy'|) in the parcel's own axes, δ = p − p_G;
//! - **impulsive** (a strike above the centre of mass, z_c > h_c, which presses the edge
//!   it pushes towards into the belt): the angular impulse z_c P⊥ about that edge must not
//!   give the box the energy to lift its centre of mass over it,
//!   (z_c P⊥)²/(2 I_e) < m g (r − h_c); the margin is the threshold impulse over P⊥.
//!
//! A margin below 1 tips the parcel. Assumptions: a rigid box with the inertia of a uniform
//! one about its centre of mass, standing on its whole footprint (no rocking back); the belt
//! friction acts in the footprint's plane (z = 0); every force of the arm and the guide acts
//! at the contact height z_c, the middle of the part of the parcel's side within the arm's
//! face band.

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

/// One tipping check: the margin (≥ 1 stands, < 1 tips) and the edge it concerns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tip {
    pub margin: f64,
    pub edge: TipEdge,
}

/// The smallest tipping margin of a run, where and how it occurred.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TipRecord {
    /// The smallest margin (infinite if nothing loaded the parcel sideways).
    pub margin: f64,
    /// t at which it occurred \[s] (infinite if never loaded).
    pub t: f64,
    /// The edge (None if never loaded).
    pub edge: Option<TipEdge>,
    /// Forces or a strike (None if never loaded).
    pub cause: Option<TipCause>,
}

impl Default for TipRecord {
    fn default() -> TipRecord {
        TipRecord {
            margin: f64::INFINITY,
            t: f64::INFINITY,
            edge: None,
            cause: None,
        }
    }
}

impl TipRecord {
    /// Keep `tip` at `t` if it is the smallest margin so far.
    pub fn note(&mut self, t: f64, tip: Tip, cause: TipCause) {
        if tip.margin < self.margin {
            *self = TipRecord {
                margin: tip.margin,
                t,
                edge: Some(tip.edge),
                cause: Some(cause),
            };
        }
    }

    /// The smaller of two records (the earlier at equal margins).
    pub fn merge(self, o: TipRecord) -> TipRecord {
        if o.margin < self.margin {
            o
        } else {
            self
        }
    }

    /// Whether the parcel tipped (margin < 1).
    pub fn tipped(&self) -> bool {
        self.margin < 1.0
    }
}

/// The height of the force of a face band \[`bottom`, `top`] on a parcel of `height`: the
/// middle of the part of the side within the band \[m]; `None` when the band misses the
/// parcel (it is lower than the band's bottom).
pub fn contact_height(height: f64, bottom: f64, top: f64) -> Option<f64> {
    let (lo, hi) = (bottom.max(0.0), top.min(height));
    (hi > lo).then_some(0.5 * (lo + hi))
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
    /// z_c: the height of the arm's (and the guide's) force \[m].
    pub contact_height: f64,
    /// m \[kg].
    pub mass: f64,
}

impl TipGeometry {
    /// Quasi-static check at one instant: `contact_force` is the sum of the arm's and the
    /// guide's forces on the parcel and `accel` its centre's acceleration (machine frame
    /// \[N], \[m/s²]), `angle` its orientation φ \[rad].
    pub fn quasi_static(&self, angle: f64, contact_force: DVec2, accel: DVec2) -> Tip {
        let shift = (self.contact_height * contact_force - self.com_height * self.mass * accel)
            / (self.mass * GRAVITY);
        let body = DVec2::from_angle(-angle).rotate(shift);
        smaller(body, self.half.x / body.x.abs(), self.half.y / body.y.abs())
    }

    /// The impulse perpendicular to an edge at half-side `half_side` from the centre that
    /// just tips the box over it: z_c J* = √(2 I_e m g (r − h_c)), r = √(half_side² + h_c²),
    /// I_e = m ((2 half_side)² + h²)/12 + m r² \[N·s].
    pub fn threshold_impulse(&self, half_side: f64) -> f64 {
        let (m, hc) = (self.mass, self.com_height);
        let r = half_side.hypot(hc);
        let inertia =
            m * (4.0 * half_side * half_side + self.height * self.height) / 12.0 + m * r * r;
        (2.0 * inertia * m * GRAVITY * (r - hc)).sqrt() / self.contact_height
    }

    /// Impulsive check of a strike of impulse `impulse` on the parcel (machine frame
    /// \[N·s]) at orientation `angle` \[rad]. A strike at or below the centre of mass's
    /// height (z_c ≤ h_c) turns the box, if at all, backwards about its centre, lifting the
    /// edge it is pushed towards: no floor impulse arises there, the box slides, and only
    /// the belt's friction afterwards can tip it (the quasi-static check): margin ∞.
    pub fn strike(&self, angle: f64, impulse: DVec2) -> Tip {
        let body = DVec2::from_angle(-angle).rotate(impulse);
        if self.contact_height <= self.com_height {
            let towards = smaller(body, self.half.x / body.x.abs(), self.half.y / body.y.abs());
            return Tip {
                margin: f64::INFINITY,
                edge: towards.edge,
            };
        }
        smaller(
            body,
            self.threshold_impulse(self.half.x) / body.x.abs(),
            self.threshold_impulse(self.half.y) / body.y.abs(),
        )
    }
}

/// The smaller of the margins `mx` (over a short side) and `my` (over a long side) of a
/// load `body` (the parcel's axes), with the edge it points to.
fn smaller(body: DVec2, mx: f64, my: f64) -> Tip {
    if mx <= my {
        Tip {
            margin: mx,
            edge: if body.x >= 0.0 {
                TipEdge::FrontShort
            } else {
                TipEdge::RearShort
            },
        }
    } else {
        Tip {
            margin: my,
            edge: if body.y >= 0.0 {
                TipEdge::LeftLong
            } else {
                TipEdge::RightLong
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 0.2 × 0.1 m footprint, 0.4 m tall, 4 kg, centre of mass at mid-height.
    fn tall(contact_height: f64) -> TipGeometry {
        TipGeometry {
            half: DVec2::new(0.1, 0.05),
            height: 0.4,
            com_height: 0.2,
            contact_height,
            mass: 4.0,
        }
    }

    /// A box held still (friction at its base balances the push, a = 0) and pushed across
    /// its width at height z tips exactly at F = m g d / (2 z), d = b.
    #[test]
    fn steady_push_tips_at_m_g_d_over_2z() {
        for z in [0.1, 0.25, 0.4] {
            let box_ = tall(z);
            let f_tip = box_.mass * GRAVITY * 0.1 / (2.0 * z);
            let at = |f: f64| box_.quasi_static(0.0, DVec2::new(0.0, f), DVec2::ZERO);
            let tip = at(f_tip);
            assert!((tip.margin - 1.0).abs() < 1e-12, "{z}: {tip:?}");
            assert_eq!(tip.edge, TipEdge::LeftLong);
            assert!(at(0.999 * f_tip).margin > 1.0 && at(1.001 * f_tip).margin < 1.0);
        }
    }

    /// The same push on a frictionless belt accelerates the box, a = F/m: the inertial
    /// force at h_c offsets it, and the box tips at F = m g (d/2)/(z − h_c), only when
    /// pushed above its centre of mass.
    #[test]
    fn accelerating_push_tips_with_the_inertial_term() {
        let box_ = tall(0.35);
        let f_tip = box_.mass * GRAVITY * 0.05 / (0.35 - 0.2);
        let at = |f: f64| box_.quasi_static(0.0, DVec2::new(0.0, f), DVec2::new(0.0, f / 4.0));
        assert!((at(f_tip).margin - 1.0).abs() < 1e-12);
        // Pushed at the centre of mass's height it never tips, however hard.
        let mid = tall(0.2);
        let m = mid.quasi_static(0.0, DVec2::new(0.0, 1e6), DVec2::new(0.0, 1e6 / 4.0));
        assert!(m.margin > 1e9, "{m:?}");
    }

    /// A sliding box decelerated by the belt alone tips forward when μ h_c > d/2.
    #[test]
    fn belt_friction_alone_tips_a_tall_narrow_box() {
        let box_ = tall(0.2);
        let w = box_.mass * GRAVITY;
        // Friction −μ m g along −y' decelerates it: δ = −h_c F/(m g) = +μ h_c along y'.
        for (mu, tips) in [(0.2, false), (0.3, true)] {
            let f = DVec2::new(0.0, -mu * w);
            let tip = box_.quasi_static(0.0, DVec2::ZERO, f / box_.mass);
            assert_eq!(tip.margin < 1.0, tips, "μ = {mu}: {tip:?}");
            assert!((tip.margin - 0.05 / (mu * 0.2)).abs() < 1e-12);
            assert_eq!(tip.edge, TipEdge::LeftLong);
        }
    }

    /// The margin is taken in the parcel's own axes: a push along the machine's y on a
    /// parcel turned by 90° loads its short side.
    #[test]
    fn margins_are_in_the_parcels_axes() {
        let box_ = tall(0.3);
        let turned = box_.quasi_static(
            std::f64::consts::FRAC_PI_2,
            DVec2::new(0.0, 10.0),
            DVec2::ZERO,
        );
        assert_eq!(turned.edge, TipEdge::FrontShort);
        let expected = 0.1 / (0.3 * 10.0 / (4.0 * GRAVITY));
        assert!((turned.margin - expected).abs() < 1e-9, "{turned:?}");
    }

    /// A strike tips the box exactly when z_c P exceeds √(2 I_e m g (r − h_c)); checked
    /// against the energy balance written out for the width (d = b = 0.1 m).
    #[test]
    fn strike_tips_at_the_closed_form_impulse() {
        let box_ = tall(0.3);
        let (m, h, hc, half): (f64, f64, f64, f64) = (4.0, 0.4, 0.2, 0.05);
        let r = (half * half + hc * hc).sqrt();
        let inertia = m * ((2.0 * half) * (2.0 * half) + h * h) / 12.0 + m * r * r;
        let lift = m * GRAVITY * (r - hc);
        let j_star = (2.0 * inertia * lift).sqrt() / 0.3;
        let tip = box_.strike(0.0, DVec2::new(0.0, j_star));
        assert!((tip.margin - 1.0).abs() < 1e-12, "{tip:?}");
        assert_eq!(tip.edge, TipEdge::LeftLong);
        // Just above: the rotational energy about the edge exceeds the lift.
        let p = 1.001 * j_star;
        assert!((0.3 * p).powi(2) / (2.0 * inertia) > lift);
        assert!(box_.strike(0.0, DVec2::new(0.0, p)).margin < 1.0);
        assert!(box_.strike(0.0, DVec2::new(0.0, -0.999 * j_star)).margin > 1.0);
        assert_eq!(
            box_.strike(0.0, DVec2::new(0.0, -p)).edge,
            TipEdge::RightLong
        );
        // Struck at or below its centre of mass, however hard, it slides: no tipping.
        for z in [0.1, 0.2] {
            let low = tall(z).strike(0.0, DVec2::new(0.0, 100.0 * j_star));
            assert_eq!(low.margin, f64::INFINITY, "z_c = {z}");
        }
    }

    #[test]
    fn contact_height_is_the_middle_of_the_band_on_the_side() {
        assert_eq!(contact_height(0.4, 0.0, f64::INFINITY), Some(0.2));
        assert_eq!(contact_height(0.4, 0.1, 0.3), Some(0.2));
        assert_eq!(contact_height(0.15, 0.05, 0.3), Some(0.1));
        assert_eq!(contact_height(0.04, 0.05, 0.3), None);
        for e in TipEdge::ALL {
            assert_eq!(TipEdge::from_label(e.label()), Some(e));
        }
    }
}
