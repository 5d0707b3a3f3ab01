//! The files a scenario reads and which of them it may read: the scenario file, its `base`
//! chain, the drive tables (`machine.drive.table`, and the same key in a further diverter's
//! `line.diverters[K].machine`), the parcel records (`mix.records`) and the arrivals log
//! (`line.arrivals`).
//!
//! The rule, so that a scenario file from elsewhere reads only the files that travel with it:
//! - it applies to every value that names a file, wherever it sits: [`FILE_KEYS`] says which
//!   keys name files by their section, and [`named_files`] finds them at any depth (nested
//!   tables, arrays of tables, a table set whole by an override or a sweep), so that a key
//!   met in a new place cannot skip the rule;
//! - a path in a scenario file is relative to that file; a path given with `--set` is
//!   relative to the working directory; an edge whose overrides come from elsewhere (the
//!   studio's page) refuses any file an override names ([`LoadOptions::overrides_name_no_files`]);
//! - it must stay there or below: an absolute path, or one with a `..` component, is refused
//!   unless [`LoadOptions::allow_outside_paths`] (`--allow-outside-paths`);
//! - it must name a regular file: a directory, a FIFO (whose open would wait for a writer)
//!   or a device such as /dev/zero (which never ends) is refused; the file is opened without
//!   waiting and checked again once open (`open_regular`), so that a file swapped for a FIFO
//!   between the two cannot hang the run;
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
    /// Refuse every file that an override names (`--set`, a sweep's value): the rule of an
    /// edge whose overrides come from a web page (the studio), which reads no file beyond
    /// its scenario's own.
    pub overrides_name_no_files: bool,
}

/// The keys that name files, as (section, key): a value at `key` in a table reached under the
/// key `section` (an array's items under the array's key), at any depth; `""`: the scenario's
/// top level only. So `drive.table` is `machine.drive.table` and also
/// `line.diverters[K].machine.drive.table`.
pub const FILE_KEYS: [(&str, &str); 4] = [
    ("", "base"),
    ("drive", "table"),
    ("mix", "records"),
    ("line", "arrivals"),
];

/// Where [`FILE_KEYS`] sit in a scenario file's own sections (the studio's page keeps them
/// out of its editor).
pub const PATH_KEYS: [&[&str]; 4] = [
    &["base"],
    &["machine", "drive", "table"],
    &["mix", "records"],
    &["line", "arrivals"],
];

/// Every value in `table` that names a file ([`FILE_KEYS`]), at any depth, with its dotted key
/// (`line.diverters[0].machine.drive.table`), in the table's order.
pub fn named_files(table: &mut toml::Table) -> Vec<(String, &mut toml::Value)> {
    let mut out = Vec::new();
    walk(table, "", "", &mut out);
    out
}

fn walk<'a>(
    table: &'a mut toml::Table,
    prefix: &str,
    section: &str,
    out: &mut Vec<(String, &'a mut toml::Value)>,
) {
    let top = prefix.is_empty();
    for (k, v) in table.iter_mut() {
        let key = if top {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        let names_a_file = FILE_KEYS
            .iter()
            .any(|&(s, name)| name == k && if s.is_empty() { top } else { s == section });
        match v {
            _ if names_a_file => out.push((key, v)),
            toml::Value::Table(t) => walk(t, &key, k, out),
            toml::Value::Array(items) => {
                for (i, item) in items.iter_mut().enumerate() {
                    if let toml::Value::Table(t) = item {
                        walk(t, &format!("{key}[{i}]"), k, out);
                    }
                }
            }
            _ => {}
        }
    }
}

/// The problem of a file named by an override where overrides may name none
/// ([`LoadOptions::overrides_name_no_files`]).
pub fn override_file_problem(key: &str) -> Problem {
    Problem::new(
        key,
        "names a file; here an override may name none (the studio reads no file beyond its scenario's: edit the scenario file and restart)",
    )
}

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

/// Why metadata `m` is not a regular file's, if it is not.
fn not_regular(m: &std::fs::Metadata) -> Option<String> {
    if m.is_file() {
        None
    } else if m.is_dir() {
        Some("it is a directory; allowed: a regular file".into())
    } else {
        Some(
            "it is not a regular file (a FIFO, a socket or a device); allowed: a regular file"
                .into(),
        )
    }
}

/// The regular file `path`, open for reading, of at most `max` bytes (`what`: "a track", "a
/// drive table", ...); else why it cannot be read. The one door through which a file a
/// scenario names is opened: checked before opening (opening a FIFO waits for a writer),
/// opened without waiting (O_NONBLOCK, which a regular file's reads ignore), and checked
/// again on the open file, so that a file swapped for a FIFO or a device between the check
/// and the open is refused instead of hanging the run.
pub(crate) fn open_regular(path: &Path, max: u64, what: &str) -> Result<std::fs::File, String> {
    let m = std::fs::metadata(path).map_err(|e| e.to_string())?;
    if let Some(why) = not_regular(&m) {
        return Err(why);
    }
    open_checked(path, max, what)
}

/// `path` opened without waiting and checked on the open file: what stands there now, not
/// what stood there when it was looked at.
fn open_checked(path: &Path, max: u64, what: &str) -> Result<std::fs::File, String> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path).map_err(|e| e.to_string())?;
    let m = file.metadata().map_err(|e| e.to_string())?;
    if let Some(why) = not_regular(&m) {
        return Err(why);
    }
    if m.len() > max {
        return Err(format!(
            "it is larger than {} MiB, the most {what} may have",
            max >> 20
        ));
    }
    Ok(file)
}

/// The text of a scenario file. A file a scenario names (`regular`) must be a regular file
/// ([`open_regular`]); the one named on the command line may also be a pipe (`<(generate)`);
/// either is read to at most [`MAX_SCENARIO_BYTES`]. Else why it cannot be read.
pub(crate) fn scenario_text(path: &Path, regular: bool) -> Result<String, String> {
    let file = match regular {
        true => open_regular(path, MAX_SCENARIO_BYTES, "a scenario file")?,
        false => std::fs::File::open(path).map_err(|e| e.to_string())?,
    };
    capped_text(file)
}

/// The text of the regular file `path` (`what`: "a track", "a drive table", ...), refused
/// by its size before it is read if larger than `max` bytes, and read to at most `max`
/// (a file growing meanwhile).
pub(crate) fn capped_file_text(path: &Path, max: u64, what: &str) -> Result<String, String> {
    let file = open_regular(path, max, what)?;
    read_capped(file, max, &|| {
        format!(
            "it is larger than {} MiB, the most {what} may have",
            max >> 20
        )
    })
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
                ..Default::default()
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
                ..Default::default()
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

    /// Hostile input round four: a file swapped for a FIFO between the regular-file check
    /// and the open hung the run (2 of 800 races). The open does not wait, and the open
    /// file is checked again.
    #[cfg(unix)]
    #[test]
    fn fifo_swapped_in_after_the_check_is_refused_not_waited_on() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("table.csv");
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap();
        assert!(made.success());
        // The open of the race's second half, on another thread: it must come back.
        let (tx, rx) = std::sync::mpsc::channel();
        let path = fifo.clone();
        std::thread::spawn(move || {
            let _ = tx.send(open_checked(&path, MAX_SCENARIO_BYTES, "a drive table").map(|_| ()));
        });
        let got = rx
            .recv_timeout(std::time::Duration::from_secs(10))
            .expect("the open waited for a writer");
        let e = got.unwrap_err();
        assert!(e.contains("not a regular file"), "{e}");
        // And the whole door refuses it before opening.
        let e = open_regular(&fifo, MAX_SCENARIO_BYTES, "a drive table").unwrap_err();
        assert!(e.contains("not a regular file"), "{e}");
    }

    /// Every key that names a file is found wherever it sits: a further diverter's machine,
    /// a section set whole, nested arrays; a key of the same name elsewhere is not a file.
    #[test]
    fn named_files_are_found_at_any_depth() {
        let mut t: toml::Table = toml::from_str(
            r#"
            base = "b.toml"
            [machine.drive]
            kind = "table"
            table = "a.csv"
            [mix]
            records = "r.csv"
            [line]
            arrivals = "t.csv"
            [[line.diverters]]
            position = 6.0
            machine = { drive = { kind = "table", table = "d0.csv" } }
            [[line.diverters]]
            position = 9.0
            machine = { cycle_time = 1.2 }
            [materials]
            table = "not a file key here"
            [design]
            base = "not the top-level base"
            "#,
        )
        .unwrap();
        let keys: Vec<String> = named_files(&mut t).into_iter().map(|(k, _)| k).collect();
        assert_eq!(
            keys,
            [
                "base",
                "line.arrivals",
                "line.diverters[0].machine.drive.table",
                "machine.drive.table",
                "mix.records",
            ]
        );
    }

    #[test]
    fn endless_input_ends_in_an_error() {
        let e = capped_text(std::io::repeat(b'a')).unwrap_err();
        assert!(e.contains("larger than 16 MiB"), "{e}");
    }
}
