//! When the arm starts: the trigger policy of a machine, part of the scenario so that no
//! entry point runs a parcel at a start the machine would not choose.
//!
//! - [`Trigger::Fixed`]: the arm starts when the parcel's front reaches R_s
//!   (`Machine::start_position`), whatever the parcel (the paper's trigger).
//! - [`Trigger::Adaptive`]: a controller that sees each parcel (a dimensioner) starts the arm
//!   at that parcel's own best R_s, found by the search of
//!   [`crate::analysis::population::adaptive_trigger::best_start`]. Such a scenario is
//!   resolved ([`crate::analysis::population::adaptive_trigger::resolve`]) into a fixed one
//!   before it is simulated; `sim::simulate` reports an unresolved one as a failed run rather
//!   than running it at the file's R_s.

/// Safety margins (issue 10): the overload ratio must stay ≤ 1 − `overload`, the divert
/// reserve d ≥ `divert` \[m], and (issue 26) a stroke's peak drive torque at most
/// `drive_torque` \[N·m].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Margins {
    /// Subtracted from the allowed S/S_fall = 1 [-]
    pub overload: f64,
    /// Required divert reserve d \[m]
    pub divert: f64,
    /// T_max: the largest allowed peak drive torque at the arm, max |M_d| over a stroke
    /// (`crate::sim::arm_loads`) \[N·m]; `None`: no limit (and no torque computed).
    pub drive_torque: Option<f64>,
}

/// The R_s search of one parcel (its methods: `analysis::population::adaptive_trigger`).
#[derive(Debug, Clone, PartialEq)]
pub struct StartSearch {
    /// R_s interval scanned \[m]
    pub range: (f64, f64),
    /// Scan step \[m], > 0
    pub step: f64,
    /// Bisection tolerance on the interval ends \[m], ≥ `adaptive_trigger::MIN_TOLERANCE`
    pub tolerance: f64,
    /// Required reserve and overload margin.
    pub margins: Margins,
}

impl Default for StartSearch {
    /// −0.5…1.5 m every 25 mm, ends to 2 mm, no margins.
    fn default() -> Self {
        StartSearch {
            range: (-0.5, 1.5),
            step: 0.025,
            tolerance: 0.002,
            margins: Margins::default(),
        }
    }
}

/// The trigger policy of a machine (module notes).
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Trigger {
    /// The arm starts at R_s for every parcel.
    #[default]
    Fixed,
    /// The arm starts at each parcel's own best R_s (never before S_d), by this search.
    Adaptive(StartSearch),
}
