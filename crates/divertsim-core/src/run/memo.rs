//! Finished pieces of long computations (a capacity column, a trigger speed, an optimiser
//! evaluation), kept by the caller so that an interrupted run resumes where it stopped.
//!
//! A piece is looked up by a hash of everything that determines it (its inputs' `Debug`
//! text, which prints every `f64` exactly) and stored in an exact binary encoding, so a
//! recalled piece is the computed one bit for bit and a resumed run's results are
//! byte-identical to an uninterrupted run's. The core never touches files: the app's
//! [`Memo`] writes them.

use serde::de::DeserializeOwned;
use serde::Serialize;
use std::fmt::Debug;

/// Where finished pieces are kept; called from any worker thread.
pub trait Memo: Sync {
    /// The bytes kept under `key`, if any.
    fn recall(&self, key: u64) -> Option<Vec<u8>>;
    /// Keep `value` under `key`.
    fn keep(&self, key: u64, value: &[u8]);
    /// Whether it keeps anything: a piece whose encoding costs (a shard's samples) is
    /// encoded only for a memo that does.
    fn keeps(&self) -> bool {
        true
    }
}

/// Keeps nothing: every piece is computed.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoMemo;

impl Memo for NoMemo {
    fn recall(&self, _: u64) -> Option<Vec<u8>> {
        None
    }
    fn keep(&self, _: u64, _: &[u8]) {}
    fn keeps(&self) -> bool {
        false
    }
}

/// 64-bit FNV-1a, fed in parts (bytes, or text through `fmt::Write`): the memo's keys and a
/// checkpoint's record checks and fingerprint.
#[derive(Debug, Clone, Copy)]
pub struct Fnv(pub u64);

impl Fnv {
    /// The hash of nothing yet.
    pub fn new() -> Fnv {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    /// The hash with `bytes` fed after what it has had.
    pub fn feed(mut self, bytes: &[u8]) -> Fnv {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
        self
    }
}

impl Default for Fnv {
    fn default() -> Fnv {
        Fnv::new()
    }
}

impl std::fmt::Write for Fnv {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        *self = self.feed(s.as_bytes());
        Ok(())
    }
}

/// The key of a piece: 64-bit FNV-1a over `kind` and the `Debug` text of its inputs (stable
/// across runs and platforms, unlike std's hasher).
pub fn key(kind: &str, inputs: &impl Debug) -> u64 {
    let mut h = Fnv::new();
    let _ = std::fmt::write(&mut h, format_args!("{kind}\u{1f}{inputs:?}"));
    h.0
}

/// The piece under `key`: recalled from `memo` (second value `true`), or computed by `f`
/// and kept. A kept value that does not decode is computed again.
pub fn cached<T: Serialize + DeserializeOwned>(
    memo: &dyn Memo,
    key: u64,
    f: impl FnOnce() -> T,
) -> (T, bool) {
    if let Some(v) = recall(memo, key) {
        return (v, true);
    }
    let v = f();
    keep(memo, key, &v);
    (v, false)
}

/// The piece kept under `key`, if one is kept and decodes.
pub fn recall<T: DeserializeOwned>(memo: &dyn Memo, key: u64) -> Option<T> {
    memo.recall(key)
        .and_then(|b| postcard::from_bytes::<T>(&b).ok())
}

/// Keep `value` under `key` (a piece that cannot be encoded is not kept).
pub fn keep<T: Serialize>(memo: &dyn Memo, key: u64, value: &T) {
    if let Some(bytes) = encode(value) {
        memo.keep(key, &bytes);
    }
}

/// A piece in the memo's encoding (what [`recall`] decodes), e.g. to send it elsewhere.
pub fn encode<T: Serialize>(value: &T) -> Option<Vec<u8>> {
    postcard::to_allocvec(value).ok()
}

/// A memo in memory: pieces kept for the life of a process (a caller that runs the same
/// work again, the tests of what keeps pieces).
#[derive(Debug, Default)]
pub struct InMemory(std::sync::Mutex<std::collections::BTreeMap<u64, Vec<u8>>>);

impl InMemory {
    fn pieces(&self) -> std::sync::MutexGuard<'_, std::collections::BTreeMap<u64, Vec<u8>>> {
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }
    /// The keys of the pieces kept, in order.
    pub fn keys(&self) -> Vec<u64> {
        self.pieces().keys().copied().collect()
    }
    /// Forget the piece under `key` (as if it was never kept).
    pub fn forget(&self, key: u64) {
        self.pieces().remove(&key);
    }
}

impl Memo for InMemory {
    fn recall(&self, key: u64) -> Option<Vec<u8>> {
        self.pieces().get(&key).cloned()
    }
    fn keep(&self, key: u64, value: &[u8]) {
        self.pieces().insert(key, value.to_vec());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recalls_exact_values_including_nan_and_errors() {
        let memo = InMemory::default();
        let v: (Vec<f64>, Result<f64, String>) = (
            vec![0.1, -0.0, f64::NAN, f64::INFINITY, 1e-310],
            Err("x".into()),
        );
        let k = key("test", &1.5f64);
        let (a, hit) = cached(&memo, k, || v.clone());
        assert!(!hit);
        let (b, hit) = cached(&memo, k, || panic!("not recomputed"));
        assert!(hit);
        let bits = |x: &(Vec<f64>, Result<f64, String>)| {
            x.0.iter().map(|f| f.to_bits()).collect::<Vec<_>>()
        };
        assert_eq!(bits(&a), bits(&b));
        assert_eq!(a.1, b.1);
    }

    #[test]
    fn keys_tell_inputs_apart_to_the_last_bit() {
        let x = 0.1f64;
        let y = f64::from_bits(x.to_bits() + 1);
        assert_ne!(key("k", &x), key("k", &y));
        assert_ne!(key("a", &x), key("b", &x));
        assert_eq!(key("k", &(x, 2)), key("k", &(x, 2)));
        // Stable across builds and platforms: FNV-1a of "k\u{1f}1".
        assert_eq!(key("k", &1u8), 0x3c97_1619_3556_9efa);
    }

    #[test]
    fn an_undecodable_value_is_recomputed() {
        let memo = InMemory::default();
        memo.keep(7, &[0xff]);
        let (v, hit) = cached(&memo, 7, || String::from("fresh"));
        assert!(!hit);
        assert_eq!(v, "fresh");
    }
}
