//! The value-list grammar of every list option (speeds, cycle times, sweeps): `A,B,C`,
//! `LO:HI/COUNT` or `LO:HI:STEP`, each value rounded to 12 significant digits so that
//! `0.65:2.3:0.05` gives 0.7, not 0.7000000000000001. The CLI parses its flags with it and
//! the api's defaults are written in it, so both edges get the same numbers.

use super::{brief, Problem};

/// One grammar for every list of values on the command line (`--speeds`, `--cycle-times`,
/// `--light-barriers`, a `--sweep`):
/// - `A,B,C`: these values;
/// - `LO:HI/N`: N evenly spaced values, LO and HI included;
/// - `LO:HI:STEP`: from LO in steps of STEP (`0.65:2.3:0.05`), HI included when a step
///   lands on it.
///
/// Every value in [lo, hi] `unit`; at most `max` values. A whole-number STEP ≥ 2 reads like
/// a count (issue 50): one larger than HI − LO, which would give a single value, is refused
/// with the count's spelling (`1:2:3` → "write 1:2/3"), and a smaller one is taken as a step
/// with a warning. Returns the values and a warning for such a step or for a range that
/// gives a single value.
pub fn parse_values(
    key: &str,
    text: &str,
    lo: f64,
    hi: f64,
    unit: &str,
    max: usize,
) -> Result<(Vec<f64>, Option<String>), Problem> {
    let bad = |why: String| {
        Problem::new(
        key,
        format!(
            "'{text}': {why}; allowed: A,B,C or LO:HI/COUNT or LO:HI:STEP, values in [{}, {}] {unit}",
            brief(lo),
            brief(hi)
        )
        .trim_end()
        .to_string(),
        )
    };
    let number = |s: &str| -> Result<f64, Problem> {
        s.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| bad(format!("'{}' is not a finite number", s.trim())))
    };
    let clean = |v: f64| format!("{v:.11e}").parse::<f64>().unwrap_or(v);
    // `stepped`: the STEP of a LO:HI:STEP range with HI > LO (the only form that can give
    // one value by mistake, or be read as a count).
    let (values, stepped) = if let Some((a, rest)) = text.split_once(':') {
        let (a, b, count, step) = match rest.split_once('/') {
            Some((b, n)) => {
                let n: usize = n
                    .trim()
                    .parse()
                    .map_err(|_| bad(format!("COUNT '{}' is not a whole number", n.trim())))?;
                (number(a)?, number(b)?, Some(n), None)
            }
            None => match rest.split_once(':') {
                Some((b, x)) => {
                    let (a, b, x) = (number(a)?, number(b)?, number(x)?);
                    if looks_like_count(x) && x > b - a && b > a {
                        return Err(bad(format!(
                            "STEP {} is larger than HI − LO = {} and gives a single value; for {} evenly spaced values write {}:{}/{}",
                            brief(x), brief(b - a), brief(x), brief(a), brief(b), brief(x)
                        )));
                    }
                    (a, b, None, Some(x))
                }
                None => return Err(bad("a range needs three parts".into())),
            },
        };
        if b < a {
            return Err(bad("HI is below LO".into()));
        }
        let values = match (count, step) {
            (Some(n), _) => {
                if !(1..=max).contains(&n) {
                    return Err(bad(format!("COUNT {n} is not in 1..={max}")));
                }
                if n > 1 && b == a {
                    return Err(bad(format!("COUNT {n} needs HI > LO")));
                }
                divertsim_core::analysis::design::capacity::linspace(a, b, n)
                    .into_iter()
                    .map(clean)
                    .collect()
            }
            (None, Some(h)) => {
                if h.is_nan() || h <= 0.0 {
                    return Err(bad(format!("STEP {} is not > 0", brief(h))));
                }
                let n = ((b - a) / h + 1e-9).floor();
                if n + 1.0 > max as f64 {
                    return Err(bad(format!("more than {max} values")));
                }
                (0..=n as usize).map(|i| clean(a + h * i as f64)).collect()
            }
            _ => Vec::new(),
        };
        (values, step.filter(|_| b > a))
    } else {
        let v: Vec<f64> = text.split(',').map(number).collect::<Result<_, _>>()?;
        (v, None)
    };
    if values.is_empty() || values.len() > max {
        return Err(bad(format!("give 1 to {max} values")));
    }
    if let Some(v) = values.iter().find(|v| !(lo..=hi).contains(*v)) {
        return Err(bad(format!("{} is out of range", brief(*v))));
    }
    let warning = if stepped.is_some() && values.len() == 1 {
        Some(format!(
            "warning: {key} '{text}' gives the single value {} (a STEP larger than the range); for a count write LO:HI/COUNT",
            brief(values[0])
        ))
    } else if let Some(x) = stepped.filter(|x| looks_like_count(*x)) {
        let lo_hi = text.rsplit_once(':').map_or(text, |p| p.0);
        Some(format!(
            "warning: {key} '{text}' is read as LO:HI:STEP, {} values ({}); for {} evenly spaced values write {lo_hi}/{}",
            values.len(),
            values.iter().map(|v| brief(*v)).collect::<Vec<_>>().join(", "),
            brief(x),
            brief(x)
        ))
    } else {
        None
    };
    Ok((values, warning))
}

/// A whole number ≥ 2: a STEP that a reader may take for a count.
fn looks_like_count(x: f64) -> bool {
    x >= 2.0 && x.fract() == 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The one grammar, table-driven: text → values (or the problem).
    #[test]
    fn value_grammar() {
        let ok = [
            ("1,1.5,2", vec![1.0, 1.5, 2.0]),
            ("1:2/3", vec![1.0, 1.5, 2.0]),
            ("0.65:0.8:0.05", vec![0.65, 0.7, 0.75, 0.8]),
            ("0.5:2.5/5", vec![0.5, 1.0, 1.5, 2.0, 2.5]),
            ("2:2/1", vec![2.0]),
            ("2:2:1", vec![2.0]),
        ];
        for (text, want) in ok {
            let (v, w) = parse_values("--x", text, 0.0, 20.0, "m/s", 100).unwrap();
            assert_eq!(v, want, "{text}");
            assert!(w.is_none(), "{text}");
        }
        let (v, w) = parse_values("--x", "1:2:1.5", 0.0, 20.0, "m/s", 100).unwrap();
        assert_eq!(v, [1.0]);
        assert!(w.unwrap().contains("LO:HI/COUNT"));
    }

    /// Issue 50: `0:10:5` is a STEP (0, 5, 10) said in a warning with the count's
    /// spelling; `1.5:2.3:9`, a STEP larger than the range, is refused with it.
    #[test]
    fn a_whole_step_is_a_step_and_is_warned_about() {
        let (v, w) = parse_values("sweep", "0:10:5", 0.0, 20.0, "", 100).unwrap();
        assert_eq!(v, [0.0, 5.0, 10.0]);
        let w = w.unwrap();
        assert!(w.contains("read as LO:HI:STEP, 3 values (0, 5, 10)"), "{w}");
        assert!(w.contains("write 0:10/5"), "{w}");
        let (v, w) = parse_values("sweep", "0:10:2", 0.0, 20.0, "", 100).unwrap();
        assert_eq!(v, [0.0, 2.0, 4.0, 6.0, 8.0, 10.0]);
        assert!(w.unwrap().contains("write 0:10/2"));
        let e = parse_values("sweep", "1.5:2.3:9", 0.0, 20.0, "", 100).unwrap_err();
        assert!(e.message.contains("write 1.5:2.3/9"), "{}", e.message);
        assert!(parse_values("sweep", "0:1:0.25", 0.0, 20.0, "", 100)
            .unwrap()
            .1
            .is_none());
        for bad in [
            "1:2", "2:1/3", "1:2:-1", "a,b", "1:2/0", "0:30:1", "1:2/1000", "nan:2:1",
        ] {
            let e = parse_values("--x", bad, 0.0, 20.0, "m/s", 100).unwrap_err();
            assert_eq!(e.key, "--x");
            assert!(
                e.message
                    .contains("allowed: A,B,C or LO:HI/COUNT or LO:HI:STEP"),
                "{bad}: {}",
                e.message
            );
        }
    }
}
