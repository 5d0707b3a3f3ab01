//! capacity (being moved here from the CLI).
