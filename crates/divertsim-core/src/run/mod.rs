//! Run infrastructure the analyses share, apart from them: parallel order-preserving maps
//! with progress ([`sweep`]), the memo of finished pieces behind `--resume` ([`memo`]), and the
//! study engine that runs a study's pieces through both ([`study`]).

pub mod memo;
pub mod study;
pub mod sweep;
