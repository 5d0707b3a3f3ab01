//! A stretch of the stream as it moved: every parcel's pose over time in the line's frame
//! and every arm's cycles, for the animated line view. Riding parcels move in straight lines
//! between keyframes (one per diverter is exact); a run gives its trajectory samples.

use super::passage::{Carried, Motion, Run};
use crate::geometry::Rect;
use serde::{Deserialize, Serialize};

/// One parcel's path.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParcelPath {
    /// i: its index in the stream
    pub index: u64,
    /// a, b \[m]
    pub length: f64,
    pub width: f64,
    /// (segment time \[s], x \[m] along the line, y \[m], φ \[rad]) of the centre, in time
    /// order; linear between keyframes.
    pub keyframes: Vec<[f64; 4]>,
    /// When it left the belt (diverted, off the near side, a collision, a failed run);
    /// `None`: it rode to the line's end.
    pub gone: Option<f64>,
}

/// The stretch: its parcels' paths and each diverter's cycle starts (segment time).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Trace {
    pub parcels: Vec<ParcelPath>,
    pub cycles: Vec<Vec<f64>>,
}

impl ParcelPath {
    /// A path with no keyframe yet.
    pub fn new(index: u64, rect: &Rect) -> ParcelPath {
        ParcelPath {
            index,
            length: rect.length,
            width: rect.width,
            keyframes: Vec::new(),
            gone: None,
        }
    }

    fn push(&mut self, k: [f64; 4]) {
        // Time order (a run starts where the riding keyframe before it ended).
        if self.keyframes.last().is_none_or(|last| k[0] >= last[0]) {
            self.keyframes.push(k);
        }
    }

    /// The pose of a riding parcel at segment time t, at a diverter at `position` \[m].
    pub fn ride(&mut self, c: &Carried, rect: &Rect, v: f64, position: f64, t: f64) {
        if c.motion == Motion::Riding {
            let (centre, phi) = c.riding_pose(rect, v, t);
            self.push([t, position + centre.x, centre.y, phi]);
        }
    }

    /// A run's samples at a diverter at `position` \[m] (its trajectory, when it kept one).
    pub fn run(&mut self, r: &Run, position: f64) {
        for s in &r.result.trajectory {
            let st = s.state;
            self.push([r.origin + st.t, position + st.x, st.y, st.phi]);
        }
        if r.after.is_none() {
            self.gone = Some(r.end);
        }
    }
}
