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
//!
//! **Memory.** At each diverter the parcels pass in stream order, and each pair of
//! neighbours is checked as the second passes ([`neighbours::check_pair`]); a run is then
//! reduced to the parcel's track (its hand-over state, outcome, largest strike). At most two
//! runs are held at a time, so a segment holds a few hundred bytes per parcel, not its
//! runs' trajectories, whatever its length.

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

/// A parcel's progress down the line: what the next diverter and its outcome need, a few
/// words (the parcel itself stays in the segment's arrivals).
struct Track {
    came: Option<Carried>,
    outcome: Option<LineOutcome>,
    decided_at: Option<u8>,
    struck: u8,
    overload_ratio: f64,
    max_impulse: f64,
    /// Boxed, as the runs: few parcels have one.
    collision: Option<Box<Collision>>,
    run: Option<Box<RunInputs>>,
    /// The last run in which an arm struck it in passing, and where.
    struck_run: Option<Box<(u8, RunInputs)>>,
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

/// The paths being recorded: those of the segment's first `parcels` parcels.
struct View<'a> {
    trace: &'a mut Trace,
    parcels: usize,
}

impl View<'_> {
    /// Parcel `k`'s path, if it is in view.
    fn path(&mut self, k: usize) -> Option<&mut ParcelPath> {
        self.trace.parcels.get_mut(k)
    }
}

/// The segment's parcels `arrivals` through every diverter of the line.
pub fn run_stream(line: &Line, arrivals: &[Arrival]) -> Segment {
    stream(line, arrivals, None, &|| {})
}

/// [`run_stream`], `stop_point` called before each parcel's passage of each diverter: a
/// caller's stop may end a long segment there (by unwinding; the segment is then lost
/// whole). It is no count of progress.
pub fn run_stream_stoppable(
    line: &Line,
    arrivals: &[Arrival],
    stop_point: &(dyn Fn() + Sync),
) -> Segment {
    stream(line, arrivals, None, stop_point)
}

/// [`run_stream`], recording every parcel's path and every arm's cycles into `trace` when
/// given (then every run keeps its trajectory; the outcomes are the same).
pub fn run_stream_traced(line: &Line, arrivals: &[Arrival], trace: Option<&mut Trace>) -> Segment {
    stream(
        line,
        arrivals,
        trace.map(|trace| View {
            trace,
            parcels: arrivals.len(),
        }),
        &|| {},
    )
}

/// [`run_stream`], recording the paths of the first `parcels` parcels and every arm's cycles
/// into `trace` (the other parcels run as in [`run_stream`]; the outcomes are the same).
pub fn run_stream_viewed(
    line: &Line,
    arrivals: &[Arrival],
    trace: &mut Trace,
    parcels: usize,
) -> Segment {
    stream(line, arrivals, Some(View { trace, parcels }), &|| {})
}

/// The stream, diverter by diverter. Each parcel's run is reduced to its track as soon as
/// the neighbour check of it and the next parcel is done: at most two runs (their
/// trajectories, loads and events) are held at a time, so a segment's memory is a few
/// hundred bytes per parcel whatever its length.
fn stream(
    line: &Line,
    arrivals: &[Arrival],
    mut view: Option<View<'_>>,
    stop_point: &(dyn Fn() + Sync),
) -> Segment {
    let v = line.belt_speed();
    let mut tracks: Vec<Track> = arrivals
        .iter()
        .map(|a| Track {
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
    if let Some(view) = view.as_mut() {
        view.trace.parcels = arrivals
            .iter()
            .take(view.parcels)
            .map(|a| ParcelPath::new(a.draw.index, &rect_of(a)))
            .collect();
    }
    let mut cycles_run = Vec::with_capacity(line.diverters.len());
    let mut busy_run = Vec::with_capacity(line.diverters.len());
    // The segment's window at the first pivot (Segment::duration's sum, in the same order).
    let duration: f64 = arrivals.iter().map(|a| a.headway).sum();
    let mut simulations = 0;
    let mut loads = SegmentLoads::default();
    for (d, div) in line.diverters.iter().enumerate() {
        let present: Vec<usize> = (0..tracks.len())
            .filter(|&k| tracks[k].came.is_some())
            .collect();
        // Made as the controller takes them, not kept: an approach is a whole draw.
        let approaches = present.iter().map(|&k| {
            let (a, came) = (&arrivals[k], tracks[k].came.expect("present"));
            let mut draw = a.draw;
            (draw.offset, draw.angle) = (came.offset, came.angle);
            Approach {
                draw,
                front_time: came.front_time,
                bound: a.destination == Some(d),
            }
        });
        let (cycles, decisions) = controller::plan_each(div, line.busy, approaches);
        cycles_run.push(cycles.len() as u32);
        busy_run.push(in_window(
            &cycles,
            div.setting.machine.cycle_time,
            div.position / v,
            duration,
        ));
        let profile = StrokeProfile::of(&div.setting);
        let free = profile
            .as_ref()
            .map_or(0.0, |p| p.loads(0.0, &[], &[]).peak_torque);
        // None until a parcel loads the stroke: a loaded stroke's peak is its runs', which
        // may lie below the free stroke's (a parcel that brakes a decelerating arm).
        let mut peaks: Vec<Option<f64>> = vec![None; cycles.len()];
        if let Some(view) = view.as_mut() {
            view.trace.cycles.push(cycles.clone());
        }
        // A parcel whose neighbour comes within a cycle and a second of it keeps its
        // trajectory: the neighbour check will want it (a run is the same either way).
        let near_time = div.setting.machine.cycle_time + NEAR_SLACK;
        let fronts: Vec<f64> = present
            .iter()
            .map(|&k| tracks[k].came.expect("present").front_time)
            .collect();
        let near = |i: usize| {
            let close = |j: usize| (fronts[j] - fronts[i]).abs() < near_time;
            (i > 0 && close(i - 1)) || (i + 1 < fronts.len() && close(i + 1))
        };
        // The visit before this one, until it has been checked against this one, and
        // whether it already collided with the one before it (a parcel collides once).
        let mut previous: Option<(Visit, bool)> = None;
        for (i, (&k, &decision)) in present.iter().zip(&decisions).enumerate() {
            stop_point();
            let a = &arrivals[k];
            let t = &mut tracks[k];
            let came = t.came.expect("present");
            let in_view = view.as_ref().is_some_and(|w| k < w.parcels);
            let recording = match near(i) || in_view {
                true => Recording::Full,
                false => Recording::VerdictOnly,
            };
            let run = pass(line, d, &cycles, decision, a, (came, recording));
            let bound = a.destination == Some(d);
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
                        t.struck_run = Some(Box::new((d as u8, r.inputs.clone())));
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
                            // Knocked off the near side on the way, or jammed there.
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
            // What it hands on (a collision found below takes it off the line).
            t.came = match &run {
                None => Some(came),
                Some(r) => r.after,
            };
            if let Some(path) = view.as_mut().and_then(|w| w.path(k)) {
                if d == 0 {
                    // Coming in: 3 m up the belt.
                    let entry = came.front_time - 3.0 / v;
                    path.ride(&came, &rect_of(a), v, div.position, entry);
                }
                match &run {
                    Some(r) => {
                        path.ride(&came, &rect_of(a), v, div.position, r.origin);
                        path.run(r, div.position);
                    }
                    None => path.ride(&came, &rect_of(a), v, div.position, came.front_time),
                }
            }
            let visit = Visit {
                track: k,
                rect: rect_of(a),
                came,
                run,
            };
            let mut collided = false;
            if let Some((before, taken)) = previous.take() {
                if !taken {
                    let (hit, reruns) = neighbours::check_pair(line, d, &before, &visit);
                    simulations += reruns;
                    if let Some(hit) = hit {
                        for (x, other) in [(&before, &visit), (&visit, &before)] {
                            let t = &mut tracks[x.track];
                            t.decide(LineOutcome::Collision, d, x.run.as_ref());
                            t.collision = Some(Box::new(Collision {
                                other: arrivals[other.track].draw.index,
                                ..hit.at
                            }));
                            t.came = None;
                            if let Some(path) = view.as_mut().and_then(|w| w.path(x.track)) {
                                path.gone = Some(hit.at.time);
                            }
                        }
                        collided = true;
                    }
                }
            }
            previous = Some((visit, collided));
        }
        loads
            .stroke_peaks
            .push(peaks.into_iter().map(|p| p.unwrap_or(free)).collect());
        if let Some(next) = line.diverters.get(d + 1) {
            let shift = next.position - div.position;
            for t in &mut tracks {
                t.came = t.came.map(|c| c.shifted(shift, v));
            }
        }
    }
    if let (Some(view), Some(last)) = (view.as_mut(), line.diverters.last()) {
        // Riding on past the last diverter, out of its reach.
        let reach = last.setting.machine.arm_length + 1.0;
        for ((t, a), path) in tracks
            .iter()
            .zip(arrivals)
            .zip(view.trace.parcels.iter_mut())
        {
            if let Some(c) = &t.came {
                path.ride(c, &rect_of(a), v, last.position, c.front_time + reach / v);
            }
        }
    }
    let parcels = tracks
        .into_iter()
        .zip(arrivals)
        .map(|(t, a)| {
            let (outcome, decided_at, run) = match t.outcome {
                Some(o) => (o, t.decided_at, t.run),
                // At the line's end: struck on the way (its last strike decides), or passed.
                None => match t.struck_run {
                    Some(b) => {
                        let (d, run) = *b;
                        (LineOutcome::StruckInPassing, Some(d), Some(Box::new(run)))
                    }
                    None => (LineOutcome::Passed, None, None),
                },
            };
            LineParcel {
                outcome,
                decided_at,
                struck: t.struck,
                overload_ratio: t.overload_ratio,
                max_impulse: t.max_impulse,
                collision: t.collision.map(|c| *c),
                run,
                ..LineParcel::of_arrival(a)
            }
        })
        .collect();
    Segment {
        parcels,
        cycles: cycles_run,
        busy: busy_run,
        simulations,
        loads,
    }
}

/// The time cycles of length `t_c` starting at `starts` spend in the window [lo, lo +
/// length) \[s]: at most its length, the cycles not overlapping.
pub fn in_window(starts: &[f64], t_c: f64, lo: f64, length: f64) -> f64 {
    let hi = lo + length;
    starts
        .iter()
        .map(|&s| ((s + t_c).min(hi) - s.max(lo)).max(0.0))
        .sum::<f64>()
        .min(length)
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
    // The run's cycles are the diverter's, as `pass` computed them: a stretch of them (the
    // cycles are in order), found by bisection so that a run costs no more in a long segment.
    let rels = r.inputs.run.cycle_starts.as_deref().unwrap_or_default();
    let (Some(&lo), Some(&hi)) = (rels.first(), rels.last()) else {
        return;
    };
    let from = cycles.partition_point(|&s| s - r.origin < lo);
    let to = cycles.partition_point(|&s| s - r.origin <= hi);
    for (j, &start) in cycles.iter().enumerate().take(to).skip(from) {
        let rel = start - r.origin;
        if !rels.contains(&rel) {
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
