//! The cells of the analyses' tables and readable reports, spelt one way for every
//! analysis: a number in a CSV cell, an optional one, and a rate in words.

/// A number for a CSV cell: the shortest text that reads back to the same `f64`, empty
/// when it is not finite (no `NaN` in a spreadsheet).
pub fn num(v: f64) -> String {
    if v.is_finite() {
        v.to_string()
    } else {
        String::new()
    }
}

/// An optional number for a CSV cell: empty when there is none.
pub fn opt(v: Option<f64>) -> String {
    v.map(num).unwrap_or_default()
}

/// A fraction as a percentage with `decimals` decimals and its sign (`1.234 %`), "–" when it
/// is not finite (a rate of no parcels).
pub fn pct(p: f64, decimals: usize) -> String {
    if p.is_finite() {
        format!("{:.*} %", decimals, 100.0 * p)
    } else {
        "–".into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_read_back_and_leave_what_is_not_a_number_empty() {
        assert_eq!(num(0.1 + 0.2), "0.30000000000000004");
        assert_eq!(num(1e-7), "0.0000001");
        assert_eq!(num(f64::NAN), "");
        assert_eq!(num(f64::INFINITY), "");
        assert_eq!(opt(None), "");
        assert_eq!(opt(Some(2.0)), "2");
        assert_eq!(pct(0.012345, 3), "1.234 %");
        assert_eq!(pct(0.5, 2), "50.00 %");
        assert_eq!(pct(f64::NAN, 3), "–");
    }
}
