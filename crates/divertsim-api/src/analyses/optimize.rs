//! optimize (being moved here from the CLI).
