//! The study engine: a long computation cut into pieces seeded by (seed, k), run in
//! parallel, kept, resumed and folded in order, with an early stop (issue 48).
//!
//! Reliability's shards, the line's segments and the line objective's measure are studies.
//! Each says what a piece is and how it folds ([`Study`]); [`execute`] owns the rest: the
//! batches, the store that keeps and hands back finished pieces, the caller's stop, the
//! progress ticks and the tally so far after each batch.
//!
//! **Determinism.** A piece depends only on its own index, and pieces are folded in index
//! order whatever the batch or the number of threads, so a study's result is bitwise the
//! same for any thread count, any batch size, and any mix of recalled and computed pieces.
//! The early stop is asked after each fold, so it stops at the same piece in every case
//! (pieces of the batch beyond it were computed, and are kept, but not folded).

use crate::run::memo::{self, Memo};
use crate::run::sweep::{no_progress, par_map, Progress};
use serde::de::DeserializeOwned;
use serde::Serialize;

/// A study: `pieces()` pieces, each run on its own and folded into a tally in order.
pub trait Study: Sync {
    /// What a piece gives: what a store keeps and hands back.
    type Piece: Send;
    /// What a worker hands to [`Study::fold`]: the piece, reduced on the worker so that a
    /// batch in flight holds only what the tally needs.
    type Part: Send;
    /// The result so far.
    type Tally;
    /// Why a piece failed.
    type Error: Send;

    /// The number of pieces at most.
    fn pieces(&self) -> u64;
    /// Pieces run side by side between two folds: 1 where a piece is parallel inside (a
    /// reliability shard), more where pieces are sequential inside (a line segment).
    fn batch(&self) -> u64;
    /// Piece `k`, computed here; `stop_point` is called inside it where a caller may stop
    /// (a long piece must not wait for its end) or count progress.
    fn run_piece(&self, k: u64, stop_point: Progress<'_>) -> Result<Self::Piece, Self::Error>;
    /// Piece `k` reduced to what [`Study::fold`] takes (on the worker thread).
    fn part(&self, k: u64, piece: Self::Piece) -> Self::Part;
    /// Add a part to the tally (called in piece order).
    fn fold(&self, tally: &mut Self::Tally, part: Self::Part);
    /// Whether the tally is enough to stop before the remaining pieces.
    fn enough(&self, _tally: &Self::Tally) -> bool {
        false
    }
}

/// Where finished pieces are kept between runs (a checkpoint, a cluster's results, or
/// nothing); called from any worker thread.
pub trait PieceStore<P>: Sync {
    /// Piece `k`, if a whole copy is kept.
    fn load(&self, k: u64) -> Result<Option<P>, String>;
    /// Keep piece `k` (whole, or not at all).
    fn save(&self, k: u64, piece: &P) -> Result<(), String>;
}

/// A store that keeps nothing: every piece is computed.
#[derive(Debug, Clone, Copy, Default)]
pub struct Unkept;

impl<P> PieceStore<P> for Unkept {
    fn load(&self, _: u64) -> Result<Option<P>, String> {
        Ok(None)
    }
    fn save(&self, _: u64, _: &P) -> Result<(), String> {
        Ok(())
    }
}

/// Pieces kept in a [`Memo`] (the app's checkpoint journal), piece `k` under
/// `memo::key(kind, &(study, k))`: a piece is recalled bit for bit, and one that does not
/// decode is computed again.
pub struct InMemo<'a> {
    pub memo: &'a dyn Memo,
    /// What the pieces are, in the key.
    pub kind: &'static str,
    /// What every piece of the study depends on, as a memo key.
    pub study: u64,
}

impl InMemo<'_> {
    /// The memo key of piece `k`.
    pub fn key(&self, k: u64) -> u64 {
        memo::key(self.kind, &(self.study, k))
    }
}

impl<P: Serialize + DeserializeOwned> PieceStore<P> for InMemo<'_> {
    fn load(&self, k: u64) -> Result<Option<P>, String> {
        Ok(memo::recall(self.memo, self.key(k)))
    }
    fn save(&self, k: u64, piece: &P) -> Result<(), String> {
        memo::keep(self.memo, self.key(k), piece);
        Ok(())
    }
}

/// How a caller watches and stops an [`execute`].
pub struct Control<'a, T> {
    /// Asked before each batch: `true` ends the study with [`StudyError::Stopped`].
    pub stop: &'a dyn Fn() -> bool,
    /// Called once per finished piece (computed or recalled), from any worker.
    pub piece_done: Progress<'a>,
    /// Handed to [`Study::run_piece`] as its `stop_point`.
    pub inside: Progress<'a>,
    /// Called with the tally after each batch is folded (the rates so far).
    pub batch_done: &'a mut dyn FnMut(&T),
}

/// Why a study stopped short.
#[derive(Debug, Clone, PartialEq)]
pub enum StudyError<E> {
    /// A piece failed.
    Piece(E),
    /// The store failed to read or keep a piece.
    Store(String),
    /// The caller's stop said so.
    Stopped,
}

/// A finished study.
#[derive(Debug, Clone, PartialEq)]
pub struct Executed<T> {
    pub tally: T,
    /// Pieces folded (read back or computed).
    pub pieces: u64,
    /// Pieces folded that the store handed back.
    pub resumed: u64,
    /// Whether [`Study::enough`] stopped it before the last piece.
    pub stopped_early: bool,
}

/// Run `study` from `tally`: batches of [`Study::batch`] pieces in parallel, each piece read
/// back from `store` if kept there, else computed and kept; the parts folded in piece order,
/// [`Study::enough`] asked after each fold.
pub fn execute<S: Study>(
    study: &S,
    mut tally: S::Tally,
    store: &dyn PieceStore<S::Piece>,
    control: &mut Control<'_, S::Tally>,
) -> Result<Executed<S::Tally>, StudyError<S::Error>> {
    let total = study.pieces();
    let batch = study.batch().max(1);
    let inside = control.inside;
    let (mut folded, mut resumed) = (0, 0);
    let mut k = 0;
    while k < total {
        if (control.stop)() {
            return Err(StudyError::Stopped);
        }
        let end = (k + batch).min(total);
        let ks: Vec<u64> = (k..end).collect();
        let parts = par_map(&ks, control.piece_done, |&k| {
            let (piece, recalled) = match store.load(k).map_err(StudyError::Store)? {
                Some(p) => (p, true),
                None => {
                    let p = study.run_piece(k, inside).map_err(StudyError::Piece)?;
                    store.save(k, &p).map_err(StudyError::Store)?;
                    (p, false)
                }
            };
            Ok((study.part(k, piece), recalled))
        });
        for part in parts {
            let (part, recalled) = part?;
            study.fold(&mut tally, part);
            folded += 1;
            resumed += u64::from(recalled);
            if folded < total && study.enough(&tally) {
                (control.batch_done)(&tally);
                return Ok(Executed {
                    tally,
                    pieces: folded,
                    resumed,
                    stopped_early: true,
                });
            }
        }
        (control.batch_done)(&tally);
        k = end;
    }
    Ok(Executed {
        tally,
        pieces: folded,
        resumed,
        stopped_early: false,
    })
}

/// [`execute`] to the end, unwatched and with no stop.
pub fn execute_quietly<S: Study>(
    study: &S,
    tally: S::Tally,
    store: &dyn PieceStore<S::Piece>,
) -> Result<Executed<S::Tally>, StudyError<S::Error>> {
    let mut done = |_: &S::Tally| {};
    execute(
        study,
        tally,
        store,
        &mut Control {
            stop: &|| false,
            piece_done: &no_progress,
            inside: &no_progress,
            batch_done: &mut done,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::sweep::one_and_many_threads;
    use std::collections::BTreeMap;
    use std::sync::atomic::{AtomicU64, Ordering};
    use std::sync::Mutex;

    /// Piece k: a few pseudo-random numbers from (seed, k); the tally their running sum in
    /// fold order (a float sum, so a change of order shows in the bits).
    struct Toy {
        pieces: u64,
        batch: u64,
        enough_at: Option<f64>,
        runs: AtomicU64,
    }

    impl Toy {
        fn new(pieces: u64, batch: u64) -> Toy {
            Toy {
                pieces,
                batch,
                enough_at: None,
                runs: AtomicU64::new(0),
            }
        }
    }

    impl Study for Toy {
        type Piece = Vec<f64>;
        type Part = f64;
        type Tally = (f64, Vec<u64>);
        type Error = String;
        fn pieces(&self) -> u64 {
            self.pieces
        }
        fn batch(&self) -> u64 {
            self.batch
        }
        fn run_piece(&self, k: u64, stop_point: Progress<'_>) -> Result<Vec<f64>, String> {
            self.runs.fetch_add(1, Ordering::Relaxed);
            if k == 999 {
                return Err("piece 999 fails".into());
            }
            let mut rng = crate::stats::splitmix::SplitMix64(7 ^ k.wrapping_mul(0x9e37));
            Ok((0..5)
                .map(|_| {
                    stop_point();
                    rng.next_f64() * 1e3 - 400.0
                })
                .collect())
        }
        fn part(&self, _: u64, piece: Vec<f64>) -> f64 {
            piece.iter().sum()
        }
        fn fold(&self, t: &mut (f64, Vec<u64>), part: f64) {
            t.0 += part;
            t.1.push(t.0.to_bits());
        }
        fn enough(&self, t: &(f64, Vec<u64>)) -> bool {
            self.enough_at.is_some_and(|a| t.0 > a)
        }
    }

    #[derive(Default)]
    struct Memory(Mutex<BTreeMap<u64, Vec<f64>>>);

    impl PieceStore<Vec<f64>> for Memory {
        fn load(&self, k: u64) -> Result<Option<Vec<f64>>, String> {
            Ok(self.0.lock().unwrap().get(&k).cloned())
        }
        fn save(&self, k: u64, p: &Vec<f64>) -> Result<(), String> {
            self.0.lock().unwrap().insert(k, p.clone());
            Ok(())
        }
    }

    #[test]
    fn the_same_bits_for_any_thread_count_batch_and_store() {
        let whole = |batch| {
            let (one, many) = one_and_many_threads(|| {
                execute_quietly(&Toy::new(40, batch), (0.0, vec![]), &Unkept).unwrap()
            });
            assert_eq!(one, many);
            one
        };
        let first = whole(1);
        assert_eq!(
            (first.pieces, first.resumed, first.stopped_early),
            (40, 0, false)
        );
        assert_eq!(first.tally.1.len(), 40);
        for batch in [3, 16, 40, 100] {
            assert_eq!(whole(batch), first, "batch {batch}");
        }
        // Kept, then some pieces lost: the recalled and the computed fold to the same bits.
        let m = Memory::default();
        let toy = Toy::new(40, 6);
        execute_quietly(&toy, (0.0, vec![]), &m).unwrap();
        for k in [0, 7, 8, 39] {
            m.0.lock().unwrap().remove(&k);
        }
        let toy = Toy::new(40, 6);
        let again = execute_quietly(&toy, (0.0, vec![]), &m).unwrap();
        assert_eq!(again.tally, first.tally);
        assert_eq!(again.resumed, 36);
        assert_eq!(toy.runs.load(Ordering::Relaxed), 4);
    }

    #[test]
    fn the_early_stop_falls_on_the_same_piece_for_any_batch() {
        let stop_at = |batch| {
            let mut toy = Toy::new(60, batch);
            toy.enough_at = Some(9000.0);
            execute_quietly(&toy, (0.0, vec![]), &Unkept).unwrap()
        };
        let one = stop_at(1);
        assert!(
            one.stopped_early,
            "the toy's sum passes 9000 before piece 60"
        );
        assert!(one.pieces < 60);
        assert!(one.tally.0 > 9000.0);
        // The piece before it had not passed.
        let before = f64::from_bits(one.tally.1[one.tally.1.len() - 2]);
        assert!(before <= 9000.0);
        for batch in [2, 7, 60] {
            assert_eq!(stop_at(batch), one, "batch {batch}");
        }
    }

    #[test]
    fn a_stop_ends_between_batches_and_a_failed_piece_is_reported() {
        let asked = AtomicU64::new(0);
        let stop = || asked.fetch_add(1, Ordering::Relaxed) >= 2;
        let mut seen = Vec::new();
        let mut batch_done = |t: &(f64, Vec<u64>)| seen.push(t.1.len());
        let ticks = AtomicU64::new(0);
        let tick = || {
            ticks.fetch_add(1, Ordering::Relaxed);
        };
        let r = execute(
            &Toy::new(20, 4),
            (0.0, vec![]),
            &Unkept,
            &mut Control {
                stop: &stop,
                piece_done: &tick,
                inside: &no_progress,
                batch_done: &mut batch_done,
            },
        );
        assert_eq!(r, Err(StudyError::Stopped));
        assert_eq!(seen, vec![4, 8]);
        assert_eq!(ticks.load(Ordering::Relaxed), 8);
        let failing = Toy::new(1000, 50);
        assert_eq!(
            execute_quietly(&failing, (0.0, vec![]), &Unkept),
            Err(StudyError::Piece("piece 999 fails".into()))
        );
        struct Broken;
        impl PieceStore<Vec<f64>> for Broken {
            fn load(&self, _: u64) -> Result<Option<Vec<f64>>, String> {
                Ok(None)
            }
            fn save(&self, k: u64, _: &Vec<f64>) -> Result<(), String> {
                Err(format!("cannot keep piece {k}"))
            }
        }
        assert_eq!(
            execute_quietly(&Toy::new(1, 1), (0.0, vec![]), &Broken),
            Err(StudyError::Store("cannot keep piece 0".into()))
        );
    }

    #[test]
    fn a_piece_in_the_memo_is_recalled_bit_for_bit_under_its_own_key() {
        let bytes = memo::InMemory::default();
        let store = InMemo {
            memo: &bytes,
            kind: "toy",
            study: 5,
        };
        let first = execute_quietly(&Toy::new(12, 5), (0.0, vec![]), &store).unwrap();
        assert_eq!(bytes.keys().len(), 12);
        assert_eq!(store.key(3), memo::key("toy", &(5u64, 3u64)));
        let toy = Toy::new(12, 5);
        let again = execute_quietly(&toy, (0.0, vec![]), &store).unwrap();
        assert_eq!((again.tally, again.resumed), (first.tally, 12));
        assert_eq!(toy.runs.load(Ordering::Relaxed), 0);
        // Another study's key recalls none of them.
        let other = InMemo { study: 6, ..store };
        let toy = Toy::new(12, 5);
        execute_quietly(&toy, (0.0, vec![]), &other).unwrap();
        assert_eq!(toy.runs.load(Ordering::Relaxed), 12);
    }
}
