//! CSV cells as `bench` and `report` write them: one spelling for both, below
//! the layers that write tables.

/// One CSV field: quoted (RFC 4180) when it holds a comma, quote or line break.
pub fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// A number for CSV: fixed digits, "inf" / "nan" spelled out.
pub fn csv_number(v: f64, digits: usize) -> String {
    if v.is_nan() {
        "nan".into()
    } else if v.is_infinite() {
        if v > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        format!("{v:.digits$}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_and_numbers() {
        assert_eq!(csv_field("max-depth"), "max-depth");
        assert_eq!(csv_field("a,b"), "\"a,b\"");
        assert_eq!(csv_field("two\nlines"), "\"two\nlines\"");
        assert_eq!(csv_field("say \"hi\""), "\"say \"\"hi\"\"\"");
        assert_eq!(csv_number(1.23456, 3), "1.235");
        assert_eq!(csv_number(f64::INFINITY, 3), "inf");
        assert_eq!(csv_number(f64::NEG_INFINITY, 3), "-inf");
        assert_eq!(csv_number(f64::NAN, 3), "nan");
    }
}
