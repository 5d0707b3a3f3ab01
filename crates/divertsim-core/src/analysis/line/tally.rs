//! The line's tally: outcome counts and rates with Clopper–Pearson intervals, throughput per
//! diverter and for the line, arm utilisation and the overload rate.
//!
//! **Throughput** is what the line delivers: parcels per hour correctly diverted,
//! 3600·(diverted)/T, T the stream's time (the sum of the parcels' headways, so a segment's
//! time is that of its own parcels and segments add up exactly). The **arrival rate** is
//! 3600·N/T. **Utilisation** is the share of T an arm spends in cycles, each segment's
//! cycles clipped to its window as the stream passes the arm (so at most 1).
//! Segments are added in order, so every figure is the same for any thread count.

use super::log::{LoggedSegment, Record};
use super::{Line, LineOutcome, RunInputs, Segment, SegmentLoads};
use crate::stats::binomial::{clopper_pearson, Proportion};
use crate::stats::loads::StrokeLoads;
use std::collections::BTreeMap;

/// One diverter's counts.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DiverterTally {
    /// Parcels bound here.
    pub bound: u64,
    /// Bound here and diverted here.
    pub diverted: u64,
    /// Bound here and skipped: the arm was busy.
    pub busy: u64,
    /// Bound here, served and not diverted.
    pub not_diverted: u64,
    /// Diverted here but bound elsewhere.
    pub wrongly_diverted: u64,
    /// Cycles started.
    pub cycles: u64,
    /// Time in cycles within the stream's window \[s] ([`super::Segment::busy`]).
    pub in_cycles: f64,
    /// Cycles of segments kept without that time (counted as whole cycles).
    pub unclipped: u64,
}

/// Everything counted over a line's segments.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LineTally {
    pub parcels: u64,
    /// T: the stream's time \[s]
    pub time: f64,
    /// Parcels per outcome kind ([`LineOutcome::KINDS`] order).
    pub outcomes: [u64; 8],
    /// not_diverted by physical reason.
    pub reasons: BTreeMap<&'static str, u64>,
    /// Parcels an arm touched in a cycle not started for them (whatever their outcome).
    pub struck: u64,
    /// Parcels struck harder than the free fall from H₀.
    pub overloaded: u64,
    pub diverters: Vec<DiverterTally>,
    pub simulations: u64,
    /// Every arm's strokes (cycles started; bins fixed by the first segment with a load,
    /// [`super::SegmentLoads`]) and the run behind the largest stroke peak.
    pub loads: StrokeLoads<Box<RunInputs>>,
}

impl LineTally {
    pub fn new(diverters: usize) -> LineTally {
        LineTally {
            diverters: vec![DiverterTally::default(); diverters],
            ..LineTally::default()
        }
    }

    pub fn add(&mut self, s: &Segment) {
        self.add_totals(s.duration(), s.simulations, &s.loads, (&s.cycles, &s.busy));
        for p in &s.parcels {
            self.add_parcel(&Record::of(p));
        }
    }

    /// [`LineTally::add`] of a segment as the log keeps it: the same figures, bit for bit.
    pub fn add_logged(&mut self, s: &LoggedSegment) {
        self.add_totals(s.duration, s.simulations, &s.loads, (&s.cycles, &s.busy));
        for r in &s.records {
            self.add_parcel(r);
        }
    }

    /// A segment's time, runs, strokes and cycles (in segment order: the time is a sum of
    /// floats, and the spectra's bins are fixed by the first segment with a load).
    fn add_totals(
        &mut self,
        duration: f64,
        simulations: u64,
        loads: &SegmentLoads,
        (cycles, busy): (&[u32], &[f64]),
    ) {
        self.time += duration;
        self.simulations += simulations;
        self.loads.count(
            loads.stroke_peaks.iter().flatten().copied(),
            loads.strike_impulses.iter().copied(),
        );
        if let Some((peak, run)) = &loads.largest {
            self.loads.offer(*peak, || run.clone());
        }
        for (k, (d, c)) in self.diverters.iter_mut().zip(cycles).enumerate() {
            d.cycles += u64::from(*c);
            match busy.get(k) {
                Some(b) => d.in_cycles += b,
                None => d.unclipped += u64::from(*c),
            }
        }
    }

    /// One parcel's outcome.
    fn add_parcel(&mut self, p: &Record) {
        self.parcels += 1;
        self.outcomes[p.outcome.kind()] += 1;
        if let Some(r) = p.outcome.reason() {
            *self.reasons.entry(r).or_default() += 1;
        }
        self.struck += u64::from(p.struck > 0);
        self.overloaded += u64::from(p.overloaded());
        if let Some(dt) = p
            .destination
            .and_then(|d| self.diverters.get_mut(usize::from(d)))
        {
            dt.bound += 1;
            match p.outcome {
                LineOutcome::Diverted => dt.diverted += 1,
                LineOutcome::ArmBusy => dt.busy += 1,
                LineOutcome::NotDiverted(_) => dt.not_diverted += 1,
                _ => {}
            }
        }
        if p.outcome == LineOutcome::WronglyDiverted {
            if let Some(dt) = p
                .decided_at
                .and_then(|d| self.diverters.get_mut(usize::from(d)))
            {
                dt.wrongly_diverted += 1;
            }
        }
    }

    /// Parcels with outcome `kind` (a [`LineOutcome::KINDS`] label).
    pub fn count(&self, kind: &str) -> u64 {
        LineOutcome::KINDS
            .iter()
            .position(|k| *k == kind)
            .map_or(0, |i| self.outcomes[i])
    }

    /// The rate of outcome `kind` among all parcels, with its interval.
    pub fn rate(&self, kind: &str, confidence: f64) -> Proportion {
        clopper_pearson(self.count(kind), self.parcels, confidence)
    }

    /// Parcels correctly sorted (diverted into their chute, or passed untouched to the end).
    pub fn correct(&self) -> u64 {
        self.count("diverted") + self.count("passed")
    }

    /// The share of parcels not where they were bound, with its interval.
    pub fn missort_rate(&self, confidence: f64) -> Proportion {
        clopper_pearson(self.parcels - self.correct(), self.parcels, confidence)
    }

    pub fn struck_rate(&self, confidence: f64) -> Proportion {
        clopper_pearson(self.struck, self.parcels, confidence)
    }

    pub fn overload_rate(&self, confidence: f64) -> Proportion {
        clopper_pearson(self.overloaded, self.parcels, confidence)
    }

    /// Among parcels bound for diverter d, the share diverted there.
    pub fn divert_rate(&self, d: usize, confidence: f64) -> Proportion {
        let t = &self.diverters[d];
        clopper_pearson(t.diverted, t.bound, confidence)
    }

    /// 3600·N/T: parcels inducted per hour.
    pub fn arrival_rate(&self) -> f64 {
        per_hour(self.parcels, self.time)
    }

    /// Parcels per hour correctly diverted at diverter d.
    pub fn throughput(&self, d: usize) -> f64 {
        per_hour(self.diverters[d].diverted, self.time)
    }

    /// Parcels per hour correctly diverted over the whole line.
    pub fn line_throughput(&self) -> f64 {
        per_hour(self.count("diverted"), self.time)
    }

    /// The share of T that diverter d's arm spends in cycles, the cycles clipped to the
    /// stream's window as it passes the arm (at most 1).
    pub fn utilisation(&self, line: &Line, d: usize) -> f64 {
        let t_c = line.diverters[d].setting.machine.cycle_time;
        let c = &self.diverters[d];
        if self.time > 0.0 {
            (c.in_cycles + c.unclipped as f64 * t_c) / self.time
        } else {
            f64::NAN
        }
    }
}

fn per_hour(n: u64, time: f64) -> f64 {
    if time > 0.0 {
        3600.0 * n as f64 / time
    } else {
        f64::NAN
    }
}
