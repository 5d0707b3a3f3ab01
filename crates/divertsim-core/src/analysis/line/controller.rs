//! When each arm starts: a diverter's controller, deciding from what a real controller sees.
//!
//! For a parcel bound for its chute, the light barrier at S_d sees the front pass and (with
//! the adaptive trigger) the dimensioner gives its sides and pose; the controller plans the
//! stroke for when the front is at R_s (fixed, or the parcel's own from the trigger table),
//! shifted by the parcel's trigger phase error δt as in `reliability`. Parcels are taken in
//! the order their fronts pass the barrier. The arm cannot start a cycle before the last
//! one has ended: a parcel whose planned start falls inside it is handled by the
//! [`BusyRule`] (skipped as `arm_busy` by default, or started late within a bound); the
//! `Barrier` rule skips a parcel already when its front passes the barrier during a cycle
//! (one parcel at a time, the paper's W).
//!
//! The controller knows nothing of the physics at its own arm: it plans from the barrier,
//! never from outcomes.

use super::{BusyRule, Diverter};
use crate::analysis::population::mix::Draw;

/// Times closer than this are the same instant \[s] (docs/model.md §12: s_{k+1} ≥ s_k + t_c
/// to 10⁻⁹ s). A headway of exactly t_c/k, or a late start delayed by exactly max_delay,
/// is then decided as stated, not by the rounding of the sums that give the times.
pub const TIE: f64 = 1e-9;

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
    plan_each(diverter, busy, approaches.iter().copied())
}

/// [`plan`] of approaches taken as they come: a segment's stream need not hold them all (an
/// approach is a whole draw; the plan keeps a few numbers of each).
pub fn plan_each(
    diverter: &Diverter,
    busy: BusyRule,
    approaches: impl IntoIterator<Item = Approach>,
) -> (Vec<f64>, Vec<Decision>) {
    let m = &diverter.setting.machine;
    let v = m.belt_speed;
    let planned: Vec<Option<(f64, f64, f64)>> = approaches
        .into_iter()
        .map(|a| {
            a.bound.then(|| {
                let front =
                    diverter.trigger.start_for(&a.draw, &diverter.setting) + v * a.draw.phase;
                let barrier = a.front_time + m.light_barrier.min(front) / v;
                (barrier, a.front_time + front / v, front)
            })
        })
        .collect();
    let mut order: Vec<usize> = (0..planned.len())
        .filter(|&k| planned[k].is_some())
        .collect();
    order.sort_by(|&i, &j| {
        let (bi, bj) = (planned[i].map(|p| p.0), planned[j].map(|p| p.0));
        bi.partial_cmp(&bj)
            .unwrap_or(std::cmp::Ordering::Equal)
            .then(i.cmp(&j))
    });
    let mut decisions = vec![Decision::NotBound; planned.len()];
    let mut cycles = Vec::new();
    let mut free_at = f64::NEG_INFINITY;
    for k in order {
        let Some((barrier, start, front)) = planned[k] else {
            continue;
        };
        let free = match busy {
            BusyRule::Barrier => barrier >= free_at - TIE,
            _ => start >= free_at - TIE,
        };
        let chosen = if free {
            Some((start, front))
        } else {
            match busy {
                BusyRule::Skip | BusyRule::Barrier => None,
                BusyRule::Late { max_delay } => (free_at - start <= max_delay + TIE)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::population::reliability::StartRule;
    use crate::model::params::Scenario;

    /// The paper's machine with R_s = 0.4 m, S_d = 0 (v = 2 m/s, t_c = 1.36 s): a parcel's
    /// stroke starts 0.2 s after its front passes the barrier at the pivot.
    fn diverter() -> Diverter {
        let mut setting = Scenario::paper_machine();
        setting.machine.start_position = 0.4;
        Diverter {
            position: 0.0,
            setting,
            trigger: StartRule::Fixed,
            share: 1.0,
            changes: Default::default(),
            table: Default::default(),
        }
    }

    fn approach(front_time: f64) -> Approach {
        Approach {
            draw: super::super::tests::compact(0, 0.2),
            front_time,
            bound: true,
        }
    }

    #[test]
    fn busy_rules_decide_as_documented() {
        // A starts at 0.2 s, the arm is free again at 1.56 s. B's planned start (1.5 s) falls
        // in A's cycle; C's (1.65 s) does not, but its front passes the barrier (1.45 s)
        // during it.
        let parcels = [approach(0.0), approach(1.3), approach(1.45)];
        let d = diverter();
        let (cycles, skip) = plan(&d, BusyRule::Skip, &parcels);
        assert_eq!(skip[1], Decision::Busy);
        assert!(matches!(skip[2], Decision::Served { start, .. } if (start - 1.65).abs() < 1e-12));
        assert_eq!(cycles.len(), 2);
        let (_, late) = plan(&d, BusyRule::Late { max_delay: 0.1 }, &parcels);
        match late[1] {
            // Started when the arm is free, its front 2 m/s × 0.06 s further on.
            Decision::Served { start, front } => {
                assert!((start - 1.56).abs() < 1e-12 && (front - 0.52).abs() < 1e-12)
            }
            other => panic!("{other:?}"),
        }
        // C now falls in B's late cycle.
        assert_eq!(late[2], Decision::Busy);
        let (cycles, barrier) = plan(&d, BusyRule::Barrier, &parcels);
        assert_eq!((barrier[1], barrier[2]), (Decision::Busy, Decision::Busy));
        assert_eq!(cycles, vec![0.2]);
    }

    /// Issue 50, item 14: exact ties were decided by the rounding of the summed times. At a
    /// headway of exactly t_c/2 the skip rule serves every other parcel (it made 129 of
    /// 3,000 more `arm_busy`), and a late start delayed by exactly max_delay is served.
    #[test]
    fn exact_ties_are_decided_within_the_tolerance() {
        let d = diverter();
        let t_c = d.setting.machine.cycle_time;
        // Times summed headway by headway, as the stream sums them.
        let fronts = |h: f64, n: usize| {
            let mut t = 0.0;
            (0..n)
                .map(|_| {
                    let a = approach(t);
                    t += h;
                    a
                })
                .collect::<Vec<_>>()
        };
        let parcels = fronts(t_c / 2.0, 3000);
        let (cycles, skip) = plan(&d, BusyRule::Skip, &parcels);
        assert_eq!(cycles.len(), 1500);
        for (i, s) in skip.iter().enumerate() {
            assert_eq!(
                matches!(s, Decision::Served { .. }),
                i % 2 == 0,
                "parcel {i}"
            );
        }
        let parcels = fronts(t_c / 3.0, 3000);
        assert_eq!(plan(&d, BusyRule::Skip, &parcels).0.len(), 1000);
        // Headway t_c − 0.1: each parcel waits 0.1 s more than the one before, so with
        // max_delay = 0.1 exactly the second is served late and the third skipped.
        let parcels = fronts(t_c - 0.1, 3);
        let (_, late) = plan(&d, BusyRule::Late { max_delay: 0.1 }, &parcels);
        assert!(matches!(late[1], Decision::Served { .. }), "{late:?}");
        assert_eq!(late[2], Decision::Busy);
    }
}
