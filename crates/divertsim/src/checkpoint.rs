//! Checkpoints of long commands (`capacity`, `trigger`, `optimize`, `replicate`, `line`,
//! `reliability`): with `--out DIR`, every finished piece of work (see
//! `divertsim_core::run::memo`; a reliability shard is its samples as Parquet bytes) is
//! appended to `.DIR.checkpoint/journal.bin` beside `DIR`, and `--resume` recalls them
//! instead of computing them again, so the resumed results are byte-identical to an
//! uninterrupted run's. A piece is read back from the file when recalled (only offsets are
//! held), also by the run that kept it (reliability's sample table is written from its
//! shards). The checkpoint is removed once `DIR` is written.
//!
//! The journal is a sequence of records `key (u64) | length (u32) | bytes | FNV-1a of
//! key, length and bytes (u64)`, little-endian; a record cut short by a kill, or damaged, ends the journal
//! there and is overwritten. `fingerprint` holds a hash of the tool version, the command
//! and every input: `--resume` refuses a checkpoint made by other inputs. The output lock
//! of `crate::outdir` keeps a second run away from it.

use divertsim_core::run::memo::{Fnv, Memo};
use std::collections::HashMap;
use std::fs::{File, OpenOptions};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// An open checkpoint: the journal file, where each piece kept (by an earlier run or this
/// one) is found, and how many an earlier run left.
#[derive(Debug)]
pub struct Journal {
    dir: PathBuf,
    recalled: usize,
    tail: Mutex<Tail>,
}

/// The journal file and where its pieces lie: only offsets are held, so a resumed run
/// of a large study (a reliability run's shards) does not hold its checkpoint in memory.
#[derive(Debug)]
struct Tail {
    file: File,
    /// The end of the last whole record: where the next one goes.
    end: u64,
    /// Each piece's value: its offset and length in the file.
    index: HashMap<u64, (u64, u32)>,
}

/// The checkpoint directory of `--out DIR`.
pub fn dir_of(out: &Path) -> PathBuf {
    crate::outdir::beside(out, "checkpoint")
}

/// The fingerprint of a run: the tool version, the command and the `Debug` text of every
/// input (exact for numbers).
pub fn fingerprint(command: &str, inputs: &impl std::fmt::Debug) -> String {
    // Hashed as it is written: the inputs' text (a records mix at every sweep point) is
    // never held whole.
    let mut hash = Fnv::new();
    let _ = std::fmt::Write::write_fmt(
        &mut hash,
        format_args!(
            "{}\u{1f}{command}\u{1f}{inputs:?}",
            env!("CARGO_PKG_VERSION")
        ),
    );
    format!(
        "divertsim {} {command} {:016x}\n",
        env!("CARGO_PKG_VERSION"),
        hash.0
    )
}

/// Open the checkpoint of `--out out` for a run with `fingerprint`: a new one, or with
/// `resume` the one an interrupted run left. Errors say what to do.
pub fn open(out: &Path, fingerprint: &str, resume: bool) -> Result<Journal, String> {
    let dir = dir_of(out);
    if dir.exists() {
        if !resume {
            return Err(format!(
                "an interrupted run left its finished work in {}; add --resume to continue it, or remove that directory to start over",
                dir.display()
            ));
        }
        let found = std::fs::read_to_string(dir.join("fingerprint")).unwrap_or_default();
        if found != fingerprint {
            return Err(format!(
                "the checkpoint {} was made by other inputs or another version ({}); resume with the same command line and scenario, or remove it to start over",
                dir.display(),
                found.trim()
            ));
        }
        return read(dir);
    }
    // Made complete under a temporary name, then renamed: a checkpoint always has its
    // fingerprint.
    let parent = dir.parent().unwrap_or(Path::new("."));
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let new = tempfile::Builder::new()
        .prefix(&format!("{name}-new-"))
        .tempdir_in(parent)
        .map_err(|e| format!("cannot write in {}: {e}", parent.display()))?;
    std::fs::write(new.path().join("fingerprint"), fingerprint)
        .and_then(|_| File::create(new.path().join("journal.bin")).map(drop))
        .and_then(|_| std::fs::rename(new.path(), &dir))
        .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let _ = new.keep();
    read(dir)
}

/// Index every whole record of the journal in `dir` (read through once, a record at a
/// time: only offsets are kept), cut off a damaged tail, and open it for appending.
fn read(dir: PathBuf) -> Result<Journal, String> {
    let path = dir.join("journal.bin");
    let mut index = HashMap::new();
    let mut reader = File::open(&path)
        .map(std::io::BufReader::new)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let mut at = 0u64;
    while let Some((key, len)) = record(&mut reader) {
        index.insert(key, (at + 12, len));
        at += 20 + u64::from(len);
    }
    let file = OpenOptions::new()
        .read(true)
        .write(true)
        .open(&path)
        .and_then(|f| {
            f.set_len(at)?;
            Ok(f)
        })
        .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(Journal {
        dir,
        recalled: index.len(),
        tail: Mutex::new(Tail {
            file,
            end: at,
            index,
        }),
    })
}

/// The next record's key and value length, its check verified; `None` at the end or at a
/// record cut short or damaged.
fn record(r: &mut impl Read) -> Option<(u64, u32)> {
    let mut head = [0u8; 12];
    r.read_exact(&mut head).ok()?;
    let key = u64::from_le_bytes(head[..8].try_into().ok()?);
    let len = u32::from_le_bytes(head[8..].try_into().ok()?);
    let mut hash = Fnv::new().feed(&head);
    let mut left = u64::from(len);
    let mut chunk = [0u8; 64 * 1024];
    while left > 0 {
        let n = left.min(chunk.len() as u64) as usize;
        r.read_exact(&mut chunk[..n]).ok()?;
        hash = hash.feed(&chunk[..n]);
        left -= n as u64;
    }
    let mut check = [0u8; 8];
    r.read_exact(&mut check).ok()?;
    (u64::from_le_bytes(check) == hash.0).then_some((key, len))
}

impl Journal {
    /// Pieces an earlier run left.
    pub fn recalled(&self) -> usize {
        self.recalled
    }

    /// The checkpoint directory (for files a command streams beside the journal).
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The run is complete and its outputs written: the checkpoint goes.
    pub fn remove(self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

impl Memo for Journal {
    /// A piece an earlier run or this one kept, read back from the file.
    fn recall(&self, key: u64) -> Option<Vec<u8>> {
        let mut tail = self.tail.lock().unwrap_or_else(|e| e.into_inner());
        let (at, len) = *tail.index.get(&key)?;
        let mut value = vec![0u8; len as usize];
        tail.file.seek(SeekFrom::Start(at)).ok()?;
        tail.file.read_exact(&mut value).ok()?;
        Some(value)
    }

    fn keep(&self, key: u64, value: &[u8]) {
        let Ok(len) = u32::try_from(value.len()) else {
            return;
        };
        let mut rec = Vec::with_capacity(value.len() + 20);
        rec.extend_from_slice(&key.to_le_bytes());
        rec.extend_from_slice(&len.to_le_bytes());
        rec.extend_from_slice(value);
        let check = Fnv::new().feed(&rec).0;
        rec.extend_from_slice(&check.to_le_bytes());
        // One write per record at the end of the last whole one; a failed write only
        // costs this piece (the next record overwrites what it left).
        let mut tail = self.tail.lock().unwrap_or_else(|e| e.into_inner());
        let end = tail.end;
        let written = tail
            .file
            .seek(SeekFrom::Start(end))
            .and_then(|_| tail.file.write_all(&rec));
        if written.is_ok() {
            tail.index.insert(key, (end + 12, len));
            tail.end = end + rec.len() as u64;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pieces_survive_and_a_torn_tail_is_dropped() {
        let t = tempfile::tempdir().unwrap();
        let out = t.path().join("o");
        let fp = fingerprint("test", &(1.5f64, "x"));
        // Hashed as written: the hash of the whole text, as before it was streamed.
        let text = format!(
            "{}\u{1f}test\u{1f}{:?}",
            env!("CARGO_PKG_VERSION"),
            (1.5f64, "x")
        );
        assert!(fp.ends_with(&format!("{:016x}\n", Fnv::new().feed(text.as_bytes()).0)));
        let j = open(&out, &fp, false).unwrap();
        j.keep(1, b"one");
        j.keep(2, &[0u8; 1000]);
        drop(j);
        // A kill in the middle of a record.
        let path = dir_of(&out).join("journal.bin");
        let mut f = OpenOptions::new().append(true).open(&path).unwrap();
        f.write_all(&3u64.to_le_bytes()).unwrap();
        f.write_all(&[9, 0]).unwrap();
        drop(f);
        assert!(open(&out, &fp, false).unwrap_err().contains("--resume"));
        let other = fingerprint("test", &(1.5000000000000002f64, "x"));
        assert!(open(&out, &other, true)
            .unwrap_err()
            .contains("other inputs"));
        let j = open(&out, &fp, true).unwrap();
        assert_eq!(j.recalled(), 2);
        assert_eq!(j.recall(1).unwrap(), b"one");
        assert_eq!(j.recall(3), None);
        j.keep(3, b"three");
        // A piece kept in this run is recalled too, and a key kept again reads its last.
        assert_eq!(j.recall(3).unwrap(), b"three");
        assert_eq!(j.recall(1).unwrap(), b"one");
        drop(j);
        let j = open(&out, &fp, true).unwrap();
        assert_eq!(j.recall(3).unwrap(), b"three", "appended after the cut");
        assert_eq!(j.recalled(), 3);
        j.remove();
        assert!(!dir_of(&out).exists());
    }

    #[test]
    fn a_damaged_record_ends_the_journal() {
        let t = tempfile::tempdir().unwrap();
        let out = t.path().join("o");
        let fp = fingerprint("test", &());
        let j = open(&out, &fp, false).unwrap();
        j.keep(1, b"aaaa");
        j.keep(2, b"bbbb");
        drop(j);
        let path = dir_of(&out).join("journal.bin");
        let mut bytes = std::fs::read(&path).unwrap();
        bytes[3] ^= 1; // the first key
        std::fs::write(&path, bytes).unwrap();
        let j = open(&out, &fp, true).unwrap();
        assert_eq!(j.recalled(), 0);
    }
}
