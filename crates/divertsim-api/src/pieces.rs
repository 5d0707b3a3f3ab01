//! Studies in pieces: the contract's side for a cluster. A study whose run is pieces seeded
//! by (point, k), independent of each other (reliability's shards, the line's segments),
//! keeps every piece in its hooks' memo under the piece's key. A cluster's workers run
//! pieces apart ([`Pieces::run_piece`]); the client hands them back as the memo of the
//! study's own run ([`run_from_pieces`]), which recalls them and tallies them in order with
//! the early stop of one machine: the same output, bit for bit. One job serves every such
//! study (the Python edge's `StudyJob`, Dask's `divertsim.dask`).

use crate::config::Loaded;
use crate::contract::{report, Analysis, Error, Hooks, Report};
use divertsim_core::run::memo::Memo;
use std::collections::HashMap;

/// Piece `k` of point `point`, and its memo key.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Piece {
    pub point: usize,
    pub k: u64,
    pub key: u64,
}

/// A study run as pieces, each kept in the memo under its own key.
pub trait Pieces: Analysis {
    /// What every piece of a bound run needs, made once per job (the points' triggers,
    /// an adaptive table among them).
    type Prepared: Send + Sync;

    /// Prepare the bound run's pieces.
    fn prepare(bound: &Self::Bound) -> Result<Self::Prepared, Error>;

    /// Every piece, in the order one machine runs them, with the memo key under which the
    /// run keeps and recalls it: known from the bound run alone, before anything is
    /// prepared, and naming everything the piece is made of (another run's piece has
    /// another key). What the keys are made of is worked out once for all pieces.
    fn pieces(bound: &Self::Bound) -> Vec<Piece>;

    /// Piece (point, k) run here: its bytes as the run keeps them (what it recalls).
    fn run_piece(
        bound: &Self::Bound,
        prepared: &Self::Prepared,
        point: usize,
        k: u64,
    ) -> Result<Vec<u8>, Error>;
}

/// Pieces computed elsewhere, by their keys: the memo of a run from them.
struct Given(HashMap<u64, Vec<u8>>);

impl Memo for Given {
    fn recall(&self, key: u64) -> Option<Vec<u8>> {
        self.0.get(&key).cloned()
    }
    fn keep(&self, _: u64, _: &[u8]) {}
    /// A piece the merge runs itself is not encoded.
    fn keeps(&self) -> bool {
        false
    }
}

/// The report of a run from pieces computed elsewhere, each (key, bytes) as
/// [`Pieces::pieces`] and [`Pieces::run_piece`] gave it: the study's own run with them
/// as its memo, reported as [`report`] reports any run. A piece not given is run here. A
/// piece whose key is not one of this run's (another run's, another scenario's, another
/// version's) or that is given twice is refused before anything runs; the bytes under a key
/// are the study's to check as it recalls them (a reliability shard must hold its point's
/// samples, a line segment that does not decode is run again).
pub fn run_from_pieces<A: Pieces>(
    base: &Loaded,
    bound: &A::Bound,
    pieces: Vec<(u64, Vec<u8>)>,
    threads: Option<usize>,
) -> Result<Report, Error> {
    let keys: HashMap<u64, (usize, u64)> = A::pieces(bound)
        .into_iter()
        .map(|p| (p.key, (p.point, p.k)))
        .collect();
    let mut given = HashMap::new();
    for (key, bytes) in pieces {
        let Some((p, k)) = keys.get(&key) else {
            return Err(Error::Invalid(vec![crate::config::Problem::new(
                "pieces",
                format!(
                    "piece {key:016x} is not one of this run's {} pieces (another run's, or \
                     another version's)",
                    keys.len()
                ),
            )]));
        };
        if given.insert(key, bytes).is_some() {
            return Err(Error::Invalid(vec![crate::config::Problem::new(
                "pieces",
                format!("piece ({p}, {k}) is given twice"),
            )]));
        }
    }
    let memo = Given(given);
    let hooks = Hooks {
        memo: &memo,
        threads,
        ..Hooks::none()
    };
    let output = crate::threads::with_threads(threads, || A::run(base, bound, &hooks))?;
    report::<A>(&output, bound, base)
}

/// A piece asked of a run that has no such point, shard or segment (`what`).
pub fn no_piece(what: &str, i: u64, n: u64) -> Error {
    Error::Invalid(vec![crate::config::Problem::new(
        what,
        format!(
            "no {what} {i}; this run has {n} (0 to {})",
            n.saturating_sub(1)
        ),
    )])
}
