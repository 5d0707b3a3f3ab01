//! The parcel log, compact: what a finished run keeps of every parcel.
//!
//! A [`LineParcel`] is about 160 bytes, most of them its inputs (sides, mass, pose, arrival,
//! headway), which are a function of (seed, i) alone ([`super::stream`]). The log keeps per
//! parcel only what its run decided, a [`Record`] of 24 bytes (outcome, where, strikes, the
//! largest strike), the rare collisions beside them, and each segment's first index; reading
//! it draws the inputs again, segment by segment from t = 0 as the segment did, so that
//! [`ParcelLog::parcels`] gives every parcel bit for bit as its segment did (without the
//! deciding run, which the edges keep for the few parcels they show).

use super::stream::Arrivals;
use super::{Collision, Line, LineOutcome, LineParcel, Segment, SegmentLoads};
use crate::analysis::population::mix::MixError;

/// What a parcel's run decided: its [`LineParcel`] without the inputs and the run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Record {
    /// Largest S/S_fall over all its strikes [-]
    pub overload_ratio: f64,
    /// Largest strike impulse S [N·s]
    pub max_impulse: f64,
    pub outcome: LineOutcome,
    pub decided_at: Option<u8>,
    pub destination: Option<u8>,
    pub struck: u8,
}

impl Record {
    pub fn of(p: &LineParcel) -> Record {
        Record {
            overload_ratio: p.overload_ratio,
            max_impulse: p.max_impulse,
            outcome: p.outcome,
            decided_at: p.decided_at,
            destination: p.destination,
            struck: p.struck,
        }
    }

    /// Struck harder than the free fall from H₀ ([`LineParcel::overloaded`]).
    pub fn overloaded(&self) -> bool {
        self.overload_ratio > 1.0
    }
}

/// A finished segment as the log keeps it: its parcels' records and its totals (what
/// [`super::tally::LineTally::add_logged`] counts).
#[derive(Debug, Clone, PartialEq)]
pub struct LoggedSegment {
    /// i of its first parcel.
    pub first: u64,
    pub records: Box<[Record]>,
    /// (position in the segment, collision), in stream order.
    pub collisions: Box<[(u32, Collision)]>,
    /// [`Segment::duration`] \[s]
    pub duration: f64,
    pub cycles: Vec<u32>,
    /// [`Segment::busy`]
    pub busy: Vec<f64>,
    pub simulations: u64,
    pub loads: SegmentLoads,
}

impl From<Segment> for LoggedSegment {
    fn from(s: Segment) -> LoggedSegment {
        let duration = s.duration();
        LoggedSegment {
            first: s.parcels.first().map_or(0, |p| p.index),
            records: s.parcels.iter().map(Record::of).collect(),
            collisions: s
                .parcels
                .iter()
                .enumerate()
                .filter_map(|(j, p)| Some((j as u32, p.collision?)))
                .collect(),
            duration,
            cycles: s.cycles,
            busy: s.busy,
            simulations: s.simulations,
            loads: s.loads,
        }
    }
}

/// One segment's part of the log.
#[derive(Debug, Clone, PartialEq)]
struct Part {
    first: u64,
    records: Box<[Record]>,
    collisions: Box<[(u32, Collision)]>,
}

/// Every parcel of a point's stream, compact: 24 bytes a parcel (and a collision's 56
/// where there is one), its inputs drawn again when read.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ParcelLog {
    seed: u64,
    parts: Vec<Part>,
}

impl ParcelLog {
    /// An empty log of the stream of `seed`.
    pub fn new(seed: u64) -> ParcelLog {
        ParcelLog {
            seed,
            parts: Vec::new(),
        }
    }

    /// Parcels logged.
    pub fn len(&self) -> u64 {
        self.parts.iter().map(|p| p.records.len() as u64).sum()
    }

    pub fn is_empty(&self) -> bool {
        self.parts.iter().all(|p| p.records.is_empty())
    }

    /// Append the next segment of the stream (its totals stay with the caller's tally).
    pub fn push(&mut self, s: LoggedSegment) {
        if s.records.is_empty() {
            return;
        }
        self.parts.push(Part {
            first: s.first,
            records: s.records,
            collisions: s.collisions,
        });
    }

    /// Every parcel, in stream order, as its segment gave it but without its deciding run
    /// (`run` is `None`); the inputs of `line`'s stream drawn again, one at a time.
    pub fn parcels<'a>(
        &'a self,
        line: &'a Line,
    ) -> impl Iterator<Item = Result<LineParcel, MixError>> + 'a {
        self.parts.iter().flat_map(move |part| {
            let end = part.first + part.records.len() as u64;
            let mut collisions = part.collisions.iter().peekable();
            Arrivals::new(line, self.seed, part.first..end)
                .zip(part.records.iter())
                .enumerate()
                .map(move |(j, (a, r))| {
                    let a = a?;
                    let collision = collisions.next_if(|c| c.0 as usize == j).map(|c| c.1);
                    Ok(LineParcel {
                        destination: r.destination,
                        outcome: r.outcome,
                        decided_at: r.decided_at,
                        struck: r.struck,
                        overload_ratio: r.overload_ratio,
                        max_impulse: r.max_impulse,
                        collision,
                        ..LineParcel::of_arrival(&a)
                    })
                })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::tally::LineTally;
    use super::super::{BusyRule, Diverter, Induction};
    use super::*;
    use crate::analysis::population::reliability::StartRule;
    use crate::model::params::Scenario;
    use crate::stats::distribution::Distribution;

    /// Two paper machines 4 m apart, half the parcels for each, gaps tight enough for
    /// collisions.
    fn two_diverter_line() -> Line {
        let diverter = |position| Diverter {
            position,
            setting: Scenario::paper_machine(),
            trigger: StartRule::Fixed,
            share: 0.5,
            changes: Default::default(),
            table: Default::default(),
        };
        Line {
            diverters: vec![diverter(0.0), diverter(4.0)],
            induction: Induction::Gaps {
                gap: Distribution::Normal { mean: 0.3, sd: 0.2 },
                min: 0.0,
            },
            mix: super::super::tests::mix(),
            busy: BusyRule::Skip,
            duration_given: false,
        }
    }

    /// The log gives back every parcel of its segments bit for bit (but the deciding run),
    /// and a tally of logged segments is the tally of the segments.
    #[test]
    fn the_log_reads_back_its_segments_and_tallies_alike() {
        let l = two_diverter_line();
        let segments = super::super::tests::segments(&l, 9, 250, 100);
        let mut log = ParcelLog::new(9);
        let (mut whole, mut logged) = (LineTally::new(2), LineTally::new(2));
        for s in &segments {
            whole.add(s);
            let c = LoggedSegment::from(s.clone());
            logged.add_logged(&c);
            log.push(c);
        }
        assert_eq!(whole, logged);
        assert_eq!(log.len(), 250);
        let back: Vec<LineParcel> = log.parcels(&l).collect::<Result<_, _>>().unwrap();
        let expected: Vec<LineParcel> = segments
            .into_iter()
            .flat_map(|s| s.parcels)
            .map(|p| LineParcel { run: None, ..p })
            .collect();
        assert!(expected.iter().any(|p| p.collision.is_some()));
        assert_eq!(back, expected);
    }
}
