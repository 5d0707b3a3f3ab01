//! The output directory's life, all or nothing and race-free (`--out DIR`):
//!
//! 1. **Claim**, before any computation: `DIR` must not exist (or be an empty directory)
//!    unless `--force`; its parent is created; an advisory lock on `.DIR.lock` beside it
//!    keeps a second writer out (the kernel drops it when a process dies, even by SIGKILL);
//!    staging folders left by killed runs are removed; a unique staging directory
//!    `.DIR.staging-XXXXXX` is made beside `DIR`, which proves the location writable.
//! 2. **Publish**: the files are written into the staging directory, which then becomes
//!    `DIR` by one rename. `--force` first renames the old `DIR` aside and removes it after.
//!    Where a rename cannot work (another filesystem, a mount point), the staged tree is
//!    copied beside the target on its filesystem and renamed from there.
//! 3. **Release**: on SIGINT, SIGTERM or SIGHUP every claimed staging directory and lock
//!    file is removed before the process exits (128 + the signal), never in the middle of
//!    a move; at a normal exit [`release_all`] does the same.
//!
//! Single files (`--plot`, `--report`) are written to a unique temporary file beside the
//! target and renamed over it.

use std::fs::{File, OpenOptions};
use std::io;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, Once};

/// One claimed output directory.
#[derive(Debug)]
struct Claim {
    target: PathBuf,
    staging: PathBuf,
    lock_path: PathBuf,
    /// Holds the advisory lock while open.
    _lock: File,
}

/// Every directory this process has claimed and not yet published.
static CLAIMS: Mutex<Vec<Claim>> = Mutex::new(Vec::new());
/// Held during a move into place; the signal handler takes it before cleaning up, so a
/// signal never interrupts a move half-way.
static MOVING: Mutex<()> = Mutex::new(());
static HANDLER: Once = Once::new();

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// The parent of `dir` ("." for a bare name) and its file name.
fn split(dir: &Path) -> (PathBuf, String) {
    let parent = dir
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
        .to_path_buf();
    let stem = dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    (parent, stem)
}

fn is_empty_dir(dir: &Path) -> bool {
    std::fs::read_dir(dir).is_ok_and(|mut d| d.next().is_none())
}

/// Claim `dir` for this run (module notes, step 1). The error names the problem and what
/// to do; nothing has been computed yet when it is returned.
pub fn claim(dir: &Path, force: bool) -> Result<(), String> {
    if lock(&CLAIMS).iter().any(|c| c.target == dir) {
        return Ok(());
    }
    if dir.as_os_str().is_empty() || dir.file_name().is_none() {
        return Err(format!("'{}' does not name a directory", dir.display()));
    }
    if dir.exists() {
        if !dir.is_dir() {
            return Err(format!("{} exists and is not a directory", dir.display()));
        }
        if !force && !is_empty_dir(dir) {
            return Err(format!(
                "{} already exists; choose another directory, or add --force to replace it whole",
                dir.display()
            ));
        }
    }
    let (parent, stem) = split(dir);
    std::fs::create_dir_all(&parent)
        .map_err(|e| format!("cannot create {}: {e}", parent.display()))?;
    let lock_path = parent.join(format!(".{stem}.lock"));
    let lock_file = take_lock(&lock_path).map_err(|e| match e.kind() {
        io::ErrorKind::WouldBlock => format!(
            "another divertsim run is writing {} (it holds {}); wait for it, or choose another directory",
            dir.display(),
            lock_path.display()
        ),
        _ => format!("cannot write in {}: {e}", parent.display()),
    })?;
    remove_stale(&parent, &stem);
    let staging = tempfile::Builder::new()
        .prefix(&format!(".{stem}.staging-"))
        .tempdir_in(&parent)
        .map_err(|e| format!("cannot write in {}: {e}", parent.display()))?
        .keep();
    install_handler();
    lock(&CLAIMS).push(Claim {
        target: dir.to_path_buf(),
        staging,
        lock_path,
        _lock: lock_file,
    });
    Ok(())
}

/// Open and lock `path` without waiting. A lock taken on a file that another run removed
/// meanwhile is let go and taken again on the new file.
fn take_lock(path: &Path) -> io::Result<File> {
    use std::os::unix::fs::MetadataExt;
    for _ in 0..8 {
        let f = OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(path)?;
        match f.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => {
                return Err(io::Error::from(io::ErrorKind::WouldBlock))
            }
            Err(std::fs::TryLockError::Error(e)) => return Err(e),
        }
        let same = match (f.metadata(), std::fs::metadata(path)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        };
        if same {
            return Ok(f);
        }
    }
    Err(io::Error::other("the lock file keeps changing"))
}

/// Remove what killed runs left beside `DIR`: staging folders (and the older
/// `.DIR.partial-PID`) and a replaced directory not yet removed. Safe under the lock: no
/// live run can own them.
fn remove_stale(parent: &Path, stem: &str) {
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    let prefixes = [
        format!(".{stem}.staging-"),
        format!(".{stem}.replaced-"),
        format!(".{stem}.partial-"),
        format!(".{stem}.copy-"),
        format!(".{stem}.checkpoint-new-"),
    ];
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if prefixes.iter().any(|p| name.starts_with(p.as_str())) {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
}

/// Write `files` and what `render` draws into `dir`'s staging directory and move it into
/// place (module notes, step 2); claims `dir` first if the command has not (without
/// `--force`). On an error nothing of this run is left behind.
pub fn publish(
    dir: &Path,
    files: &[(String, Vec<u8>)],
    render: &mut dyn FnMut(&Path) -> Result<(), String>,
) -> Result<(), String> {
    claim(dir, false)?;
    let staging = lock(&CLAIMS)
        .iter()
        .find(|c| c.target == dir)
        .map(|c| c.staging.clone())
        .ok_or("the output directory was not claimed")?;
    let staged = (|| -> Result<(), String> {
        for (name, bytes) in files {
            let p = staging.join(name);
            std::fs::write(&p, bytes).map_err(|e| format!("cannot write {}: {e}", p.display()))?;
        }
        render(&staging)
    })();
    if let Err(e) = staged {
        release(dir);
        return Err(e);
    }
    hold_for_tests();
    let moved = {
        let _moving = lock(&MOVING);
        let moved = replace_dir(&staging, dir, &|a, b| std::fs::rename(a, b));
        if moved.is_ok() {
            // Moved: the staging directory is `dir` now, not ours to remove.
            if let Some(c) = lock(&CLAIMS).iter_mut().find(|c| c.target == dir) {
                c.staging = PathBuf::new();
            }
        }
        moved
    };
    release(dir);
    moved.map_err(|e| format!("cannot move the results into {}: {e}", dir.display()))
}

/// A test hook: DIVERTSIM_TEST_HOLD_BEFORE_MOVE=SECONDS pauses with everything staged,
/// just before the move, so a test can kill the process there.
fn hold_for_tests() {
    if let Some(s) = std::env::var("DIVERTSIM_TEST_HOLD_BEFORE_MOVE")
        .ok()
        .and_then(|v| v.parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s > 0.0)
    {
        eprintln!("(test hook) staged; holding {s} s before the move");
        std::thread::sleep(std::time::Duration::from_secs_f64(s.min(600.0)));
    }
}

/// Let `dir`'s claim go: remove its staging directory (if still there) and its lock file.
fn release(dir: &Path) {
    let claim = {
        let mut claims = lock(&CLAIMS);
        claims
            .iter()
            .position(|c| c.target == dir)
            .map(|i| claims.remove(i))
    };
    if let Some(c) = claim {
        drop_claim(c);
    }
}

fn drop_claim(c: Claim) {
    if !c.staging.as_os_str().is_empty() {
        let _ = std::fs::remove_dir_all(&c.staging);
    }
    // Removed while still locked: a run that opened the old file re-takes the new one.
    let _ = std::fs::remove_file(&c.lock_path);
}

/// Remove every claimed staging directory and lock file (at exit, or on a signal).
pub fn release_all() {
    let _moving = lock(&MOVING);
    let claims: Vec<Claim> = lock(&CLAIMS).drain(..).collect();
    for c in claims {
        drop_claim(c);
    }
}

fn install_handler() {
    HANDLER.call_once(|| {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        if let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) {
            std::thread::spawn(move || {
                if let Some(sig) = signals.forever().next() {
                    release_all();
                    std::process::exit(128 + sig);
                }
            });
        }
    });
}

type Rename<'a> = &'a dyn Fn(&Path, &Path) -> io::Result<()>;

/// Whether a rename failed because it cannot work here (another filesystem, a mount point)
/// rather than for a reason a copy would meet too.
fn needs_copy(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::CrossesDevices | io::ErrorKind::ResourceBusy
    )
}

/// Make the directory `from` become `to`: moved in whole if `to` does not exist; else the
/// old `to` is renamed aside, `from` renamed in, and the old one removed. Falls back to
/// copying when a rename cannot work (module notes).
fn replace_dir(from: &Path, to: &Path, rename: Rename<'_>) -> io::Result<()> {
    if !to.exists() {
        return move_dir(from, to, rename);
    }
    let (parent, stem) = split(to);
    let aside = tempfile::Builder::new()
        .prefix(&format!(".{stem}.replaced-"))
        .tempdir_in(&parent)?
        .keep();
    // The rename replaces the empty placeholder directory.
    match rename(to, &aside) {
        Ok(()) => {
            move_dir(from, to, rename)?;
            let _ = std::fs::remove_dir_all(&aside);
            Ok(())
        }
        Err(e) if needs_copy(&e) => {
            // A mount point cannot be renamed: empty it and copy the results in.
            let _ = std::fs::remove_dir(&aside);
            for entry in std::fs::read_dir(to)? {
                let p = entry?.path();
                if p.is_dir() {
                    std::fs::remove_dir_all(&p)?;
                } else {
                    std::fs::remove_file(&p)?;
                }
            }
            for entry in std::fs::read_dir(from)? {
                let entry = entry?;
                move_entry(&entry.path(), &to.join(entry.file_name()), rename)?;
            }
            let _ = std::fs::remove_dir_all(from);
            Ok(())
        }
        Err(e) => {
            let _ = std::fs::remove_dir(&aside);
            Err(e)
        }
    }
}

/// Rename the directory `from` to the absent `to`; across filesystems, copy it to a
/// temporary sibling of `to` and rename that (so `to` still appears whole).
fn move_dir(from: &Path, to: &Path, rename: Rename<'_>) -> io::Result<()> {
    match rename(from, to) {
        Err(e) if needs_copy(&e) => {
            let (parent, stem) = split(to);
            let copy = tempfile::Builder::new()
                .prefix(&format!(".{stem}.copy-"))
                .tempdir_in(&parent)?;
            copy_tree(from, copy.path())?;
            std::fs::rename(copy.path(), to)?;
            let _ = copy.keep();
            std::fs::remove_dir_all(from)
        }
        other => other,
    }
}

/// Move one file or directory entry; across filesystems by a copy under a temporary name
/// in the target directory, then a rename.
fn move_entry(from: &Path, to: &Path, rename: Rename<'_>) -> io::Result<()> {
    match rename(from, to) {
        Err(e) if needs_copy(&e) => {
            let dir = to.parent().unwrap_or(Path::new("."));
            if from.is_dir() {
                let copy = tempfile::Builder::new().prefix(".copy-").tempdir_in(dir)?;
                copy_tree(from, copy.path())?;
                std::fs::rename(copy.path(), to)?;
                let _ = copy.keep();
            } else {
                let copy = tempfile::Builder::new().prefix(".copy-").tempfile_in(dir)?;
                std::fs::copy(from, copy.path())?;
                copy.persist(to).map_err(|e| e.error)?;
            }
            Ok(())
        }
        other => other,
    }
}

fn copy_tree(from: &Path, to: &Path) -> io::Result<()> {
    std::fs::create_dir_all(to)?;
    for entry in std::fs::read_dir(from)? {
        let entry = entry?;
        let (src, dst) = (entry.path(), to.join(entry.file_name()));
        if entry.file_type()?.is_dir() {
            copy_tree(&src, &dst)?;
        } else {
            std::fs::copy(&src, &dst)?;
        }
    }
    Ok(())
}

/// Write one file atomically: `write` fills a unique temporary file beside `path` (same
/// extension, so a renderer picks the format), which is then renamed over `path`.
pub fn write_file(
    path: &Path,
    write: &mut dyn FnMut(&Path) -> Result<(), String>,
) -> Result<(), String> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let suffix = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let stem = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = tempfile::Builder::new()
        .prefix(&format!(".{stem}.tmp-"))
        .suffix(&suffix)
        .tempfile_in(dir)
        .map_err(|e| format!("cannot write in {}: {e}", dir.display()))?;
    write(tmp.path())?;
    tmp.persist(path).map_err(|e| e.error.to_string())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tree(dir: &Path) -> Vec<(String, Vec<u8>)> {
        let mut v: Vec<_> = walk(dir, dir);
        v.sort();
        v
    }

    fn walk(root: &Path, dir: &Path) -> Vec<(String, Vec<u8>)> {
        let mut v = Vec::new();
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                v.extend(walk(root, &p));
            } else {
                let rel = p.strip_prefix(root).unwrap().display().to_string();
                v.push((rel, std::fs::read(&p).unwrap()));
            }
        }
        v
    }

    fn staged(root: &Path) -> PathBuf {
        let s = root.join("staged");
        std::fs::create_dir_all(s.join("sub")).unwrap();
        std::fs::write(s.join("a.csv"), b"x,y\n1,2\n").unwrap();
        std::fs::write(s.join("sub/b.json"), b"{}").unwrap();
        s
    }

    /// A rename that always fails as across filesystems.
    fn cross_device(_: &Path, _: &Path) -> io::Result<()> {
        Err(io::Error::from(io::ErrorKind::CrossesDevices))
    }

    #[test]
    fn cross_device_fallback_copies_a_new_target_whole() {
        let t = tempfile::tempdir().unwrap();
        let from = staged(t.path());
        let want = tree(&from);
        let to = t.path().join("out");
        replace_dir(&from, &to, &cross_device).unwrap();
        assert_eq!(tree(&to), want);
        assert!(!from.exists());
        let left: Vec<_> = std::fs::read_dir(t.path()).unwrap().collect();
        assert_eq!(left.len(), 1, "only the target is left");
    }

    #[test]
    fn cross_device_fallback_replaces_a_mount_point_contents() {
        let t = tempfile::tempdir().unwrap();
        let from = staged(t.path());
        let want = tree(&from);
        let to = t.path().join("out");
        std::fs::create_dir_all(to.join("old")).unwrap();
        std::fs::write(to.join("stale.csv"), b"old").unwrap();
        replace_dir(&from, &to, &cross_device).unwrap();
        assert_eq!(tree(&to), want, "the stale files are gone");
        assert!(!from.exists());
    }

    /// A real move across filesystems where the machine has one (/dev/shm as a tmpfs).
    #[test]
    fn real_cross_device_move() {
        use std::os::unix::fs::MetadataExt;
        let shm = Path::new("/dev/shm");
        let t = tempfile::tempdir().unwrap();
        let Ok(m) = std::fs::metadata(shm) else {
            return;
        };
        if m.dev() == std::fs::metadata(t.path()).unwrap().dev() {
            return; // the injected cases above cover the fallback
        }
        let from = staged(t.path());
        let want = tree(&from);
        let other = tempfile::tempdir_in(shm).unwrap();
        let to = other.path().join("out");
        replace_dir(&from, &to, &|a, b| std::fs::rename(a, b)).unwrap();
        assert_eq!(tree(&to), want);
        // And replacing it from another filesystem again.
        let from = staged(t.path());
        std::fs::write(to.join("stale"), b"x").unwrap();
        replace_dir(&from, &to, &|a, b| std::fs::rename(a, b)).unwrap();
        assert_eq!(tree(&to), want);
    }

    #[test]
    fn replacing_keeps_nothing_of_the_old_directory() {
        let t = tempfile::tempdir().unwrap();
        let from = staged(t.path());
        let want = tree(&from);
        let to = t.path().join("out");
        std::fs::create_dir_all(&to).unwrap();
        std::fs::write(to.join("stale.csv"), b"old").unwrap();
        replace_dir(&from, &to, &|a, b| std::fs::rename(a, b)).unwrap();
        assert_eq!(tree(&to), want);
        let left: Vec<_> = std::fs::read_dir(t.path()).unwrap().collect();
        assert_eq!(left.len(), 1, "no replaced directory is left");
    }

    #[test]
    fn single_file_keeps_a_partial_named_file() {
        let t = tempfile::tempdir().unwrap();
        let partial = t.path().join("top.partial.svg");
        std::fs::write(&partial, b"mine").unwrap();
        let path = t.path().join("top.svg");
        write_file(&path, &mut |p| {
            assert_eq!(p.extension().unwrap(), "svg");
            std::fs::write(p, b"<svg/>").map_err(|e| e.to_string())
        })
        .unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"<svg/>");
        assert_eq!(std::fs::read(&partial).unwrap(), b"mine");
        assert_eq!(std::fs::read_dir(t.path()).unwrap().count(), 2);
    }
}
