//! No code. This crate exists for its dependency list (see Cargo.toml): it gives the
//! main job, the test command and the Python build one feature set for their shared
//! dependencies, so that a newcomer compiles them once (issue 27, B4).
