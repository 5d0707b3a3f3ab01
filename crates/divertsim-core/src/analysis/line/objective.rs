//! The sorter line as an optimisation problem, in SI (docs/model.md §12): the first machine's
//! settings x = (v, t_c, R_s, S_d) that maximise the parcels per hour the line correctly
//! diverts, the missort and overload rates within their limits and the light barrier
//! upstream of the arm start (the paper's barrier order):
//! - f = −throughput/1000 (thousands of parcels per hour, minimised);
//! - g = (missort rate − limit, overload rate − limit, S_d − R_s \[m]).
//!
//! Each evaluation makes the line at x from the line as given ([`Line::with_first_machine`]:
//! every diverter that does not state a value takes the first machine's), refuses a setting
//! the line cannot run ([`Line::refusal`]) as never feasible (NaN values), builds the adaptive
//! trigger tables for that setting, and runs the same N parcels ([`LineSegments`], rates
//! only). Parcel i depends on (seed, i) only and its gap is in metres, so a setting changes
//! what happens to the parcels, never which parcels come: common random numbers.
//!
//! It lives with the line rather than beside the settings problem in `analysis/design/`:
//! the line's folder already uses the population's, which uses the design's, and the
//! folders import in that one direction.

use super::inherit::LineRefusal;
use super::study::{LineRun, LineSegments};
use super::tally::LineTally;
use super::Line;
use crate::analysis::population::mix::MixError;
use crate::analysis::population::reliability::CONFIDENCE;
use crate::optimize::{Bounds, Evaluation, Problem};
use crate::run::study::{execute, Control, StudyError, Unkept};
use crate::run::sweep::{no_progress, Progress};

/// The names of the constraints, in order.
pub const CONSTRAINTS: [&str; 3] = ["missort", "overload", "barrier"];

/// The line problem (module notes).
#[derive(Debug, Clone)]
pub struct LineProblem {
    /// The line as given: its first machine's values are replaced by x at each evaluation.
    pub line: Line,
    pub bounds: Bounds,
    /// N: parcels of every evaluation.
    pub parcels: u64,
    /// The stream's seed.
    pub seed: u64,
    /// Parcels per segment of a run.
    pub segment: u64,
    /// Largest missort rate allowed.
    pub max_missort: f64,
    /// Largest overload rate allowed.
    pub max_overload: f64,
}

/// Why a setting could not be measured.
#[derive(Debug, Clone, PartialEq)]
pub enum LineFault {
    /// The line cannot run at it.
    Refused(LineRefusal),
    /// A trigger table's grid could not be drawn from the mix.
    Table(MixError),
    /// The stream failed or was stopped.
    Run(StudyError<MixError>),
}

impl std::fmt::Display for LineFault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LineFault::Refused(r) => write!(f, "the line cannot run at this setting: {r}"),
            LineFault::Table(e) => write!(f, "a trigger table: {e}"),
            LineFault::Run(StudyError::Piece(e)) => write!(f, "the stream: {e}"),
            LineFault::Run(StudyError::Store(e)) => write!(f, "the stream's store: {e}"),
            LineFault::Run(StudyError::Stopped) => write!(f, "stopped"),
        }
    }
}

/// The line measured at one setting.
#[derive(Debug, Clone)]
pub struct LineMeasure {
    /// The line at the setting, its triggers built.
    pub line: Line,
    pub tally: LineTally,
}

impl LineProblem {
    /// The line's own setting: its first diverter's v, t_c, R_s, S_d.
    pub fn given_x(&self) -> Vec<f64> {
        let m = &self.line.diverters[0].setting.machine;
        vec![
            m.belt_speed,
            m.cycle_time,
            m.start_position,
            m.light_barrier,
        ]
    }

    /// The line at `x` (triggers not built), or why it cannot run there. S_d is put no
    /// further downstream than R_s; the barrier constraint reports the difference.
    pub fn line_at(&self, x: &[f64]) -> Result<Line, LineRefusal> {
        let mut first = self.line.diverters[0].setting.machine.clone();
        first.belt_speed = x[0];
        first.cycle_time = x[1];
        first.start_position = x[2];
        first.light_barrier = x[3].min(x[2]);
        let line = self.line.with_first_machine(first);
        match line.refusal() {
            Some(r) => Err(r),
            None => Ok(line),
        }
    }

    /// The line at `x`, its N parcels run (its adaptive triggers built first);
    /// `stop_point` is called after each segment (a caller's stop ends it there).
    pub fn measure(&self, x: &[f64], stop_point: Progress<'_>) -> Result<LineMeasure, LineFault> {
        let mut line = self.line_at(x).map_err(LineFault::Refused)?;
        line.build_triggers(self.seed, &no_progress)
            .map_err(LineFault::Table)?;
        // The rates alone: no parcel log, no parcel kept.
        let study = LineSegments {
            tally_only: true,
            ..LineSegments::new(&line, self.seed, self.parcels, self.segment)
        };
        let mut quiet = |_: &LineRun| {};
        let run = execute(
            &study,
            LineRun::new(line.diverters.len(), self.seed),
            &Unkept,
            &mut Control {
                stop: &|| false,
                piece_done: stop_point,
                inside: stop_point,
                batch_done: &mut quiet,
            },
        )
        .map_err(LineFault::Run)?;
        Ok(LineMeasure {
            tally: run.tally.tally,
            line,
        })
    }

    /// The evaluation of `x` from its measure.
    pub fn evaluation_of(&self, x: &[f64], tally: &LineTally) -> Evaluation {
        Evaluation {
            objectives: vec![-tally.line_throughput() / 1000.0],
            constraints: vec![
                tally.missort_rate(CONFIDENCE).estimate - self.max_missort,
                tally.overload_rate(CONFIDENCE).estimate - self.max_overload,
                x[3] - x[2],
            ],
        }
    }

    /// The evaluation of `x`, `stop_point` called after each segment; a setting the line
    /// cannot run, or a run that fails, is never feasible (NaN values).
    pub fn evaluate_stoppable(&self, x: &[f64], stop_point: Progress<'_>) -> Evaluation {
        match self.measure(x, stop_point) {
            Ok(m) => self.evaluation_of(x, &m.tally),
            Err(_) => Evaluation {
                objectives: vec![f64::NAN],
                constraints: vec![f64::NAN; CONSTRAINTS.len()],
            },
        }
    }
}

impl Problem for LineProblem {
    fn bounds(&self) -> &Bounds {
        &self.bounds
    }
    fn constraint_count(&self) -> usize {
        CONSTRAINTS.len()
    }
    fn evaluate(&self, x: &[f64]) -> Evaluation {
        self.evaluate_stoppable(x, &no_progress)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::line::tests::{diverter, line};

    /// The paper machine and a second 3 m on stating its own R_s = 0.3 m, 40 parcels.
    fn problem() -> LineProblem {
        let mut second = diverter(3.0, 0.5);
        second.changes.start_position = Some(0.3);
        second.setting.machine.start_position = 0.3;
        LineProblem {
            line: line(vec![diverter(0.0, 0.5), second], 1.0),
            bounds: Bounds::new(vec![0.5, 0.5, -1.0, -1.0], vec![3.0, 2.0, 1.0, 1.0]).unwrap(),
            parcels: 40,
            seed: 7,
            segment: 10,
            max_missort: 0.01,
            max_overload: 0.01,
        }
    }

    /// The evaluation is the line's figures at the setting; S_d past R_s runs at R_s and the
    /// barrier constraint reports it; a setting the line cannot run is never feasible.
    #[test]
    fn the_line_objective_is_the_lines_figures_and_refuses_what_cannot_run() {
        let p = problem();
        let x = p.given_x();
        let m = p.measure(&x, &no_progress).unwrap();
        assert_eq!(m.tally.parcels, 40);
        let e = p.evaluate(&x);
        assert_eq!(e.objectives, vec![-m.tally.line_throughput() / 1000.0]);
        assert_eq!(
            e.constraints[0],
            m.tally.missort_rate(CONFIDENCE).estimate - 0.01
        );
        let past = [x[0], x[1], x[2], x[2] + 0.1];
        assert_eq!(
            p.line_at(&past).unwrap().diverters[0]
                .setting
                .machine
                .light_barrier,
            x[2]
        );
        assert!((p.evaluate(&past).constraints[2] - 0.1).abs() < 1e-15);
        // The second diverter's R_s = 0.3 m lies upstream of the first's new S_d = 0.35 m.
        let refused = [x[0], x[1], 0.5, 0.35];
        assert_eq!(
            p.measure(&refused, &no_progress).unwrap_err(),
            LineFault::Refused(LineRefusal::BarrierDownstream { diverter: 1 })
        );
        let e = p.evaluate(&refused);
        assert!(e.objectives[0].is_nan() && e.constraints.iter().all(|g| g.is_nan()));
        assert!(!e.feasible());
    }
}
