//! Riding with the belt (docs/model.md §4): no slip, no spin. The parcel moves rigidly with
//! the belt, v_G = V_b and ω = 0, so its motion is known in closed form. Friction is
//! set-valued there; it stays stuck until a contact force exceeds the limit surface.

/// The riding state at time `t0 + dt` from a riding state `y` at `t0`.
#[inline]
pub fn advance(y: &[f64; 6], dt: f64, belt_speed: f64) -> [f64; 6] {
    [y[0] + belt_speed * dt, y[1], y[2], belt_speed, 0.0, 0.0]
}

/// Snap a state to exact riding (velocity = belt, no spin), keeping the pose.
#[inline]
pub fn snap(y: &[f64; 6], belt_speed: f64) -> [f64; 6] {
    [y[0], y[1], y[2], belt_speed, 0.0, 0.0]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn riding_moves_with_the_belt() {
        let y = [0.1, 0.3, 0.2, 2.0, 0.0, 0.0];
        let z = advance(&y, 0.5, 2.0);
        assert_eq!(z, [1.1, 0.3, 0.2, 2.0, 0.0, 0.0]);
        assert_eq!(
            snap(&[0.0, 0.0, 0.0, 1.9, 1e-12, 1e-12], 2.0),
            [0.0, 0.0, 0.0, 2.0, 0.0, 0.0]
        );
    }
}
