//! `divertsim docs`: the runs behind the documentation's figures and numbers, rerun.
//!
//! `docs/runs.toml` lists them: each a divertsim command line, the figures it draws and where
//! the documentation shows them. A number in a document is written between markers that name
//! the run and the value in its `summary.json`:
//!
//! ```text
//! <!--n mix_doc /points/0/failure_rate/estimate pct:2-->9.27<!--/n--> %
//! ```
//!
//! The pointer is a JSON pointer into the summary, where each CSV table of the run's output
//! is an array of rows under its file name (`/trigger.csv/3/start_position_m`); a last step
//! `#` is an array's length, a `*` step takes the largest value over an array's
//! elements that have one, `A|B` is the ratio of two values, and a pointer ending in `?` reads 0 where
//! the summary has nothing (a failure reason no parcel had). The format is `pct:N` (a fraction as a
//! percentage, N decimals), `fix:N` (N decimals), `int` (rounded, thousands separated) or
//! `text` (a string of the summary as it is, a finding's sentence; a boolean as yes or no).
//! A value the run has as none (a JSON null, an empty CSV cell) at a plain pointer is written
//! "—" in any format; in a ratio it is an error.
//! `divertsim docs` reruns every listed run and rewrites the figures and the marked numbers;
//! `--check` rewrites nothing and fails, naming each, when a committed figure or number
//! differs from the fresh run's.

use crate::commands::common;
use serde::Deserialize;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Arguments of `divertsim docs`.
#[derive(Debug, Clone, clap::Args)]
pub struct DocsArgs {
    /// The repository root: its docs/runs.toml lists the runs, and its paths (the
    /// scenarios, the documents, the figures) are relative to it.
    #[arg(long, value_name = "DIR", default_value = ".")]
    pub root: PathBuf,
    /// Rewrite nothing: exit 1, naming each figure and number that differs from a fresh
    /// run (what the test suite runs).
    #[arg(long)]
    pub check: bool,
    /// Only these runs (by name; repeatable). Default: all.
    #[arg(long, value_name = "NAME")]
    pub only: Vec<String>,
    /// Keep every run's output folder in DIR (DIR/NAME: its summary.json, tables and
    /// figures), to read the values a marker may name. DIR must not exist.
    #[arg(long, value_name = "DIR")]
    pub keep: Option<PathBuf>,
    /// Read the runs' outputs from DIR (a folder --keep wrote: DIR/NAME per run) instead
    /// of running them: to place markers without waiting for the runs again.
    #[arg(long, value_name = "DIR", conflicts_with = "keep")]
    pub from: Option<PathBuf>,
    /// No progress lines.
    #[arg(long, short)]
    pub quiet: bool,
}

/// The manifest: `docs/runs.toml`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// The documents whose markers are filled, relative to the root.
    pub documents: Vec<PathBuf>,
    /// The runs.
    #[serde(rename = "run")]
    pub runs: Vec<DocRun>,
}

/// One run behind the documentation.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DocRun {
    /// Its name, as markers give it.
    pub name: String,
    /// What it is, in a few words (printed as it runs).
    pub about: String,
    /// The divertsim command line, without `divertsim`, `--out` and `--quiet`;
    /// `{out:NAME}` is the output folder of an earlier run (`{out:opt}/optimum.toml`),
    /// `{scratch}` a folder of this run's own for the files its `before` commands write.
    pub args: Vec<String>,
    /// divertsim command lines run first, as they are (no `--out`): what makes the run's
    /// inputs (`["track", "configs/paper/fig13a.toml", "--synthesize", "{scratch}/13a.csv"]`).
    #[serde(default)]
    pub before: Vec<Vec<String>>,
    /// Files of its output folder the documentation shows: file name → path from the root.
    #[serde(default)]
    pub figures: BTreeMap<String, PathBuf>,
    /// A folder the documentation links whole (`replicate`'s docs/figures): the run's
    /// output folder, every file of it, is that folder.
    pub folder: Option<PathBuf>,
    /// The JSON file of its output that markers read (default summary.json).
    #[serde(default = "summary_json")]
    pub summary: String,
}

fn summary_json() -> String {
    "summary.json".into()
}

/// A marked number: where it is and what it says.
#[derive(Debug, Clone, PartialEq)]
pub struct Marker {
    /// Byte range of the value between the markers.
    pub range: std::ops::Range<usize>,
    /// 1-based line of the marker.
    pub line: usize,
    pub run: String,
    pub pointer: String,
    pub format: String,
    /// The value as committed.
    pub text: String,
}

const OPEN: &str = "<!--n ";
const CLOSE: &str = "<!--/n-->";

/// Every marker of a document, or the problem with a malformed one (by line).
pub fn markers(doc: &str) -> Result<Vec<Marker>, String> {
    let mut out = Vec::new();
    let mut at = 0;
    while let Some(i) = doc[at..].find(OPEN) {
        let start = at + i;
        let line = doc[..start].matches('\n').count() + 1;
        let head_end = doc[start..].find("-->").map(|j| start + j).ok_or(format!(
            "line {line}: a number marker without its closing -->"
        ))?;
        let fields: Vec<&str> = doc[start + OPEN.len()..head_end]
            .split_whitespace()
            .collect();
        let [run, pointer, format] = fields[..] else {
            return Err(format!(
                "line {line}: a number marker needs RUN POINTER FORMAT, found {:?}",
                fields.join(" ")
            ));
        };
        let value_start = head_end + 3;
        let value_end = doc[value_start..]
            .find(CLOSE)
            .map(|j| value_start + j)
            .ok_or(format!("line {line}: a number marker without its {CLOSE}"))?;
        // A value is one line and holds no marker: else a missing close would swallow the
        // prose up to the next marker's.
        let value = &doc[value_start..value_end];
        if value.contains('\n') || value.contains(OPEN) {
            return Err(format!("line {line}: a number marker without its {CLOSE}"));
        }
        out.push(Marker {
            range: value_start..value_end,
            line,
            run: run.to_string(),
            pointer: pointer.to_string(),
            format: format.to_string(),
            text: doc[value_start..value_end].to_string(),
        });
        at = value_end + CLOSE.len();
    }
    Ok(out)
}

/// The value at a pointer of a summary: a JSON pointer, `*` for the largest over an array,
/// `A|B` for a ratio.
pub fn value_at(summary: &Value, pointer: &str) -> Result<f64, String> {
    if let Some((a, b)) = pointer.split_once('|') {
        return Ok(value_at(summary, a)? / value_at(summary, b)?);
    }
    fn walk(v: &Value, steps: &[&str]) -> Option<f64> {
        let Some((first, rest)) = steps.split_first() else {
            return v.as_f64();
        };
        if *first == "#" {
            return Some(v.as_array()?.len() as f64);
        }
        if *first == "*" {
            // Over the elements that have a number there (a map's infeasible cells have
            // none).
            return v
                .as_array()?
                .iter()
                .filter_map(|x| walk(x, rest))
                .reduce(f64::max);
        }
        let next = match v {
            Value::Array(a) => a.get(first.parse::<usize>().ok()?)?,
            Value::Object(m) => m.get(*first)?,
            _ => return None,
        };
        walk(next, rest)
    }
    // A count the summary leaves out when it is zero (a failure reason no parcel had).
    if let Some(p) = pointer.strip_suffix('?') {
        let steps: Vec<&str> = p.trim_start_matches('/').split('/').collect();
        return Ok(walk(summary, &steps).unwrap_or(0.0));
    }
    let steps: Vec<&str> = pointer.trim_start_matches('/').split('/').collect();
    walk(summary, &steps).ok_or(format!("no number at {pointer}"))
}

/// The CSV tables of a run's output folder into its summary, each under its file name as an
/// array of rows (`/trigger.csv/3/start_position_m`: the fourth row's cell), numbers where
/// a cell reads as one.
fn add_tables(summary: &mut Value, dir: &Path) -> Result<(), String> {
    let Some(map) = summary.as_object_mut() else {
        return Ok(());
    };
    let mut names: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| e.to_string())?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "csv"))
        .collect();
    names.sort();
    for path in names {
        let mut reader = csv::ReaderBuilder::new()
            .flexible(true)
            .from_path(&path)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        let header = reader.headers().map_err(|e| e.to_string())?.clone();
        let rows: Vec<Value> = reader
            .records()
            .filter_map(Result::ok)
            .map(|r| {
                Value::Object(
                    header
                        .iter()
                        .zip(r.iter())
                        .map(|(k, v)| {
                            // An empty cell is none (written as a null is), not a word.
                            let cell = if v.is_empty() {
                                Value::Null
                            } else {
                                v.parse::<f64>()
                                    .ok()
                                    .and_then(|x| {
                                        serde_json::Number::from_f64(x).map(Value::Number)
                                    })
                                    .unwrap_or_else(|| Value::String(v.to_string()))
                            };
                            (k.to_string(), cell)
                        })
                        .collect(),
                )
            })
            .collect();
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
        if let Some(name) = name {
            map.insert(name, Value::Array(rows));
        }
    }
    Ok(())
}

/// The text at a JSON pointer (a finding's sentence) as it is; a boolean as yes or no; a
/// list of words joined by arrows (a run's stages).
pub fn text_at(summary: &Value, pointer: &str) -> Result<String, String> {
    match summary.pointer(pointer) {
        Some(Value::String(t)) => Ok(t.clone()),
        Some(Value::Bool(b)) => Ok(if *b { "yes" } else { "no" }.into()),
        // A list of words (a run's stages): joined by arrows.
        Some(Value::Array(a)) if a.iter().all(Value::is_string) => Ok(a
            .iter()
            .filter_map(Value::as_str)
            .collect::<Vec<_>>()
            .join(" → ")),
        _ => Err(format!("no text at {pointer}")),
    }
}

/// A value as a format writes it.
pub fn formatted(value: f64, format: &str) -> Result<String, String> {
    let decimals = |s: &str| {
        s.parse::<usize>()
            .ok()
            .filter(|d| *d <= 12)
            .ok_or(format!("format {format}: decimals 0 to 12"))
    };
    if !value.is_finite() {
        return Err(format!("the value is {value}"));
    }
    match format.split_once(':') {
        Some(("pct", d)) => Ok(format!("{:.*}", decimals(d)?, 100.0 * value)),
        Some(("fix", d)) => Ok(format!("{:.*}", decimals(d)?, value)),
        None if format == "int" => Ok(grouped(value.round())),
        _ => Err(format!(
            "unknown format {format}; allowed: pct:N, fix:N (N decimals), int"
        )),
    }
}

/// A whole number with thousands separators (negative ones too).
fn grouped(v: f64) -> String {
    let text = common::count_text(v.abs() as u64);
    if v < 0.0 {
        format!("-{text}")
    } else {
        text
    }
}

/// How a marker writes a value the run has as none (a JSON null, an empty CSV cell: a
/// method that never came within 0.5 % of the best), whatever its format.
pub const NONE: &str = "—";

/// A marked number whose committed text differs from its run's: `(line, what, committed,
/// fresh)`.
pub type Difference = (usize, String, String, String);

/// A document with its markers filled from the summaries: the new text and every marker
/// whose committed value differs. A marker of a run not in `summaries` is an error, unless
/// `partial` (some runs ran: the others' markers keep their text).
pub fn fill(
    doc: &str,
    summaries: &BTreeMap<String, Value>,
    partial: bool,
) -> Result<(String, Vec<Difference>), String> {
    let mut out = String::with_capacity(doc.len());
    let mut differs = Vec::new();
    let mut at = 0;
    let mut errors = Vec::new();
    for m in markers(doc)? {
        let Some(summary) = summaries.get(&m.run) else {
            if !partial {
                errors.push(format!(
                    "line {}: no run named {:?} in docs/runs.toml",
                    m.line, m.run
                ));
            }
            continue;
        };
        let fresh = match m.format.as_str() {
            _ if summary.pointer(&m.pointer).is_some_and(Value::is_null) => Ok(NONE.to_string()),
            "text" => text_at(summary, &m.pointer),
            _ => value_at(summary, &m.pointer).and_then(|v| formatted(v, &m.format)),
        };
        let fresh = match fresh {
            Ok(f) => f,
            Err(e) => {
                errors.push(format!("line {}: {} {}: {e}", m.line, m.run, m.pointer));
                continue;
            }
        };
        if fresh != m.text {
            differs.push((
                m.line,
                format!("{} {}", m.run, m.pointer),
                m.text.clone(),
                fresh.clone(),
            ));
        }
        out.push_str(&doc[at..m.range.start]);
        out.push_str(&fresh);
        at = m.range.end;
    }
    out.push_str(&doc[at..]);
    if !errors.is_empty() {
        return Err(errors.join("\n  "));
    }
    Ok((out, differs))
}

/// Read and check the manifest.
fn manifest(root: &Path) -> Result<Manifest, String> {
    let path = root.join("docs/runs.toml");
    let text = std::fs::read_to_string(&path).map_err(|e| {
        format!(
            "{}: {e} (run from the repository root, or give --root)",
            path.display()
        )
    })?;
    let m: Manifest = toml::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut names = std::collections::BTreeSet::new();
    for r in &m.runs {
        if !names.insert(r.name.as_str()) {
            return Err(format!("{}: two runs named {:?}", path.display(), r.name));
        }
        if r.args
            .iter()
            .any(|a| a == "--out" || a == "-q" || a == "--quiet")
        {
            return Err(format!(
                "{}: run {:?}: --out and --quiet are the docs command's",
                path.display(),
                r.name
            ));
        }
    }
    Ok(m)
}

/// A manifest argument with its placeholders filled: `{out:NAME}` (an earlier run's output
/// folder, beside `out`) and `{scratch}`.
fn filled(arg: &str, out: &Path) -> String {
    let mut a = arg.replace("{scratch}", &scratch(out).to_string_lossy());
    while let Some(i) = a.find("{out:") {
        let Some(j) = a[i..].find('}') else { break };
        let name = a[i + 5..i + j].to_string();
        let dir = out.parent().unwrap_or(out).join(&name);
        a.replace_range(i..i + j + 1, &dir.to_string_lossy());
    }
    a
}

/// The scratch folder of the run whose output folder is `out`.
fn scratch(out: &Path) -> PathBuf {
    out.with_extension("scratch")
}

/// Run one manifest entry into `out` with `exe` (this executable), in the root (its report on
/// stdout is not wanted; its errors are shown): its `before` commands, then itself; the
/// exit code of the first that fails, else its own.
fn run_one(root: &Path, exe: &Path, run: &DocRun, out: &Path) -> i32 {
    if let Err(e) = std::fs::create_dir_all(scratch(out)) {
        eprintln!("error: run {:?}: {e}", run.name);
        return 2;
    }
    // A `before` command's report is noise unless it fails; the run's own errors show.
    let spawn = |args: &[String], tail: &[&std::ffi::OsStr], before: bool| {
        let mut cmd = std::process::Command::new(exe);
        cmd.current_dir(root)
            .args(args.iter().map(|a| filled(a, out)))
            .args(tail)
            .stdout(std::process::Stdio::null());
        if before {
            cmd.stderr(std::process::Stdio::piped());
        }
        match cmd.output() {
            Ok(o) => {
                if before && !o.status.success() {
                    eprint!("{}", String::from_utf8_lossy(&o.stderr));
                }
                o.status.code().unwrap_or(2)
            }
            Err(e) => {
                eprintln!("error: run {:?}: {e}", run.name);
                2
            }
        }
    };
    for before in &run.before {
        let code = spawn(before, &[], true);
        if code != 0 {
            eprintln!(
                "error: run {:?}: {} exited {code}",
                run.name,
                before.join(" ")
            );
            return code;
        }
    }
    spawn(
        &run.args,
        &["--out".as_ref(), out.as_os_str(), "--quiet".as_ref()],
        false,
    )
}

/// `divertsim docs`: returns the exit code (0 fresh or rewritten, 1 differences found with
/// --check, 2 bad input or a failed run).
pub fn run(args: &DocsArgs) -> i32 {
    let root = &args.root;
    let m = match manifest(root) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    for name in &args.only {
        if !m.runs.iter().any(|r| &r.name == name) {
            let known: Vec<&str> = m.runs.iter().map(|r| r.name.as_str()).collect();
            eprintln!(
                "error: --only: no run named {name:?}; allowed: {}",
                known.join(", ")
            );
            return 2;
        }
    }
    let chosen: Vec<&DocRun> = m
        .runs
        .iter()
        .filter(|r| args.only.is_empty() || args.only.contains(&r.name))
        .collect();
    if let Some(k) = &args.keep {
        if k.exists() {
            eprintln!("error: --keep: {} exists; give a new folder", k.display());
            return 2;
        }
    }
    let work = match tempfile::tempdir() {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: a temporary folder: {e}");
            return 2;
        }
    };
    // The runs' executable: this one. On Linux through /proc/self/exe, which names this
    // process's own image even after a rebuild has replaced the file meanwhile.
    let proc_exe = Path::new("/proc/self/exe");
    let exe = match proc_exe.exists() {
        true => Ok(proc_exe.to_path_buf()),
        false => std::env::current_exe(),
    };
    let exe = match exe {
        Ok(e) => e,
        Err(e) => {
            eprintln!("error: this executable's path: {e}");
            return 2;
        }
    };
    let mut summaries = BTreeMap::new();
    let mut differs: Vec<String> = Vec::new();
    let mut figures: Vec<(PathBuf, PathBuf)> = Vec::new();
    let mut folders: Vec<(PathBuf, PathBuf)> = Vec::new();
    for (i, r) in chosen.iter().enumerate() {
        if !args.quiet {
            eprintln!("docs: [{}/{}] {}: {}", i + 1, chosen.len(), r.name, r.about);
        }
        let out = match &args.from {
            Some(from) => from.join(&r.name),
            None => work.path().join(&r.name),
        };
        let started = std::time::Instant::now();
        let code = match &args.from {
            Some(_) if out.is_dir() => 0,
            Some(_) => {
                eprintln!(
                    "error: --from: no {} (run the manifest with --keep)",
                    out.display()
                );
                return 2;
            }
            None => run_one(root, &exe, r, &out),
        };
        if code != 0 && !out.join(&r.summary).exists() {
            eprintln!(
                "error: run {:?} ({}) exited {code}",
                r.name,
                r.args.join(" ")
            );
            return 2;
        }
        if !args.quiet {
            eprintln!("docs:   {:.0} s", started.elapsed().as_secs_f64());
        }
        let summary = std::fs::read(out.join(&r.summary))
            .ok()
            .and_then(|b| serde_json::from_slice::<Value>(&b).ok());
        let Some(mut summary) = summary else {
            eprintln!("error: run {:?} wrote no readable {}", r.name, r.summary);
            return 2;
        };
        if let Err(e) = add_tables(&mut summary, &out) {
            eprintln!("error: run {:?}: {e}", r.name);
            return 2;
        }
        summaries.insert(r.name.clone(), summary);
        for (file, place) in &r.figures {
            let fresh = out.join(file);
            let Ok(bytes) = std::fs::read(&fresh) else {
                eprintln!("error: run {:?} wrote no {file}", r.name);
                return 2;
            };
            if std::fs::read(root.join(place)).ok().as_deref() != Some(bytes.as_slice()) {
                differs.push(format!(
                    "{}: differs from run {}'s {file}",
                    place.display(),
                    r.name
                ));
            }
            figures.push((fresh, root.join(place)));
        }
        if let Some(folder) = &r.folder {
            match folder_differences(&out, &root.join(folder)) {
                Ok(d) => differs.extend(d.into_iter().map(|f| {
                    format!(
                        "{}: differs from run {}'s",
                        folder.join(f).display(),
                        r.name
                    )
                })),
                Err(e) => {
                    eprintln!("error: run {:?}: {e}", r.name);
                    return 2;
                }
            }
            folders.push((out.clone(), root.join(folder)));
        }
    }
    if let Some(k) = &args.keep {
        let kept = std::fs::create_dir_all(k).and_then(|_| {
            chosen.iter().try_for_each(|r| {
                crate::outdir::copy_tree(&work.path().join(&r.name), &k.join(&r.name))
            })
        });
        if let Err(e) = kept {
            eprintln!("error: --keep {}: {e}", k.display());
            return 2;
        }
    }
    // The documents: with --only, the markers of the other runs are left as they are.
    let mut rewritten = Vec::new();
    for doc in &m.documents {
        let path = root.join(doc);
        let text = match std::fs::read_to_string(&path) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("error: {}: {e}", path.display());
                return 2;
            }
        };
        match fill(&text, &summaries, !args.only.is_empty()) {
            Ok((new, d)) => {
                for (line, what, old, fresh) in d {
                    differs.push(format!(
                        "{}:{line}: {what}: committed {old}, fresh {fresh}",
                        doc.display()
                    ));
                }
                if new != text {
                    rewritten.push((path, new));
                }
            }
            Err(e) => {
                eprintln!("error: {}: {e}", doc.display());
                return 2;
            }
        }
    }
    if args.check {
        if differs.is_empty() {
            println!(
                "docs: {} runs, their figures and numbers are those committed",
                chosen.len()
            );
            return 0;
        }
        println!(
            "docs: {} figures or numbers differ from a fresh run:",
            differs.len()
        );
        for d in &differs {
            println!("  {d}");
        }
        println!("rerun `divertsim docs` to write them, and read the prose around them");
        return 1;
    }
    for (from, to) in &figures {
        if let Err(e) = copy_atomic(from, to) {
            eprintln!("error: {}: {e}", to.display());
            return 2;
        }
    }
    for (from, to) in &folders {
        if let Err(e) = replace_folder(from, to) {
            eprintln!("error: {}: {e}", to.display());
            return 2;
        }
    }
    for (path, text) in &rewritten {
        if let Err(e) = write_atomic(path, text.as_bytes()) {
            eprintln!("error: {}: {e}", path.display());
            return 2;
        }
    }
    println!(
        "docs: {} runs; {} figures or numbers changed",
        chosen.len(),
        differs.len()
    );
    for d in &differs {
        println!("  {d}");
    }
    0
}

/// The files (relative names) that differ between two folders, or are in one only.
fn folder_differences(fresh: &Path, committed: &Path) -> std::io::Result<Vec<PathBuf>> {
    let (a, b) = (files_of(fresh)?, files_of(committed).unwrap_or_default());
    let names: std::collections::BTreeSet<&PathBuf> = a.keys().chain(b.keys()).collect();
    Ok(names
        .into_iter()
        .filter(|n| a.get(*n) != b.get(*n))
        .cloned()
        .collect())
}

/// Every file under a folder by its relative name, with its bytes.
fn files_of(dir: &Path) -> std::io::Result<BTreeMap<PathBuf, Vec<u8>>> {
    let mut out = BTreeMap::new();
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
fn replace_folder(fresh: &Path, to: &Path) -> std::io::Result<()> {
    let staged = to.with_extension(format!("new-{}", std::process::id()));
    crate::outdir::copy_tree(fresh, &staged)?;
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

fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    crate::outdir::write_file(path, &mut |tmp| {
        std::fs::write(tmp, bytes).map_err(|e| e.to_string())
    })
    .map_err(std::io::Error::other)
}

fn copy_atomic(from: &Path, to: &Path) -> std::io::Result<()> {
    if let Some(dir) = to.parent() {
        std::fs::create_dir_all(dir)?;
    }
    write_atomic(to, &std::fs::read(from)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn markers_are_found_with_their_line_and_value() {
        let doc = "a\nrate <!--n mix /points/0/r pct:2-->9.27<!--/n--> % and <!--n mix /w int-->1,390<!--/n-->\n";
        let m = markers(doc).unwrap();
        assert_eq!(m.len(), 2);
        assert_eq!(
            (m[0].line, m[0].text.as_str(), m[0].format.as_str()),
            (2, "9.27", "pct:2")
        );
        assert_eq!(&doc[m[1].range.clone()], "1,390");
        assert!(markers("<!--n a b-->1<!--/n-->")
            .unwrap_err()
            .contains("RUN POINTER FORMAT"));
        assert!(markers("<!--n a /b int-->1")
            .unwrap_err()
            .contains("<!--/n-->"));
        // A missing close does not swallow the next marker's prose.
        let open = "<!--n a /b int-->1 text <!--n a /c int-->2<!--/n-->";
        assert!(markers(open).unwrap_err().contains("line 1"));
    }

    #[test]
    fn pointers_take_the_largest_over_a_star_and_ratios() {
        let s = json!({"points": [{"t": 3.0}, {"t": 5.0}], "w": 10.0});
        assert_eq!(value_at(&s, "/points/1/t").unwrap(), 5.0);
        assert_eq!(value_at(&s, "/points/*/t").unwrap(), 5.0);
        assert_eq!(value_at(&s, "/points/#").unwrap(), 2.0);
        assert_eq!(value_at(&s, "/points/*/t|/w").unwrap(), 0.5);
        assert!(value_at(&s, "/points/2/t")
            .unwrap_err()
            .contains("no number"));
        assert_eq!(value_at(&s, "/points/0/escaped?|/w").unwrap(), 0.0);
    }

    #[test]
    fn formats_write_percentages_decimals_and_grouped_counts() {
        assert_eq!(formatted(0.09271, "pct:2").unwrap(), "9.27");
        assert_eq!(formatted(0.9647, "fix:4").unwrap(), "0.9647");
        assert_eq!(formatted(1952.4, "int").unwrap(), "1,952");
        assert!(formatted(1.0, "pct").unwrap_err().contains("allowed"));
        assert!(formatted(f64::NAN, "int").is_err());
        let s = json!({"findings": [{"verdict": "holds"}]});
        assert_eq!(text_at(&s, "/findings/0/verdict").unwrap(), "holds");
        let r = json!({"stages": ["ride", "F1"], "ok": false});
        assert_eq!(text_at(&r, "/stages").unwrap(), "ride → F1");
        assert_eq!(text_at(&r, "/ok").unwrap(), "no");
    }

    /// The fill rewrites each marked value from its run and names every one that changed.
    #[test]
    fn a_committed_number_that_differs_from_its_run_is_named_and_rewritten() {
        let doc = "x <!--n r /a fix:1-->1.0<!--/n--> y <!--n r /b int-->7<!--/n-->";
        let runs = BTreeMap::from([("r".to_string(), json!({"a": 1.04, "b": 8.0}))]);
        let (new, d) = fill(doc, &runs, false).unwrap();
        assert_eq!(
            new,
            "x <!--n r /a fix:1-->1.0<!--/n--> y <!--n r /b int-->8<!--/n-->"
        );
        assert_eq!(
            d,
            vec![(1, "r /b".to_string(), "7".to_string(), "8".to_string())]
        );
        assert!(fill("<!--n q /a int-->1<!--/n-->", &runs, false)
            .unwrap_err()
            .contains("no run named"));
    }

    /// A method that never came within 0.5 % of the best has no count: its null (or its
    /// empty CSV cell) is written as a dash in any format, while a pointer to nothing stays
    /// an error.
    #[test]
    fn a_value_the_run_has_as_none_is_written_as_a_dash() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("m.csv"),
            "method,to_within\nga,1845\ngradient,\n",
        )
        .unwrap();
        let mut summary = json!({"medians": [{"to_within": null}]});
        add_tables(&mut summary, dir.path()).unwrap();
        let runs = BTreeMap::from([("r".to_string(), summary)]);
        let doc = "<!--n r /medians/0/to_within int-->1<!--/n--> \
                   <!--n r /m.csv/0/to_within int-->0<!--/n--> \
                   <!--n r /m.csv/1/to_within int-->0<!--/n-->";
        let (new, d) = fill(doc, &runs, false).unwrap();
        assert_eq!(
            markers(&new)
                .unwrap()
                .iter()
                .map(|m| m.text.as_str())
                .collect::<Vec<_>>(),
            vec![NONE, "1,845", NONE]
        );
        assert_eq!(d.len(), 3);
        assert!(fill(
            "<!--n r /medians/1/to_within int-->1<!--/n-->",
            &runs,
            false
        )
        .unwrap_err()
        .contains("no number"));
    }
}
