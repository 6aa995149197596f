//! Names in text output: words a user reads, not the program's type names.

/// `GpsGlobalOrigin` -> `gps global origin`: a type's Debug name as lower-case words.
pub fn words(debug_name: &str) -> String {
    let mut out = String::new();
    for (i, c) in debug_name.chars().enumerate() {
        if c.is_uppercase() && i > 0 {
            out.push(' ');
        }
        out.extend(c.to_lowercase());
    }
    out
}

/// A non-negative quantity (a time, a distance) for printing: a tiny negative from rounding reads `0.0`, never
/// `-0.0`.
pub fn non_negative(v: f64) -> f64 {
    if v.is_finite() { v.max(0.0) + 0.0 } else { v }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn debug_names_become_words_and_negative_zero_disappears() {
        assert_eq!(words("GpsGlobalOrigin"), "gps global origin");
        assert_eq!(words("Landed"), "landed");
        assert_eq!(format!("{:.1}", non_negative(-0.0)), "0.0");
        assert_eq!(format!("{:.1}", non_negative(-0.01)), "0.0");
        assert_eq!(non_negative(2.5), 2.5);
    }
}
