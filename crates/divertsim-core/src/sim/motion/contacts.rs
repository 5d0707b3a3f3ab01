//! The contact set of a mode and the pair logic. The set says which contacts are active and
//! how each slides or sticks; the pair logic says, for any pair (a corner and the arm's line,
//! a corner and the guide, the arm's tip and a parcel edge), the one number whose sign tells
//! whether the pair touches (docs/model.md §6). It is the one place that says when a contact
//! starts: the gap guards watch it and nothing else decides it between events.

use crate::model::active_set::{self, Tangential};
use crate::model::contact::{self, ContactKind, Kinematics};

/// One active contact and its tangential mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ActiveContact {
    pub kind: ContactKind,
    pub mode: Tangential,
}

/// The active contacts of a mode, in the order the event logic chose them (a contact's
/// index is its row in the active-set problem and names its guards).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct ContactSet([Option<ActiveContact>; active_set::MAX_CONTACTS]);

impl ContactSet {
    pub fn new(active: &[ActiveContact]) -> Self {
        let mut set = ContactSet::default();
        for (slot, c) in set.0.iter_mut().zip(active) {
            *slot = Some(*c);
        }
        set
    }

    /// The active contacts.
    #[inline]
    pub fn iter(&self) -> impl Iterator<Item = &ActiveContact> {
        self.0.iter().flatten()
    }

    /// The active contacts' kinds.
    #[inline]
    pub fn kinds(&self) -> impl Iterator<Item = ContactKind> + '_ {
        self.iter().map(|c| c.kind)
    }

    /// Each row's contact, if any.
    #[inline]
    pub fn slots(&self) -> &[Option<ActiveContact>; active_set::MAX_CONTACTS] {
        &self.0
    }

    /// Row `k`'s contact.
    #[inline]
    pub fn get(&self, k: usize) -> Option<ActiveContact> {
        self.0[k]
    }

    /// No active contact.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.0.iter().all(Option::is_none)
    }
}

/// How far the pair `kind` is from touching at the kinematics `kin` \[m]: negative only
/// when it touches. Without the guards' margins.
///
/// - A corner and the arm: its gap, or how far it is behind the pivot, where the arm's line
///   is no obstacle. A corner crossing the line beyond the tip switches faces (the driver
///   flips its side) rather than touching.
/// - A corner and the guide: its gap, or how far it is outside the guide's extent.
/// - The tip and an edge: the same, plus the edge's shortfall: the tip touches an edge only
///   if that edge is its nearest, and the shortfall (≥ 0, 0 for the nearest edge) lifts every
///   other edge's value, continuously, to at least the largest edge gap, which is negative
///   only with the tip wholly inside the parcel.
#[inline]
pub(crate) fn separation(
    kind: ContactKind,
    kin: &Kinematics,
    phi_sc: (f64, f64),
    arm_sc: (f64, f64),
) -> f64 {
    let (gap, along, extent) = contact::gap_and_range_with(kind, kin, phi_sc, arm_sc);
    match kind {
        ContactKind::CornerArm { .. } => gap.max(extent.0 - along),
        ContactKind::CornerGuide { .. } => gap.max((extent.0 - along).max(along - extent.1)),
        ContactKind::TipEdge { edge } => {
            let shortfall = contact::tip_edge_shortfall_with(edge, kin, phi_sc, arm_sc);
            gap.max((extent.0 - along).max(along - extent.1)) + shortfall
        }
    }
}
