//! Issue 27 (B5): every example in README.md and in every `--help` example block runs as
//! written, in order, in a fresh directory (a copy of `configs/`, as a fresh clone has it),
//! and exits 0, or with the code its comment states ("(exit 4)").
//!
//! An example is a line that starts with `divertsim` (README: in ```sh blocks; `--help`:
//! under "Examples:"), run by bash with this build's binary first on PATH and HOME in the
//! temporary directory. Lines for other tools (`cargo`, `pip`, `/usr/bin/time`, the
//! placeholder `generate-scenario`) are the developer's and the installer's, tested by CI
//! itself. The README's examples run in one directory, each command's `--help` block in its
//! own. An example that repeats an earlier one exactly (the README's or another block's), on
//! `configs/` alone, is not run a second time: the first run's outputs are copied (`repeats`;
//! the binary is deterministic). It takes about 20 minutes on an idle 2-core machine (robust
//! capacity maps, a million samples, the line's optima; 47 minutes before repeats were copied
//! and the `--help` examples sized down), so it runs with DIVERTSIM_EXAMPLE_TESTS=1 and is
//! reported ignored otherwise (build.rs).

use std::collections::{BTreeSet, HashMap};
use std::path::{Path, PathBuf};
use std::process::Command;

/// One example: its command line and the exit code its text promises.
#[derive(Debug)]
struct Example {
    line: String,
    exit: i32,
    /// A server ("serves until Ctrl-C" in its comment): started, its page fetched from the
    /// address it prints, then stopped with Ctrl-C (SIGINT), after which it exits 0.
    serves: bool,
}

/// The examples of a text's lines: `divertsim …` commands (continuations joined), each
/// with the exit code its comment states.
fn examples<'a>(lines: impl Iterator<Item = &'a str>) -> Vec<Example> {
    let mut out = Vec::new();
    let mut pending = String::new();
    for raw in lines {
        let line = raw.trim();
        if let Some(start) = line.strip_suffix('\\') {
            pending += start;
            pending.push(' ');
            continue;
        }
        let whole = std::mem::take(&mut pending) + line;
        if !whole.starts_with("divertsim ") && whole != "divertsim" {
            continue;
        }
        // The comment: after a `#` preceded by whitespace (never inside these commands'
        // arguments).
        let (command, comment) = match whole.find(" #") {
            Some(k) => (whole[..k].trim().to_string(), whole[k..].to_string()),
            None => (whole.trim().to_string(), String::new()),
        };
        // "exit N" in the comment, with or without parentheses.
        let exit = comment
            .split("exit ")
            .nth(1)
            .and_then(|r| {
                r.split(|c: char| !c.is_ascii_digit())
                    .next()
                    .and_then(|n| n.parse().ok())
            })
            .unwrap_or(0);
        out.push(Example {
            line: command,
            exit,
            serves: comment.contains("serves until Ctrl-C"),
        });
    }
    out
}

/// The lines of README.md's ```sh blocks.
fn readme_lines(readme: &str) -> Vec<&str> {
    let mut inside = false;
    let mut out = Vec::new();
    for l in readme.lines() {
        if l.trim_start().starts_with("```") {
            inside = !inside && l.trim_start().starts_with("```sh");
            continue;
        }
        if inside {
            out.push(l);
        }
    }
    out
}

/// The lines of a `--help` text's "Examples:" block.
fn help_lines(help: &str) -> Vec<String> {
    help.lines()
        .skip_while(|l| !l.starts_with("Examples:"))
        .skip(1)
        .take_while(|l| l.is_empty() || l.starts_with(' '))
        .map(str::to_string)
        .collect()
}

/// A fresh directory with `configs/`, `docs/` and README.md as a clone has them (`docs`'s
/// examples read docs/runs.toml and the documents).
fn fresh(root: &Path, name: &str) -> PathBuf {
    let dir = root.join(name);
    std::fs::create_dir_all(&dir).unwrap();
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    for part in ["configs", "docs", "README.md"] {
        copy_into(&repo.join(part), &dir);
    }
    dir
}

/// `cp -r from dir/`.
fn copy_into(from: &Path, dir: &Path) {
    let status = Command::new("cp")
        .arg("-r")
        .arg(from)
        .arg(dir)
        .status()
        .unwrap();
    assert!(status.success());
}

/// A command already run in another directory: where, and the entries it created there.
struct Ran {
    dir: PathBuf,
    created: Vec<std::ffi::OsString>,
}

/// The top-level entries of a directory.
fn entries(dir: &Path) -> BTreeSet<std::ffi::OsString> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect()
}

/// Whether running `line` in `dir` repeats a run already made: a single command (no shell
/// operators), every argument that names an existing path in `dir` lies under `configs/`
/// (the same copy in every fresh directory), and nothing it created there exists here. The
/// same binary on the same arguments and inputs writes the same files (determinism is
/// tested on its own), so the repeat is replaced by a copy of what the first run created.
fn repeats<'r>(line: &str, dir: &Path, ran: &'r HashMap<String, Ran>) -> Option<&'r Ran> {
    let first = ran.get(line)?;
    let single = !line.contains(['&', '|', ';', '$', '`', '>', '<']);
    let inputs_are_configs = line
        .split_whitespace()
        .filter(|a| !a.starts_with('-') && dir.join(a).exists())
        .all(|a| a.starts_with("configs/"));
    let fresh = first.created.iter().all(|c| !dir.join(c).exists());
    (single && inputs_are_configs && fresh).then_some(first)
}

/// Run the examples in `dir`, in order; each failure described. A command that repeats an
/// earlier passing run exactly (`repeats`) is not run twice: its outputs are copied.
fn run_all(
    dir: &Path,
    what: &str,
    list: &[Example],
    ran: &mut HashMap<String, Ran>,
) -> Vec<String> {
    let bin = Path::new(env!("CARGO_BIN_EXE_divertsim"));
    let path = format!(
        "{}:{}",
        bin.parent().unwrap().display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let mut failures = Vec::new();
    for e in list {
        let started = std::time::Instant::now();
        if e.serves {
            if let Err(why) = serve_once(&e.line, dir, &path) {
                failures.push(format!("{what}: `{}`: {why}", e.line));
            }
            eprintln!(
                "{what}: {} served in {:.1} s",
                e.line,
                started.elapsed().as_secs_f64()
            );
            continue;
        }
        if let Some(first) = repeats(&e.line, dir, ran) {
            for c in &first.created {
                copy_into(&first.dir.join(c), dir);
            }
            eprintln!(
                "{what}: {} -> repeats an earlier run, outputs copied",
                e.line
            );
            continue;
        }
        let before = entries(dir);
        let out = Command::new("bash")
            .args(["-c", &e.line])
            .current_dir(dir)
            .env("PATH", &path)
            .env("HOME", dir)
            .output()
            .unwrap();
        eprintln!(
            "{what}: {} -> {:?} in {:.1} s",
            e.line,
            out.status.code(),
            started.elapsed().as_secs_f64()
        );
        if out.status.code() == Some(e.exit) && !ran.contains_key(&e.line) {
            let created = entries(dir).difference(&before).cloned().collect();
            ran.insert(
                e.line.clone(),
                Ran {
                    dir: dir.to_path_buf(),
                    created,
                },
            );
        }
        if out.status.code() != Some(e.exit) {
            failures.push(format!(
                "{what}: `{}` exited {:?}, the text says {}: {}",
                e.line,
                out.status.code(),
                e.exit,
                String::from_utf8_lossy(&out.stderr)
                    .lines()
                    .take(6)
                    .collect::<Vec<_>>()
                    .join(" | ")
            ));
        }
    }
    failures
}

/// Start a server example, fetch the page at the address it prints, stop it with SIGINT:
/// it must exit 0.
fn serve_once(line: &str, dir: &Path, path: &str) -> Result<(), String> {
    use std::io::{BufRead, Read, Write};
    // `exec`: the signal goes to the server itself, not to a shell around it.
    let mut child = Command::new("bash")
        .args(["-c", &format!("exec {line}")])
        .current_dir(dir)
        .env("PATH", path)
        .env("HOME", dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .map_err(|e| e.to_string())?;
    let mut first = String::new();
    let read = std::io::BufReader::new(child.stdout.take().unwrap()).read_line(&mut first);
    let fetched = (|| {
        read.map_err(|e| e.to_string())?;
        let addr = first
            .split("http://")
            .nth(1)
            .map(|a| a.trim().trim_end_matches('/').to_string())
            .ok_or_else(|| format!("no address printed: {first:?}"))?;
        let mut s = std::net::TcpStream::connect(&addr).map_err(|e| e.to_string())?;
        write!(
            s,
            "GET / HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"
        )
        .map_err(|e| e.to_string())?;
        let mut page = String::new();
        s.read_to_string(&mut page).map_err(|e| e.to_string())?;
        match page.starts_with("HTTP/1.1 200") {
            true => Ok(()),
            false => Err(format!("the page: {}", page.lines().next().unwrap_or(""))),
        }
    })();
    let _ = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    let status = child.wait().map_err(|e| e.to_string())?;
    fetched?;
    match status.code() {
        Some(0) => Ok(()),
        other => Err(format!("exited {other:?} after Ctrl-C")),
    }
}

#[test]
fn the_parsing_of_examples() {
    let text = "divertsim check a.toml --out u  # UNSAFE (exit 4)\ndivertsim check b.toml  # UNSAFE, exit 4\n  divertsim calibrate x \\\n      --out cal\ncargo test\ngenerate-scenario | divertsim simulate -\ndivertsim simulate\n";
    let e = examples(text.lines());
    assert_eq!(e.len(), 4, "{e:?}");
    assert_eq!(
        (e[0].line.as_str(), e[0].exit),
        ("divertsim check a.toml --out u", 4)
    );
    assert_eq!(
        (e[1].line.as_str(), e[1].exit),
        ("divertsim check b.toml", 4)
    );
    assert_eq!(e[2].line, "divertsim calibrate x  --out cal");
    assert_eq!((e[3].line.as_str(), e[3].exit), ("divertsim simulate", 0));
    assert!(e.iter().all(|e| !e.serves));
    let served =
        examples(["divertsim studio  # http://127.0.0.1:8740/ (serves until Ctrl-C)"].into_iter());
    assert!(served[0].serves && served[0].line == "divertsim studio");
    let help = "About\n\nExamples:\n  divertsim a\n\n  divertsim b  # c\n\nVariables: x\n  divertsim not\n";
    let lines = help_lines(help);
    let e = examples(lines.iter().map(String::as_str));
    assert_eq!(e.len(), 2);
}

#[test]
fn a_repeat_is_the_same_single_command_on_configs_only() {
    let tmp = tempfile::tempdir().unwrap();
    let here = fresh(tmp.path(), "here");
    std::fs::create_dir(here.join("out1")).unwrap();
    let mut ran = HashMap::new();
    for line in [
        "divertsim simulate configs/paper/machine.toml --out a",
        "divertsim simulate out1 --out b",
        "divertsim simulate configs/paper/machine.toml --out out1",
        "divertsim check configs/paper/machine.toml && divertsim simulate",
    ] {
        ran.insert(
            line.to_string(),
            Ran {
                dir: tmp.path().join("there"),
                created: vec!["a".into()],
            },
        );
    }
    let repeats_here = |l: &str| repeats(l, &here, &ran).is_some();
    assert!(repeats_here(
        "divertsim simulate configs/paper/machine.toml --out a"
    ));
    // Never run before, an input made by an earlier example, an output that exists here,
    // a shell operator.
    assert!(!repeats_here(
        "divertsim simulate configs/paper/machine.toml"
    ));
    assert!(!repeats_here("divertsim simulate out1 --out b"));
    assert!(!repeats_here(
        "divertsim simulate configs/paper/machine.toml --out out1"
    ));
    assert!(!repeats_here(
        "divertsim check configs/paper/machine.toml && divertsim simulate"
    ));
    std::fs::create_dir(here.join("a")).unwrap();
    assert!(!repeats_here(
        "divertsim simulate configs/paper/machine.toml --out a"
    ));
}

#[test]
#[cfg_attr(
    divertsim_no_example_tests,
    ignore = "every README and --help example, minutes of work: run with DIVERTSIM_EXAMPLE_TESTS=1"
)]
fn every_readme_and_help_example_runs_as_written() {
    let tmp = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let list = examples(readme_lines(&readme).into_iter());
    assert!(list.len() > 30, "{} README examples", list.len());
    let mut ran = HashMap::new();
    let mut failures = run_all(&fresh(tmp.path(), "readme"), "README.md", &list, &mut ran);
    let commands = Command::new(env!("CARGO_BIN_EXE_divertsim"))
        .arg("--help")
        .output()
        .unwrap();
    let help = String::from_utf8_lossy(&commands.stdout).to_string();
    // The subcommands, as `divertsim --help` lists them.
    let names: Vec<String> = help
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .filter(|n| n != "help")
        .collect();
    assert!(names.len() > 15, "{names:?}");
    for name in names {
        let out = Command::new(env!("CARGO_BIN_EXE_divertsim"))
            .args([&name, "--help"])
            .output()
            .unwrap();
        let lines = help_lines(&String::from_utf8_lossy(&out.stdout));
        let list = examples(lines.iter().map(String::as_str));
        if list.is_empty() {
            continue;
        }
        failures.extend(run_all(
            &fresh(tmp.path(), &name),
            &format!("divertsim {name} --help"),
            &list,
            &mut ran,
        ));
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
