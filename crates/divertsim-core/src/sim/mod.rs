//! The hybrid driver: integrates the parcel through its stages, handles events, records the
//! trajectory and returns the verdict.

pub mod result;

pub use result::{Event, EventKind, NotDivertedReason, Outcome, Sample, SimResult, Stage, State};

use crate::model::params::Scenario;

/// Run one scenario to its verdict.
pub fn simulate(scenario: &Scenario) -> SimResult {
    let _ = scenario;
    todo!("sim driver")
}
