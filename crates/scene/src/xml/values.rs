//! Numbers and number lists in attribute values, as Mitsuba 3 parses them; shared by the
//! parameter reader (`params.rs`) and the transform parser (`transform.rs`).

use super::document::Element;
use super::LoadError;
use glam::Vec3;

/// Three finite numbers from `value`; one number means all three (Mitsuba 3's
/// `parse_named_vector`).
pub(super) fn vector3(el: &Element, value: &str) -> Result<Vec3, LoadError> {
    let c = tokens(value)
        .iter()
        .map(|s| parse_float(s))
        .collect::<Result<Vec<f32>, String>>()
        .map_err(|m| el.error(m))?;
    if let Some(x) = c.iter().find(|x| !x.is_finite()) {
        return Err(el.error(format!("'{value}' holds a number that is not finite ({x})")));
    }
    match c[..] {
        [v] => Ok(Vec3::splat(v)),
        [x, y, z] => Ok(Vec3::new(x, y, z)),
        _ => Err(el.error(format!("expected 1 or 3 values in '{value}', got {}", c.len()))),
    }
}

/// Splits a list on commas and white space, as Mitsuba 3's `string::tokenize`.
pub(super) fn tokens(s: &str) -> Vec<&str> {
    s.split(|c: char| c == ',' || c.is_whitespace()).filter(|t| !t.is_empty()).collect()
}

/// One number; the whole (trimmed) string must be the number.
pub(super) fn parse_float(s: &str) -> Result<f32, String> {
    s.trim().parse::<f32>().map_err(|_| format!("cannot parse '{s}' as a number"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn number_lists() {
        assert_eq!(tokens(" 1, 2 ,3\t4 "), vec!["1", "2", "3", "4"]);
        assert_eq!(parse_float(" 2.5 "), Ok(2.5));
        assert!(parse_float("abc").is_err());
        assert!(parse_float("1,2").is_err());
        assert!(parse_float("").is_err());
    }
}
