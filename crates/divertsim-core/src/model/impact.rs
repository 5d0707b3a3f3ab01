//! Oblique impact of rough bodies: Stronge's energetic restitution with Coulomb friction
//! (docs/model.md §5), solved exactly in the impulse domain (≤ 3 linear segments).
//! Newton (kinematic) and Poisson (kinetic) restitution are options for comparison; they use
//! the same friction-mode machinery and differ only in the termination condition.
//!
//! The obstacle (arm or guide) is kinematically driven: effectively infinite mass, so only the
//! parcel's mobility enters. The configuration is frozen during the impact and belt
//! friction (finite) is neglected.
//!
//! Conventions (docs/model.md §1): n is the unit normal on the parcel, from the obstacle into the
//! parcel; t = (n_y, −n_x), so that t × n = +ẑ; r = P − G; u = relative velocity of the
//! parcel's contact point with respect to the obstacle's material point, u_t = u·t,
//! u_n = u·n < 0 when approaching. The sign of W_tn depends on this handedness.
//!
//! Also here: the closed forms of model.md §5 (an independent cross-check of the algorithm) and
//! its overload helpers (free-fall impulse, equivalent drop height, peak force with a
//! linear contact stiffness).
//!
//! References: W. J. Stronge, J. Appl. Mech. 58:1049 (1991); Proc. R. Soc. A 431:169 (1990);
//! *Impact Mechanics*, CUP (2000), ch. 5.

use glam::DVec2;

/// Which restitution law ends the impact.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum ImpactLaw {
    /// Stronge's energetic coefficient (default).
    #[default]
    Energetic,
    /// Newton: u_n,f = −e u_n,0.
    Newton,
    /// Poisson: p_f = (1 + e) p_c.
    Poisson,
}

/// (t, n): the contact basis for a normal direction, t = (n_y, −n_x) (model.md §1).
///
/// The normal is normalised here; a zero or non-finite normal gives NaN components, which
/// [`resolve`] rejects as invalid input.
#[inline]
pub fn contact_basis(normal: DVec2) -> (DVec2, DVec2) {
    let n = normal / normal.length();
    (DVec2::new(n.y, -n.x), n)
}

/// W: the mobility ("inverse inertia") matrix at the contact in the (t, n) basis [1/kg]
/// (model.md §5): Δu = W · (p_t, p_n)ᵀ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mobility {
    /// W_tt = 1/m + r_n²/I [1/kg]
    pub tt: f64,
    /// W_tn = W_nt = −r_t r_n / I [1/kg]
    pub tn: f64,
    /// W_nn = 1/m + r_t²/I [1/kg]
    pub nn: f64,
}

/// Effective masses of the closed forms (model.md §5) for an initial slip direction s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EffectiveMasses {
    /// M = 1/(W_nn − μ s W_tn): effective normal mass in the initial slip \[kg]
    pub slip: f64,
    /// M_* = 1/(W_nn + μ s W_tn): effective normal mass after reversal \[kg]
    pub reversed: f64,
    /// M_st = W_tt / det W: effective normal mass during stick \[kg]
    pub stick: f64,
    /// K = μ/(μ W_tt − s W_tn), so that p_s = |u_t0| K/μ \[kg]
    pub k: f64,
}

impl Mobility {
    /// W for a body of mass m \[kg] and moment of inertia I about G [kg·m²], contact point at
    /// r = P − G \[m], normal `normal` (normalised here) pointing into the body.
    pub fn at_contact(mass: f64, inertia: f64, r: DVec2, normal: DVec2) -> Mobility {
        let (t, n) = contact_basis(normal);
        let (r_t, r_n) = (r.dot(t), r.dot(n));
        let inv_m = 1.0 / mass;
        Mobility {
            tt: inv_m + r_n * r_n / inertia,
            tn: -r_t * r_n / inertia,
            nn: inv_m + r_t * r_t / inertia,
        }
    }

    /// det W = W_tt W_nn − W_tn² [1/kg²]; equals (1/m)(1/m + |r|²/I) for a rigid body.
    #[inline]
    pub fn det(&self) -> f64 {
        self.tt * self.nn - self.tn * self.tn
    }

    /// Whether all entries are finite and W is symmetric positive definite.
    pub fn is_positive_definite(&self) -> bool {
        self.tt.is_finite()
            && self.tn.is_finite()
            && self.nn.is_finite()
            && self.tt > 0.0
            && self.nn > 0.0
            && self.det() > 0.0
    }

    /// Δu = W·(p_t, p_n): the change of the contact velocity (Δu_t, Δu_n) [m/s] for an
    /// impulse (p_t, p_n) [N·s].
    #[inline]
    pub fn apply(&self, p_t: f64, p_n: f64) -> (f64, f64) {
        (self.tt * p_t + self.tn * p_n, self.tn * p_t + self.nn * p_n)
    }

    /// M, M_*, M_st and K of model.md §5 for friction μ and slip direction s (±1).
    pub fn effective_masses(&self, friction: f64, s: f64) -> EffectiveMasses {
        EffectiveMasses {
            slip: 1.0 / (self.nn - friction * s * self.tn),
            reversed: 1.0 / (self.nn + friction * s * self.tn),
            stick: self.tt / self.det(),
            k: friction / (friction * self.tt - s * self.tn),
        }
    }

    /// Whether sticking can hold: |W_tn| ≤ μ W_tt (model.md §5).
    #[inline]
    fn stick_possible(&self, friction: f64) -> bool {
        self.tn.abs() <= friction * self.tt
    }
}

/// A contact mode during the impact (model.md §5).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImpactMode {
    /// Slip with direction s = sgn(u_t) = ±1.
    Slip(i8),
    /// Stick: u_t ≡ 0.
    Stick,
}

/// Constant rates of one mode per unit normal impulse.
#[derive(Debug, Clone, Copy)]
struct Rates {
    /// κ = dp_t/dp
    kappa: f64,
    /// a_t = du_t/dp [1/kg]
    a_t: f64,
    /// a_n = du_n/dp [1/kg]
    a_n: f64,
}

impl ImpactMode {
    fn rates(self, w: &Mobility, friction: f64) -> Rates {
        match self {
            ImpactMode::Slip(s) => {
                let s = f64::from(s);
                Rates {
                    kappa: -friction * s,
                    a_t: w.tn - friction * s * w.tt,
                    a_n: w.nn - friction * s * w.tn,
                }
            }
            ImpactMode::Stick => Rates {
                kappa: -w.tn / w.tt,
                a_t: 0.0,
                a_n: w.det() / w.tt,
            },
        }
    }
}

/// The modes an impact went through, in order (at most two: a slip may stop once, and the
/// mode after the stop, stick or accelerating reversed slip, never changes again). No heap.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModeSequence {
    modes: [ImpactMode; 2],
    len: u8,
}

impl ModeSequence {
    fn new(first: ImpactMode) -> Self {
        ModeSequence {
            modes: [first; 2],
            len: 1,
        }
    }

    fn push(&mut self, mode: ImpactMode) {
        // The theory allows one change only; a second one (impossible) would be dropped.
        if usize::from(self.len) < self.modes.len() {
            self.modes[usize::from(self.len)] = mode;
            self.len += 1;
        }
    }

    /// The modes, first to last.
    pub fn as_slice(&self) -> &[ImpactMode] {
        &self.modes[..usize::from(self.len)]
    }

    /// Number of modes (1 or 2).
    pub fn len(&self) -> usize {
        usize::from(self.len)
    }

    /// Always false: there is at least the initial mode.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The initial mode.
    pub fn first(&self) -> ImpactMode {
        self.modes[0]
    }

    /// The mode at separation.
    pub fn last(&self) -> ImpactMode {
        self.modes[usize::from(self.len) - 1]
    }
}

/// Input of one impact, already reduced to the contact (model.md §5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpactInput {
    /// W: mobility at the contact in the (t, n) basis [1/kg]
    pub mobility: Mobility,
    /// u_t0: initial tangential relative velocity [m/s]
    pub u_t0: f64,
    /// u_n0: initial normal relative velocity [m/s], < 0 (approaching)
    pub u_n0: f64,
    /// μ: Coulomb friction coefficient at the contact (μ_a for the arm) [-]
    pub friction: f64,
    /// e (e* for the energetic law): coefficient of restitution, in [0, 1] [-]
    pub restitution: f64,
    /// Which restitution law ends the impact.
    pub law: ImpactLaw,
}

/// Result of one impact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpactOutcome {
    /// p_f: total normal impulse on the parcel [N·s]
    pub normal_impulse: f64,
    /// p_t: total tangential impulse on the parcel [N·s]
    pub tangential_impulse: f64,
    /// p_c: normal impulse at the end of compression (u_n = 0) [N·s]
    pub compression_impulse: f64,
    /// p_s: normal impulse at which the initial slip stopped; `None` if it never stopped
    /// (always `None` when μ = 0, where the slip direction does not matter) [N·s]
    pub slip_stop_impulse: Option<f64>,
    /// u_t,f: final tangential relative velocity [m/s]
    pub u_t: f64,
    /// u_n,f: final normal relative velocity [m/s]
    pub u_n: f64,
    /// W_c = ∫₀^{p_c} u_n dp: work of the normal impulse in compression, ≤ 0 \[J]
    pub compression_work: f64,
    /// W_n(p_f) = ∫₀^{p_f} u_n dp: total work of the normal impulse \[J]
    pub normal_work: f64,
    /// ∫ u_t dp_t: total work of the tangential impulse, ≤ 0 \[J]
    pub tangential_work: f64,
    /// S = √(p_f² + p_t²): magnitude of the impulse [N·s]
    pub total_impulse: f64,
    /// e_N = −u_n,f/u_n0: the equivalent Newton coefficient [-]
    pub newton_restitution: f64,
    /// e_P = (p_f − p_c)/p_c: the equivalent Poisson coefficient [-]
    pub poisson_restitution: f64,
    /// −(∫u_n dp + ∫u_t dp_t): kinetic energy lost relative to the obstacle's contact point,
    /// ≥ 0 for the energetic law \[J]
    pub dissipated: f64,
    /// The contact modes, in order.
    pub modes: ModeSequence,
}

impl ImpactOutcome {
    /// P = p_t t + p_f n: the impulse on the parcel in frame axes [N·s], for the contact
    /// normal `normal`.
    pub fn impulse_vector(&self, normal: DVec2) -> DVec2 {
        let (t, n) = contact_basis(normal);
        self.tangential_impulse * t + self.normal_impulse * n
    }
}

/// Why an impact cannot be resolved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ImpactError {
    /// u_n0 ≥ 0: the bodies are not approaching.
    #[error("contact is not approaching (u_n0 ≥ 0)")]
    NotApproaching,
    /// a_n ≤ 0 in compression: a Painlevé-type "jam" (impossible for rectangle corners with
    /// μ < 4/3, model.md §5).
    #[error("jam: normal relative velocity does not increase in compression (Painlevé type)")]
    Jam,
    /// Non-finite values, μ < 0, e ∉ [0, 1], or W not positive definite.
    #[error("invalid impact input: {0}")]
    InvalidInput(String),
}

fn validate(input: &ImpactInput) -> Result<(), ImpactError> {
    let w = &input.mobility;
    if ![
        w.tt,
        w.tn,
        w.nn,
        input.u_t0,
        input.u_n0,
        input.friction,
        input.restitution,
    ]
    .iter()
    .all(|v| v.is_finite())
    {
        return Err(ImpactError::InvalidInput("non-finite value".into()));
    }
    if input.friction < 0.0 {
        return Err(ImpactError::InvalidInput(format!(
            "friction coefficient {} < 0",
            input.friction
        )));
    }
    if !(0.0..=1.0).contains(&input.restitution) {
        return Err(ImpactError::InvalidInput(format!(
            "restitution {} outside [0, 1]",
            input.restitution
        )));
    }
    if !w.is_positive_definite() {
        return Err(ImpactError::InvalidInput(
            "mobility matrix W is not positive definite".into(),
        ));
    }
    if input.u_n0 >= 0.0 {
        return Err(ImpactError::NotApproaching);
    }
    Ok(())
}

/// The initial contact mode (model.md §5). With μ = 0 the rates do not depend on the slip
/// direction, so the label is just sgn(u_t0) (or sgn(W_tn) if u_t0 = 0).
fn initial_mode(w: &Mobility, u_t0: f64, friction: f64) -> ImpactMode {
    if u_t0 > 0.0 {
        ImpactMode::Slip(1)
    } else if u_t0 < 0.0 {
        ImpactMode::Slip(-1)
    } else if w.stick_possible(friction) {
        ImpactMode::Stick
    } else if w.tn > 0.0 {
        ImpactMode::Slip(1)
    } else {
        ImpactMode::Slip(-1)
    }
}

/// Solve one impact exactly with the ≤ 3-segment algorithm of model.md §5.
///
/// Events: slip stop (→ stick if |W_tn| ≤ μ W_tt, else reversal), compression end
/// (u_n = 0), and termination: W_n(p_f) = (1 − e²) W_c (energetic), u_n = −e u_n0 (Newton),
/// p = (1 + e) p_c (Poisson). With e = 0 the impact ends at compression end for every law.
/// With μ = 0 slip-stop events are skipped: they change nothing (κ = 0, rates independent of
/// the slip direction), and the falling-rod row A of model.md §5 has no p_s.
pub fn resolve(input: &ImpactInput) -> Result<ImpactOutcome, ImpactError> {
    validate(input)?;
    let w = &input.mobility;
    let (mu, e) = (input.friction, input.restitution);
    let u_n0 = input.u_n0;

    let mut mode = initial_mode(w, input.u_t0, mu);
    let mut modes = ModeSequence::new(mode);
    let (mut p, mut p_t) = (0.0_f64, 0.0_f64);
    let (mut u_t, mut u_n) = (input.u_t0, u_n0);
    let (mut w_n, mut w_t) = (0.0_f64, 0.0_f64);
    // W_n(p) − W_c, accumulated from zero after compression: the termination test
    // W_n − (1 − e²) W_c = (W_n − W_c) + e² W_c would lose all digits of a small e² W_c.
    let mut w_rest = 0.0_f64;
    let mut w_c: Option<f64> = None;
    let mut p_c = 0.0;
    let mut p_s: Option<f64> = None;
    let mut finished = false;

    // Each of slip stop, compression end and termination happens at most once.
    for _ in 0..4 {
        let r = mode.rates(w, mu);
        // a_n ≤ 0 in compression: u_n never reaches 0 in this mode (Painlevé type). After a
        // stop the new mode always has a_n > 0 (model.md §5), so the restitution check is a guard.
        if r.a_n <= 0.0 {
            return Err(ImpactError::Jam);
        }

        let stop_dp = match mode {
            ImpactMode::Slip(s) if mu > 0.0 && f64::from(s) * r.a_t < 0.0 => {
                Some((-u_t / r.a_t).max(0.0))
            }
            _ => None,
        };
        let end_dp = match w_c {
            None => (-u_n / r.a_n).max(0.0),
            Some(wc) => match input.law {
                ImpactLaw::Energetic => {
                    // 0.5 a_n dp² + u_n dp + c = 0 with c ≤ 0 and u_n ≥ 0: the
                    // cancellation-free form of the positive root.
                    let c = w_rest + e * e * wc;
                    let disc = (u_n * u_n - 2.0 * r.a_n * c).max(0.0);
                    let den = u_n + disc.sqrt();
                    if den > 0.0 {
                        (-2.0 * c / den).max(0.0)
                    } else {
                        0.0
                    }
                }
                ImpactLaw::Newton => ((-e * u_n0 - u_n) / r.a_n).max(0.0),
                ImpactLaw::Poisson => (e * p_c - (p - p_c)).max(0.0),
            },
        };
        let dp = stop_dp.map_or(end_dp, |d| d.min(end_dp));

        // Advance along the linear segment.
        let dw_n = u_n * dp + 0.5 * r.a_n * dp * dp;
        w_n += dw_n;
        if w_c.is_some() {
            w_rest += dw_n;
        }
        w_t += r.kappa * (u_t * dp + 0.5 * r.a_t * dp * dp);
        p += dp;
        p_t += r.kappa * dp;
        u_t += r.a_t * dp;
        u_n += r.a_n * dp;

        if let (Some(d), ImpactMode::Slip(s)) = (stop_dp, mode) {
            if d <= dp {
                u_t = 0.0;
                p_s = Some(p);
                mode = if w.stick_possible(mu) {
                    ImpactMode::Stick
                } else {
                    ImpactMode::Slip(-s)
                };
                modes.push(mode);
            }
        }
        if end_dp <= dp {
            if w_c.is_none() {
                u_n = 0.0;
                w_c = Some(w_n);
                p_c = p;
                if e == 0.0 {
                    finished = true;
                }
            } else {
                finished = true;
            }
        }
        if finished {
            break;
        }
    }
    if !finished {
        // Unreachable by model.md §5 (at most three events); reported rather than panicking.
        return Err(ImpactError::InvalidInput(
            "impact did not terminate within three segments".into(),
        ));
    }

    Ok(ImpactOutcome {
        normal_impulse: p,
        tangential_impulse: p_t,
        compression_impulse: p_c,
        slip_stop_impulse: p_s,
        u_t,
        u_n,
        compression_work: w_c.unwrap_or(w_n),
        normal_work: w_n,
        tangential_work: w_t,
        total_impulse: p.hypot(p_t),
        newton_restitution: -u_n / u_n0,
        poisson_restitution: (p - p_c) / p_c,
        dissipated: -(w_n + w_t),
        modes,
    })
}

/// Velocity jumps of the parcel's centre and rotation.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BodyImpulse {
    /// ΔV_G: jump of the centre velocity [m/s]
    pub dv: DVec2,
    /// Δω: jump of the angular velocity [rad/s]
    pub domega: f64,
}

/// ΔV_G = (p_t t + p_n n)/m and Δω = (r_t p_n − r_n p_t)/I (model.md §5), for mass m \[kg],
/// inertia I [kg·m²], r = P − G \[m], the contact normal (normalised here), and the normal and
/// tangential impulses p_n, p_t [N·s].
pub fn body_velocity_change(
    mass: f64,
    inertia: f64,
    r: DVec2,
    normal: DVec2,
    p_n: f64,
    p_t: f64,
) -> BodyImpulse {
    let (t, n) = contact_basis(normal);
    let (r_t, r_n) = (r.dot(t), r.dot(n));
    BodyImpulse {
        dv: (p_t * t + p_n * n) / mass,
        domega: (r_t * p_n - r_n * p_t) / inertia,
    }
}

/// One of two free bodies at a contact between them: its mass, its inertia and where the
/// contact point lies on it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyAtContact {
    /// m \[kg]
    pub mass: f64,
    /// I about G [kg·m²]
    pub inertia: f64,
    /// r = P − G \[m]
    pub r: DVec2,
}

impl BodyAtContact {
    /// Its own mobility at the contact, in the basis of `normal` (model.md §5a).
    pub fn mobility(&self, normal: DVec2) -> Mobility {
        Mobility::at_contact(self.mass, self.inertia, self.r, normal)
    }
}

/// W = W_A + W_B: the mobility of the relative contact velocity u = v_A(P) − v_B(P) of two
/// free bodies, A taking the impulse P and B −P (model.md §5a). With it, [`resolve`] solves
/// a strike between two parcels exactly as one on the arm: the arm is the case W_B = 0.
pub fn pair_mobility(a: &BodyAtContact, b: &BodyAtContact, normal: DVec2) -> Mobility {
    let (wa, wb) = (a.mobility(normal), b.mobility(normal));
    Mobility {
        tt: wa.tt + wb.tt,
        tn: wa.tn + wb.tn,
        nn: wa.nn + wb.nn,
    }
}

/// The velocity jumps of both bodies of a pair strike: A takes (p_t t + p_n n), B the
/// opposite, each at its own r ([`body_velocity_change`]).
pub fn pair_velocity_changes(
    a: &BodyAtContact,
    b: &BodyAtContact,
    normal: DVec2,
    p_n: f64,
    p_t: f64,
) -> (BodyImpulse, BodyImpulse) {
    (
        body_velocity_change(a.mass, a.inertia, a.r, normal, p_n, p_t),
        body_velocity_change(b.mass, b.inertia, b.r, normal, -p_n, -p_t),
    )
}

/// The closed forms of model.md §5 for the energetic law: (p_f, p_t, τ_f) with
/// τ_f = 1 + e_N. Independent of [`resolve`]; used to cross-check it. Returns NaNs for input
/// that [`resolve`] rejects (invalid, not approaching, or a jam).
pub fn closed_form_energetic(input: &ImpactInput) -> (f64, f64, f64) {
    const NAN3: (f64, f64, f64) = (f64::NAN, f64::NAN, f64::NAN);
    if validate(input).is_err() {
        return NAN3;
    }
    let w = &input.mobility;
    let (mu, e) = (input.friction, input.restitution);
    let v0 = -input.u_n0;

    if input.u_t0 == 0.0 {
        // Zero initial slip: stick throughout, or slip with s = sgn(W_tn) that accelerates.
        let tau_f = 1.0 + e;
        if w.stick_possible(mu) {
            let p_f = tau_f * v0 * w.tt / w.det();
            return (p_f, -(w.tn / w.tt) * p_f, tau_f);
        }
        let s = if w.tn > 0.0 { 1.0 } else { -1.0 };
        let m = 1.0 / (w.nn - mu * s * w.tn);
        if m <= 0.0 {
            return NAN3;
        }
        let p_f = tau_f * v0 * m;
        return (p_f, -mu * s * p_f, tau_f);
    }

    let s = input.u_t0.signum();
    let masses = w.effective_masses(mu, s);
    let m = masses.slip;
    if m <= 0.0 {
        return NAN3;
    }
    let decel = mu * w.tt - s * w.tn; // > 0 iff the initial slip decelerates
                                      // μ = 0: the stop changes nothing, treat as constant slip (as resolve does).
    if mu == 0.0 || decel <= 0.0 {
        let tau_f = 1.0 + e;
        let p_f = tau_f * v0 * m;
        return (p_f, -mu * s * p_f, tau_f);
    }
    // p_s = |u_t0| K/μ, written without the 0/0 of K/μ.
    let p_s = input.u_t0.abs() / decel;
    let tau_s = p_s / (v0 * m);
    let stick = w.stick_possible(mu);
    let m2 = if stick { masses.stick } else { masses.reversed };
    let q = m / m2;
    let tau_f = if tau_s >= 1.0 + e {
        1.0 + e
    } else if tau_s >= 1.0 {
        1.0 + ((tau_s - 1.0).powi(2) * (1.0 - q) + e * e * q).sqrt()
    } else {
        1.0 + e * ((1.0 - tau_s).powi(2) + q * tau_s * (2.0 - tau_s)).sqrt()
    };
    if tau_f <= tau_s {
        let p_f = v0 * m * tau_f;
        return (p_f, -mu * s * p_f, tau_f);
    }
    let p_f = v0 * (m * tau_s + m2 * (tau_f - tau_s));
    let p_t = if stick {
        -mu * s * p_s - (w.tn / w.tt) * (p_f - p_s)
    } else {
        -mu * s * (2.0 * p_s - p_f)
    };
    (p_f, p_t, tau_f)
}

/// S_fall = m(1 + e)√(2 g H₀): impulse of a flat drop from height H₀ \[m] onto an undeformable
/// floor, for mass m \[kg] and restitution e (model.md §5, "Overload") [N·s].
pub fn free_fall_impulse(mass: f64, restitution: f64, drop_height: f64) -> f64 {
    mass * (1.0 + restitution) * (2.0 * crate::GRAVITY * drop_height).sqrt()
}

/// H_eq = (S/(m(1 + e)))²/(2g): the drop height whose flat-drop impulse equals S [N·s]
/// (model.md §5, "Overload") \[m].
pub fn equivalent_drop_height(impulse: f64, mass: f64, restitution: f64) -> f64 {
    let dv = impulse / (mass * (1.0 + restitution));
    dv * dv / (2.0 * crate::GRAVITY)
}

/// m g H₀: the compression work of a flat drop from H₀ \[m]; the peak-force criterion with a linear
/// contact stiffness is |W_c| ≤ m g H₀ \[J].
pub fn drop_compression_work(mass: f64, drop_height: f64) -> f64 {
    mass * crate::GRAVITY * drop_height
}

/// F_max = √(2k|W_c|): peak force of a linear contact of stiffness k [N/m] that absorbs the
/// compression work W_c \[J] (model.md §5, "Overload") \[N].
pub fn peak_contact_force(stiffness: f64, compression_work: f64) -> f64 {
    (2.0 * stiffness * compression_work.abs()).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Tolerance for a value printed with 6 decimals: 1e-6 relative, or half a unit of the
    /// last printed digit (the tolerance of model.md's reference values).
    fn close6(got: f64, want: f64) -> bool {
        (got - want).abs() <= (1e-6 * want.abs()).max(0.5e-6)
    }

    #[track_caller]
    fn check6(what: &str, got: f64, want: f64) {
        assert!(close6(got, want), "{what}: got {got}, want {want}");
    }

    #[track_caller]
    fn check_rel(what: &str, got: f64, want: f64, rel: f64, scale: f64) {
        assert!(
            (got - want).abs() <= rel * scale.max(f64::MIN_POSITIVE),
            "{what}: got {got}, want {want} (rel {rel}, scale {scale})"
        );
    }

    fn zcross(r: DVec2) -> DVec2 {
        DVec2::new(-r.y, r.x)
    }

    // ---------------- falling rod (model.md §5) ----------------

    struct RodRow {
        id: char,
        theta_deg: f64,
        u_t0: f64,
        mu: f64,
        e: f64,
        p_c: f64,
        p_s: Option<f64>,
        p_f: f64,
        p_t: f64,
        u_tf: f64,
        u_nf: f64,
        domega: f64,
        e_p: f64,
        dke: f64,
        modes: &'static [ImpactMode],
    }

    use ImpactMode::{Slip, Stick};

    #[rustfmt::skip]
    const ROD: [RodRow; 9] = [
        RodRow { id: 'A', theta_deg: 45.0, u_t0: 0.5, mu: 0.0, e: 0.5, p_c: 0.400000, p_s: None, p_f: 0.600000, p_t: 0.0, u_tf: -0.400000, u_nf: 0.500000, domega: -2.545584, e_p: 0.5, dke: -0.150000, modes: &[Slip(1)] },
        RodRow { id: 'B', theta_deg: 45.0, u_t0: 1.5, mu: 0.8, e: 0.5, p_c: 0.270270, p_s: None, p_f: 0.405405, p_t: -0.324324, u_tf: 0.081081, u_nf: 0.500000, domega: -3.095981, e_p: 0.5, dke: -0.357743, modes: &[Slip(1)] },
        RodRow { id: 'C', theta_deg: 45.0, u_t0: 0.5, mu: 0.8, e: 0.5, p_c: 0.437500, p_s: Some(0.142857), p_f: 0.671055, p_t: 0.202633, u_tf: 0.0, u_nf: 0.373688, domega: -1.987346, e_p: 0.533840, dke: -0.159487, modes: &[Slip(1), Stick] },
        RodRow { id: 'D', theta_deg: 45.0, u_t0: 0.3, mu: 0.2, e: 0.5, p_c: 0.413636, p_s: Some(0.150000), p_f: 0.624131, p_t: 0.064826, u_tf: -0.474131, u_nf: 0.463087, domega: -2.372928, e_p: 0.508887, dke: -0.173196, modes: &[Slip(1), Slip(-1)] },
        RodRow { id: 'E', theta_deg: 45.0, u_t0: 1.0, mu: 0.2, e: 0.5, p_c: 0.357143, p_s: Some(0.500000), p_f: 0.536512, p_t: -0.092698, u_tf: -0.036512, u_nf: 0.480327, domega: -2.669512, e_p: 0.502235, dke: -0.184062, modes: &[Slip(1), Slip(-1)] },
        RodRow { id: 'F', theta_deg: 45.0, u_t0: -0.5, mu: 0.8, e: 0.5, p_c: 0.769231, p_s: Some(1.000000), p_f: 1.147283, p_t: 0.888370, u_tf: 0.0, u_nf: 0.535652, domega: -1.098475, e_p: 0.491467, dke: -0.488462, modes: &[Slip(-1), Stick] },
        RodRow { id: 'G', theta_deg: 60.0, u_t0: 0.0, mu: 0.5, e: 0.5, p_c: 0.812500, p_s: None, p_f: 1.218750, p_t: 0.487139, u_tf: 0.0, u_nf: 0.500000, domega: -1.125000, e_p: 0.5, dke: -0.304688, modes: &[Stick] },
        RodRow { id: 'H', theta_deg: 30.0, u_t0: 0.0, mu: 0.2, e: 0.5, p_c: 0.334427, p_s: None, p_f: 0.501640, p_t: 0.100328, u_tf: -0.476075, u_nf: 0.500000, domega: -2.305614, e_p: 0.5, dke: -0.149292, modes: &[Slip(-1)] },
        RodRow { id: 'I', theta_deg: 45.0, u_t0: 0.5, mu: 0.4, e: 1.0, p_c: 0.400000, p_s: Some(0.200000), p_f: 0.830422, p_t: 0.172169, u_tf: -0.315211, u_nf: 0.817802, domega: -2.792732, e_p: 1.076055, dke: -0.059743, modes: &[Slip(1), Slip(-1)] },
    ];

    const ROD_M: f64 = 1.0;
    const ROD_I: f64 = 1.0 / 12.0;
    const ROD_N: DVec2 = DVec2::new(0.0, 1.0);

    fn rod_r(theta_deg: f64) -> DVec2 {
        let th = theta_deg.to_radians();
        DVec2::new(-0.5 * th.cos(), -0.5 * th.sin())
    }

    fn rod_input(row: &RodRow, law: ImpactLaw) -> ImpactInput {
        ImpactInput {
            mobility: Mobility::at_contact(ROD_M, ROD_I, rod_r(row.theta_deg), ROD_N),
            u_t0: row.u_t0,
            u_n0: -1.0,
            friction: row.mu,
            restitution: row.e,
            law,
        }
    }

    #[test]
    fn rod_mobility_at_45_degrees() {
        let w = Mobility::at_contact(ROD_M, ROD_I, rod_r(45.0), ROD_N);
        check_rel("W_tt", w.tt, 2.5, 1e-14, 2.5);
        check_rel("W_tn", w.tn, -1.5, 1e-14, 2.5);
        check_rel("W_nn", w.nn, 2.5, 1e-14, 2.5);
        check_rel("det", w.det(), 4.0, 1e-14, 4.0);
        // det W = (1/m)(1/m + |r|²/I)
        check_rel(
            "det formula",
            w.det(),
            1.0 * (1.0 + 0.25 * 12.0),
            1e-14,
            4.0,
        );
        let (t, n) = contact_basis(ROD_N);
        assert_eq!(t, DVec2::new(1.0, 0.0));
        assert_eq!(n, ROD_N);
    }

    #[test]
    fn falling_rod_table() {
        for row in &ROD {
            let id = row.id;
            let inp = rod_input(row, ImpactLaw::Energetic);
            let out = resolve(&inp).unwrap_or_else(|e| panic!("row {id}: {e}"));
            check6(&format!("{id} p_c"), out.compression_impulse, row.p_c);
            match (out.slip_stop_impulse, row.p_s) {
                (Some(got), Some(want)) => check6(&format!("{id} p_s"), got, want),
                (None, None) => {}
                (got, want) => panic!("row {id}: p_s {got:?}, want {want:?}"),
            }
            check6(&format!("{id} p_f"), out.normal_impulse, row.p_f);
            check6(&format!("{id} p_t"), out.tangential_impulse, row.p_t);
            check6(&format!("{id} u_t,f"), out.u_t, row.u_tf);
            check6(&format!("{id} u_n,f"), out.u_n, row.u_nf);
            check6(&format!("{id} e_N"), out.newton_restitution, row.u_nf);
            check6(&format!("{id} e_P"), out.poisson_restitution, row.e_p);
            assert_eq!(out.modes.as_slice(), row.modes, "row {id} modes");

            // Velocity jumps of the rod, which translates at (u_t0, u_n0) without spin.
            let r = rod_r(row.theta_deg);
            let bi = body_velocity_change(
                ROD_M,
                ROD_I,
                r,
                ROD_N,
                out.normal_impulse,
                out.tangential_impulse,
            );
            check6(&format!("{id} Δω"), bi.domega, row.domega);
            let v0 = DVec2::new(row.u_t0, -1.0);
            let v1 = v0 + bi.dv;
            let dke = 0.5 * ROD_M * (v1.length_squared() - v0.length_squared())
                + 0.5 * ROD_I * bi.domega * bi.domega;
            check6(&format!("{id} ΔKE"), dke, row.dke);
            // Stationary obstacle: ΔKE = ∫u·dP = −dissipated.
            check_rel(
                &format!("{id} dissipated"),
                out.dissipated,
                -dke,
                1e-12,
                1.0,
            );
            // The contact velocity rebuilt from the body velocities matches (u_t, u_n).
            let u1 = v1 + bi.domega * zcross(r);
            check_rel(&format!("{id} u_t rebuilt"), u1.x, out.u_t, 1e-12, 1.0);
            check_rel(&format!("{id} u_n rebuilt"), u1.y, out.u_n, 1e-12, 1.0);
            // S = √(p_f² + p_t²)
            check_rel(
                &format!("{id} S"),
                out.total_impulse,
                row.p_f.hypot(row.p_t),
                2e-6,
                1.0,
            );
        }
    }

    #[test]
    fn rod_energetic_termination_condition() {
        for row in &ROD {
            let out = resolve(&rod_input(row, ImpactLaw::Energetic)).unwrap();
            let wc = out.compression_work;
            assert!(wc < 0.0, "row {}", row.id);
            check_rel(
                "W_n(p_f) = (1 − e²) W_c",
                out.normal_work,
                (1.0 - row.e * row.e) * wc,
                1e-13,
                wc.abs(),
            );
        }
    }

    #[test]
    fn rod_intermediate_closed_form_values() {
        let w = Mobility::at_contact(ROD_M, ROD_I, rod_r(45.0), ROD_N);
        let a = w.effective_masses(0.2, 1.0);
        check6("M (s=+1, μ=0.2)", a.slip, 0.357143);
        check6("M_* (s=+1, μ=0.2)", a.reversed, 0.454545);
        check6("M_st", a.stick, 0.625);
        check6("K (s=+1, μ=0.2)", a.k, 0.1);
        let b = w.effective_masses(0.8, 1.0);
        check6("M (s=+1, μ=0.8)", b.slip, 0.270270);
        check6("K (s=+1, μ=0.8)", b.k, 0.228571);
        let c = w.effective_masses(0.8, -1.0);
        check6("M (s=−1, μ=0.8)", c.slip, 0.769231);
        check6("K (s=−1, μ=0.8)", c.k, 1.6);
        // p_s = |u_t0| K/μ: rows C, D, E, F.
        check6("C p_s", 0.5 * b.k / 0.8, 0.142857);
        check6("D p_s", 0.3 * a.k / 0.2, 0.15);
        check6("E p_s", 1.0 * a.k / 0.2, 0.5);
        check6("F p_s", 0.5 * c.k / 0.8, 1.0);
    }

    #[test]
    fn rod_closed_forms_match_table() {
        for row in &ROD {
            let (p_f, p_t, tau_f) = closed_form_energetic(&rod_input(row, ImpactLaw::Energetic));
            check6(&format!("{} closed p_f", row.id), p_f, row.p_f);
            check6(&format!("{} closed p_t", row.id), p_t, row.p_t);
            check6(&format!("{} closed τ_f", row.id), tau_f, 1.0 + row.u_nf);
        }
    }

    // ---------------- parcel on the arm (model.md §5: P1, P2, overload) ----------------

    struct ArmCase {
        a: f64,
        b: f64,
        mass: f64,
        alpha: f64,
        alpha_dot: f64,
        s_c: f64,
        v: f64,
    }

    struct ArmSetup {
        inertia: f64,
        r: DVec2,
        n: DVec2,
        t: DVec2,
        p: DVec2,
        v_g: DVec2,
        u_t0: f64,
        u_n0: f64,
        w: Mobility,
    }

    /// Corner (x_max, y_min) of an axis-aligned parcel riding at (v, 0), ω = 0, on the arm
    /// face at s_c (model.md §5).
    fn arm_setup(c: &ArmCase) -> ArmSetup {
        let inertia = c.mass * (c.a * c.a + c.b * c.b) / 12.0;
        let dir = DVec2::new(c.alpha.cos(), c.alpha.sin());
        let n = DVec2::new(-c.alpha.sin(), c.alpha.cos());
        let p = c.s_c * dir;
        let g = p - DVec2::new(0.5 * c.a, -0.5 * c.b);
        let r = p - g;
        let v_g = DVec2::new(c.v, 0.0);
        let omega = 0.0;
        let u = v_g + omega * zcross(r) - c.alpha_dot * zcross(p);
        let (t, _) = contact_basis(n);
        ArmSetup {
            inertia,
            r,
            n,
            t,
            p,
            v_g,
            u_t0: u.dot(t),
            u_n0: u.dot(n),
            w: Mobility::at_contact(c.mass, inertia, r, n),
        }
    }

    struct ArmOracle {
        inertia: f64,
        r_t: f64,
        r_n: f64,
        u_t0: f64,
        u_n0: f64,
        w: [f64; 3],
        p_c: f64,
        p_f: f64,
        p_t: f64,
        s: f64,
        impulse: [f64; 2],
        v_g: [f64; 2],
        omega: f64,
        u: [f64; 2],
    }

    fn check_arm_case(name: &str, c: &ArmCase, o: &ArmOracle) -> (ArmSetup, ImpactOutcome) {
        let st = arm_setup(c);
        check6(&format!("{name} I"), st.inertia, o.inertia);
        // The tangent of the contact basis is the arm direction t(α).
        check_rel(
            &format!("{name} t = t(α)"),
            st.t.x,
            c.alpha.cos(),
            1e-15,
            1.0,
        );
        check6(&format!("{name} r_t"), st.r.dot(st.t), o.r_t);
        check6(&format!("{name} r_n"), st.r.dot(st.n), o.r_n);
        check6(&format!("{name} u_t0"), st.u_t0, o.u_t0);
        check6(&format!("{name} u_n0"), st.u_n0, o.u_n0);
        // Closed forms of the first-strike velocities (model.md §5).
        check_rel(
            &format!("{name} u_t0 = v cos α"),
            st.u_t0,
            c.v * c.alpha.cos(),
            1e-14,
            1.0,
        );
        check_rel(
            &format!("{name} u_n0 = −(v sin α + s_c α̇)"),
            st.u_n0,
            -(c.v * c.alpha.sin() + c.s_c * c.alpha_dot),
            1e-14,
            1.0,
        );
        check6(&format!("{name} W_tt"), st.w.tt, o.w[0]);
        check6(&format!("{name} W_tn"), st.w.tn, o.w[1]);
        check6(&format!("{name} W_nn"), st.w.nn, o.w[2]);

        let inp = ImpactInput {
            mobility: st.w,
            u_t0: st.u_t0,
            u_n0: st.u_n0,
            friction: 0.3,
            restitution: 0.3,
            law: ImpactLaw::Energetic,
        };
        let out = resolve(&inp).unwrap();
        assert_eq!(out.modes.as_slice(), &[Slip(1)], "{name}: slip throughout");
        assert_eq!(out.slip_stop_impulse, None);
        check6(&format!("{name} p_c"), out.compression_impulse, o.p_c);
        check6(&format!("{name} p_f"), out.normal_impulse, o.p_f);
        check6(&format!("{name} p_t"), out.tangential_impulse, o.p_t);
        check6(&format!("{name} S"), out.total_impulse, o.s);
        let imp = out.impulse_vector(st.n);
        check6(&format!("{name} P_x"), imp.x, o.impulse[0]);
        check6(&format!("{name} P_y"), imp.y, o.impulse[1]);
        let bi = body_velocity_change(
            c.mass,
            st.inertia,
            st.r,
            st.n,
            out.normal_impulse,
            out.tangential_impulse,
        );
        let v1 = st.v_g + bi.dv;
        check6(&format!("{name} V_x"), v1.x, o.v_g[0]);
        check6(&format!("{name} V_y"), v1.y, o.v_g[1]);
        check6(&format!("{name} ω"), bi.domega, o.omega);
        check6(&format!("{name} u_t,f"), out.u_t, o.u[0]);
        check6(&format!("{name} u_n,f"), out.u_n, o.u[1]);
        // The relative velocity rebuilt from the body's new state agrees with the map.
        let u1 = v1 + bi.domega * zcross(st.r) - c.alpha_dot * zcross(st.p);
        check_rel(
            &format!("{name} u_t rebuilt"),
            u1.dot(st.t),
            out.u_t,
            1e-12,
            1.0,
        );
        check_rel(
            &format!("{name} u_n rebuilt"),
            u1.dot(st.n),
            out.u_n,
            1e-12,
            1.0,
        );
        (st, out)
    }

    const P1: ArmCase = ArmCase {
        a: 0.4,
        b: 0.26,
        mass: 15.0,
        alpha: std::f64::consts::FRAC_PI_6,
        alpha_dot: 1.5,
        s_c: 0.6,
        v: 2.0,
    };

    #[test]
    fn parcel_on_arm_p1_and_overload() {
        let o = ArmOracle {
            inertia: 0.2845,
            r_t: 0.108205,
            r_n: -0.212583,
            u_t0: 1.732051,
            u_n0: -1.900000,
            w: [0.225513, 0.080853, 0.107821],
            p_c: 22.736805,
            p_f: 29.557847,
            p_t: -8.867354,
            s: 30.859298,
            impulse: [-22.458277, 21.164169],
            v_g: [0.502782, 1.410945],
            omega: 4.616020,
            u: [2.122183, 0.570000],
        };
        let (st, out) = check_arm_case("P1", &P1, &o);

        // Overload numbers: half a unit of the last printed digit (3 decimals).
        let s_fall = free_fall_impulse(15.0, 0.3, 0.3);
        assert!((s_fall - 47.309).abs() <= 0.5e-3, "S_fall {s_fall}");
        let ratio = out.total_impulse / s_fall;
        assert!((ratio - 0.652).abs() <= 0.5e-3, "ratio {ratio}");
        let h_eq = equivalent_drop_height(out.total_impulse, 15.0, 0.3);
        assert!((h_eq - 0.128).abs() <= 0.5e-3, "H_eq {h_eq}");
        assert!(h_eq <= 0.3);
        // The equivalent height of S_fall is H₀ itself.
        check_rel(
            "H_eq(S_fall)",
            equivalent_drop_height(s_fall, 15.0, 0.3),
            0.3,
            1e-14,
            0.3,
        );
        // Free-fall speeds.
        check6("v₀(0.3)", (2.0 * crate::GRAVITY * 0.3).sqrt(), 2.426108);
        check6("v₀(0.2)", (2.0 * crate::GRAVITY * 0.2).sqrt(), 1.980909);
        // Peak force: |W_c| = 21.600 J = ½ M u_n0² for a constant mode; m g H₀ = 44.145 J.
        let wc = out.compression_work.abs();
        assert!((wc - 21.600).abs() <= 0.5e-3, "|W_c| {wc}");
        let m_slip = st.w.effective_masses(0.3, 1.0).slip;
        check_rel(
            "|W_c| = ½ M u_n0²",
            wc,
            0.5 * m_slip * st.u_n0 * st.u_n0,
            1e-13,
            wc,
        );
        let w_drop = drop_compression_work(15.0, 0.3);
        assert!((w_drop - 44.145).abs() <= 0.5e-3, "m g H₀ {w_drop}");
        let f_max = peak_contact_force(6e5, out.compression_work);
        assert!((f_max - 5091.0).abs() <= 0.5, "F_max {f_max}");
        // n_G = F_max √(1 + μ²)/(m g) = 36.1 g
        let n_g = f_max * (1.0f64 + 0.09).sqrt() / (15.0 * crate::GRAVITY);
        assert!((n_g - 36.1).abs() <= 0.05, "n_G {n_g}");
    }

    #[test]
    fn parcel_on_arm_p2() {
        let c = ArmCase {
            a: 0.7,
            b: 0.1,
            mass: 5.0,
            alpha: 20f64.to_radians(),
            alpha_dot: 1.7,
            s_c: 0.8,
            v: 0.65,
        };
        let o = ArmOracle {
            inertia: 0.208333,
            r_t: 0.311791,
            r_n: -0.166692,
            u_t0: 0.610800,
            u_n0: -1.582313,
            w: [0.333373, 0.249471, 0.666627],
            p_c: 2.673795,
            p_f: 3.475934,
            p_t: -1.042780,
            s: 3.628981,
            impulse: [-2.168732, 2.909657],
            v_g: [0.216254, 0.581931],
            omega: 4.367729,
            u: [1.130308, 0.474694],
        };
        check_arm_case("P2", &c, &o);
    }

    #[test]
    fn overload_helpers_are_consistent() {
        // With S = S_fall(H) the equivalent height is H, for several masses and e.
        for &(m, e, h) in &[(0.5, 0.0, 0.2), (3.0, 0.5, 0.3), (15.0, 1.0, 1.0)] {
            let s = free_fall_impulse(m, e, h);
            check_rel("H_eq", equivalent_drop_height(s, m, e), h, 1e-14, h);
        }
        // A drop's own compression work with M = m: ½ m v₀² = m g H₀.
        let v0 = (2.0 * crate::GRAVITY * 0.3).sqrt();
        check_rel(
            "½ m v₀²",
            0.5 * 15.0 * v0 * v0,
            drop_compression_work(15.0, 0.3),
            1e-14,
            44.0,
        );
    }

    // ---------------- analytic special cases (model.md §5) ----------------

    fn input(w: Mobility, u_t0: f64, u_n0: f64, mu: f64, e: f64) -> ImpactInput {
        ImpactInput {
            mobility: w,
            u_t0,
            u_n0,
            friction: mu,
            restitution: e,
            law: ImpactLaw::Energetic,
        }
    }

    #[test]
    fn frictionless_special_case() {
        let ws = [
            Mobility::at_contact(ROD_M, ROD_I, rod_r(45.0), ROD_N),
            arm_setup(&P1).w,
            Mobility {
                tt: 0.7,
                tn: -0.4,
                nn: 1.3,
            },
        ];
        for w in ws {
            for &(u_t0, u_n0, e) in &[(0.5, -1.0, 0.5), (-2.0, -0.3, 0.0), (0.0, -3.0, 1.0)] {
                for law in [ImpactLaw::Energetic, ImpactLaw::Newton, ImpactLaw::Poisson] {
                    let inp = ImpactInput {
                        law,
                        ..input(w, u_t0, u_n0, 0.0, e)
                    };
                    let out = resolve(&inp).unwrap();
                    let p_f = (1.0 + e) * (-u_n0) / w.nn;
                    check_rel("p_f", out.normal_impulse, p_f, 1e-13, p_f);
                    assert_eq!(out.tangential_impulse, 0.0);
                    assert_eq!(out.slip_stop_impulse, None);
                    check_rel("u_t,f", out.u_t, u_t0 + w.tn * p_f, 1e-13, 1.0);
                    check_rel("e_N", out.newton_restitution, e, 1e-13, 1.0);
                    check_rel("e_P", out.poisson_restitution, e, 1e-13, 1.0);
                }
            }
        }
    }

    /// A body with r = (0, −R) and normal +y: r_t = 0, so W_tn = 0.
    fn round_body(mass: f64, inertia: f64, radius: f64) -> Mobility {
        Mobility::at_contact(
            mass,
            inertia,
            DVec2::new(0.0, -radius),
            DVec2::new(0.0, 1.0),
        )
    }

    #[test]
    fn central_impact_disk_and_sphere() {
        let (m, rad) = (2.0, 0.1);
        let disk = round_body(m, 0.5 * m * rad * rad, rad);
        let sphere = round_body(m, 0.4 * m * rad * rad, rad);
        assert_eq!(disk.tn, 0.0);
        check_rel("sphere W_tt = 7/(2m)", sphere.tt, 3.5 / m, 1e-14, 1.0);
        check_rel("disk W_tt = 3/m", disk.tt, 3.0 / m, 1e-14, 1.0);
        for w in [disk, sphere] {
            for &(u_t0, mu, e) in &[
                (0.3, 0.2, 0.5),
                (-2.0, 0.2, 0.5),
                (1.0, 0.0, 0.8),
                (-0.05, 0.9, 0.0),
                (5.0, 0.6, 1.0),
            ] {
                let u_n0 = -1.2;
                let out = resolve(&input(w, u_t0, u_n0, mu, e)).unwrap();
                let p_f = (1.0 + e) * 1.2 / w.nn;
                check_rel("p_f", out.normal_impulse, p_f, 1e-13, p_f);
                let p_t = -u_t0.signum() * (mu * p_f).min(u_t0.abs() / w.tt);
                check_rel("p_t", out.tangential_impulse, p_t, 1e-13, p_f);
            }
        }
        // Sphere rolling criterion: u_t,f = 0 iff |u_t0| ≤ 3.5 μ (1 + e) v₀.
        let (mu, e, v0) = (0.3, 0.4, 1.5);
        let limit = 3.5 * mu * (1.0 + e) * v0;
        for &(factor, rolls) in &[(0.5, true), (0.99, true), (1.01, false), (2.0, false)] {
            for sign in [1.0, -1.0] {
                let u_t0 = sign * factor * limit;
                let out = resolve(&input(sphere, u_t0, -v0, mu, e)).unwrap();
                if rolls {
                    assert_eq!(out.u_t, 0.0, "factor {factor}");
                    assert_eq!(out.modes.last(), Stick);
                } else {
                    assert!(out.u_t * sign > 1e-6, "factor {factor}: u_t {}", out.u_t);
                    assert_eq!(out.slip_stop_impulse, None);
                }
            }
        }
    }

    #[test]
    fn constant_slip_special_case() {
        // P1 (slip accelerates) and rod B (slip decelerates but outlasts the impact).
        let p1 = arm_setup(&P1);
        let b = &ROD[1];
        let cases = [
            (p1.w, p1.u_t0, p1.u_n0, 0.3, 0.3),
            (
                rod_input(b, ImpactLaw::Energetic).mobility,
                1.5,
                -1.0,
                0.8,
                0.5,
            ),
        ];
        for (w, u_t0, u_n0, mu, e) in cases {
            let m = w.effective_masses(mu, u_t0.signum()).slip;
            for law in [ImpactLaw::Energetic, ImpactLaw::Newton, ImpactLaw::Poisson] {
                let out = resolve(&ImpactInput {
                    law,
                    ..input(w, u_t0, u_n0, mu, e)
                })
                .unwrap();
                assert_eq!(out.modes.len(), 1);
                let p_f = (1.0 + e) * (-u_n0) * m;
                check_rel("p_f", out.normal_impulse, p_f, 1e-13, p_f);
                check_rel(
                    "p_t",
                    out.tangential_impulse,
                    -mu * u_t0.signum() * p_f,
                    1e-13,
                    p_f,
                );
                check_rel("e_N", out.newton_restitution, e, 1e-13, 1.0);
                check_rel("e_P", out.poisson_restitution, e, 1e-13, 1.0);
                check_rel(
                    "S = v₀ M τ_f √(1+μ²)",
                    out.total_impulse,
                    -u_n0 * m * (1.0 + e) * (1.0 + mu * mu).sqrt(),
                    1e-13,
                    p_f,
                );
            }
        }
    }

    #[test]
    fn stick_throughout_special_case() {
        let g = &ROD[6];
        let w = rod_input(g, ImpactLaw::Energetic).mobility;
        assert!(w.tn.abs() <= g.mu * w.tt);
        let m_st = w.tt / w.det();
        for e in [0.0, 0.5, 1.0] {
            let out = resolve(&input(w, 0.0, -1.0, g.mu, e)).unwrap();
            assert_eq!(out.modes.as_slice(), &[Stick]);
            let p_f = (1.0 + e) * m_st;
            check_rel("p_f", out.normal_impulse, p_f, 1e-13, p_f);
            check_rel(
                "p_t",
                out.tangential_impulse,
                -(w.tn / w.tt) * p_f,
                1e-13,
                p_f,
            );
            check_rel("e_N", out.newton_restitution, e, 1e-13, 1.0);
            check_rel("e_P", out.poisson_restitution, e, 1e-13, 1.0);
            assert_eq!(out.u_t, 0.0);
        }
    }

    #[test]
    fn zero_restitution_ends_at_compression() {
        for row in &ROD {
            for law in [ImpactLaw::Energetic, ImpactLaw::Newton, ImpactLaw::Poisson] {
                let inp = ImpactInput {
                    restitution: 0.0,
                    ..rod_input(row, law)
                };
                let out = resolve(&inp).unwrap();
                assert_eq!(out.normal_impulse, out.compression_impulse);
                assert_eq!(out.u_n, 0.0);
                assert_eq!(out.normal_work, out.compression_work);
            }
        }
    }

    #[test]
    fn newton_and_poisson_hit_their_targets() {
        // Rows with a slip stop: the laws differ, but each meets its own definition.
        for row in ROD.iter().filter(|r| r.p_s.is_some()) {
            let n = resolve(&rod_input(row, ImpactLaw::Newton)).unwrap();
            check_rel("Newton e_N", n.newton_restitution, row.e, 1e-13, 1.0);
            let p = resolve(&rod_input(row, ImpactLaw::Poisson)).unwrap();
            check_rel("Poisson e_P", p.poisson_restitution, row.e, 1e-13, 1.0);
            // Compression is law-independent.
            check6("Newton p_c", n.compression_impulse, row.p_c);
            check6("Poisson p_c", p.compression_impulse, row.p_c);
        }
    }

    #[test]
    fn tiny_restitution_is_accurate() {
        // Found by proptest: with the termination written as W_n − (1 − e²) W_c, e² W_c was
        // lost to cancellation and the energetic result drifted by 1e-12 from Newton's.
        let inp = input(
            Mobility {
                tt: 0.07388416087463186,
                tn: 0.026255177254300578,
                nn: 0.27899973339235445,
            },
            -1.1900067334792588,
            -1.935549308939088,
            1.229807748398742,
            3.679110600541151e-5,
        );
        let en = resolve(&inp).unwrap();
        assert_eq!(en.modes.len(), 1);
        for e in [3.679110600541151e-5, 1e-9, 1e-100] {
            let inp = ImpactInput {
                restitution: e,
                ..inp
            };
            let en = resolve(&inp).unwrap();
            let m = inp.mobility.effective_masses(inp.friction, -1.0).slip;
            let p_f = (1.0 + e) * -inp.u_n0 * m;
            check_rel("p_f", en.normal_impulse, p_f, 1e-14, p_f);
            check_rel("e_N", en.newton_restitution, e, 1e-9, e);
            for law in [ImpactLaw::Newton, ImpactLaw::Poisson] {
                let other = resolve(&ImpactInput { law, ..inp }).unwrap();
                check_rel("p_f", other.normal_impulse, en.normal_impulse, 1e-14, p_f);
                check_rel(
                    "p_t",
                    other.tangential_impulse,
                    en.tangential_impulse,
                    1e-14,
                    p_f,
                );
            }
        }
    }

    // ---------------- errors ----------------

    #[test]
    fn errors() {
        let w = Mobility::at_contact(ROD_M, ROD_I, rod_r(45.0), ROD_N);
        let ok = input(w, 0.5, -1.0, 0.3, 0.5);
        assert!(resolve(&ok).is_ok());
        assert_eq!(
            resolve(&ImpactInput { u_n0: 0.0, ..ok }),
            Err(ImpactError::NotApproaching)
        );
        assert_eq!(
            resolve(&ImpactInput { u_n0: 0.7, ..ok }),
            Err(ImpactError::NotApproaching)
        );
        let invalid = |inp: ImpactInput| {
            matches!(resolve(&inp), Err(ImpactError::InvalidInput(_)))
                && closed_form_energetic(&inp).0.is_nan()
        };
        assert!(invalid(ImpactInput {
            u_t0: f64::NAN,
            ..ok
        }));
        assert!(invalid(ImpactInput {
            u_n0: f64::NEG_INFINITY,
            ..ok
        }));
        assert!(invalid(ImpactInput {
            friction: -0.1,
            ..ok
        }));
        assert!(invalid(ImpactInput {
            restitution: 1.5,
            ..ok
        }));
        assert!(invalid(ImpactInput {
            restitution: -0.01,
            ..ok
        }));
        let bad_w = [
            Mobility {
                tt: 1.0,
                tn: 2.0,
                nn: 1.0,
            },
            Mobility {
                tt: -1.0,
                tn: 0.0,
                nn: 1.0,
            },
            Mobility {
                tt: 1.0,
                tn: 0.0,
                nn: 0.0,
            },
            Mobility::at_contact(0.0, 1.0, DVec2::X, DVec2::Y),
            Mobility::at_contact(1.0, 1.0, DVec2::X, DVec2::ZERO),
        ];
        for w in bad_w {
            assert!(invalid(ImpactInput { mobility: w, ..ok }), "{w:?}");
        }
        // Jam: decelerating slip with a_n = W_nn − μ s W_tn < 0.
        let jam = Mobility {
            tt: 2.0,
            tn: 1.0,
            nn: 1.0,
        };
        assert_eq!(
            resolve(&input(jam, 1.0, -1.0, 1.5, 0.5)),
            Err(ImpactError::Jam)
        );
        assert!(closed_form_energetic(&input(jam, 1.0, -1.0, 1.5, 0.5))
            .0
            .is_nan());
        // Error messages are informative.
        let msg = resolve(&ImpactInput {
            restitution: 2.0,
            ..ok
        })
        .unwrap_err()
        .to_string();
        assert!(msg.contains("restitution"), "{msg}");
    }

    // ---------------- random cases ----------------

    /// The seeded loops' generator.
    use crate::stats::splitmix::SplitMix64 as Rng;

    /// W at a random corner of a random rectangle, for a random contact normal.
    fn rectangle_corner(
        a: f64,
        b: f64,
        mass: f64,
        phi: f64,
        corner: usize,
        normal_angle: f64,
    ) -> Mobility {
        let (ha, hb) = (0.5 * a, 0.5 * b);
        let body = [
            DVec2::new(ha, -hb),
            DVec2::new(ha, hb),
            DVec2::new(-ha, hb),
            DVec2::new(-ha, -hb),
        ][corner % 4];
        let r = DVec2::from_angle(phi).rotate(body);
        let n = DVec2::from_angle(normal_angle);
        Mobility::at_contact(mass, mass * (a * a + b * b) / 12.0, r, n)
    }

    fn random_input(rng: &mut Rng) -> ImpactInput {
        let w = if rng.uniform(0.0, 1.0) < 0.6 {
            rectangle_corner(
                rng.uniform(0.05, 1.0),
                rng.uniform(0.05, 1.0),
                rng.uniform(0.2, 20.0),
                rng.uniform(-3.2, 3.2),
                (rng.next_u64() % 4) as usize,
                rng.uniform(-3.2, 3.2),
            )
        } else {
            let (tt, nn) = (rng.uniform(0.1, 5.0), rng.uniform(0.1, 5.0));
            let rho = rng.uniform(-0.99, 0.99);
            Mobility {
                tt,
                tn: rho * (tt * nn).sqrt(),
                nn,
            }
        };
        let u_t0 = match rng.next_u64() % 10 {
            0 => 0.0,
            _ => rng.uniform(-3.0, 3.0),
        };
        let mu = match rng.next_u64() % 10 {
            0 => 0.0,
            _ => rng.uniform(0.0, 1.3),
        };
        let e = match rng.next_u64() % 10 {
            0 => 0.0,
            1 => 1.0,
            _ => rng.uniform(0.0, 1.0),
        };
        input(w, u_t0, rng.uniform(-3.0, -0.01), mu, e)
    }

    #[test]
    fn closed_forms_agree_with_algorithm_on_random_cases() {
        let mut rng = Rng(0x5EED_1234);
        let (mut checked, mut stops) = (0, 0);
        for _ in 0..5000 {
            let inp = random_input(&mut rng);
            let Ok(out) = resolve(&inp) else {
                continue;
            };
            let (p_f, p_t, tau_f) = closed_form_energetic(&inp);
            let scale = out.normal_impulse.max(out.tangential_impulse.abs());
            check_rel("p_f", out.normal_impulse, p_f, 1e-12, scale);
            check_rel("p_t", out.tangential_impulse, p_t, 1e-12, scale);
            check_rel("τ_f", 1.0 + out.newton_restitution, tau_f, 1e-12, 1.0);
            // τ = 1 + u_n/|u_n0| at separation is 1 + e_N.
            check_rel(
                "τ_f − 1 = e_N",
                tau_f - 1.0,
                out.u_n / -inp.u_n0,
                1e-12,
                1.0,
            );
            checked += 1;
            stops += usize::from(out.slip_stop_impulse.is_some());
        }
        // Enough cases, and the slip-stop branches are well represented.
        assert!(checked > 4500, "{checked}");
        assert!(stops > 500, "{stops}");
    }

    #[test]
    fn rectangle_corner_bounds() {
        let mut rng = Rng(42);
        let (mut min_ratio, mut max_ratio) = (f64::INFINITY, 0.0_f64);
        for _ in 0..20_000 {
            let w = rectangle_corner(
                rng.uniform(0.01, 1.0),
                rng.uniform(0.01, 1.0),
                rng.uniform(0.1, 30.0),
                rng.uniform(-3.2, 3.2),
                (rng.next_u64() % 4) as usize,
                rng.uniform(-3.2, 3.2),
            );
            if w.tn == 0.0 {
                continue;
            }
            min_ratio = min_ratio.min(w.nn / w.tn.abs());
            max_ratio = max_ratio.max(w.tn.abs() / w.tt);
        }
        assert!(
            min_ratio >= 4.0 / 3.0 - 1e-12,
            "W_nn/|W_tn| min {min_ratio}"
        );
        assert!(max_ratio <= 0.75 + 1e-12, "|W_tn|/W_tt max {max_ratio}");
        // The bounds are sharp.
        assert!(min_ratio < 4.0 / 3.0 + 1e-3, "{min_ratio}");
        assert!(max_ratio > 0.75 - 1e-3, "{max_ratio}");
    }

    fn arb_input() -> impl Strategy<Value = ImpactInput> {
        (
            (0.05..1.0f64, 0.05..1.0f64, 0.2..20.0f64),
            (-3.2..3.2f64, 0usize..4, -3.2..3.2f64),
            (-3.0..3.0f64, -3.0..-0.01f64, 0.0..1.3f64, 0.0..=1.0f64),
        )
            .prop_map(|((a, b, m), (phi, k, na), (u_t0, u_n0, mu, e))| {
                input(rectangle_corner(a, b, m, phi, k, na), u_t0, u_n0, mu, e)
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        #[test]
        fn energetic_law_is_dissipative(inp in arb_input()) {
            // μ < 4/3 at rectangle corners: never a jam (model.md §5).
            let out = resolve(&inp).unwrap();
            let scale = out.compression_work.abs() + out.tangential_work.abs();
            prop_assert!(out.dissipated >= -1e-12 * scale, "{out:?}");
            prop_assert!(out.tangential_work <= 1e-12 * scale);
            prop_assert!(out.u_n >= -1e-12 * inp.u_n0.abs());
            prop_assert!(out.compression_impulse >= 0.0);
            prop_assert!(out.normal_impulse >= out.compression_impulse);
            prop_assert!(out.compression_work <= 0.0);
            // Friction never exceeds the cone: |p_t| ≤ μ p_f.
            prop_assert!(
                out.tangential_impulse.abs() <= inp.friction * out.normal_impulse * (1.0 + 1e-12)
            );
        }

        #[test]
        fn elastic_frictionless_conserves_energy(inp in arb_input()) {
            let inp = ImpactInput { friction: 0.0, restitution: 1.0, ..inp };
            let out = resolve(&inp).unwrap();
            let scale = out.compression_work.abs();
            prop_assert!(out.dissipated.abs() <= 1e-12 * scale, "{out:?}");
            prop_assert!((out.u_n + inp.u_n0).abs() <= 1e-12 * inp.u_n0.abs());
        }

        #[test]
        fn laws_coincide_in_constant_slip(inp in arb_input()) {
            // Make the slip outlast the impact where it would stop: p_s = |u_t0|/(μ W_tt − s W_tn)
            // beyond p_f = (1 + e) v₀ M (zero initial slip never changes mode).
            let first = resolve(&inp).unwrap();
            let inp = if first.modes.len() == 1 {
                inp
            } else {
                let (w, s) = (inp.mobility, inp.u_t0.signum());
                let m = w.effective_masses(inp.friction, s).slip;
                let decel = inp.friction * w.tt - s * w.tn;
                let u_t0 = s * 2.0 * (1.0 + inp.restitution) * -inp.u_n0 * m * decel;
                ImpactInput { u_t0, ..inp }
            };
            let en = resolve(&inp).unwrap();
            prop_assert_eq!(en.modes.len(), 1);
            for law in [ImpactLaw::Newton, ImpactLaw::Poisson] {
                let other = resolve(&ImpactInput { law, ..inp }).unwrap();
                let scale = en.normal_impulse;
                prop_assert!((other.normal_impulse - en.normal_impulse).abs() <= 1e-12 * scale);
                prop_assert!(
                    (other.tangential_impulse - en.tangential_impulse).abs() <= 1e-12 * scale
                );
                prop_assert!(
                    (other.newton_restitution - inp.restitution).abs() <= 1e-12
                );
            }
        }

        #[test]
        fn body_jump_reproduces_mobility(
            p_n in 0.0..10.0f64, p_t in -10.0..10.0f64,
            theta in -3.2..3.2f64, rx in -1.0..1.0f64, ry in -1.0..1.0f64,
        ) {
            // Δu at the contact from the body jump equals W·(p_t, p_n).
            let (m, i) = (2.5, 0.3);
            let r = DVec2::new(rx, ry);
            let normal = DVec2::from_angle(theta);
            let w = Mobility::at_contact(m, i, r, normal);
            let bi = body_velocity_change(m, i, r, normal, p_n, p_t);
            let du = bi.dv + bi.domega * zcross(r);
            let (t, n) = contact_basis(normal);
            let (du_t, du_n) = w.apply(p_t, p_n);
            let scale = 1.0 + p_n.abs() + p_t.abs();
            prop_assert!((du.dot(t) - du_t).abs() <= 1e-12 * scale * (w.tt + w.nn));
            prop_assert!((du.dot(n) - du_n).abs() <= 1e-12 * scale * (w.tt + w.nn));
            // t × n = +ẑ
            prop_assert!((t.perp_dot(n) - 1.0).abs() <= 1e-15);
        }
    }
}
