//! The stream through the line: every diverter in turn (its controller's plan, each
//! parcel's passage, the neighbour check), the hand-over to the next diverter, and each
//! parcel's outcome.
//!
//! **Outcomes.** At its own diverter a served parcel takes the run's verdict; a parcel
//! skipped as busy is `arm_busy` unless the arm diverted it anyway. Anywhere else a parcel
//! the arm diverts is `wrongly_diverted`, and one the arm touched counts as struck; a struck
//! parcel knocked off the near side leaves the line as `struck_in_passing`. A parcel still
//! on the belt goes on with its final state, translated into the next diverter's frame (a
//! parcel that has missed its chute goes on too: it may still be struck downstream).

use super::controller::{self, Approach, Decision};
use super::neighbours;
use super::passage::{inducted, pass, Carried, Run, Visit};
use super::stream::Arrival;
use super::trace::{ParcelPath, Trace};
use super::{Collision, Line, LineOutcome, LineParcel, RunInputs, Segment, SegmentLoads};
use crate::geometry::Rect;
use crate::sim::arm_loads::StrokeProfile;
use crate::sim::{Outcome, Recording};

/// How much more than a cycle apart two neighbours' fronts may pass the pivot and still be
/// checked along their trajectories \[s].
const NEAR_SLACK: f64 = 1.0;

/// A parcel's progress down the line.
struct Track {
    arrival: Arrival,
    came: Option<Carried>,
    outcome: Option<LineOutcome>,
    decided_at: Option<u8>,
    struck: u8,
    overload_ratio: f64,
    max_impulse: f64,
    collision: Option<Collision>,
    run: Option<Box<RunInputs>>,
    /// The last run in which an arm struck it in passing, and where.
    struck_run: Option<(u8, Box<RunInputs>)>,
}

impl Track {
    /// Decide the outcome at diverter `d`; a failure keeps the run that decided it (a
    /// parcel where it was bound keeps none: a million of them stay small).
    fn decide(&mut self, outcome: LineOutcome, d: usize, run: Option<&Run>) {
        self.outcome = Some(outcome);
        self.decided_at = Some(d as u8);
        self.run = match outcome.correct() {
            true => None,
            false => run.map(|r| Box::new(r.inputs.clone())),
        };
    }
}

/// The segment's parcels `arrivals` through every diverter of the line.
pub fn run_stream(line: &Line, arrivals: &[Arrival]) -> Segment {
    run_stream_traced(line, arrivals, None)
}

/// [`run_stream`], recording every parcel's path and every arm's cycles into `trace` when
/// given (then every run keeps its trajectory; the outcomes are the same).
pub fn run_stream_traced(
    line: &Line,
    arrivals: &[Arrival],
    mut trace: Option<&mut Trace>,
) -> Segment {
    let v = line.belt_speed();
    let mut tracks: Vec<Track> = arrivals
        .iter()
        .map(|a| Track {
            arrival: *a,
            came: Some(inducted(a, v)),
            outcome: None,
            decided_at: None,
            struck: 0,
            overload_ratio: 0.0,
            max_impulse: 0.0,
            collision: None,
            run: None,
            struck_run: None,
        })
        .collect();
    let mut cycles_run = Vec::with_capacity(line.diverters.len());
    let mut simulations = 0;
    let mut loads = SegmentLoads::default();
    for (d, div) in line.diverters.iter().enumerate() {
        let present: Vec<usize> = (0..tracks.len())
            .filter(|&k| tracks[k].came.is_some())
            .collect();
        let approaches: Vec<Approach> = present
            .iter()
            .map(|&k| {
                let t = &tracks[k];
                let came = t.came.expect("present");
                let mut draw = t.arrival.draw;
                (draw.offset, draw.angle) = (came.offset, came.angle);
                Approach {
                    draw,
                    front_time: came.front_time,
                    bound: t.arrival.destination == Some(d),
                }
            })
            .collect();
        let (cycles, decisions) = controller::plan(div, line.busy, &approaches);
        cycles_run.push(cycles.len() as u32);
        let profile = StrokeProfile::of(&div.setting);
        let free = profile
            .as_ref()
            .map_or(0.0, |p| p.loads(0.0, &[], &[]).peak_torque);
        // None until a parcel loads the stroke: a loaded stroke's peak is its runs', which
        // may lie below the free stroke's (a parcel that brakes a decelerating arm).
        let mut peaks: Vec<Option<f64>> = vec![None; cycles.len()];
        if let Some(tr) = trace.as_deref_mut() {
            if tr.parcels.is_empty() {
                tr.parcels = arrivals
                    .iter()
                    .map(|a| ParcelPath::new(a.draw.index, &rect_of(a)))
                    .collect();
            }
            tr.cycles.push(cycles.clone());
        }
        let mut visits = Vec::with_capacity(present.len());
        // A parcel whose neighbour comes within a cycle and a second of it keeps its
        // trajectory: the neighbour check will want it (a run is the same either way).
        let near_time = div.setting.machine.cycle_time + NEAR_SLACK;
        let fronts: Vec<f64> = approaches.iter().map(|a| a.front_time).collect();
        let near = |i: usize| {
            let close = |j: usize| (fronts[j] - fronts[i]).abs() < near_time;
            (i > 0 && close(i - 1)) || (i + 1 < fronts.len() && close(i + 1))
        };
        for (i, (&k, &decision)) in present.iter().zip(&decisions).enumerate() {
            let t = &mut tracks[k];
            let came = t.came.expect("present");
            let recording = match near(i) || trace.is_some() {
                true => Recording::Full,
                false => Recording::VerdictOnly,
            };
            let run = pass(line, d, &cycles, decision, &t.arrival, (came, recording));
            let bound = t.arrival.destination == Some(d);
            match &run {
                None => {
                    if decision == Decision::Busy {
                        t.decide(LineOutcome::ArmBusy, d, None);
                    }
                }
                Some(r) => {
                    simulations += 1;
                    if let Some(p) = &profile {
                        stroke_loads(p, &cycles, r, &mut peaks, &mut loads);
                    }
                    let o = &r.result.overload;
                    if o.overload_ratio.is_finite() {
                        t.overload_ratio = t.overload_ratio.max(o.overload_ratio);
                        t.max_impulse = t.max_impulse.max(o.max_impulse);
                    }
                    let own_cycle = matches!(decision, Decision::Served { .. });
                    if r.touched && !own_cycle {
                        t.struck = t.struck.saturating_add(1);
                        t.struck_run = Some((d as u8, Box::new(r.inputs.clone())));
                    }
                    let diverted = r.result.outcome == Outcome::Diverted;
                    let outcome = match (&r.result.outcome, bound) {
                        (Outcome::Failed(_), _) => Some(LineOutcome::Failed),
                        (Outcome::Diverted, true) => Some(LineOutcome::Diverted),
                        (Outcome::Diverted, false) => Some(LineOutcome::WronglyDiverted),
                        (Outcome::NotDiverted(reason), true) if own_cycle => {
                            Some(LineOutcome::NotDiverted(*reason))
                        }
                        (Outcome::NotDiverted(_), true) => Some(LineOutcome::ArmBusy),
                        (Outcome::NotDiverted(_), false) if r.after.is_none() => {
                            // Knocked off the near side on the way.
                            Some(LineOutcome::StruckInPassing)
                        }
                        _ => None,
                    };
                    if let Some(o) = outcome {
                        // A wrong chute overrides a miss upstream; nothing else is decided twice.
                        if t.outcome.is_none() || (diverted && !bound) || o == LineOutcome::Failed {
                            t.decide(o, d, Some(r));
                        }
                    }
                }
            }
            if let Some(path) = trace.as_deref_mut().map(|tr| &mut tr.parcels[k]) {
                if d == 0 {
                    // Coming in: 3 m up the belt.
                    let entry = came.front_time - 3.0 / v;
                    path.ride(&came, &rect_of(&t.arrival), v, div.position, entry);
                }
                match &run {
                    Some(r) => {
                        path.ride(&came, &rect_of(&t.arrival), v, div.position, r.origin);
                        path.run(r, div.position);
                    }
                    None => path.ride(
                        &came,
                        &rect_of(&t.arrival),
                        v,
                        div.position,
                        came.front_time,
                    ),
                }
            }
            visits.push(Visit {
                track: k,
                rect: rect_of(&t.arrival),
                came,
                run,
            });
        }
        for v_ in &visits {
            tracks[v_.track].came = match &v_.run {
                None => Some(v_.came),
                Some(r) => r.after,
            };
        }
        loads
            .stroke_peaks
            .push(peaks.into_iter().map(|p| p.unwrap_or(free)).collect());
        let (hits, reruns) = neighbours::check(line, d, &visits);
        simulations += reruns;
        for hit in hits {
            for (k, other) in [(hit.first, hit.second), (hit.second, hit.first)] {
                let t = &mut tracks[k];
                let run = visits
                    .iter()
                    .find(|x| x.track == k)
                    .and_then(|x| x.run.as_ref());
                t.decide(LineOutcome::Collision, d, run);
                t.collision = Some(Collision {
                    other: arrivals[other].draw.index,
                    ..hit.at
                });
                tracks[k].came = None;
                if let Some(tr) = trace.as_deref_mut() {
                    tr.parcels[k].gone = Some(hit.at.time);
                }
            }
        }
        if let Some(next) = line.diverters.get(d + 1) {
            let shift = next.position - div.position;
            for t in &mut tracks {
                t.came = t.came.map(|c| c.shifted(shift, v));
            }
        }
    }
    if let (Some(tr), Some(last)) = (trace, line.diverters.last()) {
        // Riding on past the last diverter, out of its reach.
        let reach = last.setting.machine.arm_length + 1.0;
        for (t, path) in tracks.iter().zip(tr.parcels.iter_mut()) {
            if let Some(c) = &t.came {
                path.ride(
                    c,
                    &rect_of(&t.arrival),
                    v,
                    last.position,
                    c.front_time + reach / v,
                );
            }
        }
    }
    let parcels = tracks
        .into_iter()
        .map(|t| {
            let (outcome, decided_at, run) = match t.outcome {
                Some(o) => (o, t.decided_at, t.run),
                // At the line's end: struck on the way (its last strike decides), or passed.
                None => match t.struck_run {
                    Some((d, run)) => (LineOutcome::StruckInPassing, Some(d), Some(run)),
                    None => (LineOutcome::Passed, None, None),
                },
            };
            let d = &t.arrival.draw;
            LineParcel {
                index: d.index,
                arrival: t.arrival.time,
                headway: t.arrival.headway,
                destination: t.arrival.destination.map(|d| d as u8),
                length: d.length,
                width: d.width,
                height: d.height,
                mass: d.mass,
                offset: d.offset,
                angle: d.angle,
                outcome,
                decided_at,
                struck: t.struck,
                overload_ratio: t.overload_ratio,
                max_impulse: t.max_impulse,
                collision: t.collision,
                run,
            }
        })
        .collect();
    Segment {
        parcels,
        cycles: cycles_run,
        simulations,
        loads,
    }
}

/// A run's share of its diverter's strokes: for every cycle of `cycles` the run holds and
/// the parcel loaded (a contact torque or a strike in it), that stroke's peak drive torque
/// from the run (the larger one kept in `peaks`), and every strike's angular impulse.
fn stroke_loads(
    profile: &StrokeProfile,
    cycles: &[f64],
    r: &Run,
    peaks: &mut [Option<f64>],
    loads: &mut SegmentLoads,
) {
    let res = &r.result;
    loads
        .strike_impulses
        .extend(res.arm_strikes.iter().map(|j| j.1.abs()));
    if res.arm_torque.iter().all(|m| m.1 == 0.0) && res.arm_strikes.is_empty() {
        return;
    }
    for (j, &start) in cycles.iter().enumerate() {
        // The run's cycles are the diverter's, as `pass` computed them.
        let rel = start - r.origin;
        if !r.inputs.cycle_starts.contains(&rel) {
            continue;
        }
        let l = profile.loads(rel, &res.arm_torque, &res.arm_strikes);
        if l.peak_contact_torque == 0.0 && l.max_strike_angular_impulse == 0.0 {
            continue;
        }
        peaks[j] = Some(peaks[j].map_or(l.peak_torque, |p| p.max(l.peak_torque)));
        if loads
            .largest
            .as_ref()
            .is_none_or(|(p, _)| l.peak_torque > *p)
        {
            loads.largest = Some((l.peak_torque, Box::new(r.inputs.clone())));
        }
    }
}

fn rect_of(a: &Arrival) -> Rect {
    Rect {
        length: a.draw.length,
        width: a.draw.width,
    }
}
