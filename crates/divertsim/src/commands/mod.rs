//! The analysis subcommands (one file each) and what they share ([`common`]).

pub mod capture;
pub mod common;
pub mod paths;
pub mod trigger;
