//! When each arm starts: a diverter's controller, deciding from what a real controller sees.
//!
//! For a parcel bound for its chute, the light barrier at S_d sees the front pass and (with
//! the adaptive trigger) the dimensioner gives its sides and pose; the controller plans the
//! stroke for when the front is at R_s (fixed, or the parcel's own from the trigger table),
//! shifted by the parcel's trigger phase error δt as in `reliability`. Parcels are taken in
//! the order their fronts pass the barrier. The arm cannot start a cycle before the last
//! one has ended: a parcel whose planned start falls inside it is handled by the
//! [`BusyRule`] (skipped as `arm_busy` by default, or started late within a bound).
//!
//! The controller knows nothing of the physics at its own arm: it plans from the barrier,
//! never from outcomes.

use super::{BusyRule, Diverter};
use crate::analysis::population::mix::Draw;

/// A parcel as the controller sees it approaching.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Approach {
    /// Its sides and materials, with ΔP and φ as it approaches (the dimensioner's view).
    pub draw: Draw,
    /// When its front passes the pivot's x, riding (segment time) \[s]
    pub front_time: f64,
    /// Whether it is bound for this chute.
    pub bound: bool,
}

/// The controller's decision for one parcel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Decision {
    /// Not bound here: no cycle of its own.
    NotBound,
    /// A cycle starts for it at `start` (segment time) \[s], when its front is at `front` \[m]
    /// (R_s + v·δt, plus v·delay when started late).
    Served { start: f64, front: f64 },
    /// Bound here, but the arm was busy at the planned start.
    Busy,
}

/// The cycles the arm runs (their starts, increasing, none overlapping) and the decision for
/// each parcel of `approaches`.
pub fn plan(
    diverter: &Diverter,
    busy: BusyRule,
    approaches: &[Approach],
) -> (Vec<f64>, Vec<Decision>) {
    let m = &diverter.setting.machine;
    let v = m.belt_speed;
    let planned: Vec<Option<(f64, f64, f64)>> = approaches
        .iter()
        .map(|a| {
            a.bound.then(|| {
                let front =
                    diverter.trigger.start_for(&a.draw, &diverter.setting) + v * a.draw.phase;
                let barrier = a.front_time + m.light_barrier.min(front) / v;
                (barrier, a.front_time + front / v, front)
            })
        })
        .collect();
    let mut order: Vec<usize> = (0..approaches.len())
        .filter(|&k| planned[k].is_some())
        .collect();
    order.sort_by(|&i, &j| {
        let (bi, bj) = (planned[i].map(|p| p.0), planned[j].map(|p| p.0));
        bi.partial_cmp(&bj)
            .unwrap_or(std::cmp::Ordering::Equal)
            .then(i.cmp(&j))
    });
    let mut decisions = vec![Decision::NotBound; approaches.len()];
    let mut cycles = Vec::new();
    let mut free_at = f64::NEG_INFINITY;
    for k in order {
        let Some((_, start, front)) = planned[k] else {
            continue;
        };
        let chosen = if start >= free_at {
            Some((start, front))
        } else {
            match busy {
                BusyRule::Skip => None,
                BusyRule::Late { max_delay } => (free_at - start <= max_delay)
                    .then_some((free_at, front + v * (free_at - start))),
            }
        };
        decisions[k] = match chosen {
            Some((start, front)) if start.is_finite() => {
                cycles.push(start);
                free_at = start + m.cycle_time;
                Decision::Served { start, front }
            }
            _ => Decision::Busy,
        };
    }
    (cycles, decisions)
}
