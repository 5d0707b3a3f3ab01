//! Parts of the several-parcel run (issue 49; docs/model.md §5a, §6a, §6c): which corners of
//! a group of free parcels touch which edges (the one contact-pair rule of `settle`, with
//! the pair's nearest and touchable features), and the strikes of one instant among them.
//!
//! **Strikes.** As for one parcel (`settle::strike`): every closed pair approaching faster
//! than `SPEED_TOL` (1e-8 m/s) is struck, the fastest first, by the selected impact law
//! over the pair's mobility W_A + W_B (§5a), until none approaches. A pair struck again
//! within the instant, and any strike slower than `PERSIST_SPEED` (0.01 m/s), is plastic;
//! a repeat resolves every closed pair of the group at once as one plastic impact
//! ([`active_set::select_impact_group`], §6c), and those pairs persist. More than
//! `MAX_STRIKES` (64) impulses, a group impact counting as one, is an error.
//!
//! The event loop that integrates a group between such instants is still to come.

use super::settle::MAX_STRIKES;
use super::tolerances::*;
use crate::model::active_set::{self, Group, Row, Tolerances};
use crate::model::contact::leaves_end;
use crate::model::impact::{pair_velocity_changes, resolve, BodyAtContact, ImpactInput, ImpactLaw};
use crate::model::pair_contact::{
    corner_edge_shortfall, corner_into_edge, corner_on_edge, BoxState, PairFrame,
};
use glam::DVec2;

/// Most parcels a group holds.
pub const MAX_MEMBERS: usize = 3;
/// Most closed pairs resolved at once: three parcels each flush on the other two (the
/// enumeration then tries at most 4⁶ sets).
pub const MAX_PAIRS: usize = 6;

/// One parcel of a group: its motion in the plane and its mass properties.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Member {
    pub state: BoxState,
    /// m \[kg]
    pub mass: f64,
    /// I about its centre [kg·m²]
    pub inertia: f64,
}

/// A contact between two members: corner `corner` of member `a` on edge `edge` of member
/// `b` (edge j joins corners j and j + 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PairKind {
    pub a: usize,
    pub corner: u8,
    pub b: usize,
    pub edge: u8,
}

/// How two parcels strike each other.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairLaw {
    /// μ between two parcels
    pub friction: f64,
    /// e (e* for the energetic law)
    pub restitution: f64,
    pub law: ImpactLaw,
}

/// Every closed corner–edge pair of the group (the one contact-pair rule, docs/model.md §6
/// and §6a): the gap from `DEEPEST_GAP` (−5e-7 m) to `GAP_TOL` (1e-7 m), the corner on the
/// edge and not moving off one of its ends, the edge the corner's nearest (within
/// `NEAREST_TOL`, 1e-10 m) and touchable from outside (`ARM_EDGE_TOL`, 1e-6). Where a
/// corner of A meets a corner of B and B's corner lies on A's edge at the same point, that
/// is one contact, not two: the pair that approaches faster. (Axis-aligned corners that
/// meet tip to tip tie between two edges and keep both: two rows at one point, which the
/// active set handles as any redundant pair.)
pub fn closed_pairs(members: &[Member]) -> Vec<(PairKind, PairFrame)> {
    let mut out: Vec<(PairKind, PairFrame)> = Vec::new();
    for (a, ma) in members.iter().enumerate() {
        for (b, mb) in members.iter().enumerate() {
            if a == b {
                continue;
            }
            for corner in 0..4u8 {
                for edge in 0..4u8 {
                    let frame = corner_on_edge(&ma.state, corner, &mb.state, edge);
                    let f = &frame.on_a;
                    let closed = f.gap <= GAP_TOL
                        && f.gap >= DEEPEST_GAP
                        && f.along >= f.extent.0 - RANGE_TOL
                        && f.along <= f.extent.1 + RANGE_TOL
                        && !leaves_end(f, END_TOL, LEAVE_SPEED)
                        && corner_edge_shortfall(&ma.state, corner, &mb.state, edge) <= NEAREST_TOL
                        && corner_into_edge(&ma.state, corner, &mb.state, edge) >= -ARM_EDGE_TOL;
                    if !closed {
                        continue;
                    }
                    let kind = PairKind { a, corner, b, edge };
                    // B's corner on A's edge at the same point: one contact, the one that
                    // approaches faster (the other's normal may point elsewhere).
                    let twin = out.iter().position(|(k, g)| {
                        k.a == b && k.b == a && (g.on_a.point - f.point).length() < AT_TIP
                    });
                    match twin {
                        Some(i) if f.normal_speed < out[i].1.on_a.normal_speed => {
                            out[i] = (kind, frame);
                        }
                        Some(_) => {}
                        None => out.push((kind, frame)),
                    }
                }
            }
        }
    }
    out
}

/// What the strikes of one instant leave besides the new velocities.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GroupStrikes {
    /// Every pair struck, in order (one may be struck again).
    pub struck: Vec<PairKind>,
    /// Pairs struck plastically: they persist (u_n = 0 after the strike).
    pub persisting: Vec<PairKind>,
    /// Σ |P| over the impulses of the instant \[N·s].
    pub impulse: f64,
    /// How many of them were one plastic impact of the whole group.
    pub group_impacts: usize,
}

/// Phase 1 of a group's event: strike every closed pair approaching faster than
/// `SPEED_TOL` (1e-8 m/s), the fastest first, until none approaches (module notes); the
/// members' velocities change in place.
pub fn strike(members: &mut [Member], law: &PairLaw) -> Result<GroupStrikes, String> {
    assert!(
        (2..=MAX_MEMBERS).contains(&members.len()),
        "a group holds two or three parcels"
    );
    let mut out = GroupStrikes::default();
    for impulses in 0..=MAX_STRIKES {
        let closed = closed_pairs(members);
        let Some((kind, frame)) = closed
            .iter()
            .filter(|(_, f)| f.on_a.normal_speed < -SPEED_TOL)
            .min_by(|a, b| a.1.on_a.normal_speed.total_cmp(&b.1.on_a.normal_speed))
            .copied()
        else {
            return Ok(out);
        };
        if impulses == MAX_STRIKES {
            break;
        }
        if out.struck.contains(&kind) {
            let p = match members.len() {
                2 => plastic::<6>(members, &closed, law.friction),
                _ => plastic::<9>(members, &closed, law.friction),
            };
            if let Some((impulse, pairs)) = p {
                out.impulse += impulse;
                out.group_impacts += 1;
                for k in pairs {
                    out.struck.push(k);
                    out.persisting.push(k);
                }
                continue;
            }
        }
        let f = &frame.on_a;
        let is_plastic = out.struck.contains(&kind) || -f.normal_speed < PERSIST_SPEED;
        let (a, b) = (members[kind.a], members[kind.b]);
        let at = |m: &Member, r: DVec2| BodyAtContact {
            mass: m.mass,
            inertia: m.inertia,
            r,
        };
        let (on_a, on_b) = (at(&a, f.r), at(&b, frame.r_b));
        let input = ImpactInput {
            mobility: crate::model::impact::pair_mobility(&on_a, &on_b, f.normal),
            u_t0: f.slip,
            u_n0: f.normal_speed,
            friction: law.friction,
            restitution: if is_plastic { 0.0 } else { law.restitution },
            law: law.law,
        };
        let hit = resolve(&input).map_err(|e| format!("a strike between parcels failed: {e}"))?;
        let (ja, jb) = pair_velocity_changes(
            &on_a,
            &on_b,
            f.normal,
            hit.normal_impulse,
            hit.tangential_impulse,
        );
        for (m, j) in [(kind.a, ja), (kind.b, jb)] {
            members[m].state.velocity += j.dv;
            members[m].state.omega += j.domega;
        }
        out.impulse += hit.impulse_vector(f.normal).length();
        out.struck.push(kind);
        if is_plastic {
            out.persisting.push(kind);
        }
    }
    Err(format!(
        "strikes between parcels did not settle after {MAX_STRIKES} impulses"
    ))
}

/// The closed pairs that approach, touch or separate slower than `CLOSE_SPEED` (1e-3 m/s),
/// resolved as one plastic impact of the whole group with Coulomb friction μ (docs/model.md
/// §6c): the members' velocities change in place. Returns Σ |P| and the pairs that took an
/// impulse, or `None` if no consistent impact exists.
fn plastic<const D: usize>(
    members: &mut [Member],
    closed: &[(PairKind, PairFrame)],
    friction: f64,
) -> Option<(f64, Vec<PairKind>)> {
    let mut set: Vec<&(PairKind, PairFrame)> = closed
        .iter()
        .filter(|(_, f)| f.on_a.normal_speed <= CLOSE_SPEED)
        .collect();
    set.sort_by(|a, b| a.1.on_a.normal_speed.total_cmp(&b.1.on_a.normal_speed));
    set.truncate(MAX_PAIRS);
    // The rows carry the target velocity changes: β = −u_n, β_t = −u_t.
    let rows: Vec<Row<D>> = set
        .iter()
        .map(|(k, f)| Row {
            beta: -f.on_a.normal_speed,
            beta_t: -f.on_a.slip,
            ..f.row(k.a, k.b, friction)
        })
        .collect();
    let bodies: Vec<active_set::Body> = members
        .iter()
        .map(|m| active_set::Body {
            mass: m.mass,
            inertia: m.inertia,
            external: [0.0; 3],
        })
        .collect();
    let group = Group::<D>::of(&bodies);
    let scale = members.iter().map(|m| m.mass).fold(0.0, f64::max);
    let tol = Tolerances {
        slip: 1e-8,
        force: 1e-12 * scale,
        accel: 1e-10,
    };
    let sel = active_set::select_impact_group::<D, MAX_PAIRS>(&group, &rows, &tol)?;
    let dv = sel.solution.accel;
    for (k, m) in members.iter_mut().enumerate() {
        m.state.velocity += DVec2::new(dv[3 * k], dv[3 * k + 1]);
        m.state.omega += dv[3 * k + 2];
    }
    let mut impulse = 0.0;
    let mut pairs = Vec::new();
    for (i, (k, f)) in set.iter().enumerate() {
        if sel.modes[i].is_none() {
            continue;
        }
        let (pn, pt) = (
            sel.solution.normal_force[i],
            sel.solution.tangential_force[i],
        );
        impulse += (pn * f.on_a.normal + pt * f.on_a.tangent).length();
        pairs.push(*k);
    }
    Some((impulse, pairs))
}
