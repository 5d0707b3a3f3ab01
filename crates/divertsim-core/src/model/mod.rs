//! What the machine and the parcel are: parameters and the physical laws, one file per law.
//!
//! - [`params`]: the scenario (machine, parcel, materials, run, limits) in SI units.
//! - [`drive`]: arm motion α(t) — crank-rocker four-bar and cam laws (docs/model.md §2).
//! - [`active_set`]: contact forces for an active set of unilateral contacts, LCP by
//!   enumeration (docs/model.md §6).
//! - [`belt_friction`]: Coulomb friction of a rectangular footprint on the belt (docs/model.md §3).
//! - [`contact`]: contact kinematics of corners, arm face, arm tip and side guide
//!   (docs/model.md §6).
//! - [`impact`]: oblique rough impact with Stronge's energetic restitution (docs/model.md §5).
//! - [`tipping`]: when a tall parcel's edge lifts, and the pivot of a strike (docs/model.md §12a).
//! - [`tilt`]: the tilt about an edge once it lifts: rocking, landing, going over.

pub mod active_set;
pub mod belt_friction;
pub mod contact;
pub mod drive;
pub mod impact;
pub mod pair_contact;
pub mod params;
pub mod tilt;
pub mod tipping;
pub mod trigger;
