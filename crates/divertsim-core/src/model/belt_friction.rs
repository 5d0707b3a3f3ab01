//! Dry friction of the flat rectangular footprint on the belt: sliding and spinning coupled
//! (Contensou effect), docs/model.md §3, with its velocity conventions.
//!
//! The exact law integrates Coulomb's law over the a × b footprint with uniform pressure
//! p = N/(ab) (docs/model.md §3). It is evaluated with the closed form while the
//! instantaneous centre of rotation (ICR) is within [`ASYMPTOTIC_SWITCH`] · d of the centre
//! (d = √(A² + B²), half-sides A = a/2, B = b/2), the ICR inside the footprint included, and
//! with the large-radius expansion beyond, where the closed form loses digits to
//! cancellation. The "seed" law is the founding paper's tanh/exp surrogate (stage F2) with the
//! corrections of model.md §3 (ξ/v_o instead of cos(arctg(η/ξ)), |ω| inside tanh) and coefficients
//! derived from the footprint: k₁ = mean of the two analytic small-r slopes, k₂ = 1/⟨ρ⟩,
//! L₀ = μ N ⟨ρ⟩. The coefficient may depend on the relative speed, μ_1(v_o), from a table.
//!
//! Everything is evaluated in body axes (x′ along side a); [`BeltFriction::wrench`] rotates
//! the frame-axes relative velocity v_r = v_G − V_b into body axes and the force back
//! (model.md §3). Stick (v_r = 0 and ω = 0) is the caller's business (model.md §4): the wrench is
//! then zero.
//!
//! References: docs/model.md §3 (with its reference values) and §4; the seed paper's F2
//! friction law; Contensou (1963); Zhuravlev (1998) for the coupled sliding–spinning problem.

use glam::DVec2;

/// Which footprint friction law to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum FrictionModel {
    /// Exact uniform-pressure Coulomb integrals (docs/model.md §3).
    #[default]
    Exact,
    /// The paper's tanh/exp law, corrected (docs/model.md §3).
    Seed,
}

/// μ_b: the belt friction coefficient, constant or a function of the relative speed v_o.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum FrictionCoefficient {
    /// A single kinetic coefficient.
    Constant(f64),
    /// μ_1(v_o) as [relative speed m/s, μ] points, speeds strictly increasing; linear between
    /// points, constant beyond the ends.
    Table(Vec<(f64, f64)>),
}

impl FrictionCoefficient {
    /// The largest μ at any speed (NaN for an empty table).
    pub fn max_value(&self) -> f64 {
        match self {
            FrictionCoefficient::Constant(mu) => *mu,
            FrictionCoefficient::Table(points) => points
                .iter()
                .map(|&(_, mu)| mu)
                .reduce(f64::max)
                .unwrap_or(f64::NAN),
        }
    }

    /// μ at relative speed `speed` [m/s].
    ///
    /// A table is interpolated linearly and held constant beyond its ends. An empty table
    /// (rejected by scenario validation) yields NaN so that the trouble shows in the result
    /// instead of a panic.
    pub fn at(&self, speed: f64) -> f64 {
        match self {
            FrictionCoefficient::Constant(mu) => *mu,
            FrictionCoefficient::Table(points) => table_lookup(points, speed),
        }
    }
}

/// Linear interpolation in `points` (speed strictly increasing), clamped at the ends.
fn table_lookup(points: &[(f64, f64)], speed: f64) -> f64 {
    let (Some(&(s_first, mu_first)), Some(&(s_last, mu_last))) = (points.first(), points.last())
    else {
        return f64::NAN;
    };
    if speed <= s_first {
        return mu_first;
    }
    if speed >= s_last {
        return mu_last;
    }
    // First point with a speed above `speed`; 1 ≤ hi ≤ len − 1 here because
    // s_first < speed < s_last (a NaN speed fails both tests above and lands here too).
    let hi = points.partition_point(|&(s, _)| s <= speed);
    let (Some(&(s0, mu0)), Some(&(s1, mu1))) = (points.get(hi.wrapping_sub(1)), points.get(hi))
    else {
        return mu_last;
    };
    if s1 > s0 {
        mu0 + (mu1 - mu0) * (speed - s0) / (s1 - s0)
    } else {
        // Not strictly increasing (invalid table): no slope to interpolate on.
        mu1
    }
}

/// Beyond r = `ASYMPTOTIC_SWITCH` · d the exact law uses the large-radius expansion.
///
/// Choice (measured against 60-digit evaluations of the closed form, footprints 0.4 × 0.26 and
/// 0.7 × 0.1, all sliding directions): at 30 d the expansion used here (F to ε⁴, M to ε⁵;
/// model.md §3) is within 5e-11 (F) and 1e-9 (M) relative, while the
/// closed form's own cancellation error is up to 5e-11 (F) and 1.2e-8 (M, slender box sliding
/// across) and grows as r⁴ beyond. So both branches stay below ~1e-8 and the switch is
/// continuous to that level.
pub const ASYMPTOTIC_SWITCH: f64 = 30.0;

/// ⟨ρ⟩: mean distance of the points of an a × b rectangle from its centre \[m]
/// (model.md §3), for footprint `length` a \[m] and `width` b \[m].
///
/// ⟨ρ⟩ = d/3 + (A²/(6B)) asinh(B/A) + (B²/(6A)) asinh(A/B), d = √(A² + B²); a degenerate
/// rectangle (a segment) gives its own mean distance, half of its half-length.
pub fn mean_radius(length: f64, width: f64) -> f64 {
    let a = 0.5 * length.abs();
    let b = 0.5 * width.abs();
    if a == 0.0 || b == 0.0 {
        return 0.5 * a.max(b);
    }
    let d = (a * a + b * b).sqrt();
    d / 3.0 + a * a / (6.0 * b) * (b / a).asinh() + b * b / (6.0 * a) * (a / b).asinh()
}

/// diag Λ: the small-r slopes (asinh(A/B)/A, asinh(B/A)/B) [1/m] of the friction force of an
/// a × b footprint, F ≈ −(μN/|ω|) Λ v′ in body axes (model.md §3). Their mean is the seed
/// law's k₁.
pub fn spin_slopes(length: f64, width: f64) -> DVec2 {
    let a = 0.5 * length.abs();
    let b = 0.5 * width.abs();
    DVec2::new((a / b).asinh() / a, (b / a).asinh() / b)
}

/// Moments of the footprint used by the large-radius expansion, precomputed.
#[derive(Debug, Clone, Copy)]
struct Moments {
    /// A² [m²]
    a2: f64,
    /// B² [m²]
    b2: f64,
    /// ⟨x′⁴⟩ = A⁴/5 [m⁴]
    x4: f64,
    /// ⟨y′⁴⟩ = B⁴/5 [m⁴]
    y4: f64,
    /// ⟨x′²y′²⟩ = A²B²/9 [m⁴]
    x2y2: f64,
    /// A⁶, A⁴B², A²B⁴, B⁶ for the ε⁵ moment term [m⁶]
    a6: f64,
    a4b2: f64,
    a2b4: f64,
    b6: f64,
}

/// The friction wrench of the belt on a parcel footprint.
#[derive(Debug, Clone)]
pub struct BeltFriction {
    /// A = a/2: half-side along body x′ \[m]
    half_length: f64,
    /// B = b/2: half-side along body y′ \[m]
    half_width: f64,
    /// ⟨ρ⟩: mean distance of footprint points from G \[m]
    mean_radius: f64,
    /// N = m g: normal force \[N]
    normal_force: f64,
    /// 1/(4AB): uniform pressure per unit normal force [1/m²]
    inv_area: f64,
    /// r beyond which the exact law uses the expansion, `ASYMPTOTIC_SWITCH` · d \[m]
    switch_radius: f64,
    /// Seed law k₁: mean of the two analytic small-r slopes [1/m]
    k1: f64,
    /// Seed law k₂ = 1/⟨ρ⟩ [1/m]
    k2: f64,
    /// Footprint moments for the expansion.
    moments: Moments,
    /// μ_b(v_o)
    coefficient: FrictionCoefficient,
    /// Exact or seed law.
    model: FrictionModel,
}

impl BeltFriction {
    /// Footprint `length` a × `width` b \[m], normal force N = m g \[N].
    ///
    /// The sides must be positive (scenario validation); nothing here panics otherwise, but
    /// the results are then meaningless (NaN or infinite).
    pub fn new(
        length: f64,
        width: f64,
        normal_force: f64,
        coefficient: FrictionCoefficient,
        model: FrictionModel,
    ) -> BeltFriction {
        let a = 0.5 * length.abs();
        let b = 0.5 * width.abs();
        let (a2, b2) = (a * a, b * b);
        let d = (a2 + b2).sqrt();
        let rho = mean_radius(length, width);
        let slopes = spin_slopes(length, width);
        BeltFriction {
            half_length: a,
            half_width: b,
            mean_radius: rho,
            normal_force,
            inv_area: 1.0 / (4.0 * a * b),
            switch_radius: ASYMPTOTIC_SWITCH * d,
            k1: 0.5 * (slopes.x + slopes.y),
            k2: 1.0 / rho,
            moments: Moments {
                a2,
                b2,
                x4: a2 * a2 / 5.0,
                y4: b2 * b2 / 5.0,
                x2y2: a2 * b2 / 9.0,
                a6: a2 * a2 * a2,
                a4b2: a2 * a2 * b2,
                a2b4: a2 * b2 * b2,
                b6: b2 * b2 * b2,
            },
            coefficient,
            model,
        }
    }

    /// Force F′ (body axes) \[N] and moment M_b [N·m] for the relative velocity of the centre
    /// in body axes v′ [m/s] and the spin ω [rad/s]. Zero when both are zero (stick is the
    /// caller's business, model.md §4).
    pub fn wrench_body(&self, v_rel_body: DVec2, omega: f64) -> (DVec2, f64) {
        let speed2 = v_rel_body.length_squared();
        match self.model {
            FrictionModel::Exact => {
                let mu_n = self.mu(speed2) * self.normal_force;
                self.exact(v_rel_body, speed2, omega, mu_n)
            }
            FrictionModel::Seed => {
                let speed = speed2.sqrt();
                let mu_n = self.mu_at(speed) * self.normal_force;
                self.seed(v_rel_body, speed, omega, mu_n)
            }
        }
    }

    /// Force F (frame axes) \[N] and moment M_b [N·m] for the relative velocity
    /// v_r = v_G − V_b in frame axes, spin ω and orientation φ (model.md §3).
    pub fn wrench(&self, v_rel: DVec2, omega: f64, angle: f64) -> (DVec2, f64) {
        let (sin, cos) = angle.sin_cos();
        self.wrench_rotated(v_rel, omega, DVec2::new(cos, sin))
    }

    /// As [`BeltFriction::wrench`], with the orientation given as `rotation` = (cos φ, sin φ)
    /// (saves the sine and cosine when the caller has them already).
    pub fn wrench_rotated(&self, v_rel: DVec2, omega: f64, rotation: DVec2) -> (DVec2, f64) {
        if self.model == FrictionModel::Seed {
            // The seed law is isotropic: evaluate in frame axes directly, which keeps F exactly
            // anti-parallel to v_r.
            return self.wrench_body(v_rel, omega);
        }
        let (c, s) = (rotation.x, rotation.y);
        // v′ = R(−φ) v_r
        let v_body = DVec2::new(c * v_rel.x + s * v_rel.y, c * v_rel.y - s * v_rel.x);
        let (f, m) = self.wrench_body(v_body, omega);
        // F = R(φ) F′
        (DVec2::new(c * f.x - s * f.y, s * f.x + c * f.y), m)
    }

    /// ⟨ρ⟩: mean distance of footprint points from the centre \[m] (model.md §3).
    pub fn mean_radius(&self) -> f64 {
        self.mean_radius
    }

    /// μ N at rest (the coefficient at zero relative speed times the normal force) \[N].
    pub fn max_force(&self) -> f64 {
        self.coefficient.at(0.0) * self.normal_force
    }

    /// Seed-law coefficients (k₁, k₂) [1/m]: k₁ = mean of asinh(A/B)/A and asinh(B/A)/B,
    /// k₂ = 1/⟨ρ⟩ (model.md §3).
    pub fn seed_coefficients(&self) -> (f64, f64) {
        (self.k1, self.k2)
    }

    /// μ from the squared relative speed; the constant case needs no square root.
    #[inline]
    fn mu(&self, speed2: f64) -> f64 {
        match &self.coefficient {
            FrictionCoefficient::Constant(mu) => *mu,
            FrictionCoefficient::Table(points) => table_lookup(points, speed2.sqrt()),
        }
    }

    #[inline]
    fn mu_at(&self, speed: f64) -> f64 {
        self.coefficient.at(speed)
    }

    /// Exact law: special cases, closed form, or the large-radius expansion.
    #[inline]
    fn exact(&self, v: DVec2, speed2: f64, omega: f64, mu_n: f64) -> (DVec2, f64) {
        if speed2 == 0.0 {
            // Pure spin about G (or stick): F = 0, M = −μN⟨ρ⟩ sgn ω.
            let m = if omega == 0.0 {
                0.0
            } else {
                -mu_n * self.mean_radius * omega.signum()
            };
            return (DVec2::ZERO, m);
        }
        // r = |v′|/|ω| ≥ r_s, written without division so that ω = 0 (r = ∞) lands here too,
        // where the expansion is exactly F = −μN v̂, M = 0.
        let rs = self.switch_radius * omega;
        if speed2 >= rs * rs {
            self.asymptotic(v, speed2.sqrt(), omega, mu_n)
        } else {
            self.closed_form(v, omega, mu_n)
        }
    }

    /// Closed form of model.md §3, valid for any ICR, including inside the footprint.
    ///
    /// With u = x′ − x₀ ∈ {u₁, u₂}, t = y′ − y₀ ∈ {t₁, t₂} at the four corners and
    /// R = √(u² + t²), every term of S (for G_x, G_y) and H (for I_r) is a corner value; the
    /// asinh terms only enter through the differences
    /// D_i = asinh(t₂/|u_i|) − asinh(t₁/|u_i|) and E_j = asinh(u₂/|t_j|) − asinh(u₁/|t_j|),
    /// each a single logarithm of a ratio. Cost: 4 square roots, 4 logarithms.
    #[inline]
    fn closed_form(&self, v: DVec2, omega: f64, mu_n: f64) -> (DVec2, f64) {
        let (a, b) = (self.half_length, self.half_width);
        let inv_omega = 1.0 / omega;
        // ρ₀ = (x₀, y₀) = (−v′_y/ω, v′_x/ω), the ICR in body axes.
        let x0 = -v.y * inv_omega;
        let y0 = v.x * inv_omega;
        let (u1, u2) = (-a - x0, a - x0);
        let (t1, t2) = (-b - y0, b - y0);
        let (uu1, uu2, tt1, tt2) = (u1 * u1, u2 * u2, t1 * t1, t2 * t2);
        // R_ij = |corner(u_i, t_j) − ρ₀|
        let r11 = (uu1 + tt1).sqrt();
        let r12 = (uu1 + tt2).sqrt();
        let r21 = (uu2 + tt1).sqrt();
        let r22 = (uu2 + tt2).sqrt();

        let d1 = log_ratio(shifted(t2, uu1, r12), shifted(t1, uu1, r11));
        let d2 = log_ratio(shifted(t2, uu2, r22), shifted(t1, uu2, r21));
        let e1 = log_ratio(shifted(u2, tt1, r21), shifted(u1, tt1, r11));
        let e2 = log_ratio(shifted(u2, tt2, r22), shifted(u1, tt2, r12));

        // Alternating corner sums Σ σ_i σ_j X_ij (σ = +1 at the upper limits).
        let sum_t = t2 * (r22 - r12) - t1 * (r21 - r11);
        let sum_u = u2 * (r22 - r21) - u1 * (r12 - r11);
        let sum_ut = u2 * (t2 * r22 - t1 * r21) - u1 * (t2 * r12 - t1 * r11);
        let du = uu2 * d2 - uu1 * d1;
        let et = tt2 * e2 - tt1 * e1;

        let gx = 0.5 * (sum_t + du);
        let gy = 0.5 * (sum_u + et);
        let ir =
            sum_ut / 3.0 + (u2 * uu2 * d2 - u1 * uu1 * d1 + t2 * tt2 * e2 - t1 * tt1 * e1) / 6.0;

        // −μ p sgn ω
        let k = -mu_n * self.inv_area * omega.signum();
        (DVec2::new(-k * gy, k * gx), k * (ir + x0 * gx + y0 * gy))
    }

    /// Large-radius expansion (model.md §3, to ε⁴ in F and ε⁵ in M),
    /// with ε = ω/|v′|, v̂ = v′/|v′| = (c, s) and n̂ = ẑ × v̂ = (−s, c):
    /// F·v̂ = −μN[1 − ε²⟨ρ_v²⟩/2 + ε⁴(3⟨ρ_v⁴⟩/8 − 3⟨ρ_v²ρ_n²⟩/2)],
    /// F·n̂ = −μN[ε²⟨ρ_vρ_n⟩ + ε⁴(⟨ρ_vρ_n³⟩ − 3⟨ρ_v³ρ_n⟩/2)],
    /// M = −μN[ε⟨ρ_v²⟩ + ε³(2⟨ρ_v²ρ_n²⟩ − ⟨ρ_v⁴⟩/2) + ε⁵(3⟨ρ_v²ρ_n⁴⟩ − 9⟨ρ_v⁴ρ_n²⟩/2 + 3⟨ρ_v⁶⟩/8)].
    #[inline]
    fn asymptotic(&self, v: DVec2, speed: f64, omega: f64, mu_n: f64) -> (DVec2, f64) {
        let mo = &self.moments;
        let inv_speed = 1.0 / speed;
        let (c, s) = (v.x * inv_speed, v.y * inv_speed);
        let eps = omega * inv_speed;
        let e2 = eps * eps;
        let (cc, ss, cs) = (c * c, s * s, c * s);

        let m20 = (mo.a2 * cc + mo.b2 * ss) / 3.0;
        let m11 = (mo.b2 - mo.a2) * cs / 3.0;
        let m40 = cc * cc * mo.x4 + 6.0 * cc * ss * mo.x2y2 + ss * ss * mo.y4;
        let m22 = cc * ss * (mo.x4 + mo.y4) + ((cc - ss) * (cc - ss) - 2.0 * cc * ss) * mo.x2y2;
        let m31 = cs * (-cc * mo.x4 + 3.0 * (cc - ss) * mo.x2y2 + ss * mo.y4);
        let m13 = cs * (-ss * mo.x4 + 3.0 * (ss - cc) * mo.x2y2 + cc * mo.y4);
        // 3⟨ρ_v²ρ_n⁴⟩ − 9⟨ρ_v⁴ρ_n²⟩/2 + 3⟨ρ_v⁶⟩/8 for the rectangle (derived symbolically from
        // ⟨x′⁶⟩ = A⁶/7, ⟨x′⁴y′²⟩ = A⁴B²/15, ...).
        let k5 = mo.a6 * cc * (3.0 / 56.0 * cc * cc - 9.0 / 14.0 * cc * ss + 3.0 / 7.0 * ss * ss)
            + mo.a4b2
                * (-0.3 * cc * cc * cc + 159.0 / 40.0 * cc * cc * ss - 3.4 * cc * ss * ss
                    + 0.2 * ss * ss * ss)
            + mo.a2b4
                * (0.2 * cc * cc * cc - 3.4 * cc * cc * ss + 159.0 / 40.0 * cc * ss * ss
                    - 0.3 * ss * ss * ss)
            + mo.b6 * ss * (3.0 / 7.0 * cc * cc - 9.0 / 14.0 * cc * ss + 3.0 / 56.0 * ss * ss);

        let fv = 1.0 - e2 * (0.5 * m20 - e2 * (0.375 * m40 - 1.5 * m22));
        let fn_ = e2 * (m11 + e2 * (m13 - 1.5 * m31));
        let mm = eps * (m20 + e2 * (2.0 * m22 - 0.5 * m40 + e2 * k5));
        let f = DVec2::new(fv * c - fn_ * s, fv * s + fn_ * c);
        (-mu_n * f, -mu_n * mm)
    }

    /// Seed law (model.md §3): |F| = μN tanh(k₁ r) anti-parallel to v′,
    /// L_M = L₀ e^(−k₂ r) + μN r [1 − tanh(k₁ r)], M = −L_M sgn ω, r = |v′|/|ω|.
    #[inline]
    fn seed(&self, v: DVec2, speed: f64, omega: f64, mu_n: f64) -> (DVec2, f64) {
        if speed == 0.0 {
            // r = 0: no force, full pivoting moment L₀ (zero at stick).
            let m = if omega == 0.0 {
                0.0
            } else {
                -mu_n * self.mean_radius * omega.signum()
            };
            return (DVec2::ZERO, m);
        }
        let r = speed / omega.abs();
        if !r.is_finite() {
            // ω = 0 (r = ∞): pure sliding, tanh = 1 and r (1 − tanh) → 0.
            return (v * (-mu_n / speed), 0.0);
        }
        // tanh x and 1 − tanh x from one exponential, without cancellation at large x.
        let q = (-2.0 * self.k1 * r).exp();
        let inv = 1.0 / (1.0 + q);
        let tanh = (1.0 - q) * inv;
        let one_minus_tanh = 2.0 * q * inv;
        let force = mu_n * tanh;
        let l_m = mu_n * (self.mean_radius * (-self.k2 * r).exp() + r * one_minus_tanh);
        (v * (-force / speed), -l_m * omega.signum())
    }
}

/// t + √(t² + u²) given u² and R = √(t² + u²), without cancellation for t < 0
/// (odd symmetry: there it equals u²/(R − t)).
#[inline]
fn shifted(t: f64, uu: f64, r: f64) -> f64 {
    if t >= 0.0 {
        t + r
    } else {
        uu / (r - t)
    }
}

/// ln(num/den) = asinh(t₂/|u|) − asinh(t₁/|u|) for num, den from [`shifted`]. A vanishing
/// argument means |u| = 0 (or underflows), where the difference is multiplied by u² (or u³)
/// and its term vanishes: return 0 rather than ∞ so that 0 · ∞ never makes a NaN.
#[inline]
fn log_ratio(num: f64, den: f64) -> f64 {
    let q = num / den;
    if q > 0.0 && q.is_finite() {
        q.ln()
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const G: f64 = 9.81;

    /// The reference parcel of model.md §3: 5 kg, μ_b = 0.4, μN = 19.62 N.
    fn law(a: f64, b: f64, model: FrictionModel) -> BeltFriction {
        BeltFriction::new(a, b, 5.0 * G, FrictionCoefficient::Constant(0.4), model)
    }

    /// |actual − printed| within 1e-6 relative, or half a unit of the last printed digit
    /// (`decimals` after the point), whichever is larger (as model.md's reference values).
    fn check(actual: f64, printed: f64, decimals: i32, what: &str) {
        let tol = if printed == 0.0 {
            1e-9
        } else {
            (1e-6 * printed.abs()).max(0.5 * 10f64.powi(-decimals))
        };
        assert!(
            (actual - printed).abs() <= tol,
            "{what}: got {actual}, expected {printed} (tol {tol:e})"
        );
    }

    fn rot(v: DVec2, angle: f64) -> DVec2 {
        let (s, c) = angle.sin_cos();
        DVec2::new(c * v.x - s * v.y, s * v.x + c * v.y)
    }

    /// The largest μ of a table is its largest point (speeds beyond the ends hold the end
    /// values), the constant itself otherwise, NaN for an empty table.
    #[test]
    fn max_value_bounds_every_speed() {
        let table = FrictionCoefficient::Table(vec![(0.0, 0.3), (0.5, 0.55), (2.0, 0.4)]);
        assert_eq!(table.max_value(), 0.55);
        for k in 0..=100 {
            assert!(table.at(0.03 * k as f64) <= table.max_value());
        }
        assert_eq!(FrictionCoefficient::Constant(0.4).max_value(), 0.4);
        assert!(FrictionCoefficient::Table(vec![]).max_value().is_nan());
    }

    #[test]
    fn static_friction_reference_values() {
        // (a, b, v′, ω, F′x, F′y, M, decimals of F, decimals of M)
        type Row = (f64, f64, [f64; 2], f64, f64, f64, f64, i32, i32);
        let rows: [Row; 10] = [
            (0.4, 0.26, [1.0, 0.0], 0.0, -19.62, 0.0, 0.0, 5, 6),
            (0.4, 0.26, [0.0, 0.0], 2.0, 0.0, 0.0, -2.510993, 5, 6),
            (0.4, 0.26, [0.3, 0.0], 2.0, -14.99861, 0.0, -1.510396, 5, 6),
            (0.4, 0.26, [0.0, 0.3], 2.0, 0.0, -13.34440, -1.530782, 5, 6),
            (
                0.4,
                0.26,
                [0.2, -0.15],
                -3.0,
                -7.65904,
                4.44152,
                2.151685,
                5,
                6,
            ),
            (
                0.4,
                0.26,
                [0.11, 0.05],
                1.0,
                -12.05106,
                -4.19184,
                -1.779138,
                5,
                6,
            ),
            (
                0.7,
                0.1,
                [0.5, 0.2],
                1.5,
                -16.58554,
                -5.31805,
                -1.719847,
                5,
                6,
            ),
            (0.7, 0.1, [0.05, 0.0], 4.0, -1.84565, 0.0, -3.503128, 5, 6),
            (
                0.2,
                0.1,
                [0.3, 0.4],
                -5.0,
                -11.93838,
                -12.50571,
                0.437435,
                5,
                6,
            ),
            (
                0.4,
                0.26,
                [6.0, 8.0],
                0.1,
                -11.77200,
                -15.69599,
                -0.001649,
                5,
                6,
            ),
        ];
        for (i, &(a, b, v, w, fx, fy, m, df, dm)) in rows.iter().enumerate() {
            let (f, mb) = law(a, b, FrictionModel::Exact).wrench_body(DVec2::from(v), w);
            check(f.x, fx, df, &format!("row {i} F'x"));
            check(f.y, fy, df, &format!("row {i} F'y"));
            check(mb, m, dm, &format!("row {i} M_b"));
        }
        // The last row is in the asymptotic branch: its printed leading-order value.
        let (_, mb) = law(0.4, 0.26, FrictionModel::Exact).wrench_body(DVec2::new(6.0, 8.0), 0.1);
        check(mb, -0.0016491, 7, "row 9 asymptotic");
    }

    #[test]
    fn velocity_conventions_reference_case() {
        let fr = law(0.4, 0.26, FrictionModel::Exact);
        let phi = 30f64.to_radians();
        let v_belt = DVec2::new(2.0, 0.0);
        let v_g = DVec2::new(1.5, 0.4);
        let v_rel = v_g - v_belt;
        let v_body = rot(v_rel, -phi);
        check(v_body.x, -0.233013, 6, "v'x");
        check(v_body.y, 0.596410, 6, "v'y");
        let (fb, mb) = fr.wrench_body(v_body, 2.0);
        check(fb.x, 7.234388, 6, "F'x");
        check(fb.y, -17.427844, 6, "F'y");
        check(mb, -0.457755, 6, "M_b body");
        let (f, m) = fr.wrench(v_rel, 2.0, phi);
        check(f.x, 14.979086, 6, "Fx");
        check(f.y, -11.475761, 6, "Fy");
        check(m, -0.457755, 6, "M_b frame");
    }

    #[test]
    fn mean_radius_reference_values() {
        check(mean_radius(0.4, 0.26), 0.127981, 6, "0.4x0.26");
        check(mean_radius(0.7, 0.1), 0.179136, 6, "0.7x0.1");
        check(mean_radius(0.2, 0.1), 0.059323, 6, "0.2x0.1");
        check(mean_radius(1.0, 1.0), 0.382598, 6, "unit square");
        let exact = (2f64.sqrt() + (1.0 + 2f64.sqrt()).ln()) / 6.0;
        assert!((mean_radius(1.0, 1.0) - exact).abs() < 1e-15);
        // Symmetric in a, b; a segment of length 2L has mean distance L/2.
        assert!((mean_radius(0.4, 0.26) - mean_radius(0.26, 0.4)).abs() < 1e-16);
        assert!((mean_radius(0.0, 0.6) - 0.15).abs() < 1e-16);
        assert_eq!(
            law(0.4, 0.26, FrictionModel::Exact).mean_radius(),
            mean_radius(0.4, 0.26)
        );
    }

    #[test]
    fn special_cases_and_max_force() {
        for model in [FrictionModel::Exact, FrictionModel::Seed] {
            let fr = law(0.4, 0.26, model);
            let mu_n = 0.4 * 5.0 * G;
            assert!((fr.max_force() - mu_n).abs() < 1e-14);
            // ω = 0: F = −μN v̂, M = 0
            let (f, m) = fr.wrench_body(DVec2::new(-0.3, 0.4), 0.0);
            assert!(
                (f - DVec2::new(0.6, -0.8) * mu_n).length() < 1e-13 * mu_n,
                "{model:?}"
            );
            assert_eq!(m, 0.0);
            // v = 0: F = 0, M = −μN⟨ρ⟩ sgn ω
            let (f, m) = fr.wrench_body(DVec2::ZERO, -0.7);
            assert_eq!(f, DVec2::ZERO);
            assert!((m - mu_n * mean_radius(0.4, 0.26)).abs() < 1e-14);
            // both zero
            assert_eq!(fr.wrench_body(DVec2::ZERO, 0.0), (DVec2::ZERO, 0.0));
            assert_eq!(fr.wrench(DVec2::ZERO, 0.0, 1.0), (DVec2::ZERO, 0.0));
        }
    }

    // ---- independent quadrature --------------------------------------------------------

    /// 8-point Gauss–Legendre nodes and weights on [−1, 1].
    const GL8: [(f64, f64); 8] = [
        (-0.9602898564975363, 0.1012285362903763),
        (-0.7966664774136267, 0.2223810344533745),
        (-0.525532409916329, 0.3137066458778873),
        (-0.1834346424956498, 0.362683783378362),
        (0.1834346424956498, 0.362683783378362),
        (0.525532409916329, 0.3137066458778873),
        (0.7966664774136267, 0.2223810344533745),
        (0.9602898564975363, 0.1012285362903763),
    ];

    /// ∫(w/|w|, ρ × w/|w|) dA over the cell [x_lo, x_hi] × [y_lo, y_hi], w = v + ω ẑ×ρ.
    /// Cells at least one cell size away from the ICR (where w/|w| is analytic) get an 8×8
    /// Gauss–Legendre rule; others are split in four, down to a size where the cell's whole
    /// contribution (|integrand| ≤ max|ρ|) is below 1e-16 of the footprint's.
    fn cell(lo: DVec2, hi: DVec2, v: DVec2, w: f64, icr: Option<DVec2>, acc: &mut (DVec2, f64)) {
        let size = (hi - lo).max_element();
        let near = icr.is_some_and(|p| {
            let dx = (lo.x - p.x).max(p.x - hi.x).max(0.0);
            let dy = (lo.y - p.y).max(p.y - hi.y).max(0.0);
            dx.max(dy) < size
        });
        let integrand = |p: DVec2| {
            let wv = v + w * DVec2::new(-p.y, p.x);
            let len = wv.length();
            if len == 0.0 {
                (DVec2::ZERO, 0.0)
            } else {
                let u = wv / len;
                (u, p.x * u.y - p.y * u.x)
            }
        };
        if near && size > 1e-9 {
            let mid = 0.5 * (lo + hi);
            cell(lo, mid, v, w, icr, acc);
            cell(
                DVec2::new(mid.x, lo.y),
                DVec2::new(hi.x, mid.y),
                v,
                w,
                icr,
                acc,
            );
            cell(
                DVec2::new(lo.x, mid.y),
                DVec2::new(mid.x, hi.y),
                v,
                w,
                icr,
                acc,
            );
            cell(mid, hi, v, w, icr, acc);
        } else if near {
            let area = (hi - lo).x * (hi - lo).y;
            let (f, m) = integrand(0.5 * (lo + hi));
            acc.0 += f * area;
            acc.1 += m * area;
        } else {
            let (c, h) = (0.5 * (lo + hi), 0.5 * (hi - lo));
            for &(xi, wx) in &GL8 {
                for &(yj, wy) in &GL8 {
                    let (f, m) = integrand(c + h * DVec2::new(xi, yj));
                    let wt = wx * wy * h.x * h.y;
                    acc.0 += f * wt;
                    acc.1 += m * wt;
                }
            }
        }
    }

    /// Brute-force wrench by the adaptive quadrature above, body axes.
    fn quadrature(a: f64, b: f64, mu_n: f64, v: DVec2, w: f64) -> (DVec2, f64) {
        let (ha, hb) = (0.5 * a, 0.5 * b);
        let icr = (w != 0.0).then(|| DVec2::new(-v.y / w, v.x / w));
        // Start from near-square cells so that the far/near test is meaningful.
        let (nx, ny) = if a >= b {
            (((a / b).round() as usize).max(1), 1)
        } else {
            (1, ((b / a).round() as usize).max(1))
        };
        let mut acc = (DVec2::ZERO, 0.0);
        for i in 0..nx {
            for j in 0..ny {
                let lo = DVec2::new(
                    -ha + a * i as f64 / nx as f64,
                    -hb + b * j as f64 / ny as f64,
                );
                let hi = DVec2::new(
                    -ha + a * (i + 1) as f64 / nx as f64,
                    -hb + b * (j + 1) as f64 / ny as f64,
                );
                cell(lo, hi, v, w, icr, &mut acc);
            }
        }
        let p = mu_n / (a * b);
        (-p * acc.0, -p * acc.1)
    }

    /// Deterministic pseudo-random numbers in [0, 1) (SplitMix64 of the state).
    fn rng(state: &mut u64) -> f64 {
        let mut r = crate::stats::splitmix::SplitMix64(*state);
        let u = r.next_f64();
        *state = r.0;
        u
    }

    /// The exact law against quadrature, ICR inside, on the edge, at a corner and outside.
    /// The quadrature is converged to ~1e-13 (8-point Gauss–Legendre on analytic cells at
    /// least one cell size from the kink, which converges like 5.8^(−16); the unresolved
    /// cells hold < 1e-16 of the area), so a 1e-10 tolerance (relative to μN, resp. μN⟨ρ⟩)
    /// leaves room only for rounding in the closed form (measured: ≤ 1.2e-12 in F,
    /// ≤ 2.3e-12 in M).
    #[test]
    fn exact_law_matches_quadrature() {
        let mut state = 42u64;
        for &(a, b) in &[(0.4, 0.26), (0.7, 0.1), (0.2, 0.1)] {
            let fr = law(a, b, FrictionModel::Exact);
            let mu_n = 0.4 * 5.0 * G;
            let (ha, hb) = (0.5 * a, 0.5 * b);
            let mut cases = vec![
                (DVec2::new(0.0, -ha), 1.0),        // ICR at x₀ = A exactly (on an edge)
                (DVec2::new(hb, -ha), 1.0),         // ICR at the corner (A, B)
                (DVec2::new(-0.3 * hb, 0.0), -2.0), // ICR on the x′ axis, inside
                (DVec2::new(hb, 0.0), -1.0),        // ICR at y₀ = −B exactly (on an edge)
                (DVec2::new(2.0 * hb, 0.0), 1.0),   // ICR outside, at (0, 2B)
                (DVec2::new(0.3 * hb, 4.0 * ha), 2.0), // ICR outside, beyond a corner
            ];
            for _ in 0..40 {
                // ICR uniformly in the footprint enlarged 3×, spin of random size and sign.
                let x0 = (2.0 * rng(&mut state) - 1.0) * 3.0 * ha;
                let y0 = (2.0 * rng(&mut state) - 1.0) * 3.0 * hb;
                let w =
                    (rng(&mut state) * 5.0 + 0.1) * if rng(&mut state) < 0.5 { -1.0 } else { 1.0 };
                cases.push((DVec2::new(y0 * w, -x0 * w), w));
            }
            for (v, w) in cases {
                let (f, m) = fr.wrench_body(v, w);
                let (fq, mq) = quadrature(a, b, mu_n, v, w);
                assert!(
                    (f - fq).length() < 1e-10 * mu_n,
                    "{a}x{b} v={v} w={w}: F {f} vs {fq}"
                );
                let m_scale = mu_n * fr.mean_radius();
                assert!(
                    (m - mq).abs() < 1e-10 * m_scale,
                    "{a}x{b} v={v} w={w}: M {m} vs {mq}"
                );
            }
        }
    }

    /// The asymptotic branch against quadrature beyond the switch (r = 30d … 300d).
    #[test]
    fn asymptotic_branch_matches_quadrature() {
        let mut state = 7u64;
        let mu_n = 0.4 * 5.0 * G;
        for &(a, b) in &[(0.4, 0.26), (0.7, 0.1)] {
            let fr = law(a, b, FrictionModel::Exact);
            let d = 0.5 * f64::hypot(a, b);
            for k in [31.0, 60.0, 300.0] {
                let th = rng(&mut state) * std::f64::consts::TAU;
                let w = 1.5;
                let v = DVec2::new(th.cos(), th.sin()) * (k * d * w);
                let (f, m) = fr.wrench_body(v, w);
                let (fq, mq) = quadrature(a, b, mu_n, v, w);
                // Truncation of the F series (ε⁶) is ≤ 5e-11 at 30d (measured), 1e-16 at 300d.
                assert!((f - fq).length() < 1e-10 * mu_n, "F {f} vs {fq} at {k}d");
                // M ~ μN⟨ρ_v²⟩/r is small here: compare relative to itself (ε⁷ truncation, ≤ 1e-10
                // measured at 31d).
                assert!((m - mq).abs() < 1e-9 * mq.abs(), "M {m} vs {mq} at {k}d");
            }
        }
    }

    // ---- asymptotics and limits ----------------------------------------------------------

    /// Relative jump of F and M across the switch radius, for many sliding directions.
    #[test]
    fn continuous_at_the_asymptotic_switch() {
        for &(a, b) in &[(0.4, 0.26), (0.7, 0.1), (0.2, 0.1), (1.0, 1.0)] {
            let fr = law(a, b, FrictionModel::Exact);
            for i in 0..48 {
                let th = i as f64 * std::f64::consts::TAU / 48.0 + 0.01;
                let dir = DVec2::new(th.cos(), th.sin());
                let w: f64 = -2.3;
                let below = fr.switch_radius * (1.0 - 1e-12) * w.abs();
                let above = fr.switch_radius * (1.0 + 1e-12) * w.abs();
                let (f1, m1) = fr.wrench_body(dir * below, w);
                let (f2, m2) = fr.wrench_body(dir * above, w);
                // Each side really is on its own branch.
                assert_eq!(
                    (f1, m1),
                    fr.closed_form(dir * below, w, 0.4 * fr.normal_force)
                );
                let speed = (dir * above).length();
                let mu_n = 0.4 * fr.normal_force;
                assert_eq!((f2, m2), fr.asymptotic(dir * above, speed, w, mu_n));
                assert!(
                    (f1 - f2).length() < 1e-7 * f1.length(),
                    "{a}x{b} θ={th}: F jump"
                );
                assert!(
                    (m1 - m2).abs() < 1e-7 * m1.abs(),
                    "{a}x{b} θ={th}: M jump {m1} {m2}"
                );
            }
        }
    }

    /// At 20d the expansion is already close to the closed form: its truncation error is
    /// O((d/r)⁶) in F and M, measured ≤ 6e-10 (F) and ≤ 8e-9 (M) relative for these
    /// footprints; tolerances 1e-8 and 5e-8.
    #[test]
    fn asymptotic_branch_agrees_with_closed_form_at_20d() {
        for &(a, b) in &[(0.4, 0.26), (0.7, 0.1), (0.2, 0.1)] {
            let fr = law(a, b, FrictionModel::Exact);
            let d = fr.switch_radius / ASYMPTOTIC_SWITCH;
            for i in 0..24 {
                let th = i as f64 * std::f64::consts::TAU / 24.0 + 0.1;
                let w = 0.8;
                let v = DVec2::new(th.cos(), th.sin()) * (20.0 * d * w);
                let (fc, mc) = fr.closed_form(v, w, 1.0);
                let (fa, ma) = fr.asymptotic(v, v.length(), w, 1.0);
                assert!((fc - fa).length() < 1e-8 * fc.length(), "{a}x{b} θ={th}: F");
                assert!(
                    (mc - ma).abs() < 5e-8 * mc.abs(),
                    "{a}x{b} θ={th}: M {mc} {ma}"
                );
            }
        }
    }

    /// Small r: F ≈ −(μN/|ω|) Λ v′ and M ≈ −μN⟨ρ⟩ sgn ω with zero slope at r = 0.
    #[test]
    fn small_radius_limit() {
        for &(a, b) in &[(0.4, 0.26), (0.7, 0.1)] {
            let fr = law(a, b, FrictionModel::Exact);
            let mu_n = 0.4 * 5.0 * G;
            let lambda = spin_slopes(a, b);
            let d = 0.5 * f64::hypot(a, b);
            for th in [0.0, 0.5, 1.3, 2.9] {
                let w: f64 = -3.0;
                let r = 1e-4 * d;
                let v = DVec2::new(f64::cos(th), f64::sin(th)) * (r * w.abs());
                let (f, m) = fr.wrench_body(v, w);
                let lin = -(mu_n / w.abs()) * lambda * v;
                // next term is O(r²) relative to the linear one (F is odd in v′)
                assert!((f - lin).length() < 1e-6 * lin.length(), "F {f} vs {lin}");
                let m0 = mu_n * fr.mean_radius();
                assert!((m - m0).abs() < 1e-6 * m0, "M {m} vs {m0}");
            }
        }
        // Λ itself: the seed k₁ values (model.md §3).
        let l = spin_slopes(0.4, 0.26);
        check(l.x, 6.080, 3, "k1 along a");
        check(l.y, 4.702, 3, "k1 along b");
    }

    /// Large r: F ≈ −μN[v̂(1 − ⟨ρ_v²⟩/(2r²)) + n̂⟨ρ_vρ_n⟩/r²], M ≈ −μN sgn ω ⟨ρ_v²⟩/r.
    #[test]
    fn large_radius_limit() {
        let (a, b) = (0.4, 0.26);
        let (ha, hb) = (0.5 * a, 0.5 * b);
        let fr = law(a, b, FrictionModel::Exact);
        let mu_n = 0.4 * 5.0 * G;
        let d = (ha * ha + hb * hb).sqrt();
        for th in [0.3f64, 1.0, 2.0, 4.0] {
            for r_over_d in [40.0, 1000.0] {
                let r = r_over_d * d;
                let w = 0.5;
                let vh = DVec2::new(th.cos(), th.sin());
                let nh = DVec2::new(-vh.y, vh.x);
                let mvv = (ha * ha * th.cos().powi(2) + hb * hb * th.sin().powi(2)) / 3.0;
                let mvn = (hb * hb - ha * ha) * th.cos() * th.sin() / 3.0;
                let (f, m) = fr.wrench_body(vh * (r * w), w);
                // Neglected: O((d/r)⁴) in F·v̂ and F·n̂, O((d/r)²) relative in M.
                let q = (d / r).powi(2);
                let fv = -mu_n * (1.0 - mvv / (2.0 * r * r));
                let fnn = -mu_n * mvn / (r * r);
                assert!((f.dot(vh) - fv).abs() < q * q * mu_n);
                assert!((f.dot(nh) - fnn).abs() < q * q * mu_n);
                let m_lim = -mu_n * mvv / r;
                assert!(
                    (m - m_lim).abs() < 2.0 * q * m_lim.abs(),
                    "M {m} vs {m_lim}"
                );
            }
        }
    }

    // ---- seed law ------------------------------------------------------------------------

    #[test]
    fn seed_law_reference_coefficients() {
        for &(a, b, k1a, k1b, k2) in &[
            (0.4, 0.26, 6.080, 4.702, 7.814),
            (0.7, 0.1, 7.555, 2.848, 5.582),
            (0.2, 0.1, 14.436, 9.624, 16.857),
        ] {
            let fr = law(a, b, FrictionModel::Seed);
            let (k1, k2_) = fr.seed_coefficients();
            let l = spin_slopes(a, b);
            check(l.x, k1a, 3, "k1 along a");
            check(l.y, k1b, 3, "k1 along b");
            // k₁ is the mean of the exact slopes; the printed values carry ±5e-4 each.
            check(k1, 0.5 * (k1a + k1b), 3, "k1 mean");
            check(k2_, k2, 3, "k2");
        }
    }

    #[test]
    fn seed_law_values_and_limits() {
        let fr = law(0.4, 0.26, FrictionModel::Seed);
        let mu_n = 0.4 * 5.0 * G;
        let (k1, k2) = fr.seed_coefficients();
        let rho = fr.mean_radius();
        let l0 = mu_n * rho;
        // A generic point: |F| = μN tanh(k₁r), L_M by the formula, M = −L_M sgn ω.
        let v = DVec2::new(0.12, -0.05);
        let w: f64 = -1.7;
        let r = v.length() / w.abs();
        let (f, m) = fr.wrench_body(v, w);
        assert!((f.length() - mu_n * (k1 * r).tanh()).abs() < 1e-13 * mu_n);
        let l_m = l0 * (-k2 * r).exp() + mu_n * r * (1.0 - (k1 * r).tanh());
        assert!((m - l_m).abs() < 1e-13 * l0, "M {m} vs {l_m}");
        // Exactly anti-parallel to v′.
        assert!(f.perp_dot(v).abs() <= 1e-15 * f.length() * v.length());
        assert!(f.dot(v) < 0.0);
        // r → ∞: |F| → μN, M → 0 (decays exponentially).
        let (f, m) = fr.wrench_body(DVec2::new(50.0, 0.0), 0.01);
        assert!((f.x + mu_n).abs() < 1e-12 * mu_n && f.y == 0.0);
        assert!(m.abs() < 1e-100);
        // r → 0: F → 0 linearly with slope μN k₁, L_M → L₀ with zero slope (k₂ = 1/⟨ρ⟩).
        let r = 1e-6;
        let (f, m) = fr.wrench_body(DVec2::new(r * 2.0, 0.0), 2.0);
        assert!((f.x + mu_n * k1 * r).abs() < 1e-9 * mu_n * k1 * r);
        assert!((-m - l0).abs() < 1e-10 * l0, "slope at r = 0 must vanish");
        // Frame axes: anti-parallel to v_r, independent of φ.
        let v_rel = DVec2::new(-0.4, 0.3);
        let (f, m) = fr.wrench(v_rel, 1.0, 0.7);
        assert!(f.perp_dot(v_rel).abs() <= 1e-15 * f.length() * v_rel.length());
        assert_eq!((f, m), fr.wrench(v_rel, 1.0, -2.0));
    }

    // ---- coefficient table ---------------------------------------------------------------

    #[test]
    fn coefficient_table_interpolates_and_clamps() {
        let c = FrictionCoefficient::Table(vec![(0.0, 0.5), (1.0, 0.4), (3.0, 0.3)]);
        assert_eq!(c.at(-1.0), 0.5);
        assert_eq!(c.at(0.0), 0.5);
        assert!((c.at(0.5) - 0.45).abs() < 1e-15);
        assert_eq!(c.at(1.0), 0.4);
        assert!((c.at(2.5) - 0.325).abs() < 1e-15);
        assert_eq!(c.at(3.0), 0.3);
        assert_eq!(c.at(100.0), 0.3);
        let offset = FrictionCoefficient::Table(vec![(0.5, 0.6), (1.5, 0.2)]);
        assert_eq!(offset.at(0.0), 0.6);
        assert!((offset.at(1.0) - 0.4).abs() < 1e-15);
        assert_eq!(FrictionCoefficient::Table(vec![(1.0, 0.35)]).at(7.0), 0.35);
        assert!(FrictionCoefficient::Table(vec![]).at(1.0).is_nan());
        assert_eq!(FrictionCoefficient::Constant(0.25).at(9.0), 0.25);

        // The laws use μ(|v_r|): at ω = 0, |F| = μ(|v|) N; max_force uses μ(0).
        for model in [FrictionModel::Exact, FrictionModel::Seed] {
            let fr = BeltFriction::new(0.4, 0.26, 10.0, c.clone(), model);
            let (f, _) = fr.wrench_body(DVec2::new(0.0, 2.5), 0.0);
            assert!((f.length() - 3.25).abs() < 1e-13);
            assert!((fr.max_force() - 5.0).abs() < 1e-15);
            let (f, _) = fr.wrench(DVec2::new(0.3, 0.4), 0.0, 0.4);
            assert!((f.length() - 4.5).abs() < 1e-13);
        }
    }

    // ---- invariants ----------------------------------------------------------------------

    fn arb_case() -> impl Strategy<Value = (f64, f64, DVec2, f64, f64, bool)> {
        (
            0.05f64..1.0,
            0.05f64..1.0,
            prop_oneof![-3.0f64..3.0, -0.05f64..0.05],
            prop_oneof![-3.0f64..3.0, -0.05f64..0.05],
            prop_oneof![-20.0f64..20.0, -0.01f64..0.01, Just(0.0)],
            -4.0f64..4.0,
            any::<bool>(),
        )
            .prop_map(|(a, b, vx, vy, w, phi, seed)| (a, b, DVec2::new(vx, vy), w, phi, seed))
    }

    fn model_of(seed: bool) -> FrictionModel {
        if seed {
            FrictionModel::Seed
        } else {
            FrictionModel::Exact
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(400))]

        /// Friction never does positive work: F·v′ + M ω ≤ 0.
        #[test]
        fn dissipative((a, b, v, w, _phi, seed) in arb_case()) {
            let fr = law(a, b, model_of(seed));
            let (f, m) = fr.wrench_body(v, w);
            prop_assert!(f.dot(v) + m * w <= 0.0);
        }

        /// Oddness: wrench(−v′, −ω) = −wrench(v′, ω).
        #[test]
        fn odd((a, b, v, w, _phi, seed) in arb_case()) {
            let fr = law(a, b, model_of(seed));
            let (f1, m1) = fr.wrench_body(v, w);
            let (f2, m2) = fr.wrench_body(-v, -w);
            prop_assert!((f1 + f2).length() <= 1e-13 * f1.length());
            prop_assert!((m1 + m2).abs() <= 1e-13 * m1.abs());
        }

        /// |F| ≤ μN and |M| ≤ μN⟨ρ⟩ (exact law; each footprint point contributes at most μp and
        /// μp|ρ|).
        #[test]
        fn bounded((a, b, v, w, _phi, _seed) in arb_case()) {
            let fr = law(a, b, FrictionModel::Exact);
            let mu_n = fr.max_force();
            let (f, m) = fr.wrench_body(v, w);
            prop_assert!(f.length() <= mu_n * (1.0 + 1e-12));
            prop_assert!(m.abs() <= mu_n * fr.mean_radius() * (1.0 + 1e-12));
        }

        /// Rotation covariance: the frame-axes wrench is the body wrench rotated by φ, and
        /// turning both v_r and φ by ψ turns F by ψ and leaves M. The rotations perturb v′ by
        /// rounding, and when the instantaneous centre lies far outside the footprint
        /// (r ≫ a, b: nearly pure sliding) M is a small difference of terms of size μN⟨ρ⟩, so
        /// its rounding error is relative to μN⟨ρ⟩, not to M: 1e-10 μN⟨ρ⟩ (a 16:1 footprint
        /// at r = 11 m once needed 5e-11, beyond the former 1e-12 μN⟨ρ⟩ + 2e-8 |M|).
        #[test]
        fn rotation_covariant((a, b, v, w, phi, seed) in arb_case(), psi in -3.0f64..3.0) {
            let fr = law(a, b, model_of(seed));
            let (fb, mb) = fr.wrench_body(rot(v, -phi), w);
            let (f, m) = fr.wrench(v, w, phi);
            let scale = fr.max_force();
            let m_tol = 1e-10 * scale * fr.mean_radius() + 2e-8 * m.abs();
            prop_assert!((f - rot(fb, phi)).length() <= 1e-12 * scale);
            prop_assert!((m - mb).abs() <= 1e-12 * scale * fr.mean_radius());
            let (f2, m2) = fr.wrench(rot(v, psi), w, phi + psi);
            prop_assert!((f2 - rot(f, psi)).length() <= 1e-11 * scale);
            prop_assert!((m2 - m).abs() <= m_tol, "M {} vs {}", m2, m);
        }
    }
}
