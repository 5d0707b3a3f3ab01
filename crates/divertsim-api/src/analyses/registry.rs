//! The analyses on the contract ([`crate::contract`]), by name: what the Python package,
//! a server or any edge that takes an analysis by name looks up.

use crate::contract::{entry, Entry};

/// The analyses on the contract.
pub const REGISTRY: &[Entry] = &[
    entry::<super::trigger::Trigger>(),
    entry::<super::capture::Capture>(),
    entry::<super::overload::Overload>(),
    entry::<super::worst_case::WorstCaseSearch>(),
    entry::<super::capacity::Capacity>(),
    entry::<super::optimize::Optimize>(),
];

/// The registry's entry of `name`.
pub fn find(name: &str) -> Option<&'static Entry> {
    REGISTRY.iter().find(|e| e.name == name)
}
