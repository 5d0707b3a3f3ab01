//! The output directory's life, all or nothing and race-free (`--out DIR`):
//!
//! 1. **Claim**, before any computation: `DIR` must not exist (or be an empty directory)
//!    unless `--force`; its parent is created; an advisory lock on `.DIR.lock` beside it
//!    keeps a second writer out (the kernel drops it when a process dies, even by SIGKILL);
//!    staging folders left by killed runs are removed; a unique staging directory
//!    `.DIR.staging-XXXXXX` is made beside `DIR`, which proves the location writable.
//! 2. **Publish**: the files are written into the staging directory, which then becomes
//!    `DIR` by one rename. `--force` first renames the old `DIR` aside and removes it after.
//!    Where a rename cannot work (another filesystem), the staged tree is copied beside the
//!    target on its filesystem and renamed from there. A mount point is refused as `DIR`
//!    when claimed: it cannot be renamed, so its contents could not be replaced all or
//!    nothing.
//! 3. **Release**: on SIGINT, SIGTERM or SIGHUP every claimed staging directory and lock
//!    file is removed before the process exits (128 + the signal), never in the middle of
//!    a move; at a normal exit [`release_all`] does the same.
//!
//! Single files (`--plot`, `--report`) are written to a unique temporary file beside the
//! target and renamed over it.

use std::fs::{File, OpenOptions};
use std::io;
use std::os::unix::fs::PermissionsExt;
use std::path::{Component, Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, Once};

/// One claimed output directory.
#[derive(Debug)]
struct Claim {
    /// The target, absolute: who it is (the same folder however it was spelt).
    key: PathBuf,
    /// The target as given, normalised (for moves and messages).
    target: PathBuf,
    /// `--force`: an existing target may be replaced.
    force: bool,
    staging: PathBuf,
    lock_path: PathBuf,
    /// Removed right after a successful move, still under the lock (a checkpoint).
    retire: Vec<PathBuf>,
    /// The folders this claim made for `DIR`'s parent (outermost first): removed again, if
    /// still empty, when the run ends without publishing (bad input leaves nothing behind).
    made: Vec<PathBuf>,
    /// Holds the advisory lock while open.
    _lock: File,
}

/// Every directory this process has claimed and not yet published.
static CLAIMS: Mutex<Vec<Claim>> = Mutex::new(Vec::new());
/// Held during a move into place; the signal handler takes it for good before cleaning up
/// and exiting, so a signal never interrupts a move half-way and no move starts after it.
static MOVING: Mutex<()> = Mutex::new(());
/// Set by the signal handler: no move may start.
static SHUTTING_DOWN: AtomicBool = AtomicBool::new(false);
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

/// The hidden sibling `.DIR.WHAT` of `dir` (its checkpoint, its lock).
pub fn beside(dir: &Path, what: &str) -> PathBuf {
    let (parent, stem) = split(dir);
    parent.join(format!(".{stem}.{what}"))
}

fn is_empty_dir(dir: &Path) -> bool {
    std::fs::read_dir(dir).is_ok_and(|mut d| d.next().is_none())
}

/// `dir` without `.` components or a trailing `/`, and its absolute form; an error for a
/// path that does not end in a folder name (`..`, `/`, empty).
fn normalise(dir: &Path) -> Result<(PathBuf, PathBuf), String> {
    let target: PathBuf = dir
        .components()
        .filter(|c| !matches!(c, Component::CurDir))
        .collect();
    if !matches!(target.components().next_back(), Some(Component::Normal(_))) {
        return Err(format!(
            "'{}' does not name a directory; give a path that ends in a folder name",
            dir.display()
        ));
    }
    let key = std::path::absolute(&target).unwrap_or_else(|_| target.clone());
    Ok((target, key))
}

/// Whether the directory `dir` is a mount point (or the root): another filesystem than its
/// parent's, or its own parent.
fn is_mount_point(dir: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    let Ok(real) = std::fs::canonicalize(dir) else {
        return false;
    };
    let Some(parent) = real.parent() else {
        return true; // the root
    };
    match (std::fs::metadata(&real), std::fs::metadata(parent)) {
        (Ok(d), Ok(p)) => d.dev() != p.dev() || d.ino() == p.ino(),
        _ => false,
    }
}

/// Whether an existing `target` is refused: not a directory, a mount point (whose contents
/// cannot be replaced all or nothing: it cannot be renamed, and copying into it can stop
/// half-way on a full disk), or not empty without `force`.
fn refused(target: &Path, force: bool) -> Option<String> {
    if !target.exists() {
        return None;
    }
    if !target.is_dir() {
        return Some(format!(
            "{} exists and is not a directory",
            target.display()
        ));
    }
    if is_mount_point(target) {
        return Some(format!(
            "{} is a mount point: its contents cannot be replaced all or nothing (a mount \
             point cannot be renamed); give a folder inside it, e.g. {}",
            target.display(),
            target.join("run1").display()
        ));
    }
    (!force && !is_empty_dir(target)).then(|| {
        format!(
            "{} already exists; choose another directory, or add --force to replace it whole",
            target.display()
        )
    })
}

/// Directories made for the user: the usual mode, less the umask (tempfile's 0700 would
/// make the published folder private).
fn user_dir() -> tempfile::Builder<'static, 'static> {
    let mut b = tempfile::Builder::new();
    b.permissions(std::fs::Permissions::from_mode(0o777));
    b
}

/// Claim `dir` for this run (module notes, step 1). The error names the problem and what
/// to do; nothing has been computed yet when it is returned.
pub fn claim(dir: &Path, force: bool) -> Result<(), String> {
    let (target, key) = normalise(dir)?;
    if lock(&CLAIMS).iter().any(|c| c.key == key) {
        return Ok(());
    }
    if let Some(e) = refused(&target, force) {
        return Err(e);
    }
    let (parent, stem) = split(&target);
    // The handler first: a signal from here on finds the claim and cleans up after it.
    install_handler();
    let made: Vec<PathBuf> = {
        let mut missing: Vec<PathBuf> = parent
            .ancestors()
            .filter(|a| !a.as_os_str().is_empty() && !a.exists())
            .map(Path::to_path_buf)
            .collect();
        missing.reverse();
        missing
    };
    if let Err(e) = std::fs::create_dir_all(&parent) {
        remove_made(&made);
        return Err(format!("cannot create {}: {e}", parent.display()));
    }
    let lock_path = beside(&target, "lock");
    let lock_file = take_lock(&lock_path).map_err(|e| match e.kind() {
        io::ErrorKind::WouldBlock => format!(
            "another divertsim run is writing {} (it holds {}); wait for it, or choose another directory",
            target.display(),
            lock_path.display()
        ),
        _ => format!("cannot write in {}: {e}", parent.display()),
    });
    let lock_file = match lock_file {
        Ok(f) => f,
        Err(e) => {
            remove_made(&made);
            return Err(e);
        }
    };
    remove_stale(&parent, &stem, &target);
    // Again under the lock: a restored or newly made target counts.
    if let Some(e) = refused(&target, force) {
        let _ = std::fs::remove_file(&lock_path);
        remove_made(&made);
        return Err(e);
    }
    // The staging folder is made and registered under the move lock, which the signal
    // handler takes before it cleans up: a signal never falls between the two.
    let _moving = lock(&MOVING);
    if SHUTTING_DOWN.load(Ordering::SeqCst) {
        return Err("interrupted".into());
    }
    let staging = match user_dir()
        .prefix(&format!(".{stem}.staging-"))
        .tempdir_in(&parent)
    {
        Ok(d) => d.keep(),
        Err(e) => {
            let _ = std::fs::remove_file(&lock_path);
            remove_made(&made);
            return Err(format!("cannot write in {}: {e}", parent.display()));
        }
    };
    lock(&CLAIMS).push(Claim {
        key,
        target,
        force,
        staging,
        lock_path,
        retire: Vec::new(),
        made,
        _lock: lock_file,
    });
    Ok(())
}

/// Remove `path` (a checkpoint beside `dir`) right after `dir` is published, while the lock
/// still keeps other runs away. `dir` must be claimed.
pub fn retire_on_publish(dir: &Path, path: PathBuf) {
    if let Ok((_, key)) = normalise(dir) {
        if let Some(c) = lock(&CLAIMS).iter_mut().find(|c| c.key == key) {
            c.retire.push(path);
        }
    }
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

/// Whether `name` is `prefix` followed by what this module generates after it: tempfile's
/// six letters and digits (or a process id for the older `.partial-`), nothing a user
/// would name a folder by chance.
fn generated(name: &str, prefix: &str, digits: bool) -> bool {
    name.strip_prefix(prefix).is_some_and(|rest| {
        if digits {
            !rest.is_empty() && rest.bytes().all(|b| b.is_ascii_digit())
        } else {
            rest.len() == 6 && rest.bytes().all(|b| b.is_ascii_alphanumeric())
        }
    })
}

/// Clean up after killed runs beside `DIR`: a replaced directory is put back when `DIR` is
/// missing (a kill between the two renames of `--force`), else removed, and staging
/// folders are removed. Safe under the lock: no live run can own them.
fn remove_stale(parent: &Path, stem: &str, target: &Path) {
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    let replaced = format!(".{stem}.replaced-");
    let others = [
        (format!(".{stem}.staging-"), false),
        (format!(".{stem}.copy-"), false),
        (format!(".{stem}.checkpoint-new-"), false),
        (format!(".{stem}.partial-"), true),
        (format!(".{stem}.retired-"), true),
    ];
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if generated(&name, &replaced, false) {
            if !target.exists() && std::fs::rename(e.path(), target).is_ok() {
                eprintln!(
                    "note: restored {} from a run killed while replacing it",
                    target.display()
                );
                continue;
            }
            let _ = std::fs::remove_dir_all(e.path());
        } else if others.iter().any(|(p, d)| generated(&name, p, *d)) {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
}

/// Every scenario file staged in `staging` (at any depth) with the files it names copied
/// beside it ([`divertsim_api::output::bundle_inputs`]), so that the folder reruns as it is.
fn bundle_inputs(staging: &Path) -> Result<(), String> {
    fn tomls(root: &Path, dir: &Path, out: &mut Vec<(String, Vec<u8>)>) -> std::io::Result<()> {
        for e in std::fs::read_dir(dir)? {
            let e = e?;
            let p = e.path();
            let kind = e.file_type()?;
            if kind.is_dir() {
                tomls(root, &p, out)?;
            } else if kind.is_file() && p.extension().is_some_and(|x| x == "toml") {
                let name = p.strip_prefix(root).unwrap_or(&p);
                let name = name.to_string_lossy().replace('\\', "/");
                out.push((name, std::fs::read(&p)?));
            }
        }
        Ok(())
    }
    let mut files = Vec::new();
    tomls(staging, staging, &mut files).map_err(|e| format!("cannot read the outputs: {e}"))?;
    let before: Vec<Vec<u8>> = files.iter().map(|(_, b)| b.clone()).collect();
    if divertsim_api::output::bundle_inputs(&mut files) == 0 {
        return Ok(());
    }
    for (k, (name, bytes)) in files.iter().enumerate() {
        if before.get(k) == Some(bytes) {
            continue;
        }
        let p = staging.join(name);
        std::fs::write(&p, bytes).map_err(|e| format!("cannot write {}: {e}", p.display()))?;
    }
    Ok(())
}

/// Write `files` and what `render` draws into `dir`'s staging directory and move it into
/// place (module notes, step 2); claims `dir` first if the command has not (without
/// `--force`). On an error nothing of this run is left behind and an old `dir` is kept.
pub fn publish(
    dir: &Path,
    files: &[(String, Vec<u8>)],
    render: &mut dyn FnMut(&Path) -> Result<(), String>,
) -> Result<(), String> {
    claim(dir, false)?;
    let (_, key) = normalise(dir)?;
    let (target, staging, force) = lock(&CLAIMS)
        .iter()
        .find(|c| c.key == key)
        .map(|c| (c.target.clone(), c.staging.clone(), c.force))
        .ok_or("the output directory was not claimed")?;
    let staged = (|| -> Result<(), String> {
        write_into(&staging, files)?;
        render(&staging)?;
        bundle_inputs(&staging)
    })();
    if let Err(e) = staged {
        release(&key);
        return Err(e);
    }
    hold_for_tests("DIVERTSIM_TEST_HOLD_BEFORE_MOVE");
    let moved = {
        let _moving = lock(&MOVING);
        if SHUTTING_DOWN.load(Ordering::SeqCst) {
            Err("interrupted".to_string())
        } else if let Some(e) = refused(&target, force) {
            // Made or filled by someone else during the run: never replaced without --force.
            Err(format!("{e} (it appeared during the run)"))
        } else {
            let moved = replace_dir(&staging, &target, &|a, b| std::fs::rename(a, b))
                .map_err(|e| format!("cannot move the results into {}: {e}", target.display()));
            if moved.is_ok() {
                let mut claims = lock(&CLAIMS);
                if let Some(c) = claims.iter_mut().find(|c| c.key == key) {
                    // Moved: the staging directory is `dir` now, not ours to remove.
                    c.staging = PathBuf::new();
                    for p in c.retire.drain(..) {
                        retire(&p);
                    }
                }
            }
            moved
        }
    };
    release(&key);
    moved
}

/// Remove a directory by renaming it aside first, so that a kill leaves it whole or gone.
fn retire(path: &Path) {
    if !path.exists() {
        return;
    }
    let gone = path.with_extension(format!("retired-{}", std::process::id()));
    if std::fs::rename(path, &gone).is_ok() {
        let _ = std::fs::remove_dir_all(&gone);
    }
}

/// Test hooks: `VAR=SECONDS` pauses there (before the move: everything staged; in the
/// middle of a `--force` replacement: the old output renamed aside), so that a test can
/// kill the process at that point.
fn hold_for_tests(var: &str) {
    if let Some(s) = std::env::var(var)
        .ok()
        .and_then(|v| v.parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s > 0.0)
    {
        eprintln!("(test hook) {var}: holding {s} s");
        std::thread::sleep(std::time::Duration::from_secs_f64(s.min(600.0)));
    }
}

/// Let `dir`'s claim go: remove its staging directory (if still there) and its lock file.
fn release(key: &Path) {
    let claim = {
        let mut claims = lock(&CLAIMS);
        claims
            .iter()
            .position(|c| c.key == key)
            .map(|i| claims.remove(i))
    };
    if let Some(c) = claim {
        drop_claim(c);
    }
}

fn drop_claim(c: Claim) {
    let published = c.staging.as_os_str().is_empty();
    if !published {
        let _ = std::fs::remove_dir_all(&c.staging);
    }
    // Removed while still locked: a run that opened the old file re-takes the new one.
    let _ = std::fs::remove_file(&c.lock_path);
    if !published {
        remove_made(&c.made);
    }
}

/// The folders a claim made for `DIR`'s parent (outermost first), innermost first, each
/// only if nothing else went into it.
fn remove_made(made: &[PathBuf]) {
    for d in made.iter().rev() {
        let _ = std::fs::remove_dir(d);
    }
}

/// Remove every claimed staging directory and lock file (at the end of a command).
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
                    SHUTTING_DOWN.store(true, Ordering::SeqCst);
                    // Waits for a move in progress, and is never given back: no move
                    // starts between the cleanup and the exit.
                    let moving = lock(&MOVING);
                    let claims: Vec<Claim> = lock(&CLAIMS).drain(..).collect();
                    for c in claims {
                        drop_claim(c);
                    }
                    std::mem::forget(moving);
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
/// copying when the move of `from` cannot be a rename (module notes). An old `to` that
/// cannot be renamed aside (a mount point, refused when claimed) is kept as it is: its
/// contents are never removed to make room.
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
            hold_for_tests("DIVERTSIM_TEST_HOLD_MID_REPLACE");
            if let Err(e) = move_dir(from, to, rename) {
                // The old output back in place (a failed copy may have left a partial one).
                let _ = std::fs::remove_dir_all(to);
                let _ = std::fs::rename(&aside, to);
                return Err(e);
            }
            let _ = std::fs::remove_dir_all(&aside);
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
            let copy = user_dir()
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

/// `cp -r from to`: a folder tree copied file by file.
pub(crate) fn copy_tree(from: &Path, to: &Path) -> io::Result<()> {
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

/// Write named files (a command's tables, a report's linked pages) into a staging folder,
/// each at its relative path, its folders made as needed.
pub fn write_into<B: AsRef<[u8]>>(staging: &Path, files: &[(String, B)]) -> Result<(), String> {
    for (name, bytes) in files {
        let p = staging.join(name);
        let cannot = |e: io::Error| format!("cannot write {}: {e}", p.display());
        if let Some(parent) = p.parent() {
            std::fs::create_dir_all(parent).map_err(cannot)?;
        }
        std::fs::write(&p, bytes).map_err(cannot)?;
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
        .permissions(std::fs::Permissions::from_mode(0o666))
        .tempfile_in(dir)
        .map_err(|e| format!("cannot write in {}: {e}", dir.display()))?;
    write(tmp.path())?;
    tmp.persist(path).map_err(|e| e.error.to_string())?;
    Ok(())
}

/// The files (relative names) that differ between two folders, or are in one only.
pub fn folder_differences(fresh: &Path, committed: &Path) -> std::io::Result<Vec<PathBuf>> {
    let (a, b) = (files_of(fresh)?, files_of(committed).unwrap_or_default());
    let names: std::collections::BTreeSet<&PathBuf> = a.keys().chain(b.keys()).collect();
    Ok(names
        .into_iter()
        .filter(|n| a.get(*n) != b.get(*n))
        .cloned()
        .collect())
}

/// Every file under a folder by its relative name, with its bytes.
fn files_of(dir: &Path) -> std::io::Result<std::collections::BTreeMap<PathBuf, Vec<u8>>> {
    let mut out = std::collections::BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d)? {
            let entry = entry?;
            if entry.file_type()?.is_dir() {
                stack.push(entry.path());
            } else if let Ok(rel) = entry.path().strip_prefix(dir) {
                out.insert(rel.to_path_buf(), std::fs::read(entry.path())?);
            }
        }
    }
    Ok(out)
}

/// Put a fresh folder in place of a committed one: copied beside it, then swapped in.
pub fn replace_folder(fresh: &Path, to: &Path) -> std::io::Result<()> {
    let staged = to.with_extension(format!("new-{}", std::process::id()));
    copy_tree(fresh, &staged)?;
    let old = to.with_extension(format!("old-{}", std::process::id()));
    if to.exists() {
        std::fs::rename(to, &old)?;
    }
    std::fs::rename(&staged, to)?;
    if old.exists() {
        std::fs::remove_dir_all(&old)?;
    }
    Ok(())
}

/// Write `bytes` to `path` whole or not at all (a temporary file renamed).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    write_file(path, &mut |tmp| {
        std::fs::write(tmp, bytes).map_err(|e| e.to_string())
    })
    .map_err(std::io::Error::other)
}

/// Copy a file whole or not at all, making its folder.
pub fn copy_atomic(from: &Path, to: &Path) -> std::io::Result<()> {
    if let Some(dir) = to.parent() {
        std::fs::create_dir_all(dir)?;
    }
    write_atomic(to, &std::fs::read(from)?)
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

    /// Hostile input round three: an old output that cannot be renamed aside (a mount
    /// point) was emptied and refilled by copying, half-written on a full disk. It is kept
    /// whole now, and the move reports the error.
    #[test]
    fn mount_point_contents_are_never_emptied_to_make_room() {
        let t = tempfile::tempdir().unwrap();
        let from = staged(t.path());
        let to = t.path().join("out");
        std::fs::create_dir_all(to.join("old")).unwrap();
        std::fs::write(to.join("stale.csv"), b"old").unwrap();
        let before = tree(&to);
        assert!(replace_dir(&from, &to, &cross_device).is_err());
        assert_eq!(tree(&to), before, "the old output is whole");
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
    fn a_failed_move_puts_the_old_output_back() {
        let t = tempfile::tempdir().unwrap();
        let from = staged(t.path());
        let to = t.path().join("out");
        std::fs::create_dir_all(&to).unwrap();
        std::fs::write(to.join("old.csv"), b"old").unwrap();
        let old = tree(&to);
        let calls = std::cell::Cell::new(0);
        let second_fails = |a: &Path, b: &Path| {
            calls.set(calls.get() + 1);
            if calls.get() == 2 {
                Err(io::Error::from(io::ErrorKind::StorageFull))
            } else {
                std::fs::rename(a, b)
            }
        };
        assert!(replace_dir(&from, &to, &second_fails).is_err());
        assert_eq!(tree(&to), old);
        let hidden: Vec<_> = std::fs::read_dir(t.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with(".out."))
            .collect();
        assert!(hidden.is_empty(), "{hidden:?}");
    }

    #[test]
    fn targets_are_normalised_and_generated_names_recognised() {
        let (t, _) = normalise(Path::new("a/b/./")).unwrap();
        assert_eq!(t, Path::new("a/b"));
        let (t, k) = normalise(Path::new("./out")).unwrap();
        assert_eq!(t, Path::new("out"));
        assert!(k.is_absolute());
        for bad in ["..", "/", "a/..", ""] {
            assert!(normalise(Path::new(bad)).is_err(), "{bad}");
        }
        assert!(generated(".o.staging-a1B2c3", ".o.staging-", false));
        assert!(!generated(".o.staging-a1B2c", ".o.staging-", false));
        assert!(!generated(".o.copy-my notes", ".o.copy-", false));
        assert!(generated(".o.partial-123", ".o.partial-", true));
        assert!(!generated(".o.partial-x1", ".o.partial-", true));
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
