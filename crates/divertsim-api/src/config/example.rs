//! `divertsim example`: the built-in default scenario as a TOML file that names every key the
//! format accepts, each under a comment with its meaning, unit and range.
//!
//! Generated, so that it cannot drift from the format: the keys and their order from the
//! scenario types (serialized), the comments from the JSON Schema's descriptions (the doc
//! comments), the ranges from [`super::bounds`], the values from the defaults. Keys without
//! a default, and alternatives (the link lengths, a drive table, the mix, ...), are printed
//! commented out (`# key = value`) with the example values of [`OPTIONAL_KEYS`].

use super::camera::CameraConfig;
use super::line::LineConfig;
use super::{bounds, json_schema, ScenarioFile};
use serde_json::Value as Json;
use std::collections::BTreeMap;
use toml::Value;

/// Example values of the keys that have no default, and (where the default is present)
/// another form of a key, printed as `# or: key = value`. A test loads them as a scenario.
pub const OPTIONAL_KEYS: &str = r#"
base = "machine.toml"

[machine]
arm_face_bottom = 0.0
arm_face_top = 0.4
arm_mass = 12.0
arm_inertia = 5.3

[machine.drive]
max_swing_deg = 45.0
crank = 0.057402515
coupler = 0.3
rocker = 0.15
ground = 0.330461724
table = "alpha.csv"
points = [[0.0, 0.0], [0.34, 22.5], [0.68, 45.0], [1.02, 22.5], [1.36, 0.0]]

[parcel]
com_height = 0.075
velocity = [2.0, 0.0]

[materials]
belt_friction = [[0.0, 0.5], [0.5, 0.45], [2.0, 0.4]]

[run]
duration = 3.36

[limits]
tipping = "flag"

[design.search]
arm_friction = [0.2, 0.4]
restitution = [0.2, 0.4]
height = [0.1, 0.3]

[optimize]
belt_speed = [1.0, 2.3]
cycle_time = [1.0, 1.5]
start_position = [0.0, 0.9]
light_barrier = 0.0

[mix]
records = "parcels.csv"
length = { kind = "uniform", min = 0.2, max = 0.7 }
width = { kind = "uniform", min = 0.1, max = 0.26 }
height = { kind = "uniform", min = 0.1, max = 0.3 }
mass = { kind = "uniform", min = 0.5, max = 15.0 }
density = { kind = "normal", mean = 150.0, sd = 40.0 }
offset = { kind = "uniform", min = 0.0, max = 0.44 }
offset_fraction = { kind = "uniform", min = 0.0, max = 1.0 }
angle_deg = { kind = "truncated-normal", mean = 0.0, sd = 10.0, min = -30.0, max = 30.0 }
speed = { kind = "fixed", value = 0.0 }
spin = { kind = "fixed", value = 0.0 }
phase = { kind = "truncated-normal", mean = 0.0, sd = 0.005, min = -0.01, max = 0.01 }
belt_friction = { kind = "lognormal", median = 0.4, sigma = 0.1 }
arm_friction = { kind = "discrete", values = [0.3, 0.4], weights = [3.0, 1.0] }
restitution = { kind = "normal", mean = 0.3, sd = 0.05 }
seed = 1

[line]
gap = { kind = "normal", mean = 1.5, sd = 0.25 }
min_gap = 0.3
arrivals = "arrivals.csv"
diverters = [{ position = 4.0, share = 0.3, machine = { cycle_time = 1.2 } }]

[camera]
reference_points = [[40.0, 440.0, 0.0, 0.0], [648.0, 440.0, 1.2, 0.0], [648.0, 86.0, 1.2, 0.7], [40.0, 86.0, 0.0, 0.7]]
"#;

/// Longest comment line.
const WIDTH: usize = 92;

/// A space at which [`comment`] does not break the line.
const NO_BREAK: &str = "\u{a0}";

/// The example scenario file.
pub fn example_toml() -> String {
    let schema = json_schema();
    let defaults = default_table();
    let alternatives: toml::Table = OPTIONAL_KEYS.parse().unwrap_or_default();
    let mut full = defaults.clone();
    add_missing(&mut full, &alternatives);
    let writer = Writer {
        schema: &schema,
        order: key_order(&full),
        alternatives: &alternatives,
    };
    let mut out = String::new();
    let intro = format!(
        "{} The values below are the built-in defaults (the paper's compact parcel at v = 2 m/s, \
         t_c = 1.36 s, R_s = 0). A line `# key = value` is a key without a default, or one of \
         several ways to give something: remove the `# ` to use it. `divertsim schema` \
         documents every key.",
        writer.description(&schema)
    );
    comment(&mut out, &intro);
    out.push('\n');
    writer.section(&mut out, "", &schema, Some(&defaults), &full, true);
    out
}

/// The default scenario as a table, with the sections a file leaves out when they hold
/// their defaults stated too.
fn default_table() -> toml::Table {
    let mut t = match Value::try_from(ScenarioFile::default()) {
        Ok(Value::Table(t)) => t,
        _ => toml::Table::new(),
    };
    if let Ok(camera) = Value::try_from(CameraConfig::default()) {
        t.entry("camera").or_insert(camera);
    }
    if let Ok(line) = Value::try_from(LineConfig::default()) {
        t.entry("line").or_insert(line);
    }
    if let Some(Value::Table(run)) = t.get_mut("run") {
        run.entry("cycle_starts")
            .or_insert(Value::Array(vec![Value::Float(0.0)]));
    }
    t
}

/// Add the keys of `extra` that `base` lacks, section by section.
fn add_missing(base: &mut toml::Table, extra: &toml::Table) {
    for (k, v) in extra {
        match (base.get_mut(k), v) {
            (Some(Value::Table(b)), Value::Table(e)) => add_missing(b, e),
            (Some(_), _) => {}
            (None, v) => {
                base.insert(k.clone(), v.clone());
            }
        }
    }
}

/// The keys of each table in the order the scenario types declare them (serialized through
/// the types: a `toml::Table` sorts its keys), by key path (`design.parcels[]` for the
/// entries of an array of tables).
fn key_order(full: &toml::Table) -> BTreeMap<String, Vec<String>> {
    let mut order = BTreeMap::new();
    let text = Value::Table(full.clone())
        .try_into::<ScenarioFile>()
        .ok()
        .and_then(|f| toml::to_string(&f).ok())
        .unwrap_or_default();
    if let Ok(doc) = toml::de::DeTable::parse(&text) {
        record_order(doc.get_ref(), "", &mut order);
    }
    order
}

fn record_order(
    table: &toml::de::DeTable<'_>,
    path: &str,
    order: &mut BTreeMap<String, Vec<String>>,
) {
    let mut keys: Vec<_> = table.iter().collect();
    keys.sort_by_key(|(k, _)| k.span().start);
    order.insert(
        path.to_string(),
        keys.iter().map(|(k, _)| k.get_ref().to_string()).collect(),
    );
    for (k, v) in keys {
        let p = join(path, k.get_ref());
        match v.get_ref() {
            toml::de::DeValue::Table(t) => record_order(t, &p, order),
            toml::de::DeValue::Array(a) => {
                if let Some(toml::de::DeValue::Table(t)) = a.iter().next().map(|v| v.get_ref()) {
                    record_order(t, &format!("{p}[]"), order);
                }
            }
            _ => {}
        }
    }
}

fn join(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_string()
    } else {
        format!("{path}.{key}")
    }
}

struct Writer<'a> {
    schema: &'a Json,
    order: BTreeMap<String, Vec<String>>,
    alternatives: &'a toml::Table,
}

impl Writer<'_> {
    /// The keys of the table at `path`, in declaration order (any others after, sorted).
    fn keys(&self, path: &str, table: &toml::Table) -> Vec<String> {
        let mut keys: Vec<String> = self
            .order
            .get(path)
            .map(|o| {
                o.iter()
                    .filter(|k| table.contains_key(*k))
                    .cloned()
                    .collect()
            })
            .unwrap_or_default();
        for k in table.keys() {
            if !keys.contains(k) {
                keys.push(k.clone());
            }
        }
        keys
    }

    /// The schema a `$ref` or an optional (`anyOf` with null) stands for.
    fn resolve<'s>(&'s self, mut node: &'s Json) -> &'s Json {
        for _ in 0..8 {
            if let Some(r) = node.get("$ref").and_then(Json::as_str) {
                match r.strip_prefix('#').and_then(|p| self.schema.pointer(p)) {
                    Some(n) => node = n,
                    None => return node,
                }
            } else if let Some(branches) = node.get("anyOf").and_then(Json::as_array) {
                let mut not_null = branches
                    .iter()
                    .filter(|b| b.get("type") != Some(&"null".into()));
                match (not_null.next(), not_null.next()) {
                    (Some(only), None) => node = only,
                    _ => return node,
                }
            } else {
                return node;
            }
        }
        node
    }

    /// A key whose value is written as a `[section]` (or `[[section]]` entries): a struct of
    /// the format, not a value such as a distribution.
    fn struct_schema<'s>(&'s self, prop: &'s Json, value: &Value) -> Option<&'s Json> {
        let node = self.resolve(prop);
        match value {
            Value::Table(_) => node.get("properties").map(|_| node),
            Value::Array(a) if !a.is_empty() && a.iter().all(Value::is_table) => node
                .get("items")
                .map(|i| self.resolve(i))
                .filter(|i| i.get("properties").is_some()),
            _ => None,
        }
    }

    /// The keys of one table: its plain keys with their comments, then its sections.
    fn section(
        &self,
        out: &mut String,
        path: &str,
        node: &Json,
        defaults: Option<&toml::Table>,
        full: &toml::Table,
        comments: bool,
    ) {
        let node = self.resolve(node);
        let props = node.get("properties");
        let mut sections = Vec::new();
        for k in self.keys(path, full) {
            let prop = props.and_then(|p| p.get(&k)).unwrap_or(&Json::Null);
            let value = &full[&k];
            let p = join(path, &k);
            if let Some(inner) = self.struct_schema(prop, value) {
                sections.push((k, p, prop, inner));
                continue;
            }
            if comments {
                let text = format!("{}{}", gist(self.description(prop)), ranges(&p));
                comment(out, &text);
            }
            match defaults.and_then(|d| d.get(&k)) {
                Some(v) => {
                    out.push_str(&format!("{k} = {}\n", self.inline(v, &p)));
                    let other = lookup(self.alternatives, &p).filter(|a| *a != v);
                    if let (Some(a), true) = (other, comments) {
                        out.push_str(&format!("# or: {k} = {}\n", self.inline(a, &p)));
                    }
                }
                None => out.push_str(&format!("# {k} = {}\n", self.inline(value, &p))),
            }
        }
        for (k, p, prop, inner) in sections {
            let own = defaults.and_then(|d| d.get(&k));
            match (&full[&k], own) {
                (Value::Table(t), own) => {
                    out.push('\n');
                    comment(out, &gist(self.description(prop)));
                    out.push_str(&format!("[{p}]\n"));
                    self.section(out, &p, inner, own.and_then(Value::as_table), t, comments);
                }
                (Value::Array(items), own) => {
                    let given = own.and_then(Value::as_array);
                    let rows = given.unwrap_or(items);
                    for (i, item) in rows.iter().enumerate() {
                        let Some(t) = item.as_table() else { continue };
                        out.push('\n');
                        if i == 0 {
                            comment(out, &gist(self.description(prop)));
                        }
                        // Entries the default lacks are an example: the header commented
                        // too, so that the file has none.
                        let mark = if given.is_some() { "" } else { "# " };
                        out.push_str(&format!("{mark}[[{p}]]\n"));
                        let d = given.map(|_| t);
                        self.section(out, &format!("{p}[]"), inner, d, t, comments && i == 0);
                    }
                }
                _ => {}
            }
        }
    }

    /// The property's own description, else its type's.
    fn description<'s>(&'s self, prop: &'s Json) -> &'s str {
        prop.get("description")
            .and_then(Json::as_str)
            .or_else(|| self.resolve(prop).get("description").and_then(Json::as_str))
            .unwrap_or("")
    }

    /// A value on one line; tables inline, their keys in declaration order.
    fn inline(&self, v: &Value, path: &str) -> String {
        match v {
            Value::Table(t) => {
                let parts: Vec<String> = self
                    .keys(path, t)
                    .iter()
                    .map(|k| format!("{k} = {}", self.inline(&t[k], &join(path, k))))
                    .collect();
                format!("{{ {} }}", parts.join(", "))
            }
            Value::Array(a) => {
                let parts: Vec<String> = a
                    .iter()
                    .map(|x| self.inline(x, &format!("{path}[]")))
                    .collect();
                format!("[{}]", parts.join(", "))
            }
            other => other.to_string(),
        }
    }
}

/// The value at a dotted key path.
fn lookup<'t>(table: &'t toml::Table, path: &str) -> Option<&'t Value> {
    let mut parts = path.split('.');
    let mut cur = table.get(parts.next()?)?;
    for p in parts {
        cur = cur.as_table()?.get(p)?;
    }
    Some(cur)
}

/// The ranges of a key (and of its elements), as its declaration states them.
fn ranges(path: &str) -> String {
    super::all_bounds()
        .filter_map(|b| {
            let within = b.key.strip_prefix(path)?;
            (within.is_empty() || within.starts_with('[')).then(|| {
                // A range is not broken across comment lines.
                format!(
                    " Allowed{}: {}.",
                    bounds::within_words(within),
                    b.range().replace(' ', NO_BREAK)
                )
            })
        })
        .collect()
}

/// The first sentence of a description, on one line: the meaning and the unit. Not the
/// "Default ..." sentence (the value beside it shows it) nor the ranges the schema appended
/// (stated from the table).
fn gist(description: &str) -> String {
    let text: Vec<&str> = description
        .lines()
        .filter(|l| !l.starts_with("Allowed"))
        .collect();
    let text = text
        .join(" ")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ");
    let mut end = text.len();
    for (i, _) in text.match_indices(". ") {
        let next = text[i + 2..].chars().next().unwrap_or(' ');
        let abbreviation = text[..i].ends_with("e.g") || text[..i].ends_with("i.e");
        if !abbreviation && (next.is_uppercase() || next == '`' || next == '"') {
            end = i + 1;
            break;
        }
    }
    text[..end].to_string()
}

/// `text` as `# ` comment lines of at most [`WIDTH`] characters.
fn comment(out: &mut String, text: &str) {
    let mut line = String::from("#");
    // Split at plain spaces and line ends only: NO_BREAK is whitespace too.
    for word in text.split([' ', '\n']).filter(|w| !w.is_empty()) {
        if line.chars().count() + 1 + word.chars().count() > WIDTH && line != "#" {
            out.push_str(&line);
            out.push('\n');
            line = String::from("#");
        }
        line.push(' ');
        line.push_str(&word.replace(NO_BREAK, " "));
    }
    if line != "#" {
        out.push_str(&line);
        out.push('\n');
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config;

    /// Every key path of the schema's sections (`design.parcels[].mass` for the entries of
    /// an array of tables); distributions and other values are not descended into.
    fn schema_paths(w: &Writer<'_>, node: &Json, path: &str, out: &mut Vec<String>) {
        let node = w.resolve(node);
        if let Some(props) = node.get("properties").and_then(Json::as_object) {
            for (k, p) in props {
                let kp = join(path, k);
                out.push(kp.clone());
                schema_paths(w, p, &kp, out);
            }
        } else if let Some(items) = node.get("items").filter(|i| i.is_object()) {
            if w.resolve(items).get("properties").is_some() {
                schema_paths(w, items, &format!("{path}[]"), out);
            }
        }
    }

    fn toml_paths(t: &toml::Table, path: &str, out: &mut Vec<String>) {
        for (k, v) in t {
            let kp = join(path, k);
            out.push(kp.clone());
            match v {
                Value::Table(inner) => toml_paths(inner, &kp, out),
                Value::Array(a) => {
                    if let Some(Value::Table(first)) = a.first() {
                        toml_paths(first, &format!("{kp}[]"), out);
                    }
                }
                _ => {}
            }
        }
    }

    /// The example with its commented-out keys (`# key = value`) given.
    fn uncommented(text: &str) -> String {
        text.lines()
            .map(|l| match l.strip_prefix("# ") {
                Some(rest)
                    if rest.split_once(" = ").is_some_and(|(k, _)| {
                        k.chars()
                            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
                    }) =>
                {
                    rest
                }
                // An example array-of-tables header.
                Some(rest) if rest.starts_with("[[") && rest.ends_with("]]") => rest,
                _ => l,
            })
            .collect::<Vec<_>>()
            .join("\n")
    }

    #[test]
    fn the_example_loads_as_the_built_in_default() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("example.toml");
        std::fs::write(&path, example_toml()).unwrap();
        let from_file = config::load(Some(&path), &[]).unwrap();
        let built_in = config::load(None, &[]).unwrap();
        assert_eq!(from_file.file, built_in.file);
        assert_eq!(
            format!("{:?}", from_file.scenario),
            format!("{:?}", built_in.scenario)
        );
        assert_eq!(from_file.file, ScenarioFile::default());
    }

    #[test]
    fn the_example_names_every_key_of_the_schema() {
        let text = example_toml();
        let all: toml::Table = uncommented(&text).parse().unwrap();
        // Every key it names, commented or not, is a key of the format with a value of
        // the right type.
        let _: ScenarioFile = Value::Table(all.clone()).try_into().unwrap();
        let _: ScenarioFile = toml::from_str(OPTIONAL_KEYS).unwrap();
        let schema = json_schema();
        let w = Writer {
            schema: &schema,
            order: BTreeMap::new(),
            alternatives: &toml::Table::new(),
        };
        let mut want = Vec::new();
        schema_paths(&w, &schema, "", &mut want);
        let mut have = Vec::new();
        toml_paths(&all, "", &mut have);
        let missing: Vec<_> = want.iter().filter(|k| !have.contains(k)).collect();
        assert!(want.len() > 80, "{want:?}");
        assert!(
            missing.is_empty(),
            "not in the example: {missing:?}\n{text}"
        );
    }

    #[test]
    fn every_key_has_its_comment_and_ranges() {
        let text = example_toml();
        for (line, above) in [
            (
                "belt_width = 0.7",
                "# P_max: belt width [m]. Allowed: [0.01, 10] m.",
            ),
            (
                "belt_speed = 2.0",
                "# v: belt speed [m/s]. Allowed: [0, 20] m/s.",
            ),
            ("# max_swing_deg = 45.0", "Allowed: (0, 90] deg."),
            ("# duration = 3.36", "# The largest simulated time [s]."),
        ] {
            let i = text
                .find(&format!("\n{line}\n"))
                .unwrap_or_else(|| panic!("{line}\n{text}"));
            let before = text[..i].lines().last().unwrap();
            assert!(before.contains(above), "{line}: {before}");
        }
        assert!(text.contains("\n[[design.parcels]]\n"));
        assert!(text.contains("\n# or: belt_friction = [[0.0, 0.5]"));
        assert!(text.contains("\n# length = { kind = \"uniform\", min = 0.2, max = 0.7 }\n"));
    }
}
