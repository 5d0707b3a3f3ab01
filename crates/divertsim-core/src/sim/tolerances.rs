//! The hybrid driver's tolerances, in one place: when a pair counts as closed, struck,
//! separating, at an end or drifting; when the belt slip counts as zero; where the motion's
//! guards fire. Each is stated in the unit of the quantity it bounds, and the relations the
//! event logic relies on are checked at compile time at the bottom (docs/model.md §6, the
//! contact-pair rule, and §7).

// ---- Closed contacts: gaps and extents [m] ----

/// A contact within this gap counts as closed \[m].
pub const GAP_TOL: f64 = 1e-7;

/// Deepest gap still taken as a touching contact (it is struck if approaching) \[m].
pub const DEEPEST_GAP: f64 = -5e-7;

/// Largest gap of a contact held until an event that is still taken as its drift, not as a
/// separation ([`remove_drift`](super::drift::remove_drift)) \[m].
pub const HELD_GAP_TOL: f64 = 1e-5;

/// Drift of a held contact beyond which [`remove_drift`](super::drift::remove_drift) moves the parcel back onto its
/// obstacles \[m]: smaller drifts are left alone, well inside [`GAP_TOL`].
pub const DRIFT_TOL: f64 = 0.25 * GAP_TOL;

/// How far a tip–edge pair's gap may fall short of the nearest edge's and still count as
/// between nearest features \[m] (exact ties: the tip at a corner).
pub const NEAREST_TOL: f64 = 1e-10;

/// How far past its obstacle's end a contact point still counts as on it \[m] (a parcel
/// corner a hair beyond the arm tip is the corner-on-tip contact, not no contact). The
/// range guards fire further out ([`RANGE_MARGIN`]).
pub const RANGE_TOL: f64 = 1e-7;

/// A corner this close to the arm tip takes the face on the parcel's side \[m].
pub const AT_TIP: f64 = 1e-6;

/// How close to an end of its obstacle a contact point counts as at that end
/// ([`leaves_end`](crate::model::contact::leaves_end)) \[m]: where the tip slides off a parcel edge at its corner, that
/// corner crosses the arm's line at the tip, placed by the drift of the tip's contact; on
/// an edge at a small angle to the arm a drift of 3e-9 m put it 1.5e-7 m inside the tip.
pub const END_TOL: f64 = AT_TIP;

/// How far the arm behind its tip may lie inside an edge's half-plane and the tip still touch
/// that edge, t(α)·n ≥ −ARM_EDGE_TOL ([`arm_into_edge`](crate::model::contact::arm_into_edge)): the drift of a side
/// supported along the arm \[rad].
pub const ARM_EDGE_TOL: f64 = 1e-6;

/// Largest widening of a corner's tip tolerance for a held tip–edge drift ((`settle::end_tolerances`))
/// \[m]: beyond it the edge runs along the arm, where the crossing point means nothing.
pub const MAX_END_WIDENING: f64 = 1e-4;

/// Deepest approach of a riding parcel to a receding contact that is closed in closed
/// form (`settle::ride_with_contacts`) \[m].
pub const TAIL_DEPTH: f64 = 0.5 * GAP_TOL;

// ---- Normal and tangential speeds at an event [m/s] ----

/// A closed contact approaching faster than this is struck [m/s].
pub const SPEED_TOL: f64 = 1e-8;

/// Speed along its obstacle above which a contact point at one of the obstacle's ends counts
/// as moving off it [m/s] ([`leaves_end`](crate::model::contact::leaves_end)).
pub const LEAVE_SPEED: f64 = SPEED_TOL;

/// Approach speed below which a contact held until the event is taken as drifting (the
/// integration error of a persistent contact), not struck: the projection takes it up [m/s].
pub const HELD_DRIFT: f64 = 1e-4;

/// Approach speed below which a touch can be a graze (`settle::grazes`) [m/s].
pub const GRAZE_SPEED: f64 = HELD_DRIFT;

/// A closed contact separating slower than this still enters the active-set problem (it may
/// be accelerating back in) [m/s], if it was held until this instant, has just touched, or a
/// strike at this instant set it separating (the seesaw lift of a flush side's far end after
/// a plastic strike at its near end); any other closed contact enters it only if it separates
/// no faster than [`SPEED_TOL`].
pub const CLOSE_SPEED: f64 = 1e-3;

/// Approach speed below which a strike is plastic and the contact persists [m/s].
pub const PERSIST_SPEED: f64 = 0.01;

/// Normal speed a corner needs to count as crossing the arm's line beyond the tip [m/s].
pub const FACE_CROSSING_SPEED: f64 = 1e-6;

// ---- Belt slip [m/s] ----

/// Slip |w| [m/s] at which a free slide is ended in closed form (`Motion::stop_tail`): the
/// time left is about |w|/|ẇ| ≈ 2.5e-8 s (μ_b = 0.4), the distance left ~1e-15 m, and the
/// error of the stop time a fraction of the time left, as far as the slip direction still
/// turns (the reference slide of model.md §4 at 1 m/s and 3 rad/s stops 2e-12 s apart when
/// ended at 1e-7 and at 1e-9 m/s). Below [`RIDE_SLIP`], so that the parcel then rides.
pub const END_SLIP: f64 = 1e-7;

/// Belt slip below which a parcel without contacts rides [m/s].
pub const RIDE_SLIP: f64 = 1e-6;

/// Belt slip below which the belt friction is ramped to zero while contacts are active
/// [m/s] (regularised Coulomb law; see `belt_wrench`).
pub const CONTACT_SLIP_REG: f64 = 1e-5;

/// Slip below which a contact counts as at rest, where the strict tolerances find no
/// consistent contact state [m/s] (the relaxed selection; the contact-force record's notion
/// of sliding, `motion::ContactCheck`).
pub const REST_SLIP: f64 = crate::model::active_set::REVERSAL_SLIP;

// ---- The motion's guards ----

/// Gap at which an approaching contact's guard fires \[m].
pub const GAP_MARGIN: f64 = 1e-9;

/// Normal speed above which a pair at its gap's root counts as separating [m/s]
/// (`Motion::configure`).
pub const SEPARATING_SPEED: f64 = 1e-6;

/// Where the guard of a separating pair at its gap's root starts \[m]: strictly on its
/// pre-side, by a depth that moves its next touch by a negligible time.
pub const SEPARATING_BASE: f64 = 1e-12;

/// Largest depth by which a gap guard is re-based at a mode change \[m]: a closed pair can
/// lie as deep as [`DEEPEST_GAP`] (moved there by the drift removal of
/// another contact at a strike), and a guard starting below zero would never fire.
pub const MAX_REBASE: f64 = -DEEPEST_GAP + GAP_MARGIN;

/// Largest extra depth of a re-armed gap guard \[m] (below the closed-contact tolerance).
pub const MAX_GAP_EXTRA: f64 = 0.5 * GAP_TOL;

/// Range overshoot at which a contact point counts as past its obstacle's end \[m].
pub const RANGE_MARGIN: f64 = 2.0 * RANGE_TOL;

/// Slip speed margin of the slip-reversal guard [m/s].
pub const SLIP_MARGIN: f64 = 1e-9;

/// Normal-force margin of the release guard, relative to m g.
pub const FORCE_MARGIN: f64 = 1e-9;

/// Largest extra depth of a re-armed force guard, relative to m g (`Motion::mute`).
pub const MAX_FORCE_EXTRA: f64 = 1e-6;

/// How far ahead a degenerate riding contact is judged (`settle::ride_with_contacts`) \[s].
pub const LOOK_AHEAD: f64 = 1e-6;

// ---- How they relate (compile-time checks) ----

// A guard fires before a pair is closed, and a closed pair is less deep than the deepest
// touching one; drift is removed well inside the closed band, and a held pair's drift
// band is wider than it.
const _: () = assert!(GAP_MARGIN < DRIFT_TOL && DRIFT_TOL < GAP_TOL && GAP_TOL < -DEEPEST_GAP);
const _: () = assert!(GAP_TOL < HELD_GAP_TOL && NEAREST_TOL < GAP_TOL);
const _: () = assert!(MAX_GAP_EXTRA < GAP_TOL && TAIL_DEPTH < GAP_TOL);
// A re-based guard starts above the deepest closed pair.
const _: () = assert!(MAX_REBASE > -DEEPEST_GAP);
// A point past an end counts as off it at the range guard only after the on-it band.
const _: () = assert!(RANGE_TOL < RANGE_MARGIN && END_TOL < MAX_END_WIDENING);
// Strike speeds: what closes is below what drifts, below a graze, below plastic persistence.
const _: () = assert!(SPEED_TOL <= LEAVE_SPEED && LEAVE_SPEED < SEPARATING_SPEED);
const _: () = assert!(HELD_DRIFT <= GRAZE_SPEED && GRAZE_SPEED < CLOSE_SPEED);
const _: () = assert!(CLOSE_SPEED < PERSIST_SPEED);
// A free slide ended in closed form then rides, and a riding parcel's slip is inside the
// contact law's ramp.
const _: () = assert!(END_SLIP < RIDE_SLIP && RIDE_SLIP < CONTACT_SLIP_REG);
