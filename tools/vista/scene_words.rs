//! Scene type errors in the scene's terms. serde's messages name Rust types
//! ("expected u32", "data did not match any variant of untagged enum
//! Extent"); a scene's author needs the key and what it takes.

/// What each scene key takes, in words.
const KEYS: [(&str, &str); 11] = [
    ("source", "a height map path (PNG16 or EXR) or \"procedural\""),
    ("extent", "metres: one positive number, or [x, y]"),
    ("height_range", "[lo, hi] in metres"),
    ("clamp_heights", "true or false"),
    ("spacing", "a positive number of metres"),
    ("lods", "a whole number 1 to 10"),
    ("seed", "a whole number 0 or more"),
    ("terraces", "true or false"),
    ("origin", "[east, north] in metres"),
    ("circle", "[x, y, radius] in metres"),
    ("polygon", "[[x, y], ...] in metres, at least 3 corners"),
];

/// serde's words for a type, and the user's.
const TYPES: [(&str, &str); 8] = [
    ("expected u32", "a whole number"),
    ("expected u64", "a whole number 0 or more"),
    ("expected u8", "a whole number"),
    ("expected f64", "a number"),
    ("expected f32", "a number"),
    ("expected a boolean", "true or false"),
    ("expected a string", "text in quotes"),
    ("expected a sequence", "a list [..]"),
];

/// `message` from the TOML parser about `line` (the scene's text there):
/// kept when it already speaks the scene's terms (unknown keys, syntax),
/// else "KEY takes WHAT (found VALUE)".
pub fn reword(message: &str, line: Option<&str>) -> String {
    let jargon =
        ["invalid type", "invalid value", "invalid length", "did not match any variant", "expected u", "expected f"];
    if !jargon.iter().any(|j| message.contains(j)) {
        return message.to_string();
    }
    let (key, value) = match line.and_then(|l| l.split_once('=')) {
        Some((k, v)) => (k.trim().trim_matches('"'), v.trim()),
        None => ("", ""),
    };
    let takes = KEYS
        .iter()
        .find(|(k, _)| key == *k)
        .map(|(_, t)| t.to_string())
        .or_else(|| TYPES.iter().find(|(j, _)| message.contains(j)).map(|(_, t)| t.to_string()));
    match (key.is_empty(), takes) {
        (false, Some(t)) => format!("{key} takes {t} (found {value})"),
        (false, None) => format!("{key} = {value} is not a value it takes"),
        (true, _) => "a value of the wrong kind".to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn type_errors_name_the_key_and_what_it_takes() {
        assert_eq!(
            reword("invalid type: string \"x\", expected u32", Some("lods = \"x\"")),
            "lods takes a whole number 1 to 10 (found \"x\")"
        );
        let e = reword("data did not match any variant of untagged enum Extent", Some("extent = \"big\""));
        assert_eq!(e, "extent takes metres: one positive number, or [x, y] (found \"big\")");
        assert_eq!(
            reword("invalid type: string \"a\", expected f64", Some("snow_line_m = \"a\"")),
            "snow_line_m takes a number (found \"a\")"
        );
        // Already in the scene's terms: kept.
        assert_eq!(reword("unknown field `bogus`", Some("bogus = 1")), "unknown field `bogus`");
    }
}
