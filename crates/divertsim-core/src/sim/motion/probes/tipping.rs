//! The tipping probe: at every accepted state, the lift-off margin of the plane model's loads
//! ([`crate::model::tipping::TipGeometry::loads`]) and the tilt about a footprint edge
//! followed through the stretch ([`crate::model::tilt`]); a strike's impulse starts or
//! changes the tilt. Under [`TippingRule::Verdict`] a box that goes over ends the run.

use super::super::dynamics::Dynamics;
use super::Probe;
use crate::model::active_set;
use crate::model::params::TippingRule;
use crate::model::tilt::{LoadSample, Rocker, Tilt};
use crate::model::tipping::{TipCause, TipEdge, TipGeometry, TipRecord};
use crate::sim::recorder::Recorder;
use glam::DVec2;

/// The tilt and the tipping record of one run.
pub(crate) struct Tipping {
    geo: TipGeometry,
    rule: TippingRule,
    /// The smallest tipping margin since the last drain.
    record: TipRecord,
    /// Went over under [`TippingRule::Verdict`]: the run stops.
    halt: bool,
    /// The tilt about a footprint edge.
    rocker: Rocker,
    /// The tilt loads at the last accepted state of this stretch (none after an event), and
    /// whether the box stood there with no edge lifting.
    last_load: Option<(LoadSample, bool)>,
}

impl Tipping {
    pub fn new(geo: TipGeometry, rule: TippingRule) -> Self {
        Tipping {
            geo,
            rule,
            record: TipRecord::default(),
            halt: false,
            rocker: Rocker::default(),
            last_load: None,
        }
    }

    /// The tilt loads at (t, y): the contacts' forces and the centre's acceleration from the
    /// plane model; none while riding. `None` where the plane model's forces are not finite.
    fn loads(&self, d: &Dynamics, t: f64, y: &[f64; 6]) -> Option<LoadSample> {
        if d.riding {
            return Some(LoadSample::none(t));
        }
        let m = d.ctx.mass;
        let mut forces = [DVec2::ZERO; active_set::MAX_CONTACTS];
        let accel = if d.contacts.is_empty() {
            // Free sliding: the belt alone, m a = F_belt; the step's first derivative is
            // usually the last step's end (first same as last).
            match d.free_derivative_at(t, y) {
                Some(dy) => DVec2::new(dy[3], dy[4]),
                None => {
                    let f = d.belt_wrench(y);
                    DVec2::new(f[0], f[1]) / m
                }
            }
        } else {
            let (a, f) = d.evaluated(t, y, |e| (e.accel, e.forces));
            for (slot, f) in forces.iter_mut().zip(f) {
                *slot = DVec2::new(f[0], f[1]);
            }
            DVec2::new(a[0], a[1])
        };
        if !(accel.is_finite() && forces.iter().all(|f| f.is_finite())) {
            return None;
        }
        Some(LoadSample {
            t,
            loads: self.geo.loads(
                y[2],
                &forces,
                accel,
                DVec2::new(y[3] - d.ctx.belt_speed, y[4]),
            ),
        })
    }

    /// Follow the tilt to `sample` from the last one of this stretch, and keep `sample`.
    fn advance(&mut self, sample: LoadSample) {
        let geo = self.geo;
        // A standing box with no edge lifting at either end stays standing (the loads are
        // linear in between): nothing to follow.
        let still = self.rocker.is_flat()
            && TipEdge::ALL
                .iter()
                .zip(&sample.loads)
                .all(|(e, l)| !Rocker::lifts(&geo, *e, l));
        if let Some((from, from_still)) = self.last_load {
            if !(still && from_still) {
                let max_tilt = self.rocker.advance(&geo, &from, &sample);
                self.record.note_tilt(max_tilt);
                if let Tilt::Over { edge, t } = self.rocker.tilt {
                    let alpha = geo.edge(edge).over_angle;
                    self.record.note_over(t, edge, alpha);
                    if self.rule == TippingRule::Verdict {
                        self.halt = true;
                    }
                }
            }
        }
        self.last_load = Some((sample, still));
    }
}

impl Probe for Tipping {
    #[cfg(test)]
    fn name(&self) -> &'static str {
        "tipping"
    }

    /// The lift-off margin there, and the tilt followed from the last accepted state of this
    /// stretch to this one.
    fn at_step(&mut self, d: &Dynamics, t: f64, y: &[f64; 6]) {
        if d.riding && self.rocker.is_flat() {
            return;
        }
        let Some(sample) = self.loads(d, t, y) else {
            return;
        };
        if !d.riding {
            self.record
                .note(t, self.geo.lift(&sample.loads), TipCause::Forces);
        }
        self.advance(sample);
    }

    /// The state just before an event is checked like a step start, and the next stretch
    /// starts its loads afresh (they jump at the event).
    fn at_stretch_end(&mut self, d: &Dynamics, t: f64, y: &[f64; 6]) {
        self.at_step(d, t, y);
        self.last_load = None;
    }

    /// The stretch's last loads held on to `t`.
    fn at_tail(&mut self, t: f64) {
        if let Some((last, _)) = self.last_load {
            if t > last.t {
                self.advance(LoadSample { t, ..last });
            }
        }
    }

    /// A strike's pivot ([`TipGeometry::strike`]): its margin is kept and its tilt rate
    /// joins the tilt. Whether the box goes over is the tilt's to say, later.
    fn at_strike(&mut self, t: f64, phi: f64, impulse: DVec2) {
        if let Some((tip, pivot)) = self.geo.strike(phi, impulse) {
            self.record.note(t, tip, TipCause::Strike);
            self.rocker.strike(&pivot);
        }
    }

    /// The tilt is followed (0.05 s at a time) until the box stands or goes over.
    fn ride_out(&mut self, t: f64, horizon: f64) -> bool {
        if self.rocker.is_flat() {
            return self.rocker.is_over();
        }
        self.last_load = Some((LoadSample::none(t), false));
        let mut now = t;
        while !self.rocker.is_flat() && !self.rocker.is_over() && now < t + horizon {
            now += 0.05;
            self.advance(LoadSample::none(now));
        }
        self.last_load = None;
        self.rocker.is_over()
    }

    fn halt(&self) -> bool {
        self.halt
    }

    fn drain(&mut self, rec: &mut Recorder) {
        rec.tipping = rec.tipping.merge(std::mem::take(&mut self.record));
    }
}
