//! The scenario file (TOML): its schema, `--set` overrides, validation and conversion into
//! the core's SI scenario.
//!
//! The keys are a public contract. Every key is optional: a key left out takes the value of
//! the built-in default scenario (the paper's compact parcel at v = 2 m/s, t_c = 1.36 s,
//! R_s = 0). Angles are in degrees and carry `_deg` in their names; everything else is SI.
//! Every problem is reported at once, each naming its key path and the allowed range.

use divertsim_core::analysis::design::design_set::{
    DesignCase, DesignSet, Margins, WorstDefinition,
};
use divertsim_core::analysis::design::worst_case::{Pose, PoseBox};
use divertsim_core::model::belt_friction::{FrictionCoefficient, FrictionModel};
use divertsim_core::model::drive::{ArmDrive, DriveSpec, FourBar};
use divertsim_core::model::impact::ImpactLaw;
use divertsim_core::model::params::{
    Limits, Machine, Materials, NearSide, Parcel, RunSettings, Scenario,
};
use glam::DVec2;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::{Path, PathBuf};

pub mod bounds;
pub mod camera;
pub mod example;
pub mod files;
pub mod line;
pub mod mix;
pub mod values;

mod convert;
mod design;
mod load;
mod problems;
mod schema;
mod validate;
use bounds::Bound;
use camera::CameraConfig;
pub use convert::*;
pub use design::*;
pub use files::LoadOptions;
use files::Origin;
use line::LineConfig;
pub use load::*;
use mix::{AdaptiveConfig, MixConfig, TriggerConfig};
pub use problems::*;
pub use schema::*;
pub use validate::*;

/// Every section's ranges, each declared once beside its key (`#[key(range = …)]`, the
/// derive of crate `divertsim-keys`), in the file's order. Gathered here, in the sections'
/// parent: `bounds` (which every section uses for its `Bound`) names no section.
pub const SECTIONS: &[&[Bound]] = &[
    MachineConfig::BOUNDS,
    DriveConfig::BOUNDS,
    AdaptiveConfig::BOUNDS,
    ParcelConfig::BOUNDS,
    MaterialsConfig::BOUNDS,
    RunConfig::BOUNDS,
    LimitsConfig::BOUNDS,
    DesignParcelConfig::BOUNDS,
    OverloadParcelConfig::BOUNDS,
    SearchBoxConfig::BOUNDS,
    mix::DistConfig::BOUNDS,
    CameraConfig::BOUNDS,
    LineConfig::BOUNDS,
    line::DiverterConfig::BOUNDS,
];

/// Every bound of the scenario file.
pub fn all_bounds() -> impl Iterator<Item = &'static Bound> {
    SECTIONS.iter().flat_map(|s| s.iter())
}

/// The JSON Schema of the scenario file, with the ranges of [`all_bounds`] (so an editor
/// flags `belt_speed = -3` as validation does).
pub fn json_schema() -> serde_json::Value {
    let mut schema = serde_json::to_value(schemars::schema_for!(ScenarioFile)).unwrap_or_default();
    bounds::annotate(&mut schema);
    schema
}
