//! The motion's caches. The event locator asks every guard, one after the other, at the same
//! few sample instants of a step, and the free slide's next step starts where the last one
//! ended: what an instant costs (the arm's state and trigonometry, a contact evaluation, a
//! free-slide derivative) is kept in small rings and read in place. Pure memoisation: a hit
//! gives bitwise what a miss would compute.

use crate::model::drive::ArmState;
use std::cell::{Cell, RefCell};

/// Slots of the per-instant geometry cache (≥ the sample points of one step).
const GEO_SLOTS: usize = 8;

/// Slots of the per-state evaluation cache.
const EVAL_SLOTS: usize = 8;

/// The arm state and the trigonometry at one (t, φ).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Geo {
    pub t: f64,
    pub phi: f64,
    pub arm: ArmState,
    /// (sin φ, cos φ).
    pub phi_sc: (f64, f64),
    /// (sin α, cos α).
    pub arm_sc: (f64, f64),
}

/// The geometry of the last few instants asked.
pub(crate) struct GeoCache(RefCell<([Geo; GEO_SLOTS], usize)>);

impl GeoCache {
    pub fn new() -> Self {
        let empty = Geo {
            t: f64::NAN,
            phi: f64::NAN,
            arm: ArmState::default(),
            phi_sc: (0.0, 1.0),
            arm_sc: (0.0, 1.0),
        };
        GeoCache(RefCell::new(([empty; GEO_SLOTS], 0)))
    }

    /// The geometry at (t, φ): kept, or made by `make` and kept.
    #[inline]
    pub fn get(&self, t: f64, phi: f64, make: impl FnOnce() -> Geo) -> Geo {
        let mut cache = self.0.borrow_mut();
        let (slots, next) = &mut *cache;
        // Newest first: the locator asks guard after guard at the same few instants.
        for k in 1..=GEO_SLOTS {
            let g = &slots[(*next + GEO_SLOTS - k) % GEO_SLOTS];
            if g.t == t && g.phi == phi {
                return *g;
            }
        }
        let g = make();
        slots[*next] = g;
        *next = (*next + 1) % GEO_SLOTS;
        g
    }
}

/// A cached evaluation with its (t, y).
type EvalSlot<E> = (f64, [f64; 6], E);

/// The evaluations of the last few states asked, read in place: the guards ask one number
/// each of an evaluation several hundred bytes long, many times per sample instant.
pub(crate) struct EvalCache<E>(RefCell<([Option<EvalSlot<E>>; EVAL_SLOTS], usize)>);

impl<E: Copy> EvalCache<E> {
    pub fn new() -> Self {
        EvalCache(RefCell::new(([None; EVAL_SLOTS], 0)))
    }

    /// Forget every evaluation (the mode changed).
    pub fn clear(&self) {
        *self.0.borrow_mut() = ([None; EVAL_SLOTS], 0);
    }

    /// What `read` takes of the evaluation at (t, y): kept, or made by `make` and kept.
    #[inline]
    pub fn read<R>(
        &self,
        t: f64,
        y: &[f64; 6],
        make: impl FnOnce() -> E,
        read: impl FnOnce(&E) -> R,
    ) -> R {
        {
            let cache = self.0.borrow();
            if let Some((_, _, e)) = cache
                .0
                .iter()
                .flatten()
                .find(|(ct, cy, _)| *ct == t && cy == y)
            {
                return read(e);
            }
        }
        let e = make();
        let value = read(&e);
        let mut cache = self.0.borrow_mut();
        let k = cache.1;
        cache.0[k] = Some((t, *y, e));
        cache.1 = (k + 1) % EVAL_SLOTS;
        value
    }
}

/// Free sliding: the last (t, y, dy/dt), which is the next step's start (first same as last).
pub(crate) struct FreeDerivative(Cell<Option<StateDerivative>>);

/// (t, y, dy/dt).
type StateDerivative = (f64, [f64; 6], [f64; 6]);

impl FreeDerivative {
    pub fn new() -> Self {
        FreeDerivative(Cell::new(None))
    }

    pub fn keep(&self, t: f64, y: &[f64; 6], dy: [f64; 6]) {
        self.0.set(Some((t, *y, dy)));
    }

    /// dy/dt at (t, y) if it is the one kept.
    #[inline]
    pub fn at(&self, t: f64, y: &[f64; 6]) -> Option<[f64; 6]> {
        match self.0.get() {
            Some((ct, cy, dy)) if ct == t && cy == *y => Some(dy),
            _ => None,
        }
    }
}
