//! A line point's stream as a study ([`crate::run::study`]): segment k is the parcels
//! k·size .. (k + 1)·size, each segment run with an empty belt and every arm at rest
//! ([`super::run_segment_stoppable`]), batches of segments in parallel, each reduced on its
//! worker to the parcel log's part and the few parcels kept whole, folded in stream order
//! into a [`LineRun`].
//!
//! The line analysis (its segments kept in a memo for `--resume`) and the line objective of
//! the optimiser (a measure per setting) both run this study.

use super::log::{LoggedSegment, ParcelLog};
use super::tally::LineTally;
use super::{run_segment_stoppable, Line, LineParcel, Segment};
use crate::analysis::population::mix::MixError;
use crate::run::study::Study;
use crate::run::sweep::Progress;

/// Parcels at the head of the stream a result keeps whole (the animated view's and more).
pub const KEPT_FIRST: u64 = 1_000;

/// Failures of each outcome a result keeps whole beyond [`KEPT_FIRST`], the first in stream
/// order (the edges show the first few of each kind and link to their runs).
pub const KEPT_FAILURES: u64 = 32;

/// A line point's stream, in segments.
pub struct LineSegments<'a> {
    pub line: &'a Line,
    /// The stream's seed: parcel i depends on (seed, i) only.
    pub seed: u64,
    /// Parcels in the stream.
    pub parcels: u64,
    /// Parcels per segment (the last segment is cut at `parcels`).
    pub size: u64,
    /// Segments run side by side between two folds.
    pub batch: u64,
    /// Only the tally: no parcel log and no parcel kept whole (a measure that needs the
    /// rates alone, the line objective's, holds nothing per parcel).
    pub tally_only: bool,
}

impl<'a> LineSegments<'a> {
    /// The stream of `parcels` from `seed` on `line`, in segments of `size`, four segments
    /// per worker thread in a batch (enough to keep every worker busy while a batch ends).
    pub fn new(line: &'a Line, seed: u64, parcels: u64, size: u64) -> LineSegments<'a> {
        LineSegments {
            line,
            seed,
            parcels,
            size,
            batch: (rayon::current_num_threads() as u64 * 4).max(1),
            tally_only: false,
        }
    }

    /// The parcels of segment `k`.
    pub fn range(&self, k: u64) -> std::ops::Range<u64> {
        let size = self.size.max(1);
        (k * size).min(self.parcels)..((k + 1) * size).min(self.parcels)
    }
}

/// A point's stream run so far: its tally, every parcel's log, and the parcels kept whole.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LineRun {
    pub tally: LineTally,
    /// Every parcel, in stream order, compact.
    pub log: ParcelLog,
    /// The first [`KEPT_FIRST`] parcels of the stream and the first [`KEPT_FAILURES`]
    /// failures of each outcome, whole, in stream order.
    pub kept: Vec<LineParcel>,
    /// Failures of each outcome met so far (exact while below [`KEPT_FAILURES`]: a
    /// segment's candidates hold all of its failures of a kind up to that many).
    failures: [u64; 8],
}

impl LineRun {
    /// Nothing run yet, on a line of `diverters` diverters and the stream of `seed`.
    pub fn new(diverters: usize, seed: u64) -> LineRun {
        LineRun {
            tally: LineTally::new(diverters),
            log: ParcelLog::new(seed),
            ..LineRun::default()
        }
    }

    /// Keep those of a segment's candidates that are among the first of the stream.
    fn take(&mut self, candidates: Vec<LineParcel>) {
        for p in candidates {
            if first_failure(&mut self.failures, &p) || p.index < KEPT_FIRST {
                self.kept.push(p);
            }
        }
    }
}

/// Whether `p` is a failure among the first [`KEPT_FAILURES`] of its outcome in `seen`
/// (and counts it).
fn first_failure(seen: &mut [u64; 8], p: &LineParcel) -> bool {
    !p.outcome.correct() && {
        let n = &mut seen[p.outcome.kind()];
        *n += 1;
        *n <= KEPT_FAILURES
    }
}

/// The parcels of a segment that may be kept whole: those of the stream's head, and the
/// first [`KEPT_FAILURES`] failures of each outcome in it (the run keeps those of them that
/// are among the first of the stream, [`LineRun::take`]).
fn candidates(s: &Segment) -> Vec<LineParcel> {
    let mut seen = [0u64; 8];
    s.parcels
        .iter()
        .filter(|p| first_failure(&mut seen, p) || p.index < KEPT_FIRST)
        .cloned()
        .collect()
}

impl Study for LineSegments<'_> {
    type Piece = Segment;
    type Part = (LoggedSegment, Vec<LineParcel>);
    type Tally = LineRun;
    type Error = MixError;

    fn pieces(&self) -> u64 {
        self.parcels.div_ceil(self.size.max(1))
    }
    fn batch(&self) -> u64 {
        self.batch
    }
    fn run_piece(&self, k: u64, stop_point: Progress<'_>) -> Result<Segment, MixError> {
        run_segment_stoppable(self.line, self.seed, self.range(k), stop_point)
    }
    /// A segment reduced at once to its log: a batch in flight holds no parcel whole but
    /// the few kept ones.
    fn part(&self, _: u64, s: Segment) -> (LoggedSegment, Vec<LineParcel>) {
        let whole = match self.tally_only {
            true => Vec::new(),
            false => candidates(&s),
        };
        (LoggedSegment::from(s), whole)
    }
    fn fold(&self, run: &mut LineRun, (segment, whole): (LoggedSegment, Vec<LineParcel>)) {
        run.tally.add_logged(&segment);
        if !self.tally_only {
            run.log.push(segment);
            run.take(whole);
        }
    }
}
