//! Contact dynamics with an active set of unilateral contacts (docs/model.md §6).
//!
//! With k active contacts, each sliding (friction at the Coulomb limit against the slip) or
//! sticking (tangential force unknown, tangential relative acceleration zero):
//!
//!   𝕄 q̈ = f + Σ_c (J_n,cᵀ λ_n,c + J_t,cᵀ λ_t,c),   J_n,c q̈ = β_c,   \[stick] J_t,c q̈ = β_t,c
//!
//! with 𝕄 = diag(m, m, I), q = (x, y, φ), sliding λ_t = −μ s λ_n (s = sgn u_t). Eliminating
//! q̈ gives a small dense system (R 𝕄⁻¹ C) λ = b − R 𝕄⁻¹ f, solved by Gaussian elimination.
//! For one sliding contact R 𝕄⁻¹ C = W_nn − μ s W_tn, the effective normal mobility of the
//! impact; it is positive for rectangles whenever μ < 4/3, so there is no Painlevé paradox
//! (model.md §5, §6).
//!
//! Which closed contacts carry force, and whether each sticks or slides, is a linear
//! complementarity problem; with at most four closed contacts it is solved here by
//! enumerating the active sets (Pfeiffer & Glocker, *Multibody Dynamics with Unilateral
//! Contacts*, 1996, for the formulation).
//!
//! A group of N parcels (docs/model.md §6c) is the same problem over q = (x₁, y₁, φ₁, …,
//! x_N, y_N, φ_N) and 𝕄 = diag(m₁, m₁, I₁, …): [`Group`], [`solve_group`], [`select_group`]
//! and [`select_impact_group`], generic over the coordinates D = 3N and the contacts C. One
//! body is D = 3, C = 4, with the same arithmetic in the same order.

/// A sliding contact whose slip, below [`REVERSAL_SLIP`], would reverse within this time \[s]
/// under the solution's own acceleration does not slide on (`consistent`): it is at rest at
/// the resolution of events, which the caller's relaxed tolerances (slip ≥ `REVERSAL_SLIP`)
/// then treat it as. A faster slip that stops soon is the motion's business (its slip-stop
/// guard).
pub const REVERSAL_TIME: f64 = 1e-6;
/// See [`REVERSAL_TIME`] [m/s].
pub const REVERSAL_SLIP: f64 = 1e-6;

/// Most contacts handled at once on one body.
pub const MAX_CONTACTS: usize = 4;

/// The tangential behaviour of an active contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Tangential {
    /// Sliding with slip direction `s` = sgn(u_t) = ±1; friction λ_t = −μ s λ_n.
    Slide(f64),
    /// Sticking: u_t stays 0, |λ_t| ≤ μ λ_n.
    Stick,
}

/// One contact's constraint data over D generalised coordinates, three per body
/// (x, y, φ): a contact of one body (D = 3, [`ContactRow`], from `model::contact`), or of a
/// group of bodies, where a contact between two of them has both bodies' columns
/// (`model::pair_contact`) and every other column zero.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row<const D: usize> {
    /// J_n = [n_x, n_y, r×n] on each body the contact touches
    pub normal: [f64; D],
    /// β with g̈ = J_n q̈ − β
    pub beta: f64,
    /// J_t = [t_x, t_y, r×t] on each body the contact touches
    pub tangent: [f64; D],
    /// β_t with u̇_t = J_t q̈ − β_t
    pub beta_t: f64,
    /// μ: Coulomb coefficient at this contact
    pub friction: f64,
    /// u_t: current slip
    pub slip: f64,
}

/// One contact's constraint data on one body.
pub type ContactRow = Row<3>;

impl ContactRow {
    /// This one-body row as body `k`'s row in a group of D / 3 bodies (its columns at 3k,
    /// zero elsewhere): a contact of one parcel with the arm or the guide.
    pub fn on_body<const D: usize>(&self, k: usize) -> Row<D> {
        let mut normal = [0.0; D];
        let mut tangent = [0.0; D];
        normal[3 * k..3 * k + 3].copy_from_slice(&self.normal);
        tangent[3 * k..3 * k + 3].copy_from_slice(&self.tangent);
        Row {
            normal,
            tangent,
            beta: self.beta,
            beta_t: self.beta_t,
            friction: self.friction,
            slip: self.slip,
        }
    }
}

/// Accelerations and contact forces for one active set, over D coordinates and at most C
/// contacts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Solved<const D: usize, const C: usize> {
    /// q̈: (ẍ, ÿ, φ̈) of each body
    pub accel: [f64; D],
    /// λ_n per contact (in the order given; 0 for inactive ones)
    pub normal_force: [f64; C],
    /// λ_t per contact
    pub tangential_force: [f64; C],
}

impl<const D: usize, const C: usize> Default for Solved<D, C> {
    fn default() -> Self {
        Solved {
            accel: [0.0; D],
            normal_force: [0.0; C],
            tangential_force: [0.0; C],
        }
    }
}

/// Accelerations and contact forces of one body's active set.
pub type Solution = Solved<3, MAX_CONTACTS>;

/// The mass matrix diagonal and the external generalised force (belt friction).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Body {
    /// m \[kg]
    pub mass: f64,
    /// I [kg·m²]
    pub inertia: f64,
    /// f = (F_x, F_y, M) [N, N, N·m]
    pub external: [f64; 3],
}

impl Body {
    /// The body as a group of one.
    pub fn as_group(&self) -> Group<3> {
        Group {
            inverse_mass: [1.0 / self.mass, 1.0 / self.mass, 1.0 / self.inertia],
            external: self.external,
        }
    }

    /// q̈ under the external force alone.
    pub fn free_accel(&self) -> [f64; 3] {
        self.as_group().free_accel()
    }
}

/// Several bodies in one solve: the diagonal of 𝕄⁻¹ and the external generalised force,
/// three coordinates (x, y, φ) per body in the bodies' order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Group<const D: usize> {
    /// (1/m, 1/m, 1/I) of each body
    pub inverse_mass: [f64; D],
    /// f = (F_x, F_y, M) of each body [N, N, N·m]
    pub external: [f64; D],
}

impl<const D: usize> Group<D> {
    /// The bodies' masses (m, I) in order, with their external forces.
    pub fn of(bodies: &[Body]) -> Group<D> {
        assert_eq!(3 * bodies.len(), D, "three coordinates per body");
        let mut g = Group {
            inverse_mass: [0.0; D],
            external: [0.0; D],
        };
        for (k, b) in bodies.iter().enumerate() {
            let one = b.as_group();
            g.inverse_mass[3 * k..3 * k + 3].copy_from_slice(&one.inverse_mass);
            g.external[3 * k..3 * k + 3].copy_from_slice(&one.external);
        }
        g
    }

    /// q̈ under the external force alone.
    pub fn free_accel(&self) -> [f64; D] {
        std::array::from_fn(|d| self.external[d] * self.inverse_mass[d])
    }
}

/// a·b, summed in index order.
fn dot<const D: usize>(a: &[f64; D], b: &[f64; D]) -> f64 {
    (1..D).fold(a[0] * b[0], |s, d| s + a[d] * b[d])
}

/// Solve the equations of motion with the contacts `rows[i]` active in `modes[i]`
/// (`None` = inactive). Returns `None` when the system is singular.
pub fn solve(body: &Body, rows: &[ContactRow], modes: &[Option<Tangential>]) -> Option<Solution> {
    solve_group(&body.as_group(), rows, modes)
}

/// [`solve`] for a group of bodies: at most C contacts, at most D unknowns.
pub fn solve_group<const D: usize, const C: usize>(
    group: &Group<D>,
    rows: &[Row<D>],
    modes: &[Option<Tangential>],
) -> Option<Solved<D, C>> {
    // A planar rigid body has three degrees of freedom, a group 3N: more unknowns (two
    // sticking contacts on one body) make J𝕄⁻¹Jᵀ singular, whatever rounding leaves in its
    // pivots. So at most D unknowns are ever solved for, and the arrays hold no more.
    let inv = group.inverse_mass;
    // Unknowns: one λ_n per active contact, plus one λ_t per sticking contact.
    // Each unknown has a force column (generalised) and a constraint row.
    let mut cols = [[0.0f64; D]; D];
    let mut crow = [[0.0f64; D]; D];
    let mut rhs_b = [0.0f64; D];
    let mut owner = [(0usize, false); D]; // (contact, is tangential)
    let mut n = 0;
    // Unknowns of contacts that touch one body alone, per body: no more than its three
    // degrees of freedom (in a group the pivot test, scaled by the whole matrix, cannot be
    // trusted to see a body over-constrained on its own).
    let mut own = [0usize; D];
    for (i, (row, mode)) in rows.iter().zip(modes).enumerate().take(C) {
        let Some(mode) = mode else { continue };
        let unknowns = if *mode == Tangential::Stick { 2 } else { 1 };
        if n + unknowns > D {
            return None;
        }
        if D > 3 {
            if let Some(b) = sole_body(row) {
                own[b] += unknowns;
                if own[b] > 3 {
                    return None;
                }
            }
        }
        let col = match mode {
            Tangential::Slide(s) => {
                let k = -row.friction * s;
                std::array::from_fn(|d| row.normal[d] + k * row.tangent[d])
            }
            Tangential::Stick => row.normal,
        };
        cols[n] = col;
        crow[n] = row.normal;
        rhs_b[n] = row.beta;
        owner[n] = (i, false);
        n += 1;
        if *mode == Tangential::Stick {
            cols[n] = row.tangent;
            crow[n] = row.tangent;
            rhs_b[n] = row.beta_t;
            owner[n] = (i, true);
            n += 1;
        }
    }
    let a0 = group.free_accel();
    let mut a = [[0.0f64; D]; D];
    let mut b = [0.0f64; D];
    for r in 0..n {
        for c in 0..n {
            a[r][c] = (1..D).fold(crow[r][0] * inv[0] * cols[c][0], |s, d| {
                s + crow[r][d] * inv[d] * cols[c][d]
            });
        }
        b[r] = rhs_b[r] - dot(&crow[r], &a0);
    }
    let lambda = gauss(&mut a, &mut b, n)?;
    let mut sol = Solved {
        accel: a0,
        ..Solved::default()
    };
    for u in 0..n {
        for d in 0..D {
            sol.accel[d] += inv[d] * cols[u][d] * lambda[u];
        }
        let (i, tangential) = owner[u];
        if tangential {
            sol.tangential_force[i] = lambda[u];
        } else {
            sol.normal_force[i] = lambda[u];
            if let Some(Tangential::Slide(s)) = modes[i] {
                sol.tangential_force[i] = -rows[i].friction * s * lambda[u];
            }
        }
    }
    Some(sol)
}

/// Whether body `b`'s columns of `row` (normal or tangent) are not all zero.
fn touches<const D: usize>(row: &Row<D>, b: usize) -> bool {
    (3 * b..3 * b + 3).any(|d| row.normal[d] != 0.0 || row.tangent[d] != 0.0)
}

/// The one body a contact touches, if it touches exactly one (the arm's or the guide's
/// contact with a parcel; a pair touches two).
fn sole_body<const D: usize>(row: &Row<D>) -> Option<usize> {
    let mut bodies = (0..D / 3).filter(|&b| touches(row, b));
    let first = bodies.next()?;
    bodies.next().is_none().then_some(first)
}

/// The law a candidate set is judged by: each body's law under contacts (`body`) where one
/// of the set's contacts touches it, its free law (`free`) elsewhere, as the motion will
/// integrate it (docs/model.md §6c). For one body: the free law for the empty set only.
fn law_of<const D: usize>(
    body: &Group<D>,
    free: &Group<D>,
    rows: &[Row<D>],
    mask: u32,
) -> Group<D> {
    if mask == 0 {
        return *free;
    }
    let mut law = *body;
    for b in 0..D / 3 {
        let touched = rows
            .iter()
            .enumerate()
            .any(|(i, r)| mask & (1 << i) != 0 && touches(r, b));
        if !touched {
            law.external[3 * b..3 * b + 3].copy_from_slice(&free.external[3 * b..3 * b + 3]);
        }
    }
    law
}

/// Gaussian elimination with partial pivoting on the leading n×n block.
fn gauss<const M: usize>(a: &mut [[f64; M]; M], b: &mut [f64; M], n: usize) -> Option<[f64; M]> {
    let scale = (0..n)
        .flat_map(|r| (0..n).map(move |c| (r, c)))
        .map(|(r, c)| a[r][c].abs())
        .fold(0.0, f64::max);
    for k in 0..n {
        let p = (k..n).max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))?;
        let pivot_ok = a[p][k].abs() > 1e-12 * scale.max(f64::MIN_POSITIVE);
        if !pivot_ok {
            return None;
        }
        a.swap(k, p);
        b.swap(k, p);
        let (head, tail) = a.split_at_mut(k + 1);
        let pivot_row = &head[k];
        for (i, row) in tail.iter_mut().enumerate().take(n - k - 1) {
            let f = row[k] / pivot_row[k];
            for (x, &p) in row[k..n].iter_mut().zip(&pivot_row[k..n]) {
                *x -= f * p;
            }
            b[k + 1 + i] -= f * b[k];
        }
    }
    let mut x = [0.0; M];
    for k in (0..n).rev() {
        let s: f64 = (k + 1..n).map(|j| a[k][j] * x[j]).sum();
        x[k] = (b[k] - s) / a[k][k];
    }
    Some(x)
}

/// Tolerances of the active-set test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerances {
    /// Slip below which a contact may stick or start sliding either way [m/s].
    pub slip: f64,
    /// Force slack \[N] (negative normal forces above −force count as zero).
    pub force: f64,
    /// Acceleration slack [m/s²].
    pub accel: f64,
}

/// The chosen active set: per closed contact its mode (`None`: it carries no force).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Selected<const D: usize, const C: usize> {
    pub modes: [Option<Tangential>; C],
    pub solution: Solved<D, C>,
}

/// One body's chosen active set.
pub type Selection = Selected<3, MAX_CONTACTS>;

/// Choose which of the closed contacts (gap and normal speed ≈ 0) carry force, and how each
/// behaves tangentially, so that all normal forces are ≥ 0, sticking forces lie in the
/// friction cone, contacts starting to slide do so against their friction, and no inactive
/// contact accelerates into penetration. Tries active sets from the most contacts down and
/// prefers sticking; returns the first consistent one, or `None` if none is (the caller
/// reports a failure).
pub fn select(body: &Body, rows: &[ContactRow], tol: &Tolerances) -> Option<Selection> {
    select_preferring(body, rows, tol, 0)
}

/// As [`select`], but active sets that include more of the contacts in the bit mask
/// `prefer` are tried first (e.g. contacts just struck plastically: where an active set with
/// them and one without are both consistent, the contact persists instead of creeping back
/// in and being struck again).
pub fn select_preferring(
    body: &Body,
    rows: &[ContactRow],
    tol: &Tolerances,
    prefer: u32,
) -> Option<Selection> {
    select_with_free(body, body.external, rows, tol, prefer)
}

/// As [`select_preferring`], with the external force `free_external` acting instead of
/// `body.external` when no contact is active: the caller's law of free motion where it
/// differs from the law under contacts (the belt friction is regularised only while a
/// contact is active), so that every candidate set is judged by exactly the law the motion
/// will then integrate.
pub fn select_with_free(
    body: &Body,
    free_external: [f64; 3],
    rows: &[ContactRow],
    tol: &Tolerances,
    prefer: u32,
) -> Option<Selection> {
    select_group(&body.as_group(), free_external, rows, tol, prefer)
}

/// [`select_with_free`] for a group of bodies: the same rules, over at most C contacts
/// (C ≤ 16). A candidate set is judged with `free_external` on each body that none of its
/// contacts touches (a body of the group moving freely beside a held pair).
pub fn select_group<const D: usize, const C: usize>(
    group: &Group<D>,
    free_external: [f64; D],
    rows: &[Row<D>],
    tol: &Tolerances,
    prefer: u32,
) -> Option<Selected<D, C>> {
    let free = Group {
        external: free_external,
        ..*group
    };
    // Per contact, the options when active: a slipping contact slides on (a Coulomb force
    // law at finite slip), one at rest sticks or starts to slide either way.
    let options = |r: &Row<D>| -> ([Tangential; 3], usize) {
        if r.slip.abs() > tol.slip {
            (
                [
                    Tangential::Slide(r.slip.signum()),
                    Tangential::Stick,
                    Tangential::Stick,
                ],
                1,
            )
        } else if r.friction > 0.0 {
            (
                [
                    Tangential::Stick,
                    Tangential::Slide(1.0),
                    Tangential::Slide(-1.0),
                ],
                3,
            )
        } else {
            (
                [Tangential::Slide(1.0), Tangential::Stick, Tangential::Stick],
                1,
            )
        }
    };
    enumerate(group, &free, rows, prefer, options, |modes, sol| {
        consistent(rows, modes, sol, tol)
    })
}

/// The simultaneous plastic impact of the closed contacts `rows` (model.md §6–§7, the LCP at
/// the velocity level; Moreau's impact law with e = 0): impulses P_n ≥ 0 such that every active
/// contact ends with u_n′ = 0 and no other approaches, with Coulomb friction on the final
/// slip: sticking (u_t′ = 0, |P_t| ≤ μ P_n) or sliding (P_t = −μ s P_n with s u_t′ ≥ 0), and
/// the impact dissipating (Σ_c P_c·(u_c + u_c′)/2 ≤ 0, u the relative velocity at the
/// contact, which changes linearly along the impulse).
///
/// The rows carry the target velocity changes as β = −u_n and β_t = −u_t, and the solution's
/// `accel` is the change of q̇, its forces the impulses. `None` if no set is consistent.
///
/// Reference: J. J. Moreau, "Unilateral contact and dry friction in finite freedom
/// dynamics", in *Nonsmooth Mechanics and Applications*, CISM 302 (1988) 1–82.
pub fn select_impact(body: &Body, rows: &[ContactRow], tol: &Tolerances) -> Option<Selection> {
    select_impact_group(&body.as_group(), rows, tol)
}

/// [`select_impact`] for a group of bodies: the impulses of a simultaneous plastic impact
/// among them and their obstacles, over at most C contacts.
pub fn select_impact_group<const D: usize, const C: usize>(
    group: &Group<D>,
    rows: &[Row<D>],
    tol: &Tolerances,
) -> Option<Selected<D, C>> {
    let options = |r: &Row<D>| -> ([Tangential; 3], usize) {
        if r.friction == 0.0 {
            ([Tangential::Slide(1.0); 3], 1)
        } else {
            let s = if r.slip < 0.0 { -1.0 } else { 1.0 };
            (
                [
                    Tangential::Slide(s),
                    Tangential::Stick,
                    Tangential::Slide(-s),
                ],
                3,
            )
        }
    };
    enumerate(group, group, rows, 0, options, |modes, sol| {
        if !consistent(rows, modes, sol, tol) {
            return false;
        }
        let (mut work, mut scale) = (0.0, 0.0);
        for (i, (row, mode)) in rows.iter().zip(modes).enumerate() {
            let Some(mode) = mode else { continue };
            // u_n0 = −β, Δu_n = J Δq̇; likewise tangentially.
            let (un0, dun) = (-row.beta, dot(&row.normal, &sol.accel));
            let (ut0, dut) = (-row.beta_t, dot(&row.tangent, &sol.accel));
            // Friction opposes the final slip.
            if let Tangential::Slide(s) = mode {
                if row.friction > 0.0 && s * (ut0 + dut) < -tol.slip {
                    return false;
                }
            }
            let (pn, pt) = (sol.normal_force[i], sol.tangential_force[i]);
            work += pn * (un0 + 0.5 * dun) + pt * (ut0 + 0.5 * dut);
            scale += (pn * un0).abs() + (pt * ut0).abs() + (pn * dun).abs() + (pt * dut).abs();
        }
        // Rounding aside, no energy is created.
        work <= 1e-9 * scale
    })
}

/// Tries the active sets of `rows` (those including more of the bit mask `prefer` first, then
/// larger sets first) and, for each, the combinations of tangential modes that `options`
/// allows, and returns the first solution `accept` takes. `free` is each body's law with
/// none of its contacts active ([`law_of`]).
fn enumerate<const D: usize, const C: usize>(
    body: &Group<D>,
    free: &Group<D>,
    rows: &[Row<D>],
    prefer: u32,
    options: impl Fn(&Row<D>) -> ([Tangential; 3], usize),
    accept: impl Fn(&[Option<Tangential>], &Solved<D, C>) -> bool,
) -> Option<Selected<D, C>> {
    const {
        assert!(
            C <= 16,
            "the enumeration takes at most 16 contacts (4^C solves)"
        )
    };
    let k = rows.len().min(C);
    let mut masks: Vec<u32> = (0u32..(1 << k)).collect();
    // Larger sets first: where a flush side makes several sets consistent within the
    // tolerances, keeping every touching contact (one may carry ≈ 0) avoids a contact
    // creeping in unwatched; a set with a contact that really pulls (λ_n < 0) is refused.
    masks.sort_by_key(|m| {
        (
            (prefer & !m).count_ones(),
            std::cmp::Reverse(m.count_ones()),
        )
    });
    for mask in masks {
        let law = law_of(body, free, &rows[..k], mask);
        // Iterate over the product of options of the active contacts.
        let total: usize = (0..k)
            .filter(|i| mask & (1 << i) != 0)
            .map(|i| options(&rows[i]).1)
            .product();
        for combo in 0..total {
            let mut modes = [None; C];
            let mut c = combo;
            for i in 0..k {
                if mask & (1 << i) != 0 {
                    let (opts, cnt) = options(&rows[i]);
                    modes[i] = Some(opts[c % cnt]);
                    c /= cnt;
                }
            }
            let Some(sol) = solve_group(&law, &rows[..k], &modes[..k]) else {
                continue;
            };
            if accept(&modes[..k], &sol) {
                return Some(Selected {
                    modes,
                    solution: sol,
                });
            }
        }
    }
    None
}

fn consistent<const D: usize, const C: usize>(
    rows: &[Row<D>],
    modes: &[Option<Tangential>],
    sol: &Solved<D, C>,
    tol: &Tolerances,
) -> bool {
    for (i, (row, mode)) in rows.iter().zip(modes).enumerate() {
        match mode {
            None => {
                let g_ddot = dot(&row.normal, &sol.accel) - row.beta;
                if g_ddot < -tol.accel {
                    return false;
                }
            }
            Some(m) => {
                let ln = sol.normal_force[i];
                if ln < -tol.force {
                    return false;
                }
                match m {
                    Tangential::Stick => {
                        if sol.tangential_force[i].abs() > row.friction * ln.max(0.0) + tol.force {
                            return false;
                        }
                    }
                    Tangential::Slide(s) => {
                        // (A frictionless contact has no direction to choose.)
                        if row.friction > 0.0 {
                            let ut_dot = dot(&row.tangent, &sol.accel) - row.beta_t;
                            if row.slip.abs() <= tol.slip {
                                // Starting to slide: the slip must grow in the chosen
                                // direction.
                                if s * ut_dot < -tol.accel {
                                    return false;
                                }
                            } else if row.slip.abs() <= REVERSAL_SLIP
                                && row.slip.abs() + s * ut_dot * REVERSAL_TIME < 0.0
                            {
                                // Sliding on, but so hard against the slip that it reverses
                                // at once (a slip of 1e-8 m/s left by the velocity projection
                                // as a stick broke, under 1.6e4 m/s² the other way): the
                                // contact is at rest, for the tolerances that allow it.
                                return false;
                            }
                        }
                    }
                }
            }
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{cross, perp, rotate};
    use approx::assert_relative_eq;
    use glam::DVec2;

    #[allow(clippy::too_many_arguments)]
    /// Corner-on-arm row built by hand from model.md §6 (independent of model::contact).
    fn arm_row(
        g: DVec2,
        v: DVec2,
        omega: f64,
        r: DVec2,
        alpha: f64,
        rate: f64,
        accel: f64,
        mu: f64,
    ) -> ContactRow {
        let n = DVec2::new(-alpha.sin(), alpha.cos());
        let t = DVec2::new(n.y, -n.x);
        let p = g + r;
        let s = p.dot(t);
        let gap = p.dot(n);
        let vp = v + omega * perp(r);
        ContactRow {
            normal: [n.x, n.y, cross(r, n)],
            beta: omega * omega * r.dot(n) + 2.0 * rate * vp.dot(t) + accel * s + rate * rate * gap,
            tangent: [t.x, t.y, cross(r, t)],
            beta_t: omega * omega * r.dot(t) - rate * vp.dot(n),
            friction: mu,
            slip: vp.dot(t) + rate * gap,
        }
    }

    /// The F5 reference case of model.md §6 with arm friction and α̈: 0.4×0.26, 5 kg, side a on
    /// the arm,
    /// α = 20°, α̇ = 1.2, α̈ = 3, s = 0.5, ṡ = 0.3, μ_a = 0.3, no belt friction.
    #[test]
    fn f5_oracle_with_friction() {
        let (m, a, b) = (5.0, 0.4, 0.26);
        let inertia = m * (a * a + b * b) / 12.0;
        let (alpha, rate, accel) = (20f64.to_radians(), 1.2, 3.0);
        let (s, s_dot, h) = (0.5, 0.3, b / 2.0);
        let t = DVec2::new(alpha.cos(), alpha.sin());
        let n = perp(t);
        let g = s * t + h * n;
        let v = (s_dot - h * rate) * t + s * rate * n;
        let r1 = rotate(DVec2::new(-a / 2.0, -b / 2.0), alpha);
        let r2 = rotate(DVec2::new(a / 2.0, -b / 2.0), alpha);
        let rows = [
            arm_row(g, v, rate, r1, alpha, rate, accel, 0.3),
            arm_row(g, v, rate, r2, alpha, rate, accel, 0.3),
        ];
        assert!(rows[0].slip > 0.0 && rows[1].slip > 0.0);
        let body = Body {
            mass: m,
            inertia,
            external: [0.0; 3],
        };
        let tol = Tolerances {
            slip: 1e-9,
            force: 1e-9,
            accel: 1e-9,
        };
        let sel = select(&body, &rows, &tol).expect("an active set");
        assert_eq!(sel.modes[0], Some(Tangential::Slide(1.0)));
        assert_eq!(sel.modes[1], Some(Tangential::Slide(1.0)));
        let sol = sel.solution;
        let (n1, n2) = (sol.normal_force[0], sol.normal_force[1]);
        let total = n1 + n2;
        let a_g = DVec2::new(sol.accel[0], sol.accel[1]);
        let s_ddot = a_g.dot(t) + h * accel + s * rate * rate;
        let delta = (n2 - n1) / total * a / 2.0;
        assert_relative_eq!(total, 10.164000, max_relative = 1e-6);
        assert_relative_eq!(s_ddot, 0.500160, max_relative = 1e-6);
        assert_relative_eq!(delta, 0.066991, max_relative = 1e-5);
        assert_relative_eq!(n1, 3.379760, max_relative = 1e-6);
        assert_relative_eq!(n2, 6.784240, max_relative = 1e-6);
        // The parcel turns with the arm: φ̈ = α̈.
        assert_relative_eq!(sol.accel[2], accel, max_relative = 1e-12);
    }

    /// One sliding contact: the effective mass is 1/(W_nn − μ s W_tn) (model.md §6).
    #[test]
    fn one_contact_has_the_impact_effective_mass() {
        let (m, i) = (2.0, 0.05);
        let r = DVec2::new(0.1, -0.2);
        let n = DVec2::new(0.3, 1.0).normalize();
        let t = DVec2::new(n.y, -n.x);
        let (rt, rn) = (r.dot(t), r.dot(n));
        let (wtt, wtn, wnn) = (1.0 / m + rn * rn / i, -rt * rn / i, 1.0 / m + rt * rt / i);
        let _ = wtt;
        let mu = 0.3;
        let row = ContactRow {
            normal: [n.x, n.y, cross(r, n)],
            beta: 1.7,
            tangent: [t.x, t.y, cross(r, t)],
            beta_t: 0.0,
            friction: mu,
            slip: 0.5,
        };
        let body = Body {
            mass: m,
            inertia: i,
            external: [0.0; 3],
        };
        let sol = solve(&body, &[row], &[Some(Tangential::Slide(1.0))]).unwrap();
        assert_relative_eq!(
            sol.normal_force[0],
            1.7 / (wnn - mu * wtn),
            max_relative = 1e-12
        );
        assert_relative_eq!(
            sol.tangential_force[0],
            -mu * sol.normal_force[0],
            max_relative = 1e-12
        );
    }

    /// A contact pulled away from the obstacle is released: the empty set is chosen.
    #[test]
    fn separating_contact_is_inactive() {
        let row = ContactRow {
            normal: [0.0, 1.0, 0.0],
            beta: -1.0,
            tangent: [1.0, 0.0, 0.0],
            beta_t: 0.0,
            friction: 0.3,
            slip: 0.0,
        };
        let body = Body {
            mass: 1.0,
            inertia: 0.1,
            external: [0.0; 3],
        };
        let tol = Tolerances {
            slip: 1e-9,
            force: 1e-9,
            accel: 1e-9,
        };
        let sel = select(&body, &[row], &tol).unwrap();
        assert_eq!(sel.modes[0], None);
    }

    /// A block pressed on a floor by a force inside the friction cone sticks; outside it
    /// slides against the push with friction at the limit.
    #[test]
    fn stick_inside_the_cone_slide_outside() {
        // Point mass on the floor y = 0 (n = (0,1)); pushed down with 10 N and sideways.
        let row = ContactRow {
            normal: [0.0, 1.0, 0.0],
            beta: 0.0,
            tangent: [1.0, 0.0, 0.0],
            beta_t: 0.0,
            friction: 0.5,
            slip: 0.0,
        };
        let tol = Tolerances {
            slip: 1e-9,
            force: 1e-9,
            accel: 1e-9,
        };
        let inside = Body {
            mass: 1.0,
            inertia: 1.0,
            external: [4.0, -10.0, 0.0],
        };
        let sel = select(&inside, &[row], &tol).unwrap();
        assert_eq!(sel.modes[0], Some(Tangential::Stick));
        assert_relative_eq!(sel.solution.tangential_force[0], -4.0, epsilon = 1e-12);
        assert_relative_eq!(sel.solution.accel[0], 0.0, epsilon = 1e-12);
        let outside = Body {
            mass: 1.0,
            inertia: 1.0,
            external: [7.0, -10.0, 0.0],
        };
        let sel = select(&outside, &[row], &tol).unwrap();
        assert_eq!(sel.modes[0], Some(Tangential::Slide(1.0)));
        assert_relative_eq!(sel.solution.accel[0], 7.0 - 5.0, epsilon = 1e-12);
    }
}
