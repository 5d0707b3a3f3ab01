//! Plane geometry of the parcel footprint: rotations, corners, extents.
//!
//! The parcel is a homogeneous a × b rectangle (docs/model.md §1); its corners in body axes are
//! ρ_k = (±a/2, ±b/2).

use glam::DVec2;

/// R(φ)·v: rotate a vector counter-clockwise by `angle` \[rad].
#[inline]
pub fn rotate(v: DVec2, angle: f64) -> DVec2 {
    let (s, c) = angle.sin_cos();
    DVec2::new(c * v.x - s * v.y, s * v.x + c * v.y)
}

/// ẑ × v = (−v_y, v_x).
#[inline]
pub fn perp(v: DVec2) -> DVec2 {
    DVec2::new(-v.y, v.x)
}

/// r × F = r_x F_y − r_y F_x (scalar z-component).
#[inline]
pub fn cross(a: DVec2, b: DVec2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// A rectangle of length `a` (along body x') and width `b` (along body y').
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rect {
    /// a: side along the body x' axis \[m]
    pub length: f64,
    /// b: side along the body y' axis \[m]
    pub width: f64,
}

impl Rect {
    /// Corners ρ_k in body axes, counter-clockwise from (+a/2, −b/2).
    pub fn body_corners(&self) -> [DVec2; 4] {
        let (ha, hb) = (0.5 * self.length, 0.5 * self.width);
        [
            DVec2::new(ha, -hb),
            DVec2::new(ha, hb),
            DVec2::new(-ha, hb),
            DVec2::new(-ha, -hb),
        ]
    }

    /// Corners in the frame for centre `centre` and orientation φ = `angle`.
    pub fn corners(&self, centre: DVec2, angle: f64) -> [DVec2; 4] {
        self.body_corners().map(|r| centre + rotate(r, angle))
    }

    /// Half-extents of the axis-aligned bounding box at orientation `angle`.
    pub fn half_extents(&self, angle: f64) -> DVec2 {
        let (s, c) = angle.sin_cos();
        let (ha, hb) = (0.5 * self.length, 0.5 * self.width);
        DVec2::new(ha * c.abs() + hb * s.abs(), ha * s.abs() + hb * c.abs())
    }

    /// i²: squared radius of gyration (a² + b²)/12 about the vertical axis through G.
    pub fn gyration_sq(&self) -> f64 {
        (self.length * self.length + self.width * self.width) / 12.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn extents_match_corners() {
        let r = Rect {
            length: 0.4,
            width: 0.26,
        };
        for k in 0..50 {
            let phi = -3.0 + 0.13 * k as f64;
            let cs = r.corners(DVec2::ZERO, phi);
            let mx = cs.iter().map(|c| c.x).fold(f64::MIN, f64::max);
            let my = cs.iter().map(|c| c.y).fold(f64::MIN, f64::max);
            let e = r.half_extents(phi);
            assert_relative_eq!(mx, e.x, epsilon = 1e-14);
            assert_relative_eq!(my, e.y, epsilon = 1e-14);
        }
    }

    #[test]
    fn cross_and_perp_are_consistent() {
        let a = DVec2::new(0.3, -1.2);
        let b = DVec2::new(2.0, 0.7);
        assert_relative_eq!(cross(a, b), perp(a).dot(b), epsilon = 1e-15);
        let q = rotate(a, std::f64::consts::FRAC_PI_2);
        assert_relative_eq!(q.x, perp(a).x, epsilon = 1e-15);
        assert_relative_eq!(q.y, perp(a).y, epsilon = 1e-15);
    }
}
