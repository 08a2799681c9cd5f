//! Reading a material set's TOML (`[[material]]`, `[[texture_set]]`,
//! `[[control_texture]]`): one-line errors naming the key.

use super::*;

/// Errors here are messages without the origin, which the caller prepends.
pub(super) fn parse(table: &toml::Table, base: &Path) -> std::result::Result<MaterialSet, String> {
    let mut set = MaterialSet::default();
    if let Some(key) = table.keys().find(|k| !["textures", "material", "control_texture"].contains(&k.as_str())) {
        return Err(format!("unknown key {key} (known: textures, material, control_texture)"));
    }
    if let Some(v) = table.get("textures") {
        let sets = v.as_table().ok_or_else(|| wrong("textures", "a table of texture sets", v))?;
        for (name, v) in sets {
            let source = texture_source(&format!("textures.{name}"), v, base)?;
            match set.textures.iter().position(|t| t.name == *name) {
                Some(i) => set.textures[i].source = source,
                None if set.textures.len() == MAX_TEXTURE_SETS => {
                    return Err(format!(
                        "textures.{name}: more than {MAX_TEXTURE_SETS} texture sets ({} named, plus the default \
                         grass, rock, snow and scree)",
                        sets.len()
                    ));
                }
                None => set.textures.push(TextureSet { name: name.clone(), source }),
            }
        }
    }
    if let Some(v) = table.get("control_texture") {
        parse_control(&mut set, v)?;
    }
    let Some(v) = table.get("material") else { return Ok(set) };
    let list = v.as_array().ok_or_else(|| wrong("material", "an array of tables ([[material]])", v))?;
    let mut first_at: [Option<usize>; MATERIAL_COUNT] = [None; MATERIAL_COUNT];
    for (i, m) in list.iter().enumerate() {
        let key = format!("material[{i}]");
        let m = m.as_table().ok_or_else(|| wrong(&key, "a table", m))?;
        const KNOWN: [&str; 4] = ["id", "texture", "tiling_m", "rotation_deg"];
        if let Some(k) = m.keys().find(|k| !KNOWN.contains(&k.as_str())) {
            return Err(format!("unknown key {key}.{k} (known: {})", KNOWN.join(", ")));
        }
        let want_id = "a whole number 0..=255";
        let id = m.get("id").ok_or_else(|| format!("{key}.id is missing ({want_id})"))?;
        let id = match id.as_integer() {
            Some(n) if (0..MATERIAL_COUNT as i64).contains(&n) => n as usize,
            _ => return Err(wrong(&format!("{key}.id"), want_id, id)),
        };
        if let Some(j) = first_at[id].replace(i) {
            return Err(format!("{key}.id = {id} repeats material[{j}].id"));
        }
        let entry = &mut set.table[id];
        if let Some(v) = m.get("texture") {
            let name = v.as_str().ok_or_else(|| wrong(&format!("{key}.texture"), "a texture set name", v))?;
            let layer = set.textures.iter().position(|t| t.name == name).ok_or_else(|| {
                let known: Vec<&str> = set.textures.iter().map(|t| t.name.as_str()).collect();
                format!("{key}.texture: unknown texture set {name:?} (known: {})", known.join(", "))
            })? as u32;
            (entry.albedo, entry.normal, entry.height) = (layer, layer, layer);
        }
        if let Some(v) = m.get("tiling_m") {
            let want = "a finite number > 0";
            entry.tiling_m = number(v)
                .filter(|x| x.is_finite() && *x > 0.0 && (*x as f32).is_normal())
                .ok_or_else(|| wrong(&format!("{key}.tiling_m"), want, v))? as f32;
        }
        if let Some(v) = m.get("rotation_deg") {
            let deg = number(v)
                .filter(|x| x.is_finite())
                .ok_or_else(|| wrong(&format!("{key}.rotation_deg"), "a finite number", v))?;
            // Whole turns change nothing but would cost f32 precision.
            entry.rotation_deg = deg.rem_euclid(360.0) as f32;
        }
    }
    Ok(set)
}

/// `[[control_texture]]` entries over the default control table.
pub(super) fn parse_control(set: &mut MaterialSet, v: &toml::Value) -> std::result::Result<(), String> {
    let list = v.as_array().ok_or_else(|| wrong("control_texture", "an array of tables ([[control_texture]])", v))?;
    let mut first_at: [Option<usize>; CONTROL_TEXTURES] = [None; CONTROL_TEXTURES];
    for (i, m) in list.iter().enumerate() {
        let key = format!("control_texture[{i}]");
        let m = m.as_table().ok_or_else(|| wrong(&key, "a table", m))?;
        const KNOWN: [&str; 7] =
            ["index", "texture", "tiling_m", "threshold", "sharpness", "slope_damp", "normal_damp"];
        if let Some(k) = m.keys().find(|k| !KNOWN.contains(&k.as_str())) {
            return Err(format!("unknown key {key}.{k} (known: {})", KNOWN.join(", ")));
        }
        let want_index = "a whole number 0..=31";
        let index = m.get("index").ok_or_else(|| format!("{key}.index is missing ({want_index})"))?;
        let index = match index.as_integer() {
            Some(n) if (0..CONTROL_TEXTURES as i64).contains(&n) => n as usize,
            _ => return Err(wrong(&format!("{key}.index"), want_index, index)),
        };
        if let Some(j) = first_at[index].replace(i) {
            return Err(format!("{key}.index = {index} repeats control_texture[{j}].index"));
        }
        let entry = &mut set.control[index];
        if let Some(v) = m.get("texture") {
            let name = v.as_str().ok_or_else(|| wrong(&format!("{key}.texture"), "a texture set name", v))?;
            entry.layer = set.textures.iter().position(|t| t.name == name).ok_or_else(|| {
                let known: Vec<&str> = set.textures.iter().map(|t| t.name.as_str()).collect();
                format!("{key}.texture: unknown texture set {name:?} (known: {})", known.join(", "))
            })? as u32;
        }
        if let Some(v) = m.get("tiling_m") {
            entry.tiling_m = number(v)
                .filter(|x| x.is_finite() && *x > 0.0 && (*x as f32).is_normal())
                .ok_or_else(|| wrong(&format!("{key}.tiling_m"), "a finite number > 0", v))?
                as f32;
        }
        for (name, field) in [
            ("threshold", &mut entry.threshold),
            ("sharpness", &mut entry.sharpness),
            ("slope_damp", &mut entry.slope_damp),
            ("normal_damp", &mut entry.normal_damp),
        ] {
            if let Some(v) = m.get(name) {
                *field = number(v)
                    .filter(|x| (0.0..=1.0).contains(x))
                    .ok_or_else(|| wrong(&format!("{key}.{name}"), "a number 0..=1", v))?
                    as f32;
            }
        }
    }
    Ok(())
}

pub(super) fn texture_source(key: &str, v: &toml::Value, base: &Path) -> std::result::Result<TextureSource, String> {
    let want = "\"procedural:KIND\" or a table { albedo, normal, height } of PNG files";
    match v {
        toml::Value::String(s) => {
            let kind = s.strip_prefix("procedural:").ok_or_else(|| wrong(key, want, v))?;
            ProceduralKind::from_name(kind).map(TextureSource::Procedural).ok_or_else(|| {
                let known: Vec<&str> = ProceduralKind::ALL.iter().map(|k| k.name()).collect();
                format!("{key}: unknown procedural texture {kind:?} (known: {})", known.join(", "))
            })
        }
        toml::Value::Table(t) => {
            const KNOWN: [&str; 3] = ["albedo", "normal", "height"];
            if let Some(k) = t.keys().find(|k| !KNOWN.contains(&k.as_str())) {
                return Err(format!("unknown key {key}.{k} (known: {})", KNOWN.join(", ")));
            }
            let file = |k: &str| -> std::result::Result<PathBuf, String> {
                let key = format!("{key}.{k}");
                let v = t.get(k).ok_or_else(|| format!("{key} is missing (a PNG file)"))?;
                let s = v.as_str().ok_or_else(|| wrong(&key, "a file path (string)", v))?;
                let path = crate::world::resolve_relative(base, Path::new(s));
                if !path.is_file() {
                    return Err(format!("{key}: file {} does not exist", path.display()));
                }
                Ok(path)
            };
            Ok(TextureSource::Files { albedo: file("albedo")?, normal: file("normal")?, height: file("height")? })
        }
        _ => Err(wrong(key, want, v)),
    }
}

pub(super) fn number(v: &toml::Value) -> Option<f64> {
    v.as_float().or(v.as_integer().map(|i| i as f64))
}

/// `KEY must be WANT, not VALUE`: numbers and strings are shown as given
/// (the usual mistake is the value), other types by name.
pub(super) fn wrong(key: &str, want: &str, v: &toml::Value) -> String {
    let got = match v {
        toml::Value::Integer(i) => i.to_string(),
        // Debug keeps the ".0" that says the value was a float.
        toml::Value::Float(x) => format!("{x:?}"),
        toml::Value::String(s) => format!("{:?}", one_line(s)),
        toml::Value::Boolean(b) => b.to_string(),
        toml::Value::Datetime(_) => "a date".into(),
        toml::Value::Array(_) => "an array".into(),
        toml::Value::Table(_) => "a table".into(),
    };
    format!("{key} must be {want}, not {got}")
}

pub(super) fn one_line(s: &str) -> String {
    s.trim().lines().map(str::trim).collect::<Vec<_>>().join("; ")
}
