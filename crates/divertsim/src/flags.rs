//! The command line's flags of the analyses: an analysis's options type
//! ([`divertsim_api::contract::Analysis::Options`]) becomes clap arguments from its JSON
//! Schema (names, kinds, help texts, defaults, choices), and the api's problems, keyed by
//! option names, come back keyed by those flags. Every analysis command's options go
//! through here; no command declares its own.

use clap::{Arg, ArgAction, ArgMatches, Command};
use divertsim_api::config::{self, Problem};
use divertsim_api::contract::Analysis;
use serde_json::{Map, Value};
use std::marker::PhantomData;

/// How an option is written on the command line.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    /// `--name` alone sets it.
    Flag,
    /// A number.
    Number,
    /// Numbers separated by commas.
    Numbers,
    /// A text, given to the options as it is (a list or interval grammar).
    Text,
    /// Texts, one per use of the flag.
    Texts,
}

/// One option of an analysis: its name, kind, help text, default as text and, for a
/// choice, the values allowed.
#[derive(Debug, Clone)]
struct OptionSpec {
    name: String,
    /// The flag's long name: the option's, or the schema's `x-flag`; `no-NAME` for a
    /// switch that is on by default.
    flag: String,
    kind: Kind,
    help: String,
    default: Option<String>,
    choices: Vec<String>,
    /// The value's name in the help (the schema's `x-value`, else the option's name).
    value_name: String,
}

/// The values of a choice (a string enum, possibly behind a `$ref` or an optional one's
/// `anyOf`), else none.
fn choices_of(p: &Value, schema: &Value) -> Vec<String> {
    if let Some(Value::Array(variants)) = p.get("anyOf") {
        return variants
            .iter()
            .find(|v| v.get("type").and_then(Value::as_str) != Some("null"))
            .filter(|_| variants.len() == 2)
            .map_or_else(Vec::new, |v| choices_of(v, schema));
    }
    let target = p
        .get("$ref")
        .and_then(Value::as_str)
        .and_then(|r| r.strip_prefix("#/"))
        .and_then(|r| r.split('/').try_fold(schema, |v, k| v.get(k)))
        .unwrap_or(p);
    let strings = |v: &Value| -> Vec<String> {
        v.as_array()
            .map(|a| {
                a.iter()
                    .filter_map(|x| x.as_str().map(String::from))
                    .collect()
            })
            .unwrap_or_default()
    };
    match (target.get("enum"), target.get("oneOf")) {
        (Some(e), _) => strings(e),
        (None, Some(Value::Array(variants))) => variants
            .iter()
            .flat_map(|v| match v.get("const") {
                Some(c) => c.as_str().map(String::from).into_iter().collect(),
                None => v.get("enum").map(strings).unwrap_or_default(),
            })
            .collect(),
        _ => Vec::new(),
    }
}

/// A doc comment as help: lines of a paragraph joined, option names in backticks as flags,
/// and one paragraph without its final period (as clap does with doc comments).
fn help_of(doc: &str) -> String {
    let text = doc
        .split("\n\n")
        .map(|para| para.lines().map(str::trim).collect::<Vec<_>>().join(" "))
        .collect::<Vec<_>>()
        .join("\n\n");
    let text = flags_in(&text);
    match text.contains("\n\n") {
        true => text,
        false => text.strip_suffix('.').unwrap_or(&text).to_string(),
    }
}

/// The options of `A` from its JSON Schema, by name.
fn option_specs<A: Analysis>() -> Vec<OptionSpec> {
    let schema = serde_json::to_value(schemars::schema_for!(A::Options)).unwrap_or_default();
    let Some(props) = schema.get("properties").and_then(Value::as_object) else {
        return Vec::new();
    };
    let mut specs: Vec<OptionSpec> = props
        .iter()
        .map(|(name, p)| {
            // The type, a nullable one (`["integer", "null"]`) as its other type.
            let ty = match p.get("type") {
                Some(Value::Array(types)) => types
                    .iter()
                    .filter_map(Value::as_str)
                    .find(|t| *t != "null"),
                t => t.and_then(Value::as_str),
            };
            let texts = p.get("x-repeat") == Some(&Value::Bool(true))
                || p.pointer("/items/type").and_then(Value::as_str) == Some("string");
            let kind = match ty {
                _ if texts => Kind::Texts,
                Some("boolean") => Kind::Flag,
                Some("number" | "integer") => Kind::Number,
                Some("array") => Kind::Numbers,
                _ => Kind::Text,
            };
            let on = kind == Kind::Flag && p.get("default") == Some(&Value::Bool(true));
            let flag = match (p.get("x-flag").and_then(Value::as_str), on) {
                (Some(f), _) => f.to_string(),
                (None, true) => format!("no-{}", name.replace('_', "-")),
                (None, false) => name.replace('_', "-"),
            };
            let default = p.get("default").and_then(|d| match d {
                Value::Bool(_) | Value::Null => None,
                Value::String(s) => Some(s.clone()),
                Value::Array(v) if v.is_empty() => None,
                // An interval [lo, hi] is written LO:HI, a list of numbers A,B.
                Value::Array(v) if kind == Kind::Text => {
                    Some(v.iter().map(Value::to_string).collect::<Vec<_>>().join(":"))
                }
                Value::Array(v) => {
                    Some(v.iter().map(Value::to_string).collect::<Vec<_>>().join(","))
                }
                other => Some(other.to_string()),
            });
            OptionSpec {
                name: name.clone(),
                flag,
                kind,
                help: p
                    .get("description")
                    .and_then(Value::as_str)
                    .unwrap_or("")
                    .to_string(),
                default,
                choices: choices_of(p, &schema),
                value_name: p
                    .get("x-value")
                    .and_then(Value::as_str)
                    .map_or_else(|| name.to_uppercase(), String::from),
            }
        })
        .collect();
    // The help texts, option names in backticks as their flags; a switch that is on by
    // default is turned off by its flag.
    let named = specs.clone();
    for spec in &mut specs {
        spec.help = help_of(&flags_of_names(&named, &spec.help));
        if spec.kind == Kind::Flag && spec.flag.starts_with("no-") {
            let mut chars = spec.help.chars();
            let first = chars.next().map(|c| c.to_lowercase().to_string());
            spec.help = format!("Turn off {}{}", first.unwrap_or_default(), chars.as_str());
        }
    }
    specs
}

/// The options of analysis `A` given on the command line, as the JSON object its options
/// type reads (options not given keep the type's defaults).
pub struct OptionArgs<A> {
    /// The options given, by option name.
    pub given: Map<String, Value>,
    analysis: PhantomData<fn() -> A>,
}

impl<A> Clone for OptionArgs<A> {
    fn clone(&self) -> Self {
        OptionArgs {
            given: self.given.clone(),
            analysis: PhantomData,
        }
    }
}

impl<A> std::fmt::Debug for OptionArgs<A> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OptionArgs")
            .field("given", &self.given)
            .finish()
    }
}

impl<A: Analysis> clap::FromArgMatches for OptionArgs<A> {
    fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
        let mut given = Map::new();
        for spec in option_specs::<A>() {
            let from_user =
                m.value_source(&spec.name) == Some(clap::parser::ValueSource::CommandLine);
            if !from_user {
                continue;
            }
            let value = match spec.kind {
                // A switch on by default: its flag turns it off.
                Kind::Flag => Value::Bool(m.get_flag(&spec.name) != spec.flag.starts_with("no-")),
                Kind::Texts => Value::Array(
                    m.get_many::<String>(&spec.name)
                        .into_iter()
                        .flatten()
                        .map(|t| Value::String(t.clone()))
                        .collect(),
                ),
                _ => {
                    let text = m.get_one::<String>(&spec.name).cloned().unwrap_or_default();
                    json_of(spec.kind, &text)
                }
            };
            given.insert(spec.name, value);
        }
        Ok(OptionArgs {
            given,
            analysis: PhantomData,
        })
    }

    fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

/// A flag's text as the JSON the options type reads; a text that is not what the kind
/// needs stays a text, so that the options type names the option in its problem.
fn json_of(kind: Kind, text: &str) -> Value {
    let number = |t: &str| -> Option<Value> {
        let t = t.trim();
        t.parse::<u64>()
            .ok()
            .map(Value::from)
            .or_else(|| t.parse::<i64>().ok().map(Value::from))
            .or_else(|| {
                t.parse::<f64>()
                    .ok()
                    .and_then(serde_json::Number::from_f64)
                    .map(Value::Number)
            })
    };
    let fallback = || Value::String(text.to_string());
    match kind {
        Kind::Number => number(text).unwrap_or_else(fallback),
        Kind::Numbers => text
            .split(',')
            .map(number)
            .collect::<Option<Vec<Value>>>()
            .map(Value::Array)
            .unwrap_or_else(fallback),
        Kind::Flag | Kind::Text | Kind::Texts => fallback(),
    }
}

impl<A: Analysis> clap::Args for OptionArgs<A> {
    fn augment_args(mut cmd: Command) -> Command {
        for spec in option_specs::<A>() {
            let mut arg = Arg::new(spec.name.clone())
                .long(spec.flag.clone())
                .help(spec.help.clone());
            arg = match spec.kind {
                Kind::Flag => arg.action(ArgAction::SetTrue),
                Kind::Texts => arg
                    .action(ArgAction::Append)
                    .value_name(spec.value_name.clone())
                    .allow_hyphen_values(true),
                _ => arg
                    .action(ArgAction::Set)
                    .value_name(spec.value_name.clone())
                    .allow_hyphen_values(true),
            };
            if let Some(d) = spec.default {
                arg = arg.default_value(d);
            }
            if !spec.choices.is_empty() {
                arg = arg.value_parser(clap::builder::PossibleValuesParser::new(spec.choices));
            }
            cmd = cmd.arg(arg);
        }
        cmd
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}

/// Problems keyed by option names as problems keyed by the flags of analysis `A` (an
/// option's own flag name, `--no-NAME` for a switch on by default), option names in
/// backticks in the messages too; other keys as [`flags`] gives them.
pub fn flags_for<A: Analysis>(problems: Vec<Problem>) -> Vec<Problem> {
    let specs = option_specs::<A>();
    let problems = problems.into_iter().map(|p| {
        let message = flags_of_names(&specs, &p.message);
        match specs.iter().find(|s| s.name == p.key) {
            Some(spec) => Problem::new(format!("--{}", spec.flag), message),
            None => Problem::new(p.key, message),
        }
    });
    flags(problems.collect())
}

/// Option names of analysis `A` in backticks in an api text (`` `speeds` ``) as their
/// flags (`--speeds`).
pub fn flags_named<A: Analysis>(text: &str) -> String {
    flags_of_names(&option_specs::<A>(), text)
}

/// Option names in backticks in an api text (`` `speeds` ``) as their flags (`--speeds`).
fn flags_of_names(specs: &[OptionSpec], text: &str) -> String {
    specs.iter().fold(text.to_string(), |t, spec| {
        t.replace(&format!("`{}`", spec.name), &format!("--{}", spec.flag))
    })
}

/// The scenario file's sections: keys of problems that stay as they are.
const SECTIONS: [&str; 10] = [
    "base",
    "machine",
    "parcel",
    "materials",
    "run",
    "limits",
    "optimize",
    "design",
    "mix",
    "camera",
];

/// The api's problems keyed by option names (`scan_step`) as the command line's flags
/// (`--scan-step`); scenario keys (`machine.belt_speed`) and flags stay as they are. An
/// option the message names in backticks becomes its flag too.
pub fn flags(problems: Vec<config::Problem>) -> Vec<config::Problem> {
    problems
        .into_iter()
        .map(|p| {
            let message = flags_in(&p.message);
            match p.key.contains(['.', '-', ' ']) || SECTIONS.contains(&p.key.as_str()) {
                true => config::Problem::new(p.key, message),
                false => config::Problem::new(flag_of(&p.key), message),
            }
        })
        .collect()
}

/// Option names in backticks (`` `worst` ``) as flags (`--worst`).
pub fn flags_in(text: &str) -> String {
    let parts: Vec<&str> = text.split('`').collect();
    let mut out = String::new();
    for (i, part) in parts.iter().enumerate() {
        let name = i % 2 == 1 && i + 1 < parts.len();
        match name && !part.is_empty() && part.chars().all(|c| c.is_ascii_lowercase() || c == '_') {
            true => out += &flag_of(part),
            false if name => out += &format!("`{part}`"),
            false => out += part,
        }
    }
    out
}

/// The flag of an option name: `scan_step` → `--scan-step`.
pub fn flag_of(name: &str) -> String {
    format!("--{}", name.replace('_', "-"))
}
