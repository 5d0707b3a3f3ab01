//! The numeric ranges of the scenario file, written once: validation checks values against
//! them and words its messages from them, `divertsim schema` carries them as
//! `minimum`/`maximum`/`exclusiveMinimum`/`exclusiveMaximum` (and in the descriptions), and
//! `divertsim example` prints them. Ranges that depend on other keys (width ≤ length, a
//! parcel on the belt) stay in the validation code.
//!
//! A bound's `key` is a path in the schema: dotted section and key names, `[]` for every
//! element of an array, `[0]` for one position of a fixed-length array, `*` for every key of
//! a section (`mix.*.sd`: the `sd` of every distribution of the mix).

use super::{brief, Problem};
use divertsim_core::analysis::design::worst_case::PoseBox;
use divertsim_core::analysis::population::adaptive_trigger::MIN_TOLERANCE;
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
    /// [lo, hi].
    pub const fn closed(key: &'static str, lo: f64, hi: f64, unit: &'static str) -> Bound {
        Bound {
            key,
            lo,
            lo_open: false,
            hi,
            hi_open: false,
            unit,
            why: "",
        }
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
    pub const fn open_closed(key: &'static str, lo: f64, hi: f64, unit: &'static str) -> Bound {
        Bound {
            lo_open: true,
            ..Bound::closed(key, lo, hi, unit)
        }
    }

    /// (lo, ∞).
    pub const fn above(key: &'static str, lo: f64, unit: &'static str) -> Bound {
        Bound::open_closed(key, lo, f64::INFINITY, unit)
    }

    /// [lo, ∞).
    pub const fn at_least(key: &'static str, lo: f64, unit: &'static str) -> Bound {
        Bound::closed(key, lo, f64::INFINITY, unit)
    }

    /// A band (lo, hi) as [lo, hi].
    pub const fn band(key: &'static str, b: (f64, f64), unit: &'static str) -> Bound {
        Bound::closed(key, b.0, b.1, unit)
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
const SIDE: (f64, f64) = PoseBox::LIMITS.length;
/// Parcel masses.
const MASS: (f64, f64) = PoseBox::LIMITS.mass;
const SIDE_WHY: &str = "a parcel side under 1 mm is below the contact tolerances";
const MASS_WHY: &str = "a mass under 1 g makes forces vanish against the tolerances";
/// The range of a table's node count.
const NODES: (f64, f64) = (1.0, 50.0);
const NO_JAM: &str = "μ ≥ 4/3 would allow Painlevé jams";

/// Declares each bound as a constant and lists them all in [`ALL`], so that no bound can be
/// checked without also reaching the schema.
macro_rules! bounds {
    ($($name:ident = $bound:expr;)*) => {
        $(#[doc = concat!("The range of `", stringify!($name), "`.")] pub const $name: Bound = $bound;)*
        /// Every bound of the scenario file.
        pub const ALL: &[Bound] = &[$($name),*];
    };
}

/// The belt speeds of an analysis that needs a moving belt (trigger, capture, the
/// reference setting): [`BELT_SPEED`] without 0.
pub const MOVING_BELT_SPEED: Bound =
    Bound::open_closed("speeds", BELT_SPEED.lo, BELT_SPEED.hi, BELT_SPEED.unit);
/// The belt speeds the capacity map and the optimiser search over: a sorter's speeds.
pub const SEARCHED_BELT_SPEED: Bound = Bound::closed("speeds", 0.05, 10.0, "m/s");
/// The cycle times the capacity map and the optimiser search over.
pub const SEARCHED_CYCLE_TIME: Bound = Bound::closed("cycle_times", 0.2, 10.0, "s");
/// The light-barrier positions the capacity map and the optimiser search over.
pub const SEARCHED_LIGHT_BARRIER: Bound = Bound::closed("light_barriers", -5.0, 5.0, "m");
/// The start positions the optimiser searches over (and the capacity map's R_s range).
pub const SEARCHED_START_POSITION: Bound = Bound::closed("start_range", -5.0, 5.0, "m");

bounds! {
    BELT_WIDTH = Bound::closed("machine.belt_width", 0.01, 10.0, "m")
        .because("a belt narrower than 1 cm carries no parcel");
    BELT_SPEED = Bound::closed("machine.belt_speed", 0.0, 20.0, "m/s");
    ARM_LENGTH = Bound::closed("machine.arm_length", 0.01, 10.0, "m")
        .because("an arm shorter than 1 cm reaches no parcel");
    CYCLE_TIME = Bound::closed("machine.cycle_time", 0.1, 60.0, "s")
        .because("a faster cycle is beyond any drive and strikes beyond the rigid-impact model");
    START_POSITION = Bound::closed("machine.start_position", -10.0, 10.0, "m");
    LIGHT_BARRIER = Bound::closed("machine.light_barrier", -10.0, 10.0, "m");
    ARM_FACE_BOTTOM = Bound::closed("machine.arm_face_bottom", 0.0, 2.0, "m");
    ARM_FACE_TOP = Bound::open_closed("machine.arm_face_top", 0.0, 5.0, "m");
    ARM_MASS = Bound::closed("machine.arm_mass", 0.0, 1000.0, "kg");
    ARM_INERTIA = Bound::closed("machine.arm_inertia", 0.0, 10000.0, "kg·m²");
    MAX_SWING = Bound::open_closed("machine.drive.max_swing_deg", 0.0, 90.0, "deg");
    CRANK = Bound::open_closed("machine.drive.crank", 0.0, 10.0, "m");
    COUPLER = Bound::open_closed("machine.drive.coupler", 0.0, 10.0, "m");
    ROCKER = Bound::open_closed("machine.drive.rocker", 0.0, 10.0, "m");
    GROUND = Bound::open_closed("machine.drive.ground", 0.0, 10.0, "m");
    LENGTH_NODES = Bound::band("machine.adaptive.length_nodes", NODES, "");
    ASPECT_NODES = Bound::band("machine.adaptive.aspect_nodes", NODES, "");
    OFFSET_NODES = Bound::band("machine.adaptive.offset_nodes", NODES, "");
    ANGLE_NODES = Bound::band("machine.adaptive.angle_nodes", NODES, "");
    // Checked by the core's StartSearch::problems (the test ties the two).
    ADAPTIVE_STEP = Bound::above("machine.adaptive.step", 0.0, "m");
    ADAPTIVE_TOLERANCE = Bound::at_least("machine.adaptive.tolerance", MIN_TOLERANCE, "m");

    PARCEL_LENGTH = Bound::band("parcel.length", SIDE, "m").because(SIDE_WHY);
    PARCEL_WIDTH = Bound::band("parcel.width", SIDE, "m").because(SIDE_WHY);
    PARCEL_HEIGHT = Bound::band("parcel.height", SIDE, "m").because(SIDE_WHY);
    PARCEL_MASS = Bound::band("parcel.mass", MASS, "kg").because(MASS_WHY);
    COM_HEIGHT = Bound::open_closed("parcel.com_height", 0.0, 5.0, "m");
    PARCEL_ANGLE = Bound::closed("parcel.angle_deg", -180.0, 180.0, "deg");
    PARCEL_SPIN = Bound::closed("parcel.spin", -100.0, 100.0, "rad/s");
    PARCEL_VELOCITY = Bound::closed("parcel.velocity[]", -20.0, 20.0, "m/s");

    BELT_FRICTION = Bound::closed("materials.belt_friction", 0.0, 2.0, "");
    BELT_FRICTION_SPEED = Bound::closed("materials.belt_friction[][0]", 0.0, 100.0, "m/s");
    BELT_FRICTION_MU = Bound::closed("materials.belt_friction[][1]", 0.0, 2.0, "");
    ARM_FRICTION = Bound::closed("materials.arm_friction", 0.0, 1.3, "").because(NO_JAM);
    RESTITUTION = Bound::closed("materials.restitution", 0.0, 1.0, "");

    DURATION = Bound::closed("run.duration", 1e-3, 3600.0, "s")
        .because("the integrator's step budget grows with the duration up to an hour");
    TOLERANCE = Bound::closed("run.tolerance", 1e-12, 1e-4, "")
        .because("tighter meets round-off in the event location, looser misses contacts");
    DROP_HEIGHT = Bound::closed("limits.drop_height", 1e-3, 10.0, "m")
        .because("the reference fall must be finite and non-zero for the overload ratios");

    DESIGN_LENGTH = Bound::band("design.parcels[].length", SIDE, "m").because(SIDE_WHY);
    DESIGN_WIDTH = Bound::band("design.parcels[].width", SIDE, "m").because(SIDE_WHY);
    DESIGN_HEIGHT = Bound::band("design.parcels[].height", SIDE, "m").because(SIDE_WHY);
    DESIGN_MASS = Bound::band("design.parcels[].mass", MASS, "kg").because(MASS_WHY);
    DESIGN_ANGLE = Bound::closed("design.parcels[].angle_deg", -180.0, 180.0, "deg");
    OVERLOAD_LENGTH = Bound::band("design.overload.length", SIDE, "m").because(SIDE_WHY);
    OVERLOAD_WIDTH = Bound::band("design.overload.width", SIDE, "m").because(SIDE_WHY);
    OVERLOAD_HEIGHT = Bound::band("design.overload.height", SIDE, "m").because(SIDE_WHY);
    OVERLOAD_MASS = Bound::band("design.overload.mass", MASS, "kg").because(MASS_WHY);
    // Checked by the core's PoseBox::problems against the same PoseBox::LIMITS.
    SEARCH_LENGTH = Bound::band("design.search.length[]", PoseBox::LIMITS.length, "m");
    SEARCH_WIDTH = Bound::band("design.search.width[]", PoseBox::LIMITS.width, "m");
    SEARCH_MASS = Bound::band("design.search.mass[]", PoseBox::LIMITS.mass, "kg");
    SEARCH_ANGLE = Bound::band("design.search.angle_deg[]", PoseBox::LIMITS.angle_deg, "deg");
    SEARCH_PHASE = Bound::band("design.search.phase[]", PoseBox::LIMITS.phase, "s");
    SEARCH_SPEED_SCALE =
        Bound::band("design.search.belt_speed_scale[]", PoseBox::LIMITS.belt_speed_scale, "");
    SEARCH_FRICTION_SCALE = Bound::band(
        "design.search.belt_friction_scale[]",
        PoseBox::LIMITS.belt_friction_scale,
        "",
    );
    SEARCH_ARM_FRICTION = Bound::band("design.search.arm_friction[]", ARM_FRICTION_BAND, "");
    SEARCH_RESTITUTION = Bound::band("design.search.restitution[]", RESTITUTION_BAND, "");
    SEARCH_HEIGHT = Bound::band("design.search.height[]", SIDE, "m").because(SIDE_WHY);

    // Checked by the core's Distribution::problems (the test ties the two).
    MIX_SD = Bound::above("mix.*.sd", 0.0, "");
    MIX_MEDIAN = Bound::above("mix.*.median", 0.0, "");
    MIX_SIGMA = Bound::above("mix.*.sigma", 0.0, "");
    MIX_WEIGHTS = Bound::at_least("mix.*.weights[]", 0.0, "");

    FRAME_RATE = Bound::open_closed("camera.frame_rate", 0.0, 1e5, "1/s");
    IMAGE_SIZE = Bound::closed("camera.image_size[]", 1.0, 1e6, "px");
    MARKER_OFFSET = Bound::closed("camera.marker_offset[]", -5.0, 5.0, "m");
}

const ARM_FRICTION_BAND: (f64, f64) = match PoseBox::LIMITS.arm_friction {
    Some(b) => b,
    None => (0.0, 1.3),
};
const RESTITUTION_BAND: (f64, f64) = match PoseBox::LIMITS.restitution {
    Some(b) => b,
    None => (0.0, 1.0),
};

/// The sides and mass of a parcel, of a design parcel and of the overload parcel.
pub const PARCEL_BOX: [Bound; 4] = [PARCEL_LENGTH, PARCEL_WIDTH, PARCEL_HEIGHT, PARCEL_MASS];
/// See [`PARCEL_BOX`].
pub const DESIGN_BOX: [Bound; 4] = [DESIGN_LENGTH, DESIGN_WIDTH, DESIGN_HEIGHT, DESIGN_MASS];
/// See [`PARCEL_BOX`].
pub const OVERLOAD_BOX: [Bound; 4] = [
    OVERLOAD_LENGTH,
    OVERLOAD_WIDTH,
    OVERLOAD_HEIGHT,
    OVERLOAD_MASS,
];

/// The bound of a key path in the schema's terms (`design.parcels[].mass`), if it has one.
pub fn find(key: &str) -> Option<&'static Bound> {
    ALL.iter().find(|b| b.key == key)
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

/// Write every bound of [`ALL`] into the schema: the range keywords on each number it
/// applies to, and "Allowed: …" at the end of its property's description.
pub fn annotate(schema: &mut Value) {
    let mut described = BTreeSet::new();
    for b in ALL {
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
    use crate::config::{apply_set, deserialize_collecting, json_schema, validate};

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
        for b in ALL {
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

    #[test]
    fn allowed_ranges_read_as_before() {
        assert_eq!(BELT_SPEED.allowed(), "[0, 20] m/s");
        assert_eq!(MAX_SWING.allowed(), "(0, 90] deg");
        assert_eq!(
            ARM_FRICTION.allowed(),
            "[0, 1.3] (μ ≥ 4/3 would allow Painlevé jams)"
        );
        assert_eq!(MIX_SD.allowed(), "> 0");
        assert_eq!(ADAPTIVE_TOLERANCE.allowed(), "≥ 1e-9 m");
        assert!(!MIX_SD.contains(0.0) && MIX_SD.contains(1e-300));
        assert!(!BELT_SPEED.contains(f64::NAN));
    }
}
