//! The files a scenario reads and which of them it may read: the scenario file, its `base`
//! chain, the drive table (`machine.drive.table`) and the parcel records (`mix.records`).
//!
//! The rule, so that a scenario file from elsewhere reads only the files that travel with it:
//! - a path in a scenario file is relative to that file; a path given with `--set` is
//!   relative to the working directory;
//! - it must stay there or below: an absolute path, or one with a `..` component, is refused
//!   unless [`LoadOptions::allow_outside_paths`] (`--allow-outside-paths`);
//! - it must name a regular file: a directory, a FIFO (whose open would wait for a writer)
//!   or a device such as /dev/zero (which never ends) is refused before it is opened;
//! - no error shows what such a file holds: a TOML error names the line, the column and the
//!   parser's message, never the text around it (the CSV readers name line and column).
//!
//! - symbolic links are resolved before the rule applies: a link inside the directory to a
//!   file outside it is refused like the outside path itself (and its content is never read).

use super::Problem;
use std::io::Read;
use std::path::{Component, Path};

/// How a scenario is loaded.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// Read files outside the scenario's directory (or, for `--set`, the working
    /// directory): absolute paths and paths with a `..` component.
    pub allow_outside_paths: bool,
}

/// The keys whose values are paths of files to read, as key paths.
pub const PATH_KEYS: [&[&str]; 4] = [
    &["base"],
    &["machine", "drive", "table"],
    &["mix", "records"],
    &["line", "arrivals"],
];

/// Largest scenario file read [bytes]: far beyond any real scenario, small enough that
/// `/dev/zero` or a runaway pipe given as the scenario ends in an error, not in memory
/// exhaustion.
pub const MAX_SCENARIO_BYTES: u64 = 16 << 20;

/// Why `raw` leaves the directory it is relative to, if it does.
fn leaves(raw: &str) -> Option<&'static str> {
    let p = Path::new(raw);
    if p.is_absolute()
        || p.has_root()
        || matches!(p.components().next(), Some(Component::Prefix(_)))
    {
        Some("is an absolute path")
    } else if p.components().any(|c| c == Component::ParentDir) {
        Some("has a `..` component")
    } else {
        None
    }
}

/// Where a path was written.
#[derive(Debug, Clone, Copy)]
pub enum Origin<'a> {
    /// In this scenario file.
    File(&'a str),
    /// With `--set`.
    Set,
}

/// Whether `path`, its symbolic links resolved, lies outside `dir` (its links resolved). A
/// path that does not resolve (a missing file) is not outside: reading it reports it.
fn escapes_by_link(path: &Path, dir: &Path) -> bool {
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    match (std::fs::canonicalize(path), std::fs::canonicalize(dir)) {
        (Ok(target), Ok(root)) => !target.starts_with(&root),
        _ => false,
    }
}

/// The problem with the path `raw` at `key`, relative to `dir` (its file's directory, or
/// the working directory for `--set`), under `options`, if there is one: it is absolute,
/// climbs with `..`, or resolves through a symbolic link to a file outside `dir`.
pub fn outside_problem(
    key: &str,
    raw: &str,
    dir: &Path,
    origin: Origin<'_>,
    options: LoadOptions,
) -> Option<Problem> {
    if options.allow_outside_paths {
        return None;
    }
    let why = match leaves(raw) {
        Some(why) => why,
        None if escapes_by_link(&dir.join(raw), dir) => {
            "is a symbolic link (or passes through one) to a file outside that directory"
        }
        None => return None,
    };
    let (prefix, rule) = match origin {
        Origin::File(file) => (
            format!("in {file}: "),
            "a scenario file may name only files in its own directory or below it",
        ),
        Origin::Set => (
            String::new(),
            "a path given with --set is relative to the working directory and may name only files there or below it",
        ),
    };
    Some(Problem::new(
        key,
        format!("{prefix}\"{raw}\" {why}; {rule}; add --allow-outside-paths to read it anyway"),
    ))
}

/// `path` is a regular file (checked before opening: opening a FIFO waits for a writer);
/// else why it cannot be read.
pub(crate) fn regular_file(path: &Path) -> Result<(), String> {
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() => Ok(()),
        Ok(m) if m.is_dir() => Err("it is a directory; allowed: a regular file".into()),
        Ok(_) => Err(
            "it is not a regular file (a FIFO, a socket or a device); allowed: a regular file"
                .into(),
        ),
        Err(e) => Err(e.to_string()),
    }
}

/// The text of a scenario file. A file a scenario names (`regular`) must be a regular file;
/// the one named on the command line may also be a pipe (`<(generate)`); either is read to
/// at most [`MAX_SCENARIO_BYTES`]. Else why it cannot be read.
pub(crate) fn scenario_text(path: &Path, regular: bool) -> Result<String, String> {
    if regular {
        regular_file(path)?;
    }
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    capped_text(file)
}

/// The text of the regular file `path` (`what`: "a track", "a drive table", ...), refused
/// by its size before it is read if larger than `max` bytes, and read to at most `max`
/// (a file growing meanwhile).
pub(crate) fn capped_file_text(path: &Path, max: u64, what: &str) -> Result<String, String> {
    let too_large = || {
        format!(
            "it is larger than {} MiB, the most {what} may have",
            max >> 20
        )
    };
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    if file.metadata().map_err(|e| e.to_string())?.len() > max {
        return Err(too_large());
    }
    read_capped(file, max, &too_large)
}

/// Text read to at most [`MAX_SCENARIO_BYTES`].
pub(crate) fn capped_text(r: impl Read) -> Result<String, String> {
    read_capped(r, MAX_SCENARIO_BYTES, &|| {
        format!(
            "it is larger than {} MiB; a scenario file is a short text",
            MAX_SCENARIO_BYTES >> 20
        )
    })
}

/// Text read to at most `max` bytes; beyond, the error `too_large` gives.
fn read_capped(r: impl Read, max: u64, too_large: &dyn Fn() -> String) -> Result<String, String> {
    let mut text = String::new();
    r.take(max + 1)
        .read_to_string(&mut text)
        .map_err(|e| e.to_string())?;
    if text.len() as u64 > max {
        return Err(too_large());
    }
    Ok(text)
}

/// Parse TOML; an error names the line, the column and the parser's message, and shows
/// none of the text (the file may be anything).
pub fn parse_toml(text: &str) -> Result<toml::Table, String> {
    text.parse::<toml::Table>().map_err(|e| {
        let at = e
            .span()
            .map(|s| {
                let before = &text[..s.start.min(text.len())];
                let line = before.matches('\n').count() + 1;
                let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
                format!(" at line {line}, column {column}")
            })
            .unwrap_or_default();
        let message: Vec<&str> = e
            .message()
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty())
            .collect();
        format!("not valid TOML{at}: {}", redact(&message.join("; ")))
    })
}

/// The parser's message without what it quotes from the file (a duplicate key's name,
/// say): only its own words and the `expected` tokens stay.
fn redact(message: &str) -> String {
    // Quoted fragments are either the parser's expected tokens (short, punctuation or
    // keywords) or text of the file; keep the former.
    let mut out = String::new();
    let mut parts = message.split('`');
    if let Some(first) = parts.next() {
        out.push_str(first);
    }
    let mut quoted = true;
    for part in parts {
        if quoted {
            let token = part.len() <= 6 && !part.chars().any(char::is_alphanumeric)
                || ["true", "false", "inf", "nan"].contains(&part);
            out.push('`');
            out.push_str(if token { part } else { "…" });
            out.push('`');
        } else {
            out.push_str(part);
        }
        quoted = !quoted;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn toml_errors_name_the_place_but_never_the_text() {
        for (text, place) in [
            ("root:x:0:0:secret\n", "line 1"),
            ("a = 1\nsecret = \n", "line 2"),
            ("secret = 1\nsecret = 2\n", "line 2"),
            ("[secret\n", "line 1"),
            ("x = \"secret\n", "line 1"),
            ("x = [1, 2\nsecret", "line 2"),
        ] {
            let e = parse_toml(text).unwrap_err();
            assert!(
                e.starts_with("not valid TOML") && e.contains(place),
                "{text:?}: {e}"
            );
            assert!(
                !e.contains("secret") && !e.contains("root"),
                "{text:?}: {e}"
            );
        }
    }

    #[test]
    fn outside_paths_are_absolute_or_climb() {
        let none = LoadOptions::default();
        for (raw, refused) in [
            ("alpha.csv", false),
            ("sub/alpha.csv", false),
            ("./alpha.csv", false),
            ("a..b.csv", false),
            ("../alpha.csv", true),
            ("sub/../../alpha.csv", true),
            ("/etc/passwd", true),
        ] {
            let p = outside_problem("mix.records", raw, Path::new("."), Origin::Set, none);
            assert_eq!(p.is_some(), refused, "{raw}");
            if let Some(p) = p {
                assert!(p.message.contains(raw) && p.message.contains("--allow-outside-paths"));
            }
            let allowed = LoadOptions {
                allow_outside_paths: true,
            };
            assert!(
                outside_problem("mix.records", raw, Path::new("."), Origin::Set, allowed).is_none()
            );
        }
    }

    /// Hostile input round three: a link inside the scenario's folder to a file outside it
    /// was read (its values copied into outputs, echoed in errors). Links are resolved
    /// before the rule applies; a link that stays inside is fine.
    #[cfg(unix)]
    #[test]
    fn symlink_to_a_file_outside_the_folder_is_refused() {
        let root = std::env::temp_dir().join(format!("divertsim-link-{}", std::process::id()));
        let (scen, elsewhere) = (root.join("scen"), root.join("elsewhere"));
        std::fs::create_dir_all(&scen).unwrap();
        std::fs::create_dir_all(&elsewhere).unwrap();
        std::fs::write(elsewhere.join("secret.toml"), "x = 1\n").unwrap();
        std::fs::write(scen.join("inside.toml"), "x = 1\n").unwrap();
        std::os::unix::fs::symlink("../elsewhere/secret.toml", scen.join("b.toml")).unwrap();
        std::os::unix::fs::symlink("inside.toml", scen.join("c.toml")).unwrap();
        std::os::unix::fs::symlink("../elsewhere", scen.join("sub")).unwrap();
        let none = LoadOptions::default();
        let origin = Origin::File("scen/a.toml");
        for raw in ["b.toml", "sub/secret.toml"] {
            let p = outside_problem("base", raw, &scen, origin, none).expect(raw);
            assert!(p.message.contains("symbolic link"), "{}", p.message);
            assert!(p.message.contains("--allow-outside-paths"), "{}", p.message);
            let allowed = LoadOptions {
                allow_outside_paths: true,
            };
            assert!(outside_problem("base", raw, &scen, origin, allowed).is_none());
        }
        for raw in ["c.toml", "inside.toml", "missing.toml"] {
            assert!(
                outside_problem("base", raw, &scen, origin, none).is_none(),
                "{raw}"
            );
        }
        let _ = std::fs::remove_dir_all(&root);
    }

    #[test]
    fn endless_input_ends_in_an_error() {
        let e = capped_text(std::io::repeat(b'a')).unwrap_err();
        assert!(e.contains("larger than 16 MiB"), "{e}");
    }
}
