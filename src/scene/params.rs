//! Reading a scene's parameter values: one-line errors that name the key
//! (`effects.lighting.sun_color must be an array ..., not a string`).

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

pub fn bad(msg: String) -> Error {
    Error::Scene(msg)
}

pub fn type_name(v: &toml::Value) -> &'static str {
    match v {
        toml::Value::String(_) => "a string",
        toml::Value::Integer(_) => "an integer",
        toml::Value::Float(_) => "a float",
        toml::Value::Boolean(_) => "a boolean",
        toml::Value::Datetime(_) => "a date",
        toml::Value::Array(_) => "an array",
        toml::Value::Table(_) => "a table",
    }
}

pub fn wrong(key: &str, want: &str, v: &toml::Value) -> Error {
    bad(format!("{key} must be {want}, not {}", type_name(v)))
}

pub fn number(key: &str, v: &toml::Value, lo: f64, hi: f64) -> Result<f64> {
    let x = v.as_float().or(v.as_integer().map(|i| i as f64));
    match x {
        Some(x) if x.is_finite() && (lo..=hi).contains(&x) => Ok(x),
        Some(x) => Err(bad(format!("{key} = {x} is outside {lo}..={hi}"))),
        None => Err(wrong(key, "a number", v)),
    }
}

pub fn whole(key: &str, v: &toml::Value, lo: i64, hi: i64) -> Result<u32> {
    let n = v.as_integer().filter(|n| (lo..=hi).contains(n));
    Ok(n.ok_or_else(|| match v.as_integer() {
        Some(n) => bad(format!("{key} = {n} is outside {lo}..={hi}")),
        None => wrong(key, &format!("a whole number {lo}..={hi}"), v),
    })? as u32)
}

pub fn colour(key: &str, v: &toml::Value) -> Result<[f32; 3]> {
    let want = "an array of 3 non-negative numbers (linear RGB)";
    let arr = v.as_array().filter(|a| a.len() == 3).ok_or_else(|| wrong(key, want, v))?;
    let mut out = [0.0f32; 3];
    for (o, x) in out.iter_mut().zip(arr) {
        let x = x.as_float().or(x.as_integer().map(|i| i as f64)).filter(|x| x.is_finite() && *x >= 0.0);
        *o = x.ok_or_else(|| wrong(key, want, v))? as f32;
    }
    Ok(out)
}

pub fn file(key: &str, v: &toml::Value, base: &Path) -> Result<PathBuf> {
    let s = v.as_str().ok_or_else(|| wrong(key, "a file path (string)", v))?;
    let path = crate::world::resolve_relative(base, Path::new(s));
    if !path.is_file() {
        return Err(bad(format!("{key}: file {} does not exist", path.display())));
    }
    Ok(path)
}

/// A hash seed: any u32.
pub fn seed(key: &str, v: &toml::Value) -> Result<u32> {
    let seed = v.as_integer().filter(|s| (0..=i64::from(u32::MAX)).contains(s));
    Ok(seed.ok_or_else(|| wrong(key, "a whole number 0..=4294967295", v))? as u32)
}

/// A switch: true or false.
pub fn boolean(key: &str, v: &toml::Value) -> Result<bool> {
    v.as_bool().ok_or_else(|| wrong(key, "true or false", v))
}
