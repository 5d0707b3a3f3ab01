//! # divertsim-core
//!
//! The pure physics core of divertsim, a simulator of swing-arm ("deflection scraper") parcel
//! diverters. No files, no printing, no global state: every function takes its inputs and
//! returns its outputs.
//!
//! - [`geometry`]: rectangles, rotations, corners.
//! - [`model`]: what the machine and the parcel are, one file per physical law
//!   (arm drive, belt friction, impact map, ...).
//! - [`integrate`]: an adaptive Dormand–Prince 5(4) integrator with dense output and
//!   directional event location; it knows nothing of parcels.
//! - [`sim`]: the hybrid driver (stages, events, trajectory, outcome).
//!
//! Conventions follow docs/model.md §1: frame at the arm pivot, x downstream,
//! y across the belt towards the discharge side, angles counter-clockwise, α = 0 retracted
//! along y = 0. SI units and radians throughout.
//!
//! ```
//! use divertsim_core::{model::params::Scenario, sim::simulate};
//! let result = simulate(&Scenario::paper_default());
//! assert!(result.final_state.t > 0.0);
//! ```

pub mod analysis;
pub mod geometry;
pub mod integrate;
pub mod model;
pub mod optimize;
pub mod run;
pub mod sim;
pub mod stats;

/// g: gravitational acceleration [m/s²] (docs/model.md §1).
pub const GRAVITY: f64 = 9.81;
