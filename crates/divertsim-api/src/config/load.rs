//! Loading: a file and its `base` chain (or standard input, or a table), `--set` overrides
//! applied exactly, deserialisation with every problem collected, and the resolved file
//! written back (a pose's scenario, a standalone file, TOML text).

// The sibling files this one uses, named so that the import-cycle check sees them.
use super::convert::to_scenario;
use super::design::design_set;
use super::problems::{Problem, Problems};
use super::schema::{BeltFrictionConfig, ParcelConfig, ScenarioFile};
use super::validate::validate;
#[allow(unused_imports)]
use super::*;

/// A validated scenario: what the file said (after defaults and overrides) and the core's
/// SI scenario built from it.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// The file, resolved: no `base` (its keys merged in), a drive table read into
    /// `machine.drive.points`, and `mix.records` relative to the working directory.
    pub file: ScenarioFile,
    pub scenario: Scenario,
    /// The `[design]` section as the core's design set.
    pub design: DesignSet,
    /// The `[mix]` section as the core's parcel mix (defaults filled in).
    pub mix: divertsim_core::analysis::population::mix::ParcelMix,
    /// The rule it was loaded under (its variants load under the same).
    pub options: LoadOptions,
}

/// Where a scenario comes from.
#[derive(Debug, Clone, Default)]
enum Source {
    /// The built-in default scenario.
    #[default]
    Default,
    /// A file (or `-`, standard input) and its `base` chain.
    File(PathBuf),
    /// A table an edge built from its own data; its paths relative to `dir`, `name` standing
    /// for it in messages.
    Table {
        table: toml::Table,
        name: String,
        dir: PathBuf,
    },
    /// A table whose `base` chain is merged in and whose paths are resolved already.
    Merged(toml::Table),
    /// A loaded scenario's resolved file.
    Resolved(Box<ScenarioFile>),
}

/// The one way to load a scenario: its source (the built-in default, a file with its `base`
/// chain, or a table an edge built), the rule for the files it names ([`files`]), and
/// overrides applied exactly as `--set` applies them. [`ScenarioBuilder::load`] validates
/// and converts, reporting every problem at once; [`ScenarioBuilder::merged`] reads the
/// source once for many variants (a sweep, a batch of overrides).
///
/// ```
/// use divertsim_api::config::ScenarioBuilder;
///
/// let loaded = ScenarioBuilder::new()
///     .set("machine.belt_speed=1.5")
///     .load()
///     .expect("a valid scenario");
/// assert_eq!(loaded.scenario.machine.belt_speed, 1.5);
///
/// // Every problem at once, each named by its key.
/// let problems = ScenarioBuilder::new()
///     .set("machine.belt_speed=-3")
///     .set("parcel.mass=0")
///     .load()
///     .unwrap_err();
/// let keys: Vec<&str> = problems.0.iter().map(|p| p.key.as_str()).collect();
/// assert_eq!(keys, ["machine.belt_speed", "parcel.mass"]);
///
/// // One source, read once, many variants.
/// let base = ScenarioBuilder::new().merged().unwrap();
/// for v in [1.0, 2.0] {
///     let l = base.clone().value("machine.belt_speed", toml::Value::Float(v)).load().unwrap();
///     assert_eq!(l.scenario.machine.belt_speed, v);
/// }
/// ```
#[derive(Debug, Clone, Default)]
pub struct ScenarioBuilder {
    source: Source,
    options: LoadOptions,
    sets: Vec<Result<(String, toml::Value), Problem>>,
}

impl ScenarioBuilder {
    /// The built-in default scenario.
    pub fn new() -> ScenarioBuilder {
        ScenarioBuilder::default()
    }

    /// A scenario file (`-`: standard input) with its `base` chain.
    pub fn file(path: impl Into<PathBuf>) -> ScenarioBuilder {
        ScenarioBuilder {
            source: Source::File(path.into()),
            ..ScenarioBuilder::default()
        }
    }

    /// A file, or the built-in default for `None`.
    pub fn path(path: Option<&Path>) -> ScenarioBuilder {
        path.map_or_else(ScenarioBuilder::new, ScenarioBuilder::file)
    }

    /// A scenario given as a table (an edge's own data, e.g. a Python dict): the paths it
    /// names (`base`, `machine.drive.table`, `mix.records`) are relative to `dir` and follow
    /// the rule of [`files`] as if the table were a file there; `name` stands for it in
    /// messages. An empty table is the built-in default scenario.
    pub fn table(table: toml::Table, name: &str, dir: &Path) -> ScenarioBuilder {
        ScenarioBuilder {
            source: Source::Table {
                table,
                name: name.to_string(),
                dir: dir.to_path_buf(),
            },
            ..ScenarioBuilder::default()
        }
    }

    /// A loaded scenario's resolved file as the source (no `base`, the drive table inline,
    /// the records' path relative to the working directory), under the rule it was loaded
    /// with: its variants load exactly as the file with `--set` would.
    pub fn resolved(loaded: &Loaded) -> ScenarioBuilder {
        ScenarioBuilder {
            source: Source::Resolved(Box::new(loaded.file.clone())),
            options: loaded.options,
            ..ScenarioBuilder::default()
        }
    }

    /// The rule for the files the scenario names.
    pub fn options(mut self, options: LoadOptions) -> ScenarioBuilder {
        self.options = options;
        self
    }

    /// Let the scenario read files outside its directory (`--allow-outside-paths`).
    pub fn allow_outside_paths(mut self, allow: bool) -> ScenarioBuilder {
        self.options.allow_outside_paths = allow;
        self
    }

    /// An override as `--set` gives it: `KEY=VALUE`, the value in TOML.
    pub fn set(mut self, text: &str) -> ScenarioBuilder {
        self.sets.push(parse_set(text));
        self
    }

    /// Overrides as `--set` texts, in order.
    pub fn sets(self, texts: &[String]) -> ScenarioBuilder {
        texts.iter().fold(self, |b, t| b.set(t))
    }

    /// An override of a dotted key by a TOML value, exactly.
    pub fn value(mut self, key: &str, value: toml::Value) -> ScenarioBuilder {
        self.sets.push(Ok((key.to_string(), value)));
        self
    }

    /// Overrides as (dotted key, value) pairs, in order.
    pub fn values(self, pairs: &[(String, toml::Value)]) -> ScenarioBuilder {
        pairs.iter().fold(self, |b, (k, v)| b.value(k, v.clone()))
    }

    /// The source read once (its `base` chain merged in, its paths checked and resolved),
    /// the overrides given so far kept: clone it for each variant.
    pub fn merged(self) -> Result<ScenarioBuilder, Problems> {
        let (table, sets, options) = self.into_parts()?;
        Ok(ScenarioBuilder {
            source: Source::Merged(table),
            options,
            sets,
        })
    }

    /// Read, override, validate and convert: the scenario, or every problem.
    pub fn load(self) -> Result<Loaded, Problems> {
        let (table, sets, options) = self.into_parts()?;
        resolve(table, sets.into_iter(), options)
    }

    /// The merged table, the overrides and the rule.
    #[allow(clippy::type_complexity)]
    fn into_parts(
        self,
    ) -> Result<
        (
            toml::Table,
            Vec<Result<(String, toml::Value), Problem>>,
            LoadOptions,
        ),
        Problems,
    > {
        let table = match self.source {
            Source::Default => toml::Table::new(),
            Source::File(p) => read_layered(&p, 0, self.options)?,
            Source::Table { table, name, dir } => layered(table, &name, &dir, 0, self.options)?,
            Source::Merged(t) => t,
            Source::Resolved(f) => toml::Table::try_from(&*f)
                .map_err(|e| Problems(vec![Problem::new("scenario", e.to_string())]))?,
        };
        Ok((table, self.sets, self.options))
    }
}

/// The default scenario or a file with `--set` overrides, files outside the scenario's
/// directory refused: `ScenarioBuilder::path(path).sets(sets).load()`.
pub fn load(path: Option<&Path>, sets: &[String]) -> Result<Loaded, Problems> {
    load_with(path, sets, LoadOptions::default())
}

/// [`load`] under the rule `options`: `ScenarioBuilder::path(path).options(options)
/// .sets(sets).load()`.
pub fn load_with(
    path: Option<&Path>,
    sets: &[String],
    options: LoadOptions,
) -> Result<Loaded, Problems> {
    ScenarioBuilder::path(path)
        .options(options)
        .sets(sets)
        .load()
}

/// Override, validate and convert a scenario table whose `base` chain is merged in already.
pub(super) fn resolve(
    mut table: toml::Table,
    sets: impl Iterator<Item = Result<(String, toml::Value), Problem>>,
    options: LoadOptions,
) -> Result<Loaded, Problems> {
    let mut problems = Vec::new();
    // The paths the files named are checked and resolved already; one an override adds or
    // replaces, wherever it sits (a whole section set at once, a diverter's machine), is
    // relative to the working directory, or refused where overrides may name no file.
    let from_files: std::collections::BTreeMap<String, toml::Value> =
        files::named_files(&mut table)
            .into_iter()
            .map(|(k, v)| (k, v.clone()))
            .collect();
    for set in sets {
        if let Err(p) = set.and_then(|(key, value)| set_value(&mut table, &key, value)) {
            problems.push(p);
        }
    }
    for (key, value) in files::named_files(&mut table) {
        if from_files.get(&key) == Some(value) {
            continue;
        }
        if options.overrides_name_no_files {
            problems.push(files::override_file_problem(&key));
        } else if let toml::Value::String(raw) = value {
            problems.extend(files::outside_problem(
                &key,
                raw,
                Path::new("."),
                Origin::Set,
                options,
            ));
        }
    }
    let mut file = deserialize_collecting(table, &mut problems);
    validate(&file, &mut problems);
    if !problems.is_empty() {
        return Err(Problems(problems));
    }
    let (scenario, rows) = to_scenario(&file).map_err(Problems)?;
    // A cycle under way at t = 0 may put the arm inside the parcel: no state a machine is
    // ever in, and the run would start with a strike from inside it.
    if let Some((alpha, depth)) = divertsim_core::sim::arm_across_parcel_at_start(&scenario) {
        return Err(Problems(vec![Problem::new(
            "run.cycle_starts",
            format!(
                "a cycle under way at t = 0 puts the arm at α = {:.1}° across the parcel, {:.1} \
                 cm deep (the parcel is placed by parcel.offset, parcel.angle_deg and \
                 machine.start_position); allowed: a start that leaves the arm clear of the \
                 parcel at t = 0: start the cycle later, or place the parcel clear of the arm",
                alpha.to_degrees(),
                100.0 * depth
            ),
        )]));
    }
    // The table travels with the file from here on: a file written from it stands alone.
    if let Some(rows) = rows {
        file.machine.drive.table = None;
        file.machine.drive.points = Some(rows);
    }
    let design = design_set(&file.design, file.machine.belt_width);
    let mix = mix::parcel_mix(&file.mix, file.design.search.height).map_err(Problems)?;
    Ok(Loaded {
        file,
        scenario,
        design,
        mix,
        options,
    })
}

/// The scenario file of one searched pose: `file` with the setting of `setting` (v, t_c,
/// R_s, S_d, the run length) and the parcel and materials of `pose`, resolved exactly as
/// [`Pose::scenario`] resolves them, so that loading the file gives that scenario bit for
/// bit. The file stands alone ([`standalone`]).
pub fn pose_file(file: &ScenarioFile, setting: &Scenario, pose: &Pose) -> ScenarioFile {
    scenario_file(file, &pose.scenario(setting), pose.angle_deg)
}

/// The scenario file of a resolved run `s` (setting, parcel, materials and run length; φ
/// given in degrees as `angle_deg`, so that the file states what the caller chose):
/// `file`'s other keys, standing alone ([`standalone`]).
pub fn scenario_file(file: &ScenarioFile, s: &Scenario, angle_deg: f64) -> ScenarioFile {
    let mut f = standalone(file);
    f.machine.belt_speed = s.machine.belt_speed;
    f.machine.cycle_time = s.machine.cycle_time;
    f.machine.start_position = s.machine.start_position;
    // An early arrival can put R_s upstream of S_d, which a file may not state; S_d does not
    // change a run (only the capacity), so it moves with R_s.
    f.machine.light_barrier = s.machine.light_barrier.min(s.machine.start_position);
    f.machine.trigger = crate::config::mix::TriggerConfig::Fixed;
    f.parcel = ParcelConfig {
        length: s.parcel.length,
        width: s.parcel.width,
        height: s.parcel.height,
        com_height: s.parcel.com_height,
        mass: s.parcel.mass,
        offset: s.parcel.offset,
        angle_deg,
        velocity: s.parcel.velocity.map(|v| [v.x, v.y]),
        spin: s.parcel.spin,
    };
    f.materials.belt_friction = match &s.materials.belt_friction {
        FrictionCoefficient::Constant(m) => BeltFrictionConfig::Constant(*m),
        FrictionCoefficient::Table(t) => {
            BeltFrictionConfig::Table(t.iter().map(|&(v, m)| [v, m]).collect())
        }
    };
    f.materials.arm_friction = s.materials.arm_friction;
    f.materials.restitution = s.materials.restitution;
    f.run.duration = Some(s.run.duration);
    f
}

/// A resolved scenario file (as [`load`] gives it) that stands alone, so that a file
/// written from it reloads wherever it is put: no `base`, the drive table inline (`load`
/// reads it into `machine.drive.points`), and `mix.records`, a file too large to inline,
/// made absolute. An output folder then copies such files beside the scenario files that name
/// them ([`crate::output::bundle_inputs`]), so that it reruns without `--allow-outside-paths`.
pub fn standalone(file: &ScenarioFile) -> ScenarioFile {
    let mut f = file.clone();
    f.base = None;
    let absolute = |t: &mut Option<String>| {
        if let Some(rel) = t.as_ref().filter(|t| Path::new(t.as_str()).is_relative()) {
            let p = PathBuf::from(rel);
            let p = p
                .canonicalize()
                .or_else(|_| std::path::absolute(&p))
                .unwrap_or(p);
            *t = Some(p.display().to_string());
        }
    };
    absolute(&mut f.machine.drive.table);
    absolute(&mut f.mix.records);
    absolute(&mut f.line.arrivals);
    // A further diverter's machine is a free table: every file it names, wherever.
    for d in &mut f.line.diverters {
        for (_, v) in files::named_files(&mut d.machine) {
            if let toml::Value::String(raw) = v {
                let mut t = Some(std::mem::take(raw));
                absolute(&mut t);
                *raw = t.unwrap_or_default();
            }
        }
    }
    f
}

/// A scenario file as TOML text, with a comment heading it; the file stands alone
/// ([`standalone`]).
pub fn to_toml(file: &ScenarioFile, heading: &str) -> Result<String, crate::contract::Error> {
    let body = toml::to_string(&standalone(file)).map_err(crate::contract::Error::io)?;
    let head: String = heading.lines().map(|l| format!("# {l}\n")).collect();
    Ok(format!("{head}\n{body}"))
}

/// Largest chain of `base` files.
pub(super) const MAX_BASE_DEPTH: usize = 8;

/// Read a scenario file as a TOML table with its `base` chain merged underneath (the file's
/// own keys win). Every path a file names is checked against the rule of [`files`] and made
/// relative to the working directory, so that it still names the same file once merged.
pub(super) fn read_layered(
    p: &Path,
    depth: usize,
    options: LoadOptions,
) -> Result<toml::Table, Problems> {
    let key = p.display().to_string();
    let text = if depth == 0 && p == Path::new("-") {
        stdin_text().map_err(|e| {
            Problems(vec![Problem::new(
                "-",
                format!("cannot read the scenario from standard input: {e}"),
            )])
        })?
    } else {
        files::scenario_text(p, depth > 0).map_err(|e| {
            Problems(vec![Problem::new(
                &key,
                format!("cannot read the scenario file: {e}"),
            )])
        })?
    };
    // An empty file or an empty pipe is almost always a mistake upstream (a generator that
    // failed, a file not yet written): running the built-in default in its place would
    // answer a question nobody asked.
    if text.trim().is_empty() {
        return Err(Problems(vec![Problem::new(
            &key,
            "is empty; allowed: a scenario naming at least one key (run the command without a \
             scenario for the built-in default)",
        )]));
    }
    let table = files::parse_toml(&text).map_err(|e| Problems(vec![Problem::new(&key, e)]))?;
    layered(
        table,
        &key,
        p.parent().unwrap_or(Path::new("")),
        depth,
        options,
    )
}

/// The scenario table `table`, read from `key` in directory `dir`, with its `base` chain
/// merged underneath and its paths checked and made relative to the working directory.
pub(super) fn layered(
    mut table: toml::Table,
    key: &str,
    dir: &Path,
    depth: usize,
    options: LoadOptions,
) -> Result<toml::Table, Problems> {
    let mut problems = Vec::new();
    for (k, value) in files::named_files(&mut table) {
        if let toml::Value::String(raw) = value {
            match files::outside_problem(&k, raw, dir, Origin::File(key), options) {
                Some(pr) => problems.push(pr),
                None => *raw = dir.join(raw.as_str()).display().to_string(),
            }
        }
    }
    if !problems.is_empty() {
        return Err(Problems(problems));
    }
    let Some(base) = table.remove("base") else {
        return Ok(table);
    };
    let toml::Value::String(base) = base else {
        return Err(Problems(vec![Problem::new(
            "base",
            format!("in {key}: must be a string, the path of another scenario file"),
        )]));
    };
    if depth + 1 >= MAX_BASE_DEPTH {
        return Err(Problems(vec![Problem::new(
            "base",
            format!("in {key}: more than {MAX_BASE_DEPTH} files chained by `base` (a cycle?)"),
        )]));
    }
    let base_path = PathBuf::from(base);
    let mut merged = read_layered(&base_path, depth + 1, options).map_err(|mut e| {
        for pr in &mut e.0 {
            if pr.key == base_path.display().to_string() {
                pr.key = "base".into();
                pr.message = format!("in {key}: {}: {}", base_path.display(), pr.message);
            }
        }
        e
    })?;
    merge_tables(&mut merged, table);
    Ok(merged)
}

/// A scenario given as `-`: standard input, read once (a command may load it several
/// times: per sweep point, per track); relative paths in it are relative to the working
/// directory.
pub(super) fn stdin_text() -> Result<String, String> {
    static TEXT: std::sync::OnceLock<Result<String, String>> = std::sync::OnceLock::new();
    TEXT.get_or_init(|| files::capped_text(std::io::stdin()))
        .clone()
}

/// Deep merge: keys of `top` override those of `bottom`; sections merge key by key.
pub(super) fn merge_tables(bottom: &mut toml::Table, top: toml::Table) {
    for (k, v) in top {
        match (bottom.get_mut(&k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(t)) => merge_tables(b, t),
            (_, v) => {
                bottom.insert(k, v);
            }
        }
    }
}

/// Apply one `--set KEY=VALUE`; VALUE is a TOML value (`1.5`, `[3.0, 0.0]`, `"seed"`); a bare
/// word is taken as a string.
pub fn apply_set(table: &mut toml::Table, set: &str) -> Result<(), Problem> {
    let (key, value) = parse_set(set)?;
    set_value(table, &key, value)
}

/// Split one `--set KEY=VALUE` into its key and its TOML value (see [`apply_set`]).
pub fn parse_set(set: &str) -> Result<(String, toml::Value), Problem> {
    let Some((key, raw)) = set.split_once('=') else {
        return Err(Problem::new(
            "--set",
            format!("'{set}' is not KEY=VALUE (e.g. machine.belt_speed=1.5)"),
        ));
    };
    let key = key.trim();
    let raw = raw.trim();
    if raw.contains('\n') || raw.contains('\r') {
        return Err(Problem::new(
            key,
            "--set value spans several lines; allowed: one TOML value on one line",
        ));
    }
    check_key(key, &format!("'{set}'"))?;
    let parsed = toml::from_str::<toml::Table>(&format!("v = {raw}"));
    // A key that names a file takes a bare path as written (`mix.records=dims.csv`), as an
    // enum key takes a bare word: only a quoted TOML string is read as TOML there.
    if names_a_file(key)
        && !matches!(&parsed, Ok(t) if matches!(t.get("v"), Some(toml::Value::String(_))))
    {
        if raw.is_empty() {
            return Err(Problem::new(
                key,
                "--set gives an empty path; allowed: a file name",
            ));
        }
        return Ok((key.to_string(), toml::Value::String(raw.to_string())));
    }
    let value = match parsed {
        Ok(mut t) => t
            .remove("v")
            .unwrap_or(toml::Value::String(raw.to_string())),
        Err(_)
            if !raw.is_empty() && raw.chars().all(|c| c.is_alphanumeric() || "-_".contains(c)) =>
        {
            toml::Value::String(raw.to_string())
        }
        Err(e) => {
            return Err(Problem::new(
                key,
                format!(
                    "--set value '{raw}' is not a TOML value: {}",
                    first_line(&e.to_string())
                ),
            ));
        }
    };
    Ok((key.to_string(), value))
}

/// Whether a dotted `--set` key names a file ([`super::files::FILE_KEYS`]: `base`,
/// `machine.drive.table`, `mix.records`, `line.arrivals`).
fn names_a_file(key: &str) -> bool {
    let parts: Vec<&str> = key.split('.').collect();
    super::files::FILE_KEYS.iter().any(|(section, name)| {
        parts.last() == Some(name)
            && match parts.len() {
                1 => section.is_empty(),
                n => !section.is_empty() && parts[n - 2] == *section,
            }
    })
}

/// A dotted key has no empty part; `what` names the override in the message.
pub(super) fn check_key(key: &str, what: &str) -> Result<(), Problem> {
    if key.is_empty() || key.split('.').any(str::is_empty) {
        return Err(Problem::new(
            "--set",
            format!("{what}: the key must be a dotted path such as machine.belt_speed"),
        ));
    }
    Ok(())
}

/// Set the value at a dotted key path (`machine.belt_speed`), creating the sections on the
/// way: the override of [`apply_set`] once its value is parsed.
pub fn set_value(table: &mut toml::Table, key: &str, value: toml::Value) -> Result<(), Problem> {
    check_key(key, &format!("'{key}'"))?;
    let parts: Vec<&str> = key.split('.').collect();
    let mut cur = table;
    for (i, part) in parts[..parts.len() - 1].iter().enumerate() {
        let entry = cur
            .entry(part.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        cur = match entry {
            toml::Value::Table(t) => t,
            _ => {
                return Err(Problem::new(
                    parts[..=i].join("."),
                    "is a value, not a section, so it has no sub-keys",
                ))
            }
        };
    }
    cur.insert(parts[parts.len() - 1].to_string(), value);
    Ok(())
}

pub(super) fn first_line(s: &str) -> String {
    s.lines()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("")
        .trim()
        .to_string()
}

/// Deserialize, collecting every structural problem (unknown key, wrong type): each one is
/// recorded with its path, the offending key removed, and deserialization retried.
pub(super) fn deserialize_collecting(
    mut table: toml::Table,
    problems: &mut Vec<Problem>,
) -> ScenarioFile {
    for _ in 0..MAX_STRUCTURAL {
        match serde_path_to_error::deserialize::<_, ScenarioFile>(table.clone()) {
            Ok(file) => return file,
            Err(err) => {
                let mut path: Vec<String> = err.path().iter().map(|s| s.to_string()).collect();
                let message = err.inner().to_string();
                // An unknown key's path ends at its section; the key is named in the message.
                if let Some(unknown) = unknown_field(&message) {
                    if path.last().map(String::as_str) != Some(unknown.as_str()) {
                        path.push(unknown);
                    }
                }
                let key = path
                    .iter()
                    .filter(|s| s.as_str() != "?")
                    .cloned()
                    .collect::<Vec<_>>()
                    .join(".")
                    .replace(".[", "[");
                problems.push(Problem::new(
                    if key.is_empty() {
                        "scenario".to_string()
                    } else {
                        key
                    },
                    tidy(&message),
                ));
                if !remove_path(&mut table, &path) {
                    return ScenarioFile::default();
                }
            }
        }
    }
    ScenarioFile::default()
}

/// A deserializer's message without the values it quotes from the file (`invalid type:
/// string "…"`, `unknown variant `…``, `unknown field `…``): the key path says where, the expected type or the
/// allowed variants say what; the file's text is never echoed (it may be anything).
pub(super) fn without_quoted_values(message: &str) -> String {
    let mut out = String::new();
    let mut rest = message;
    loop {
        // (pattern, what stays, closing quote); the earliest in the message first.
        let patterns = [
            ("string \"", "a string", '"'),
            ("unknown variant `", "unknown variant", '`'),
            ("unknown field `", "unknown field", '`'),
        ];
        let Some((at, (open, keep, close))) = patterns
            .iter()
            .filter_map(|p| rest.find(p.0).map(|at| (at, *p)))
            .min_by_key(|(at, _)| *at)
        else {
            break;
        };
        let open = open.len();
        out.push_str(&rest[..at]);
        out.push_str(keep);
        // Skip the quoted value (a string's Debug form escapes its quotes).
        let body = &rest[at + open..];
        let mut escaped = false;
        let mut end = body.len();
        for (i, c) in body.char_indices() {
            if escaped {
                escaped = false;
            } else if c == '\\' && close == '"' {
                escaped = true;
            } else if c == close {
                end = i + c.len_utf8();
                break;
            }
        }
        rest = &body[end..];
    }
    out.push_str(rest);
    out
}

/// Structural problems (unknown keys, wrong types) collected before giving up.
pub(super) const MAX_STRUCTURAL: usize = 256;

pub(super) fn unknown_field(message: &str) -> Option<String> {
    let rest = message.strip_prefix("unknown field `")?;
    Some(rest.split('`').next()?.to_string())
}

pub(super) fn tidy(message: &str) -> String {
    let mut m = without_quoted_values(message)
        .replace("unknown field", "unknown key")
        .replace("f64", "a number");
    for section in [
        "machine",
        "drive",
        "parcel",
        "materials",
        "run",
        "limits",
        "design",
    ] {
        let name = format!(
            "struct {}{}Config",
            section[..1].to_uppercase(),
            &section[1..]
        );
        m = m.replace(&name, &format!("a [{section}] section (a table of keys)"));
    }
    m = m
        .replace(
            "struct DesignParcelConfig",
            "a [[design.parcels]] entry (a table of keys)",
        )
        .replace(
            "struct OverloadParcelConfig",
            "a [design.overload] section (a table of keys)",
        )
        .replace(
            "data did not match any variant of untagged enum SearchRange",
            "expected a number (a fixed value) or [low, high]",
        )
        .replace("struct MixConfig", "a [mix] section (a table of keys)")
        .replace("struct CameraConfig", "a [camera] section (a table of keys)")
        .replace(
            "struct AdaptiveConfig",
            "a [machine.adaptive] section (a table of keys)",
        )
        .replace(
            "internally tagged enum DistConfig",
            "a distribution: a table with kind = \"fixed\", \"uniform\", \"normal\", \"truncated-normal\", \"lognormal\" or \"discrete\" and its parameters",
        );
    first_line(&m)
}

pub(super) fn remove_path(table: &mut toml::Table, path: &[String]) -> bool {
    match path {
        [] => false,
        [last] => table.remove(last).is_some(),
        [head, rest @ ..] => match table.get_mut(head) {
            Some(toml::Value::Table(t)) => {
                if remove_path(t, rest) {
                    true
                } else {
                    // The problem is with the section itself (e.g. wrong type inside an
                    // array): drop the whole value.
                    table.remove(head).is_some()
                }
            }
            Some(_) => table.remove(head).is_some(),
            None => false,
        },
    }
}
