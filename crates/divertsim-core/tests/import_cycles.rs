//! The workspace's layout rule (ARCHITECTURE.md, "Dependency rules"): no file-level import
//! cycle inside a crate. Each source file is a node; a file depends on another when it names
//! a path into it (`use`, including brace groups, and inline `crate::`/`super::`/child-module
//! paths). A module's file that only declares or re-exports its children (`mod x; pub use
//! x::Y;`) is their parent, not a peer: edges from a parent to its own children are the
//! module tree, not imports, and are left out.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Module path (e.g. `["sim", "motion"]`) of each source file of a crate's `src`.
fn modules(src: &Path) -> BTreeMap<Vec<String>, PathBuf> {
    let mut out = BTreeMap::new();
    let mut stack = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let p = entry.unwrap().path();
            if p.is_dir() {
                stack.push(p);
                continue;
            }
            if p.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let rel = p.strip_prefix(src).unwrap();
            let mut parts: Vec<String> = rel
                .iter()
                .map(|s| s.to_string_lossy().trim_end_matches(".rs").to_string())
                .collect();
            if matches!(
                parts.last().map(String::as_str),
                Some("mod" | "lib" | "main")
            ) {
                parts.pop();
            }
            if parts.first().is_some_and(|f| f == "bin") {
                continue;
            }
            out.insert(parts, p);
        }
    }
    out
}

/// The source without comments, strings and `#[cfg(test)]` modules' bodies (a test module
/// may use anything of its parent).
fn code_of(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let b = text.as_bytes();
    let mut i = 0;
    while i < b.len() {
        if b[i..].starts_with(b"//") {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if b[i..].starts_with(b"/*") {
            i += 2;
            while i + 1 < b.len() && !b[i..].starts_with(b"*/") {
                i += 1;
            }
            i += 2;
        } else if b[i] == b'"' {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                if b[i] == b'\\' {
                    i += 1;
                }
                i += 1;
            }
            i += 1;
            out.push_str("\"\"");
        } else if b[i] == b'\'' && i + 2 < b.len() && (b[i + 2] == b'\'' || b[i + 1] == b'\\') {
            // a char literal ('"', '\n'); lifetimes ('a) pass through
            i += 1;
            while i < b.len() && b[i] != b'\'' {
                if b[i] == b'\\' {
                    i += 1;
                }
                i += 1;
            }
            i += 1;
        } else {
            let ch = text[i..].chars().next().unwrap();
            out.push(ch);
            i += ch.len_utf8();
        }
    }
    match out.find("#[cfg(test)]") {
        Some(at) => out[..at].to_string(),
        None => out,
    }
}

/// Every path a `use` tree names, brace groups expanded (`a::{b, c::d}` → `a::b`, `a::c::d`).
fn expand(tree: &str) -> Vec<String> {
    let tree: String = tree.chars().filter(|c| !c.is_whitespace()).collect();
    fn go(prefix: &str, t: &str, out: &mut Vec<String>) {
        match t.find('{') {
            None => out.push(format!("{prefix}{t}")),
            Some(open) => {
                let head = &t[..open];
                let inner = &t[open + 1..t.len() - 1];
                let mut depth = 0;
                let mut start = 0;
                for (k, c) in inner.char_indices() {
                    match c {
                        '{' => depth += 1,
                        '}' => depth -= 1,
                        ',' if depth == 0 => {
                            go(&format!("{prefix}{head}"), &inner[start..k], out);
                            start = k + 1;
                        }
                        _ => {}
                    }
                }
                if start < inner.len() {
                    go(&format!("{prefix}{head}"), &inner[start..], out);
                }
            }
        }
    }
    let mut out = Vec::new();
    go("", &tree, &mut out);
    out
}

/// Paths named in a file's code: its `use` trees and inline `a::b::c` paths.
fn named_paths(code: &str) -> Vec<Vec<String>> {
    let mut paths = Vec::new();
    let mut rest = code;
    // `use` statements (brace groups may span lines)
    while let Some(at) = rest.find("use ") {
        let before = rest[..at].chars().last();
        let after = &rest[at + 4..];
        rest = after;
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let Some(end) = after.find(';') else { break };
        for p in expand(&after[..end]) {
            let p = p.split(" as ").next().unwrap_or("").to_string();
            paths.push(p.split("::").map(str::to_string).collect());
        }
    }
    // inline paths
    let bytes = code.as_bytes();
    let mut i = 0;
    while i < bytes.len() {
        if (bytes[i].is_ascii_alphabetic() || bytes[i] == b'_')
            && (i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_'))
            && (i == 0 || bytes[i - 1] != b':')
        {
            let start = i;
            while i < bytes.len()
                && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_' || bytes[i] == b':')
            {
                i += 1;
            }
            let path = &code[start..i];
            if path.contains("::") {
                paths.push(
                    path.split("::")
                        .filter(|s| !s.is_empty())
                        .map(str::to_string)
                        .collect(),
                );
            }
        } else {
            i += 1;
        }
    }
    paths
}

/// The file a path of module `at` names, if any: the longest module prefix of the path
/// resolved from `crate`, `super`, `self` or a child module of `at`.
fn target(
    at: &[String],
    path: &[String],
    mods: &BTreeMap<Vec<String>, PathBuf>,
) -> Option<Vec<String>> {
    let mut base: Vec<String> = at.to_vec();
    let mut rest = path;
    match path.first()?.as_str() {
        "crate" => {
            base.clear();
            rest = &path[1..];
        }
        "self" => rest = &path[1..],
        "super" => {
            while rest.first().is_some_and(|s| s == "super") {
                base.pop()?;
                rest = &rest[1..];
            }
        }
        first => {
            let mut child = at.to_vec();
            child.push(first.to_string());
            if !mods.contains_key(&child) {
                return None;
            }
        }
    }
    let start = base.clone();
    let mut full = base;
    let mut best = None;
    for seg in rest {
        full.push(seg.clone());
        if mods.contains_key(&full) {
            best = Some(full.clone());
        } else {
            break;
        }
    }
    // No module prefix: the path names an item of the module it starts from (an inline
    // module's item is its file's).
    best.or_else(|| (!rest.is_empty() && path[0] != "self").then_some(start))
        .filter(|m| mods.contains_key(m))
}

/// The files of one crate's `src` by module path, and which import which (a file to
/// itself and a parent to its own descendant left out: the module tree).
type Graph = (
    BTreeMap<Vec<String>, PathBuf>,
    BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
);

fn file_graph(src: &Path) -> Graph {
    let mods = modules(src);
    let mut edges: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    for (m, file) in &mods {
        let code = code_of(&std::fs::read_to_string(file).unwrap());
        for p in named_paths(&code) {
            if let Some(t) = target(m, &p, &mods) {
                if &t != m && !t.starts_with(m) {
                    edges.entry(m.clone()).or_default().insert(t);
                }
            }
        }
    }
    (mods, edges)
}

/// The strongly connected components of more than one node (Tarjan's algorithm).
fn components(adj: &[Vec<usize>]) -> Vec<Vec<usize>> {
    let n = adj.len();
    let (mut index, mut low, mut on) = (vec![usize::MAX; n], vec![0; n], vec![false; n]);
    let (mut stack, mut next, mut out) = (Vec::new(), 0, Vec::new());
    type State<'a> = (
        &'a mut Vec<usize>,
        &'a mut Vec<usize>,
        &'a mut Vec<bool>,
        &'a mut Vec<usize>,
        &'a mut usize,
    );
    fn visit(v: usize, adj: &[Vec<usize>], st: &mut State, out: &mut Vec<Vec<usize>>) {
        st.0[v] = *st.4;
        st.1[v] = *st.4;
        *st.4 += 1;
        st.3.push(v);
        st.2[v] = true;
        for &w in &adj[v] {
            if st.0[w] == usize::MAX {
                visit(w, adj, st, out);
                st.1[v] = st.1[v].min(st.1[w]);
            } else if st.2[w] {
                st.1[v] = st.1[v].min(st.0[w]);
            }
        }
        if st.1[v] == st.0[v] {
            let mut comp = Vec::new();
            loop {
                let w = st.3.pop().unwrap();
                st.2[w] = false;
                comp.push(w);
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                out.push(comp);
            }
        }
    }
    for v in 0..n {
        if index[v] == usize::MAX {
            let mut st = (&mut index, &mut low, &mut on, &mut stack, &mut next);
            visit(v, adj, &mut st, &mut out);
        }
    }
    out
}

/// The cycles of a graph given as named edges, each as its node names sorted.
fn cycles_of(
    nodes: &BTreeSet<String>,
    edges: &BTreeMap<String, BTreeSet<String>>,
) -> Vec<Vec<String>> {
    let names: Vec<&String> = nodes.iter().collect();
    let index_of: BTreeMap<&String, usize> =
        names.iter().enumerate().map(|(i, n)| (*n, i)).collect();
    let adj: Vec<Vec<usize>> = names
        .iter()
        .map(|m| {
            edges
                .get(*m)
                .map(|s| s.iter().map(|t| index_of[t]).collect())
                .unwrap_or_default()
        })
        .collect();
    components(&adj)
        .into_iter()
        .map(|comp| {
            let mut c: Vec<String> = comp.iter().map(|&i| names[i].clone()).collect();
            c.sort();
            c
        })
        .collect()
}

/// The import cycles of one crate's `src` (each as its files in order), none if acyclic.
fn cycles(src: &Path) -> Vec<Vec<String>> {
    let (mods, edges) = file_graph(src);
    let name = |m: &Vec<String>| format!("{}", mods[m].strip_prefix(src).unwrap().display());
    let nodes: BTreeSet<String> = mods.keys().map(name).collect();
    let edges: BTreeMap<String, BTreeSet<String>> = edges
        .iter()
        .map(|(m, ts)| (name(m), ts.iter().map(name).collect()))
        .collect();
    cycles_of(&nodes, &edges)
}

/// The folder-level import cycles of one crate's `src`: folders that import each other
/// through any of their files (`analysis/paper/` and `analysis/design/`). A file's import
/// of another in a different folder is an edge between the two folders just below their
/// common parent, so that sibling folders are compared whatever their depth; a folder and
/// its own parent or child folder are the module tree, not peers.
fn folder_cycles(src: &Path) -> Vec<Vec<String>> {
    let (mods, edges) = file_graph(src);
    let folder = |m: &Vec<String>| -> Vec<String> {
        let rel = mods[m].strip_prefix(src).unwrap();
        rel.parent()
            .map(|p| p.iter().map(|s| s.to_string_lossy().into_owned()).collect())
            .unwrap_or_default()
    };
    let mut nodes = BTreeSet::new();
    let mut folder_edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (m, ts) in &edges {
        let a = folder(m);
        for t in ts {
            let b = folder(t);
            let k = a.iter().zip(&b).take_while(|(x, y)| x == y).count();
            if k == a.len() || k == b.len() {
                continue;
            }
            let (x, y) = (a[..=k].join("/") + "/", b[..=k].join("/") + "/");
            nodes.insert(x.clone());
            nodes.insert(y.clone());
            folder_edges.entry(x).or_default().insert(y);
        }
    }
    cycles_of(&nodes, &folder_edges)
}

fn workspace_crates() -> Vec<PathBuf> {
    let crates = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut v: Vec<PathBuf> = std::fs::read_dir(&crates)
        .unwrap()
        .map(|e| e.unwrap().path().join("src"))
        .filter(|p| p.is_dir())
        .collect();
    v.sort();
    v
}

#[test]
fn no_file_level_import_cycle_in_any_crate() {
    let mut found = Vec::new();
    for src in workspace_crates() {
        for c in cycles(&src) {
            found.push(format!("{}: {}", src.display(), c.join(" <-> ")));
        }
    }
    assert!(found.is_empty(), "import cycles:\n{}", found.join("\n"));
}

/// Issue 48, item 7: folders that import each other (`paper/` and `design/`) are one
/// component in two places; the check covers folders as it covers files.
#[test]
fn no_folder_level_import_cycle_in_any_crate() {
    let mut found = Vec::new();
    for src in workspace_crates() {
        for c in folder_cycles(&src) {
            found.push(format!("{}: {}", src.display(), c.join(" <-> ")));
        }
    }
    assert!(
        found.is_empty(),
        "folder import cycles:\n{}",
        found.join("\n")
    );
}

/// The checker finds a cycle where there is one (two files naming each other), and none in
/// a parent that only declares its children.
#[test]
fn the_cycle_check_sees_a_planted_cycle() {
    let dir = tempfile_dir("file");
    let src = dir.join("src");
    std::fs::create_dir_all(src.join("a")).unwrap();
    std::fs::write(src.join("lib.rs"), "pub mod a;\npub use a::x::X;\n").unwrap();
    std::fs::write(src.join("a.rs"), "pub mod x;\npub mod y;\n").unwrap();
    std::fs::write(
        src.join("a/x.rs"),
        "use super::y::{Y, /* z */ W};\npub struct X;\n",
    )
    .unwrap();
    std::fs::write(
        src.join("a/y.rs"),
        "pub fn f() { let _ = crate::a::x::X; }\n",
    )
    .unwrap();
    assert_eq!(
        cycles(&src),
        vec![vec!["a/x.rs".to_string(), "a/y.rs".into()]]
    );
    std::fs::write(
        src.join("a/y.rs"),
        "pub fn f() { let _ = \"crate::a::x::X\"; }\n",
    )
    .unwrap();
    assert!(cycles(&src).is_empty());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A path through an inline module (`crate::assets::{A as B}`, the inline `mod assets` of
/// lib.rs, as the report crate has) names lib.rs: the resolver took the unmatched tail for
/// a longer prefix than the path had and panicked on the slice.
#[test]
fn a_path_through_an_inline_module_names_its_file() {
    let dir = tempfile_dir("inline");
    let src = dir.join("src");
    std::fs::create_dir_all(&src).unwrap();
    std::fs::write(
        src.join("lib.rs"),
        "pub mod run;\npub mod assets { pub const A: u8 = 1; }\n",
    )
    .unwrap();
    std::fs::write(
        src.join("run.rs"),
        "use crate::assets::{A as B};\npub fn f() -> u8 { B }\n",
    )
    .unwrap();
    let (_, edges) = file_graph(&src);
    assert_eq!(
        edges.get(&vec!["run".to_string()]),
        Some(&BTreeSet::from([Vec::<String>::new()]))
    );
    assert!(cycles(&src).is_empty());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The folder check finds two sibling folders that import each other through different
/// files (no file-level cycle), and none between a folder and its own child folder.
#[test]
fn the_folder_check_sees_sibling_folders_importing_each_other() {
    let dir = tempfile_dir("folders");
    let src = dir.join("src");
    std::fs::create_dir_all(src.join("a/p/deep")).unwrap();
    std::fs::create_dir_all(src.join("a/d")).unwrap();
    std::fs::write(src.join("lib.rs"), "pub mod a;\n").unwrap();
    std::fs::write(src.join("a/mod.rs"), "pub mod d;\npub mod p;\n").unwrap();
    std::fs::write(src.join("a/p/mod.rs"), "pub mod deep;\npub mod low;\n").unwrap();
    std::fs::write(src.join("a/p/low.rs"), "pub struct L;\n").unwrap();
    std::fs::write(src.join("a/p/deep/mod.rs"), "pub mod high;\n").unwrap();
    std::fs::write(
        src.join("a/p/deep/high.rs"),
        "use crate::a::d::set::S;\npub struct H;\n",
    )
    .unwrap();
    std::fs::write(src.join("a/d/mod.rs"), "pub mod set;\n").unwrap();
    std::fs::write(
        src.join("a/d/set.rs"),
        "use crate::a::p::low::L;\npub struct S;\n",
    )
    .unwrap();
    assert!(cycles(&src).is_empty());
    assert_eq!(
        folder_cycles(&src),
        vec![vec!["a/d/".to_string(), "a/p/".into()]]
    );
    // The higher file moved up into `a/`: a parent folder using its children is the tree.
    std::fs::remove_dir_all(src.join("a/p/deep")).unwrap();
    std::fs::write(src.join("a/p/mod.rs"), "pub mod low;\n").unwrap();
    std::fs::write(
        src.join("a/mod.rs"),
        "pub mod d;\npub mod high;\npub mod p;\n",
    )
    .unwrap();
    std::fs::write(
        src.join("a/high.rs"),
        "use crate::a::d::set::S;\npub struct H;\n",
    )
    .unwrap();
    assert!(folder_cycles(&src).is_empty());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A fresh folder of its own for each test (`name`): the tests run as threads of one
/// process, so the process id alone is shared.
fn tempfile_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("divertsim-cycles-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}
