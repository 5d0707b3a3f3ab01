//! paths (being moved here from the CLI).
