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
//! The marker grammar (pointers, formats) is [`divertsim_report::markers`], which also adds
//! each CSV table of a run's output to its summary as an array of rows under its file name
//! (`/trigger.csv/3/start_position_m`), an empty cell as none; here are the runs and files.
//! `divertsim docs` reruns every listed run and rewrites the figures and the marked numbers;
//! `--check` rewrites nothing and fails, naming each, when a committed figure or number
//! differs from the fresh run's.

use crate::outdir;
use divertsim_report::markers::{add_tables, fill};
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

/// The CSV files of a run's output folder, by name in order, with their bytes (for
/// [`divertsim_report::markers::add_tables`]).
fn tables_of(dir: &Path) -> Result<Vec<(String, Vec<u8>)>, String> {
    let mut names: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| e.to_string())?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "csv"))
        .collect();
    names.sort();
    names
        .iter()
        .map(|p| {
            let bytes = std::fs::read(p).map_err(|e| format!("{}: {e}", p.display()))?;
            let name = p.file_name().map(|n| n.to_string_lossy().into_owned());
            Ok((name.unwrap_or_default(), bytes))
        })
        .collect()
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
        if let Err(e) = tables_of(&out).and_then(|t| add_tables(&mut summary, &t)) {
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
            match outdir::folder_differences(&out, &root.join(folder)) {
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
        if let Err(e) = outdir::copy_atomic(from, to) {
            eprintln!("error: {}: {e}", to.display());
            return 2;
        }
    }
    for (from, to) in &folders {
        if let Err(e) = outdir::replace_folder(from, to) {
            eprintln!("error: {}: {e}", to.display());
            return 2;
        }
    }
    for (path, text) in &rewritten {
        if let Err(e) = outdir::write_atomic(path, text.as_bytes()) {
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
