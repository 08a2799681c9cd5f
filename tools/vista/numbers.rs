//! Number options parsed in words. clap's default parsers pass the standard
//! library's messages through ("invalid digit found in string", "number too
//! large to fit in target type"), which say neither what was wrong nor what
//! the option takes. clap prefixes these with the option's name.

/// A whole number from 0 to `max`.
fn whole(s: &str, max: u64) -> Result<u64, String> {
    let t = s.trim();
    if t.is_empty() {
        return Err(format!("nothing given: it takes a whole number from 0 to {max}"));
    }
    if let Ok(v) = t.parse::<u64>() {
        return if v <= max { Ok(v) } else { Err(format!("{t} is too large: at most {max}")) };
    }
    match t.parse::<f64>() {
        Ok(v) if v < 0.0 => Err(format!("{t} is negative: it takes a whole number from 0 to {max}")),
        Ok(v) if v.is_finite() && v.fract() == 0.0 => Err(format!("{t} is too large: at most {max}")),
        Ok(_) => Err(format!("{t} is not a whole number")),
        Err(_) => Err(format!("{t:?} is not a number: it takes a whole number from 0 to {max}")),
    }
}

pub fn whole_u8(s: &str) -> Result<u8, String> {
    whole(s, u8::MAX.into()).map(|v| v as u8)
}

pub fn whole_u32(s: &str) -> Result<u32, String> {
    whole(s, u32::MAX.into()).map(|v| v as u32)
}

pub fn whole_u64(s: &str) -> Result<u64, String> {
    whole(s, u64::MAX)
}

/// Any number as written (infinities and NaN included: each option's own
/// check says what range it takes).
pub fn number_f64(s: &str) -> Result<f64, String> {
    let t = s.trim();
    if t.is_empty() {
        return Err("nothing given: it takes a number".into());
    }
    t.parse::<f64>().map_err(|_| format!("{t:?} is not a number"))
}

pub fn number_f32(s: &str) -> Result<f32, String> {
    number_f64(s).map(|v| v as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_failure_says_what_the_option_takes() {
        assert_eq!(whole_u32("12"), Ok(12));
        assert!(whole_u32("").unwrap_err().contains("nothing given"));
        assert!(whole_u32("-1").unwrap_err().contains("negative"));
        assert!(whole_u32("1.5").unwrap_err().contains("not a whole number"));
        assert!(whole_u32("99999999999").unwrap_err().contains("at most 4294967295"));
        assert!(whole_u8("300").unwrap_err().contains("at most 255"));
        assert!(whole_u64("1e30").unwrap_err().contains("too large"));
        assert!(whole_u32("abc").unwrap_err().contains("\"abc\" is not a number"));
        assert_eq!(number_f32("0.5"), Ok(0.5));
        assert!(number_f64("x").unwrap_err().contains("not a number"));
        assert!(number_f64("inf").unwrap().is_infinite());
    }
}
