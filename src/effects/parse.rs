//! Reads a scene's `[effects]` table into [`Effects`] through the
//! registry: each effect reads its own parameters, in its folder.

use super::registry::kind_of;
use super::requested::Effects;
use crate::error::Result;
use crate::scene::effect::Effect;
use crate::scene::params::{bad, boolean, type_name};
use std::path::Path;

impl Effects {
    /// Reads a scene's `[effects]` table; files it names are resolved
    /// against `base` (the scene file's folder) and must exist. Errors are
    /// one line naming the key (`effects.lighting.sun_color: ...`).
    pub fn from_toml(table: &toml::Table, base: &Path) -> Result<Effects> {
        let mut fx = Effects::default();
        for (key, value) in table {
            let Some(effect) = Effect::from_name(key) else {
                let known: Vec<&str> = Effect::ALL.iter().map(|e| e.name()).collect();
                return Err(bad(format!("unknown effect effects.{key} (known: {})", known.join(", "))));
            };
            match value {
                toml::Value::Boolean(on) => fx.set(effect, *on),
                toml::Value::Table(t) => fx.read_table(effect, t, base)?,
                other => {
                    return Err(bad(format!(
                        "effects.{key} must be true, false or a table of parameters, not {}",
                        type_name(other)
                    )))
                }
            }
        }
        Ok(fx)
    }

    /// One effect's table: `enabled` and the parameters its kind reads.
    fn read_table(&mut self, effect: Effect, t: &toml::Table, base: &Path) -> Result<()> {
        let kind = kind_of(effect);
        let mut on = true;
        for (k, v) in t {
            let key = format!("effects.{}.{k}", effect.name());
            if k == "enabled" {
                on = boolean(&key, v)?;
            } else if kind.parameters().contains(&k.as_str()) {
                kind.read(self, &key, k, v, base)?;
            } else {
                let mut known = vec!["enabled"];
                known.extend(kind.parameters());
                return Err(bad(format!("unknown parameter {key} (known: {})", known.join(", "))));
            }
        }
        kind.validate(self)?;
        self.set(effect, on);
        Ok(())
    }
}
