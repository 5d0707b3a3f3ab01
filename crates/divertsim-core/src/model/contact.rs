//! Contact kinematics between the parcel and the obstacles (physics.md §5.1, §2.1):
//! a parcel corner on the arm face (either side), a parcel corner on the side guide, and the
//! arm tip on a parcel edge. For each pair: the gap, its rate, the slip, the contact frame,
//! and the acceleration-level constraint rows J q̈ = β (normal) and J_t q̈ = β_t (stick).
//!
//! Filled by the contact-kinematics work.
