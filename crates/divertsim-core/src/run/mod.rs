//! Run infrastructure the analyses share, apart from them: parallel order-preserving maps
//! with progress ([`sweep`]) and the memo of finished pieces behind `--resume` ([`memo`]).

pub mod memo;
pub mod sweep;
