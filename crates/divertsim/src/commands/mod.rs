//! The analysis subcommands (one file each) and what they share ([`common`]).

pub mod analysis;
pub mod calibrate;
pub mod capacity;
pub mod capture;
pub mod check;
pub mod common;
pub mod compare;
pub mod docs;
pub mod line;
pub mod optimize;
pub mod overload;
pub mod paths;
pub mod reliability;
pub mod replicate;
pub mod studio;
pub mod track;
pub mod trigger;
pub mod worst_case;
