//! Empty: cargo counts build-dependencies (here syn's features) only for a package with a
//! build script.
fn main() {}
