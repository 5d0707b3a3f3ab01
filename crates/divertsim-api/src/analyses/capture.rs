//! capture (being moved here from the CLI).
