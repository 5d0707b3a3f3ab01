//! The number markers of the documentation: a number in a document written between
//! markers that name a run, a pointer into its summary and a format
//! (`<!--n RUN POINTER FORMAT-->value<!--/n-->`), found, read from the run's summary and
//! rewritten. Pure text: `divertsim docs` runs the runs, reads their outputs and writes the
//! documents.
//!
//! The pointer is a JSON pointer into the summary; a last step `#` is an array's length, a
//! `*` step takes the largest value over an array's elements that have one, `A|B` is the
//! ratio of two values, and a pointer ending in `?` reads 0 where the summary has nothing.
//! The format is `pct:N` (a fraction as a percentage, N decimals), `fix:N` (N decimals),
//! `int` (rounded, thousands separated) or `text` (a string as it is; a boolean as yes or
//! no). A value the run has as none (a JSON null) at a plain pointer is written "—".

use serde_json::Value;
use std::collections::BTreeMap;

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
    let text = divertsim_api::analyses::count_text(v.abs() as u64);
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

/// A run's CSV tables (each file's name and bytes, in order) into its summary, each under its
/// file name as an array of rows (`/trigger.csv/3/start_position_m`: the fourth row's cell), numbers where
/// a cell reads as one.
pub fn add_tables(summary: &mut Value, tables: &[(String, Vec<u8>)]) -> Result<(), String> {
    let Some(map) = summary.as_object_mut() else {
        return Ok(());
    };
    for (name, bytes) in tables {
        let mut reader = csv::ReaderBuilder::new()
            .flexible(true)
            .from_reader(bytes.as_slice());
        let header = reader
            .headers()
            .map_err(|e| format!("{name}: {e}"))?
            .clone();
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
        map.insert(name.clone(), Value::Array(rows));
    }
    Ok(())
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
        let table = b"method,to_within\nga,1845\ngradient,\n".to_vec();
        let mut summary = json!({"medians": [{"to_within": null}]});
        add_tables(&mut summary, &[("m.csv".to_string(), table)]).unwrap();
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
