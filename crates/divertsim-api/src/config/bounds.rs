//! The numeric ranges of the scenario file: the `Bound` type, and what is done with the
//! ranges. Each range is declared once, beside its key (`#[key(range = …)]` on the field,
//! crate `divertsim-keys`), and gathered in the sections' parent (`config::SECTIONS`; this
//! file names no section, since every section names it): validation checks values against
//! them and words its messages from them, `divertsim schema` carries them as
//! `minimum`/`maximum`/`exclusiveMinimum`/`exclusiveMaximum` (and in the descriptions, with
//! each plain default), and `divertsim example` prints them. Ranges that depend on other
//! keys (width ≤ length, a parcel on the belt) stay in the validation code.
//!
//! A bound's `key` is a path in the schema: dotted section and key names, `[]` for every
//! element of an array, `[0]` for one position of a fixed-length array, `*` for every key of
//! a section (`mix.*.sd`: the `sd` of every distribution of the mix).

use super::{brief, Problem};
use divertsim_core::analysis::design::worst_case::PoseBox;
use serde_json::{Map, Value};
use std::collections::BTreeSet;

/// The allowed range of one numeric key.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bound {
    /// The key path in the schema (module notes).
    pub key: &'static str,
    /// Lower end; `-∞` for none.
    pub lo: f64,
    /// The lower end itself is not allowed.
    pub lo_open: bool,
    /// Upper end; `+∞` for none.
    pub hi: f64,
    /// The upper end itself is not allowed.
    pub hi_open: bool,
    /// The unit, as messages print it ("" for a pure number).
    pub unit: &'static str,
    /// Why the range ends where it does, when that is not obvious ("" for none).
    pub why: &'static str,
}

impl Bound {
    /// [lo, hi]; its key is given by [`Bound::at`] (the derive does: crate `divertsim-keys`).
    pub const fn closed(lo: f64, hi: f64, unit: &'static str) -> Bound {
        Bound {
            key: "",
            lo,
            lo_open: false,
            hi,
            hi_open: false,
            unit,
            why: "",
        }
    }

    /// This range at the key path `key`.
    pub const fn at(self, key: &'static str) -> Bound {
        Bound { key, ..self }
    }

    /// The range as the list grammar's parser takes it, with at most `max` values.
    pub const fn list(&self, max: usize) -> (f64, f64, &'static str, usize) {
        (self.lo, self.hi, self.unit, max)
    }

    /// The ends and the unit: (lo, hi, unit).
    pub const fn ends(&self) -> (f64, f64, &'static str) {
        (self.lo, self.hi, self.unit)
    }

    /// (lo, hi].
    pub const fn open_closed(lo: f64, hi: f64, unit: &'static str) -> Bound {
        Bound {
            lo_open: true,
            ..Bound::closed(lo, hi, unit)
        }
    }

    /// (lo, ∞).
    pub const fn above(lo: f64, unit: &'static str) -> Bound {
        Bound::open_closed(lo, f64::INFINITY, unit)
    }

    /// [lo, ∞).
    pub const fn at_least(lo: f64, unit: &'static str) -> Bound {
        Bound::closed(lo, f64::INFINITY, unit)
    }

    /// A band (lo, hi) as [lo, hi].
    pub const fn band(b: (f64, f64), unit: &'static str) -> Bound {
        Bound::closed(b.0, b.1, unit)
    }

    /// This bound with the reason for its ends.
    pub const fn because(self, why: &'static str) -> Bound {
        Bound { why, ..self }
    }

    /// v lies in the range (NaN never does).
    pub fn contains(&self, v: f64) -> bool {
        let above = if self.lo_open {
            v > self.lo
        } else {
            v >= self.lo
        };
        let below = if self.hi_open {
            v < self.hi
        } else {
            v <= self.hi
        };
        above && below
    }

    /// The range as messages state it: `[0.01, 10] m (why)`, `(0, 90] deg`, `> 0 m`.
    pub fn allowed(&self) -> String {
        if self.why.is_empty() {
            self.range()
        } else {
            format!("{} ({})", self.range(), self.why)
        }
    }

    /// The range and its unit, without the reason: `[0.01, 10] m`.
    pub fn range(&self) -> String {
        let range = match (self.lo.is_finite(), self.hi.is_finite()) {
            (true, true) => format!(
                "{}{}, {}{}",
                if self.lo_open { '(' } else { '[' },
                brief(self.lo),
                brief(self.hi),
                if self.hi_open { ')' } else { ']' }
            ),
            (true, false) => format!(
                "{} {}",
                if self.lo_open { ">" } else { "≥" },
                brief(self.lo)
            ),
            (false, true) => format!(
                "{} {}",
                if self.hi_open { "<" } else { "≤" },
                brief(self.hi)
            ),
            (false, false) => "a finite number".to_string(),
        };
        if self.unit.is_empty() {
            range
        } else {
            format!("{range} {}", self.unit)
        }
    }

    /// The problem with the value `v` of `key` (this bound's key with its indices filled
    /// in), if there is one.
    pub fn problem(&self, key: &str, v: f64) -> Option<Problem> {
        if !v.is_finite() {
            Some(Problem::new(
                key,
                format!("{v} is not a finite number; allowed: {}", self.allowed()),
            ))
        } else if !self.contains(v) {
            Some(Problem::new(
                key,
                format!("{} is out of range; allowed: {}", brief(v), self.allowed()),
            ))
        } else {
            None
        }
    }

    /// The JSON Schema keywords of the range.
    pub fn keywords(&self) -> Vec<(&'static str, f64)> {
        let mut k = Vec::new();
        if self.lo.is_finite() {
            k.push((
                if self.lo_open {
                    "exclusiveMinimum"
                } else {
                    "minimum"
                },
                self.lo,
            ));
        }
        if self.hi.is_finite() {
            k.push((
                if self.hi_open {
                    "exclusiveMaximum"
                } else {
                    "maximum"
                },
                self.hi,
            ));
        }
        k
    }
}

/// Parcel sides (the search box's length band is the widest the model supports).
pub(super) const SIDE: (f64, f64) = PoseBox::LIMITS.length;
/// Parcel masses.
pub(super) const MASS: (f64, f64) = PoseBox::LIMITS.mass;
pub(super) const SIDE_WHY: &str = "a parcel side under 1 mm is below the contact tolerances";
pub(super) const MASS_WHY: &str = "a mass under 1 g makes forces vanish against the tolerances";
pub(super) const NO_JAM: &str = "μ ≥ 4/3 would allow Painlevé jams";

/// The belt speeds the capacity map and the optimiser search over: a sorter's speeds.
pub const SEARCHED_BELT_SPEED: Bound = Bound::closed(0.05, 10.0, "m/s").at("speeds");
/// The cycle times the capacity map and the optimiser search over.
pub const SEARCHED_CYCLE_TIME: Bound = Bound::closed(0.2, 10.0, "s").at("cycle_times");
/// The light-barrier positions the capacity map and the optimiser search over.
pub const SEARCHED_LIGHT_BARRIER: Bound = Bound::closed(-5.0, 5.0, "m").at("light_barriers");
/// The start positions the optimiser searches over (and the capacity map's R_s range).
pub const SEARCHED_START_POSITION: Bound = Bound::closed(-5.0, 5.0, "m").at("start_range");

/// The bound of a key path in the schema's terms (`design.parcels[].mass`), if it has one.
pub fn find(key: &str) -> Option<&'static Bound> {
    super::all_bounds().find(|b| b.key == key)
}

/// One step of a key path.
#[derive(Debug, Clone, PartialEq)]
enum Step {
    Key(String),
    AnyKey,
    Each,
    At(usize),
}

fn steps(key: &str) -> Vec<Step> {
    let mut out = Vec::new();
    for part in key.split('.') {
        let (name, mut rest) = part.split_at(part.find('[').unwrap_or(part.len()));
        out.push(if name == "*" {
            Step::AnyKey
        } else {
            Step::Key(name.to_string())
        });
        while let Some(inner) = rest.strip_prefix('[') {
            let (index, after) = inner.split_at(inner.find(']').unwrap_or(inner.len()));
            out.push(match index.parse() {
                Ok(i) => Step::At(i),
                Err(_) => Step::Each,
            });
            rest = after.get(1..).unwrap_or("");
        }
    }
    out
}

/// The numbers of a value (a scenario file as TOML, whose floats keep NaN and ±∞) at a
/// bound's key path, each with its key, indices filled in (`materials.belt_friction[2][1]`,
/// `mix.length.sd`); what is not there, or not a number, is not listed.
pub fn values_at(value: &toml::Value, key: &str) -> Vec<(String, f64)> {
    fn go(v: &toml::Value, at: String, steps: &[Step], out: &mut Vec<(String, f64)>) {
        let Some((step, rest)) = steps.split_first() else {
            match v {
                toml::Value::Float(x) => out.push((at, *x)),
                toml::Value::Integer(i) => out.push((at, *i as f64)),
                _ => {}
            }
            return;
        };
        let dot = |k: &str| match at.is_empty() {
            true => k.to_string(),
            false => format!("{at}.{k}"),
        };
        match step {
            Step::Key(k) => {
                if let Some(n) = v.get(k) {
                    go(n, dot(k), rest, out);
                }
            }
            Step::AnyKey => {
                for (k, n) in v.as_table().into_iter().flatten() {
                    go(n, dot(k), rest, out);
                }
            }
            Step::Each => {
                for (i, n) in v.as_array().into_iter().flatten().enumerate() {
                    go(n, format!("{at}[{i}]"), rest, out);
                }
            }
            Step::At(i) => {
                if let Some(n) = v.get(*i) {
                    go(n, format!("{at}[{i}]"), rest, out);
                }
            }
        }
    }
    let mut out = Vec::new();
    go(value, String::new(), &steps(key), &mut out);
    out
}

/// A number in the schema that a bound applies to.
#[derive(Debug)]
struct Target {
    /// JSON pointer of the numeric schema.
    number: String,
    /// JSON pointer of the property it belongs to (whose description names the range).
    property: String,
    /// The path after that property (`[]`, `[][0]` or empty).
    within: String,
}

/// Follow `steps` from the schema at `at`, through `$ref`s and `anyOf`/`oneOf`, to the
/// numeric schemas. A fixed-length array addressed by position gets `prefixItems` (one
/// schema per position) in place of its common `items`.
fn walk(root: &mut Value, at: &str, steps: &[Step], property: (&str, &str), out: &mut Vec<Target>) {
    let Some(node) = root.pointer(at) else {
        return;
    };
    if let Some(r) = node.get("$ref").and_then(Value::as_str) {
        if let Some(p) = r.strip_prefix('#') {
            let p = p.to_string();
            walk(root, &p, steps, property, out);
        }
        return;
    }
    for combinator in ["anyOf", "oneOf", "allOf"] {
        if let Some(n) = node.get(combinator).and_then(Value::as_array).map(Vec::len) {
            for i in 0..n {
                walk(
                    root,
                    &format!("{at}/{combinator}/{i}"),
                    steps,
                    property,
                    out,
                );
            }
            return;
        }
    }
    let Some((step, rest)) = steps.split_first() else {
        if has_type(node, "number") || has_type(node, "integer") {
            out.push(Target {
                number: at.to_string(),
                property: property.0.to_string(),
                within: property.1.to_string(),
            });
        }
        return;
    };
    let keys: Vec<String> = match step {
        Step::Key(k) => vec![k.clone()],
        Step::AnyKey => node
            .get("properties")
            .and_then(Value::as_object)
            .map(|p| p.keys().cloned().collect())
            .unwrap_or_default(),
        Step::Each => {
            if node.get("items").is_some_and(Value::is_object) {
                let within = format!("{}[]", property.1);
                walk(
                    root,
                    &format!("{at}/items"),
                    rest,
                    (property.0, &within),
                    out,
                );
            }
            return;
        }
        Step::At(i) => {
            let i = *i;
            if let Some(Value::Object(n)) = root.pointer_mut(at) {
                if !n.contains_key("prefixItems") {
                    if let (Some(items), Some(len)) = (
                        n.get("items").cloned(),
                        n.get("maxItems").and_then(Value::as_u64),
                    ) {
                        n.remove("items");
                        let len = usize::try_from(len).unwrap_or(0);
                        n.insert("prefixItems".into(), Value::Array(vec![items; len]));
                    }
                }
            }
            let within = format!("{}[{i}]", property.1);
            walk(
                root,
                &format!("{at}/prefixItems/{i}"),
                rest,
                (property.0, &within),
                out,
            );
            return;
        }
    };
    let present: Vec<String> = keys
        .into_iter()
        .filter(|k| node.get("properties").and_then(|p| p.get(k)).is_some())
        .collect();
    for k in present {
        let p = format!(
            "{at}/properties/{}",
            k.replace('~', "~0").replace('/', "~1")
        );
        walk(root, &p, rest, (&p, ""), out);
    }
}

fn has_type(node: &Value, t: &str) -> bool {
    match node.get("type") {
        Some(Value::String(s)) => s == t,
        Some(Value::Array(a)) => a.iter().any(|v| v.as_str() == Some(t)),
        _ => false,
    }
}

/// How a range names the part of a key it applies to: `[]` (each value), `[][0]`
/// (\[i]\[0]), or nothing for the key itself.
pub fn within_words(within: &str) -> String {
    match within {
        "" => String::new(),
        "[]" => " (each value)".to_string(),
        w => format!(" ({})", w.replace("[]", "[i]")),
    }
}

/// Write every bound of [`super::all_bounds`] into the schema: the range keywords on each
/// number it applies to, and "Allowed: …" at the end of its property's description; and before it,
/// "Default …" from the property's default where that is a number, a switch or a list of
/// numbers and the description does not already word it (`Default: height / 2.`).
pub fn annotate(schema: &mut Value) {
    describe_defaults(schema);
    let mut described = BTreeSet::new();
    for b in super::all_bounds() {
        let mut targets = Vec::new();
        walk(schema, "", &steps(b.key), ("", ""), &mut targets);
        for t in targets {
            if let Some(Value::Object(n)) = schema.pointer_mut(&t.number) {
                for k in ["minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum"] {
                    n.remove(k);
                }
                // A count's ends as integers, as the schema of a count states them.
                let integer = has_type(&Value::Object(n.clone()), "integer");
                for (k, v) in b.keywords() {
                    let v = if integer && v.fract() == 0.0 {
                        Value::from(v as i64)
                    } else {
                        Value::from(v)
                    };
                    n.insert(k.into(), v);
                }
            }
            if !described.insert((t.property.clone(), t.within.clone())) {
                continue;
            }
            if let Some(Value::Object(p)) = schema.pointer_mut(&t.property) {
                let line = format!("Allowed{}: {}.", within_words(&t.within), b.allowed());
                let text = match p.get("description").and_then(Value::as_str) {
                    Some(d) => format!("{d}\n{line}"),
                    None => line,
                };
                p.insert("description".into(), Value::String(text));
            }
        }
    }
}

/// Append "Default X." to the description of every property whose default is plain (a
/// number, true/false, or a list of numbers), so that the default is stated once: at its
/// key's declaration.
fn describe_defaults(node: &mut Value) {
    fn plain(v: &Value) -> Option<String> {
        match v {
            Value::Number(n) => n.as_f64().map(brief),
            Value::Bool(b) => Some(b.to_string()),
            Value::Array(a) if !a.is_empty() => {
                let items: Option<Vec<String>> = a.iter().map(plain).collect();
                items
                    .filter(|_| a.iter().all(Value::is_number))
                    .map(|i| format!("[{}]", i.join(", ")))
            }
            _ => None,
        }
    }
    match node {
        Value::Object(o) => {
            if let Some(Value::Object(props)) = o.get_mut("properties") {
                for p in props.values_mut() {
                    let Value::Object(p) = p else { continue };
                    let Some(value) = p.get("default").and_then(plain) else {
                        continue;
                    };
                    let text = p.get("description").and_then(Value::as_str).unwrap_or("");
                    if !text.to_lowercase().contains("default") {
                        let text = match text.is_empty() {
                            true => format!("Default {value}."),
                            false => format!("{text} Default {value}."),
                        };
                        p.insert("description".into(), Value::String(text));
                    }
                }
            }
            for v in o.values_mut() {
                describe_defaults(v);
            }
        }
        Value::Array(a) => a.iter_mut().for_each(describe_defaults),
        _ => {}
    }
}

/// The range keywords found at a key path of the schema, one map per number it reaches
/// (for the tests: what an editor checks).
pub fn schema_ranges(schema: &Value, key: &str) -> Vec<Map<String, Value>> {
    let mut copy = schema.clone();
    let mut targets = Vec::new();
    walk(&mut copy, "", &steps(key), ("", ""), &mut targets);
    targets
        .iter()
        .filter_map(|t| copy.pointer(&t.number).and_then(Value::as_object))
        .map(|n| {
            n.iter()
                .filter(|(k, _)| k.contains("inimum") || k.contains("aximum"))
                .map(|(k, v)| (k.clone(), v.clone()))
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::mix::{AdaptiveConfig, DistConfig};
    use crate::config::{
        all_bounds, apply_set, deserialize_collecting, json_schema, validate, DriveConfig,
        MachineConfig, MaterialsConfig,
    };

    /// Sets that put `v` at the bound's key in an otherwise valid scenario (on a 10 m belt,
    /// so that the largest parcel fits), and the key a problem with it is reported at.
    fn fixture(b: &Bound, v: &str) -> (Vec<String>, String) {
        let mut sets = vec!["machine.belt_width=10.0".to_string()];
        let parcel = |field: &str| {
            let mut p = vec![
                ("length", "0.2"),
                ("width", "0.1"),
                ("mass", "1.0"),
                ("offset", "0.0"),
            ];
            p.retain(|(k, _)| *k != field);
            p.push((field, v));
            let fields: Vec<String> = p.iter().map(|(k, x)| format!("{k} = {x}")).collect();
            format!("design.parcels=[{{ name = \"a\", {} }}]", fields.join(", "))
        };
        let key = match b.key {
            // Cross-key checks against the parcel's height: a parcel taller than the range.
            "parcel.com_height" | "machine.arm_face_bottom" => {
                sets.push("parcel.height=5.0".into());
                sets.push(format!("{}={v}", b.key));
                b.key.to_string()
            }
            "parcel.velocity[]" => {
                sets.push(format!("parcel.velocity=[{v}, 0.0]"));
                "parcel.velocity[0]".to_string()
            }
            "materials.belt_friction[][0]" => {
                sets.push(format!("materials.belt_friction=[[{v}, 0.4]]"));
                "materials.belt_friction[0][0]".to_string()
            }
            "materials.belt_friction[][1]" => {
                sets.push(format!("materials.belt_friction=[[0.0, {v}]]"));
                "materials.belt_friction[0][1]".to_string()
            }
            "camera.image_size[]" | "camera.marker_offset[]" => {
                let k = b.key.trim_end_matches("[]");
                sets.push(format!("{k}=[{v}, 1.0]"));
                format!("{k}[0]")
            }
            "mix.*.sd" => {
                sets.push(format!(
                    "mix.length={{ kind = \"normal\", mean = 0.3, sd = {v} }}"
                ));
                "mix.length.sd".to_string()
            }
            "mix.*.median" => {
                sets.push(format!(
                    "mix.length={{ kind = \"lognormal\", median = {v}, sigma = 0.3 }}"
                ));
                "mix.length.median".to_string()
            }
            "mix.*.sigma" => {
                sets.push(format!(
                    "mix.length={{ kind = \"lognormal\", median = 0.3, sigma = {v} }}"
                ));
                "mix.length.sigma".to_string()
            }
            "mix.*.weights[]" => {
                sets.push(format!(
                    "mix.length={{ kind = \"discrete\", values = [0.2, 0.3], weights = [{v}, 1.0] }}"
                ));
                "mix.length.weights".to_string()
            }
            "line.diverters[].position" | "line.diverters[].share" => {
                let (position, share) = match b.key.ends_with("position") {
                    true => (v, "0.0"),
                    false => ("5.0", v),
                };
                sets.push("line.share=0.0".into());
                sets.push(format!(
                    "line.diverters=[{{ position = {position}, share = {share} }}]"
                ));
                b.key.replace("[]", "[0]")
            }
            "run.cycle_starts[]" => {
                sets.push(format!("run.cycle_starts=[{v}]"));
                sets.push("run.duration=1.0".into());
                "run.cycle_starts[0]".to_string()
            }
            k if k.starts_with("design.parcels[].") => {
                let field = &k["design.parcels[].".len()..];
                sets.push(parcel(field));
                format!("design.parcels[0].{field}")
            }
            k if k.starts_with("design.search.") => {
                let k = k.trim_end_matches("[]");
                if k == "design.search.width" {
                    sets.push("design.search.length=[0.001, 5.0]".into());
                }
                sets.push(format!("{k}=[{v}, {v}]"));
                k.to_string()
            }
            k => {
                assert!(!k.contains('[') && !k.contains('*'), "no fixture for {k}");
                if k == "machine.light_barrier" {
                    sets.push("machine.start_position=10.0".into());
                }
                sets.push(format!("{k}={v}"));
                k.to_string()
            }
        };
        (sets, key)
    }

    /// The validator's problems at `key` for the scenario of `sets`.
    fn problems_at(sets: &[String], key: &str) -> Vec<Problem> {
        let mut table = toml::Table::new();
        let mut problems = Vec::new();
        for s in sets {
            apply_set(&mut table, s).unwrap();
        }
        let file = deserialize_collecting(table, &mut problems);
        validate(&file, &mut problems);
        problems.retain(|p| p.key == key);
        problems
    }

    /// What the schema's keywords say about `v`.
    fn schema_allows(ranges: &Map<String, Value>, v: f64) -> bool {
        let get = |k: &str| ranges.get(k).and_then(Value::as_f64);
        get("minimum").is_none_or(|m| v >= m)
            && get("exclusiveMinimum").is_none_or(|m| v > m)
            && get("maximum").is_none_or(|m| v <= m)
            && get("exclusiveMaximum").is_none_or(|m| v < m)
    }

    /// For every bound: the schema states exactly its range at its key, and a value just
    /// outside each end is rejected by validation (with the range named) and by the
    /// schema, one just inside by neither.
    #[test]
    fn schema_and_validation_share_every_bound() {
        let schema = json_schema();
        let mut failures = Vec::new();
        for b in all_bounds() {
            let ranges = schema_ranges(&schema, b.key);
            let want: Map<String, Value> = b
                .keywords()
                .into_iter()
                .map(|(k, v)| (k.to_string(), Value::from(v)))
                .collect();
            let same = |r: &Map<String, Value>| {
                r.len() == want.len()
                    && want
                        .iter()
                        .all(|(k, v)| r.get(k).and_then(Value::as_f64) == v.as_f64())
            };
            if ranges.is_empty() || !ranges.iter().all(same) {
                failures.push(format!("{}: schema has {ranges:?}, want {want:?}", b.key));
                continue;
            }
            let integer = b.key.ends_with("_nodes");
            let text = |v: f64| {
                if integer {
                    format!("{}", v as i64)
                } else {
                    format!("{v:?}")
                }
            };
            let (below, above) = if integer { (-1.0, 1.0) } else { (0.0, 0.0) };
            let step_down = |x: f64| if integer { x + below } else { x.next_down() };
            let step_up = |x: f64| if integer { x + above } else { x.next_up() };
            let mut cases = Vec::new();
            if b.lo.is_finite() {
                let (out, inside) = if b.lo_open {
                    (b.lo, step_up(b.lo))
                } else {
                    (step_down(b.lo), b.lo)
                };
                cases.push((out, false));
                // The scan step also bounds the number of scan points: a step just above 0
                // is a cross-key problem, not this bound's.
                let inside = if b.key == "machine.adaptive.step" {
                    0.001
                } else {
                    inside
                };
                cases.push((inside, true));
            }
            if b.hi.is_finite() {
                let (out, inside) = if b.hi_open {
                    (b.hi, step_down(b.hi))
                } else {
                    (step_up(b.hi), b.hi)
                };
                cases.push((out, false));
                cases.push((inside, true));
            }
            for (v, ok) in cases {
                let (sets, key) = fixture(b, &text(v));
                let found = problems_at(&sets, &key);
                let validator_ok = found.is_empty();
                let schema_ok = ranges.iter().all(|r| schema_allows(r, v));
                let worded = found.iter().all(|p| p.message.contains("allowed"));
                if validator_ok != ok || schema_ok != ok || !worded {
                    failures.push(format!(
                        "{} = {v:e}: validator ok {validator_ok}, schema ok {schema_ok}, want {ok}: {found:?}",
                        b.key
                    ));
                }
            }
        }
        assert!(failures.is_empty(), "{}", failures.join("\n"));
    }

    /// The example: an editor using the schema flags a negative belt speed.
    #[test]
    fn a_negative_belt_speed_violates_the_schema() {
        let schema = json_schema();
        let speed = &schema["$defs"]["MachineConfig"]["properties"]["belt_speed"];
        assert_eq!(speed["minimum"].as_f64(), Some(0.0), "{speed}");
        assert!(-3.0 < speed["minimum"].as_f64().unwrap());
        let found = problems_at(&["machine.belt_speed=-3".into()], "machine.belt_speed");
        assert!(
            found[0].message.contains("allowed: [0, 20] m/s"),
            "{found:?}"
        );
        assert!(speed["description"]
            .as_str()
            .unwrap()
            .contains("Allowed: [0, 20] m/s."));
    }

    /// Every section that declares ranges is gathered in `config::SECTIONS`: one left out would
    /// have its ranges neither checked by key path nor written into the schema.
    #[test]
    fn every_section_that_declares_ranges_is_gathered() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/src/config");
        let mut sections = Vec::new();
        for entry in std::fs::read_dir(dir).unwrap() {
            let text = std::fs::read_to_string(entry.unwrap().path()).unwrap();
            for part in text.split("#[keys(section = \"").skip(1) {
                let section = &part[..part.find('"').unwrap()];
                let declares = part
                    .find("\n}\n")
                    .is_some_and(|end| part[..end].contains("range ="));
                if declares {
                    sections.push(section.to_string());
                }
            }
        }
        assert!(
            sections.len() >= crate::config::SECTIONS.len(),
            "{sections:?}"
        );
        for section in sections {
            let prefix = format!("{section}.");
            assert!(
                all_bounds().any(|b| b.key.starts_with(&prefix)),
                "section {section} declares ranges but is not in config::SECTIONS"
            );
        }
    }

    /// A key's default is declared once, beside its field; the schema's description words
    /// it from there, and leaves a default the help text words itself alone.
    #[test]
    fn the_schema_words_each_plain_default_from_its_declaration() {
        let schema = json_schema();
        let description = |section: &str, key: &str| {
            schema["$defs"][section]["properties"][key]["description"]
                .as_str()
                .unwrap()
                .to_string()
        };
        let width = description("MachineConfig", "belt_width");
        assert!(
            width.starts_with("P_max: belt width [m]. Default 0.7.\n"),
            "{width}"
        );
        assert_eq!(MachineConfig::default().belt_width, 0.7);
        let size = description("CameraConfig", "image_size");
        assert!(size.contains("Default [640, 480]."), "{size}");
        assert!(description("RunConfig", "arm").contains("Default true."));
        let com = description("ParcelConfig", "com_height");
        assert_eq!(com.matches("Default").count(), 1, "{com}");
    }

    #[test]
    fn allowed_ranges_read_as_before() {
        assert_eq!(MachineConfig::BELT_SPEED.allowed(), "[0, 20] m/s");
        assert_eq!(DriveConfig::MAX_SWING_DEG.allowed(), "(0, 90] deg");
        assert_eq!(
            MaterialsConfig::ARM_FRICTION.allowed(),
            "[0, 1.3] (μ ≥ 4/3 would allow Painlevé jams)"
        );
        assert_eq!(DistConfig::SD.allowed(), "> 0");
        assert_eq!(AdaptiveConfig::TOLERANCE.allowed(), "≥ 1e-9 m");
        assert!(!DistConfig::SD.contains(0.0) && DistConfig::SD.contains(1e-300));
        assert!(!MachineConfig::BELT_SPEED.contains(f64::NAN));
    }

    #[test]
    fn values_at_fills_in_the_indices_of_a_key_path() {
        let v: toml::Value = toml::from_str(
            "machine = { belt_speed = 2.0, arm_length = nan }\n\
             materials = { belt_friction = [[0.0, 0.5], [2.0, 0.4]] }\n\
             mix = { length = { kind = \"normal\", sd = 0.1 }, width = { sd = \"x\" } }",
        )
        .unwrap();
        assert_eq!(
            values_at(&v, "machine.belt_speed"),
            [("machine.belt_speed".to_string(), 2.0)]
        );
        assert!(values_at(&v, "machine.arm_mass").is_empty());
        assert!(values_at(&v, "machine.arm_length")[0].1.is_nan());
        assert_eq!(
            values_at(&v, "materials.belt_friction[][1]"),
            [
                ("materials.belt_friction[0][1]".to_string(), 0.5),
                ("materials.belt_friction[1][1]".to_string(), 0.4)
            ]
        );
        assert_eq!(
            values_at(&v, "mix.*.sd"),
            [("mix.length.sd".to_string(), 0.1)]
        );
    }
}
