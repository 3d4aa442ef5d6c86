//! Numbers in messages as people write them: a value a user typed as `1e300` is not echoed
//! back as 301 digits.

/// `v` as `Display` writes it when that is short (at most six digits before the point, no
/// more than four zeros after it before the first digit), else in scientific notation
/// (`1e300`, `2.5e-7`).
pub fn number(v: f64) -> String {
    let a = v.abs();
    if v.is_finite() && a != 0.0 && !(1e-4..1e6).contains(&a) {
        format!("{v:e}")
    } else {
        v.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::number;

    #[test]
    fn numbers_read_as_typed() {
        assert_eq!(number(1e300), "1e300");
        assert_eq!(number(-5.0), "-5");
        assert_eq!(number(0.1), "0.1");
        assert_eq!(number(123456.5), "123456.5");
        assert_eq!(number(2.5e-7), "2.5e-7");
        assert_eq!(number(0.0), "0");
        assert_eq!(number(f64::INFINITY), "inf");
    }
}
