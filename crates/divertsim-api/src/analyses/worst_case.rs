//! worst_case (being moved here from the CLI).
