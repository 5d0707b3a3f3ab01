//! The scenario presets of the repository's `configs/` (the paper's machine and figures,
//! the hub mix, the default), built into the binary so that an installed `divertsim` has
//! them too: `divertsim preset` lists them, prints one, or writes them all into a folder.

use std::path::Path;

/// Every preset: its path below `configs/` and its text.
pub const PRESETS: &[(&str, &str)] = &[
    (
        "default.toml",
        include_str!("../../../configs/default.toml"),
    ),
    (
        "mix/hub.toml",
        include_str!("../../../configs/mix/hub.toml"),
    ),
    (
        "paper/fig03.toml",
        include_str!("../../../configs/paper/fig03.toml"),
    ),
    (
        "paper/fig05.toml",
        include_str!("../../../configs/paper/fig05.toml"),
    ),
    (
        "paper/fig06.toml",
        include_str!("../../../configs/paper/fig06.toml"),
    ),
    (
        "paper/fig07.toml",
        include_str!("../../../configs/paper/fig07.toml"),
    ),
    (
        "paper/fig08.toml",
        include_str!("../../../configs/paper/fig08.toml"),
    ),
    (
        "paper/fig13a.toml",
        include_str!("../../../configs/paper/fig13a.toml"),
    ),
    (
        "paper/fig13b.toml",
        include_str!("../../../configs/paper/fig13b.toml"),
    ),
    (
        "paper/fig14a.toml",
        include_str!("../../../configs/paper/fig14a.toml"),
    ),
    (
        "paper/fig14b.toml",
        include_str!("../../../configs/paper/fig14b.toml"),
    ),
    (
        "paper/fig15a.toml",
        include_str!("../../../configs/paper/fig15a.toml"),
    ),
    (
        "paper/fig15b.toml",
        include_str!("../../../configs/paper/fig15b.toml"),
    ),
    (
        "paper/line.toml",
        include_str!("../../../configs/paper/line.toml"),
    ),
    (
        "paper/line_two.toml",
        include_str!("../../../configs/paper/line_two.toml"),
    ),
    (
        "paper/machine.toml",
        include_str!("../../../configs/paper/machine.toml"),
    ),
    (
        "paper/mix.toml",
        include_str!("../../../configs/paper/mix.toml"),
    ),
    (
        "paper/proposed.toml",
        include_str!("../../../configs/paper/proposed.toml"),
    ),
    (
        "paper/robust_optimum.toml",
        include_str!("../../../configs/paper/robust_optimum.toml"),
    ),
    ("wedge.toml", include_str!("../../../configs/wedge.toml")),
];

/// The preset called `name`: its path below `configs/` with or without `.toml` or a leading
/// `configs/` ("paper/fig13a", "configs/paper/fig13a.toml").
pub fn find(name: &str) -> Option<(&'static str, &'static str)> {
    let n = name.trim().trim_start_matches("./");
    let n = n.strip_prefix("configs/").unwrap_or(n);
    let n = n.strip_suffix(".toml").unwrap_or(n);
    PRESETS
        .iter()
        .copied()
        .find(|(p, _)| p.strip_suffix(".toml") == Some(n))
}

/// The first comment line of a preset (what it is).
pub fn description(text: &str) -> &str {
    text.lines()
        .next()
        .and_then(|l| l.strip_prefix('#'))
        .map_or("", str::trim)
}

/// Write every preset below `dir`, keeping the folders (`paper/fig13a.toml` builds on
/// `paper/machine.toml` through its relative `base`).
pub fn write_all(dir: &Path) -> Result<(), crate::contract::Error> {
    use crate::contract::Error;
    for (path, text) in PRESETS {
        let p = dir.join(path);
        if let Some(parent) = p.parent() {
            std::fs::create_dir_all(parent)
                .map_err(|e| Error::Io(format!("cannot create {}: {e}", parent.display())))?;
        }
        std::fs::write(&p, text)
            .map_err(|e| Error::Io(format!("cannot write {}: {e}", p.display())))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every file of configs/ is a preset, byte for byte.
    #[test]
    fn presets_are_the_configs_folder() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs");
        let mut on_disk = Vec::new();
        fn walk(root: &Path, dir: &Path, out: &mut Vec<String>) {
            for e in std::fs::read_dir(dir).unwrap() {
                let p = e.unwrap().path();
                if p.is_dir() {
                    walk(root, &p, out);
                } else if p.extension().is_some_and(|x| x == "toml") {
                    out.push(p.strip_prefix(root).unwrap().display().to_string());
                }
            }
        }
        walk(&root, &root, &mut on_disk);
        on_disk.sort();
        let built_in: Vec<String> = PRESETS.iter().map(|(p, _)| p.to_string()).collect();
        assert_eq!(
            built_in, on_disk,
            "a new file in configs/ must be added to PRESETS"
        );
        for (p, text) in PRESETS {
            assert_eq!(std::fs::read_to_string(root.join(p)).unwrap(), *text, "{p}");
        }
    }

    #[test]
    fn names_are_forgiving() {
        for n in [
            "paper/fig13a",
            "paper/fig13a.toml",
            "configs/paper/fig13a.toml",
            "./paper/fig13a",
        ] {
            assert_eq!(find(n).unwrap().0, "paper/fig13a.toml", "{n}");
        }
        assert!(find("paper/fig99").is_none());
        assert!(description(find("paper/machine").unwrap().1).starts_with("The paper's machine"));
    }
}
