//! Collects the trajectory, events and stage sequence of one run.

use super::result::{ContactCheck, Event, EventKind, Impact, Sample, Stage, State, TipRecord};
use crate::integrate::DenseStep;

/// Largest spacing of trajectory samples inside one integrator step \[s]; long steps get
/// interpolated points from the dense output so plots and CSVs are smooth.
pub const MAX_SAMPLE_SPACING: f64 = 0.005;

pub(crate) struct Recorder {
    pub samples: Vec<Sample>,
    pub events: Vec<Event>,
    pub stages: Vec<Stage>,
    pub max_lateral: f64,
    /// Smallest and largest x of the centre so far.
    pub along: (f64, f64),
    pub impacts: Vec<Impact>,
    pub contact_check: ContactCheck,
    pub tipping: TipRecord,
    pub arm_torque: Vec<(f64, f64)>,
    pub arm_strikes: Vec<(f64, f64)>,
    /// The last state recorded (kept also when samples are not).
    pub last: Option<State>,
    /// Whether trajectory samples are stored ([`Recording::Full`]).
    keep_samples: bool,
}

/// What a run records besides its verdict, strikes, events and stages.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Recording {
    /// The dense trajectory: every sample with its arm angle and contact points.
    #[default]
    Full,
    /// No trajectory (batch work: sweeps, searches, Monte Carlo). The largest lateral
    /// position is still taken over the same sample instants, so every figure of the
    /// result is bitwise the one of a full run.
    VerdictOnly,
}

pub(crate) fn state_of(t: f64, y: &[f64; 6]) -> State {
    State {
        t,
        x: y[0],
        y: y[1],
        phi: y[2],
        vx: y[3],
        vy: y[4],
        omega: y[5],
    }
}

impl Recorder {
    pub fn new(recording: Recording) -> Self {
        let keep_samples = recording == Recording::Full;
        Recorder {
            samples: Vec::with_capacity(if keep_samples { 512 } else { 0 }),
            events: Vec::new(),
            stages: Vec::new(),
            max_lateral: f64::NEG_INFINITY,
            along: (f64::INFINITY, f64::NEG_INFINITY),
            impacts: Vec::new(),
            contact_check: ContactCheck::default(),
            tipping: TipRecord::default(),
            arm_torque: Vec::new(),
            arm_strikes: Vec::new(),
            last: None,
            keep_samples,
        }
    }

    /// Enter a stage (consecutive repeats merged).
    pub fn enter(&mut self, stage: Stage) {
        if self.stages.last() != Some(&stage) {
            self.stages.push(stage);
        }
    }

    pub fn event(&mut self, t: f64, kind: EventKind) {
        self.events.push(Event { t, kind });
    }

    pub fn sample(&mut self, t: f64, y: &[f64; 6], arm_angle: f64, stage: Stage) {
        self.sample_with(t, y, arm_angle, stage, [None, None]);
    }

    pub fn sample_with(
        &mut self,
        t: f64,
        y: &[f64; 6],
        arm_angle: f64,
        stage: Stage,
        contacts: [Option<[f64; 2]>; 2],
    ) {
        self.extremes(y);
        let state = state_of(t, y);
        self.last = Some(state);
        if self.keep_samples {
            self.samples.push(Sample {
                state,
                arm_angle,
                stage,
                contacts,
            });
        }
    }

    /// Take a sample's y and x into the extremes.
    fn extremes(&mut self, y: &[f64; 6]) {
        self.max_lateral = self.max_lateral.max(y[1]);
        self.along = (self.along.0.min(y[0]), self.along.1.max(y[0]));
    }

    /// Whether trajectory samples are stored.
    pub fn keeps_samples(&self) -> bool {
        self.keep_samples
    }

    /// Interior points (spacing ≤ MAX_SAMPLE_SPACING) and the end point of a step.
    pub fn step(
        &mut self,
        step: &DenseStep<6>,
        stage: Stage,
        arm_angle: impl Fn(f64) -> f64,
        contacts: impl Fn(f64, &[f64; 6]) -> [Option<[f64; 2]>; 2],
    ) {
        let h = step.t1 - step.t0;
        let pieces = (h / MAX_SAMPLE_SPACING).ceil().max(1.0) as usize;
        for k in 1..pieces {
            let t = step.t0 + h * k as f64 / pieces as f64;
            let y = step.eval(t);
            if self.keep_samples {
                self.sample_with(t, &y, arm_angle(t), stage, contacts(t, &y));
            } else {
                self.extremes(&y);
            }
        }
        if !self.keep_samples {
            self.extremes(&step.y1);
            self.last = Some(state_of(step.t1, &step.y1));
            return;
        }
        self.sample_with(
            step.t1,
            &step.y1,
            arm_angle(step.t1),
            stage,
            contacts(step.t1, &step.y1),
        );
    }
}
