//! The induction: when each parcel arrives, where it is bound, and the parcel itself.
//!
//! Parcel i is the mix's sample i ([`crate::analysis::population::mix`]); its gap and its
//! destination take two numbers from the line's own ChaCha8 stream i (seed ⊕ a fixed salt),
//! so the parcels are the same whatever the gap law, the shares or the settings of a sweep
//! (common random numbers), and the same as `reliability`'s samples for that seed.
//!
//! **Gaps.** The clear gap g_i between parcel i's rear and parcel i+1's front along the belt
//! is drawn and raised to the stated minimum (the induction holds a parcel back until the
//! gap is there); parcel i+1's front then passes the first pivot (a_i's extent along the
//! belt + g_i)/v after parcel i's. **Logged arrivals** replay a log's headways in order,
//! repeated when the stream is longer than the log.

use super::Line;
use crate::analysis::population::mix::{open_unit_pair, Draw, MixError};
use crate::geometry::Rect;
use crate::stats::distribution::Distribution;
use std::sync::Arc;

/// How parcels follow each other.
#[derive(Debug, Clone, PartialEq)]
pub enum Induction {
    /// Clear gaps (rear of one parcel to the front of the next, along the belt) drawn from
    /// `gap` \[m] and raised to at least `min` \[m].
    Gaps { gap: Distribution, min: f64 },
    /// A log's arrival times at the first pivot \[s], strictly increasing (at least two):
    /// its headways, replayed in order.
    Times(Arc<[f64]>),
}

impl Induction {
    /// A log's headways and how many times a stream of `parcels` runs through them (`None`
    /// for drawn gaps, or a log long enough): a replay is said, not silent (issue 50).
    pub fn replays(&self, parcels: u64) -> Option<(u64, f64)> {
        match self {
            Induction::Times(times) => {
                let headways = times.len() as u64 - 1;
                (parcels > headways).then(|| (headways, parcels as f64 / headways as f64))
            }
            Induction::Gaps { .. } => None,
        }
    }
}

/// The line's salt: its stream of sample i is independent of the mix's.
const LINE_SALT: u64 = 0x6c69_6e65_2d67_6170;

/// One inducted parcel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Arrival {
    pub draw: Draw,
    /// When its front passes the first pivot, riding (segment time) \[s]
    pub time: f64,
    /// Time to the next parcel's arrival \[s]
    pub headway: f64,
    /// The diverter it is bound for; `None`: straight through.
    pub destination: Option<usize>,
}

/// Its extent along the belt \[m].
pub fn extent_along(d: &Draw) -> f64 {
    let r = Rect {
        length: d.length,
        width: d.width,
    };
    2.0 * r.half_extents(d.angle).x
}

/// The destination for a uniform u: the first diverter whose cumulative share exceeds u.
pub fn destination(shares: impl Iterator<Item = f64>, u: f64) -> Option<usize> {
    let mut sum = 0.0;
    for (d, s) in shares.enumerate() {
        sum += s;
        if u < sum {
            return Some(d);
        }
    }
    None
}

/// The parcels `range` of the stream, the first arriving at t = 0.
pub fn arrivals(
    line: &Line,
    seed: u64,
    range: std::ops::Range<u64>,
) -> Result<Vec<Arrival>, MixError> {
    let mut out = Vec::with_capacity(range.end.saturating_sub(range.start) as usize);
    for a in Arrivals::new(line, seed, range) {
        out.push(a?);
    }
    Ok(out)
}

/// The parcels of a range of the stream one by one, the first arriving at t = 0: what
/// [`arrivals`] collects, bit for bit, without holding them (a parcel log reads its inputs
/// back this way).
#[derive(Debug, Clone)]
pub struct Arrivals<'a> {
    line: &'a Line,
    seed: u64,
    range: std::ops::Range<u64>,
    /// The next parcel's arrival (segment time) \[s]
    time: f64,
}

impl<'a> Arrivals<'a> {
    pub fn new(line: &'a Line, seed: u64, range: std::ops::Range<u64>) -> Arrivals<'a> {
        Arrivals {
            line,
            seed,
            range,
            time: 0.0,
        }
    }
}

impl Iterator for Arrivals<'_> {
    type Item = Result<Arrival, MixError>;

    fn next(&mut self) -> Option<Self::Item> {
        let i = self.range.next()?;
        let line = self.line;
        let draw = match line.mix.draw(&line.diverters[0].setting, self.seed, i) {
            Ok(d) => d,
            Err(e) => return Some(Err(e)),
        };
        let (u_gap, u_dest) = open_unit_pair(self.seed ^ LINE_SALT, i);
        let headway = match &line.induction {
            Induction::Gaps { gap, min } => {
                (extent_along(&draw) + gap.quantile(u_gap).max(*min)) / line.belt_speed()
            }
            Induction::Times(times) => {
                let n = times.len() as u64 - 1;
                let k = (i % n) as usize;
                times[k + 1] - times[k]
            }
        };
        let time = self.time;
        self.time += headway;
        Some(Ok(Arrival {
            draw,
            time,
            headway,
            destination: destination(line.diverters.iter().map(|d| d.share), u_dest),
        }))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        self.range.size_hint()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn destinations_follow_the_cumulative_shares() {
        let shares = [0.5, 0.3];
        assert_eq!(destination(shares.into_iter(), 0.1), Some(0));
        assert_eq!(destination(shares.into_iter(), 0.5), Some(1));
        assert_eq!(destination(shares.into_iter(), 0.79), Some(1));
        assert_eq!(destination(shares.into_iter(), 0.8), None);
        assert_eq!(destination([1.0].into_iter(), 0.999_999), Some(0));
    }
}
