//! The analysis subcommands (one file each) and what they share ([`common`]).

pub mod common;
pub mod paths;
