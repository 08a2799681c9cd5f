//! Where the bake puts each material: absolute rules in degrees of slope
//! and metres of altitude, so a 1 km hill has no snow and a sea floor no
//! grass, whatever the world's height range.

use serde::{Deserialize, Serialize};

use super::error::{Result, WorldError};
use super::hash::Fnv64;
use super::payload::Material;
use super::source::Ground;

/// A point of ground the rules judge.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Site {
    pub slope_deg: f32,
    pub altitude_m: f32,
    /// What water and rockfall left there (all zero where the source
    /// knows nothing of them).
    pub ground: Ground,
}

/// The material rules of a bake. The defaults suit real mountains (the
/// Alps): the climatic snow line there lies near 2 800 m, slopes past about
/// 40 degrees hold no soil, loose scree rests up to its angle of repose of
/// about 33 degrees, and a beach rises a couple of metres above the sea.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MaterialRules {
    /// Ground steeper than this (degrees) is bare rock, at any altitude.
    pub rock_slope_deg: f32,
    /// Ground steeper than this (degrees) and not rock is scree.
    pub scree_slope_deg: f32,
    /// Above this altitude (metres) ground that is not rock is snow.
    pub snow_line_m: f32,
    /// The sea surface (metres): ground below it is sand (sea floor).
    pub sea_level_m: f32,
    /// Gentle ground up to this many metres above the sea is sand (beach).
    pub beach_height_m: f32,
    /// Ground at least this wet (0..1: a gully's head to a valley's floor)
    /// holds soil up to the rock slope: grass, not scree, below the snow
    /// line. Above 1: never.
    pub valley_wet: f32,
    /// Ground with at least this much talus (0..1: rock that slid down from
    /// steeper ground) is scree at any slope below the rock slope, unless
    /// wet enough for grass or under snow. Above 1: never.
    pub talus_scree: f32,
}

impl Default for MaterialRules {
    fn default() -> Self {
        MaterialRules {
            rock_slope_deg: 40.0,
            scree_slope_deg: 30.0,
            snow_line_m: 2800.0,
            sea_level_m: 0.0,
            beach_height_m: 2.0,
            valley_wet: 0.5,
            talus_scree: 0.35,
        }
    }
}

impl MaterialRules {
    /// One-line error for a rule that cannot be meant.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(WorldError::InvalidDesc(format!("material rules: {m}")));
        for (name, v) in [("rock_slope_deg", self.rock_slope_deg), ("scree_slope_deg", self.scree_slope_deg)] {
            if !(0.0..=90.0).contains(&v) {
                return bad(format!("{name} must be 0..=90 degrees, got {v}"));
            }
        }
        if self.scree_slope_deg > self.rock_slope_deg {
            return bad(format!(
                "scree_slope_deg ({}) must not exceed rock_slope_deg ({})",
                self.scree_slope_deg, self.rock_slope_deg
            ));
        }
        for (name, v) in [("snow_line_m", self.snow_line_m), ("sea_level_m", self.sea_level_m)] {
            if !v.is_finite() {
                return bad(format!("{name} must be finite, got {v}"));
            }
        }
        for (name, v) in [("valley_wet", self.valley_wet), ("talus_scree", self.talus_scree)] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(format!("{name} must be finite and >= 0 (above 1: never), got {v}"));
            }
        }
        if !(self.beach_height_m.is_finite() && self.beach_height_m >= 0.0) {
            return bad(format!("beach_height_m must be finite and >= 0, got {}", self.beach_height_m));
        }
        Ok(())
    }

    /// The material at a sample: slope in degrees, altitude in metres, on
    /// ground nothing is known of.
    pub fn material(&self, slope_deg: f32, altitude_m: f32) -> Material {
        self.material_at(&Site { slope_deg, altitude_m, ground: Ground::default() })
    }

    /// The material at a site: rock where too steep for anything to rest,
    /// sand by the sea, snow above its line, then scree where rock slid
    /// (talus) or the slope sheds soil unless water keeps it, else grass.
    pub fn material_at(&self, site: &Site) -> Material {
        let (slope, altitude, g) = (site.slope_deg, site.altitude_m, site.ground);
        let wet = g.wet >= self.valley_wet;
        if slope > self.rock_slope_deg {
            Material::Rock
        } else if altitude < self.sea_level_m
            || (altitude <= self.sea_level_m + self.beach_height_m && slope <= self.scree_slope_deg)
        {
            Material::Sand
        } else if altitude > self.snow_line_m {
            Material::Snow
        } else if !wet && (g.talus >= self.talus_scree || slope > self.scree_slope_deg) {
            Material::Scree
        } else {
            Material::Grass
        }
    }

    /// Part of the cache key.
    pub fn hash(&self) -> u64 {
        let mut h = Fnv64::new();
        let values = [
            self.rock_slope_deg,
            self.scree_slope_deg,
            self.snow_line_m,
            self.sea_level_m,
            self.beach_height_m,
            self.valley_wet,
            self.talus_scree,
        ];
        for v in values {
            h = h.f64(f64::from(v));
        }
        h.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_are_absolute() {
        let r = MaterialRules::default();
        // A gentle 1 km hill is grass at its top, whatever the world range.
        assert_eq!(r.material(10.0, 1000.0), Material::Grass);
        assert_eq!(r.material(10.0, 3000.0), Material::Snow);
        assert_eq!(r.material(45.0, 3000.0), Material::Rock);
        assert_eq!(r.material(35.0, 500.0), Material::Scree);
        assert_eq!(r.material(35.0, 3000.0), Material::Snow);
        assert_eq!(r.material(5.0, 1.5), Material::Sand);
        assert_eq!(r.material(35.0, 1.5), Material::Scree);
        assert_eq!(r.material(20.0, -40.0), Material::Sand);
        assert_eq!(r.material(50.0, -40.0), Material::Rock);
        assert!(r.validate().is_ok());
        let bad = MaterialRules { scree_slope_deg: 50.0, ..r };
        assert!(bad.validate().unwrap_err().to_string().contains("scree_slope_deg (50)"));
        assert!(MaterialRules { snow_line_m: f32::NAN, ..r }.validate().is_err());
        assert_ne!(r.hash(), MaterialRules { snow_line_m: 2000.0, ..r }.hash());
        assert_ne!(r.hash(), MaterialRules { valley_wet: 0.9, ..r }.hash());
        assert!(MaterialRules { talus_scree: -1.0, ..r }.validate().is_err());
    }

    #[test]
    fn water_keeps_soil_and_rockfall_makes_scree() {
        let r = MaterialRules::default();
        let at = |slope_deg, altitude_m, wet, talus| {
            r.material_at(&Site { slope_deg, altitude_m, ground: Ground { wet, talus } })
        };
        // A 35 degree gully bed holds grass; the same slope dry is scree.
        assert_eq!(at(35.0, 800.0, 0.8, 0.0), Material::Grass);
        assert_eq!(at(35.0, 800.0, 0.1, 0.0), Material::Scree);
        // A gentle apron under a cliff is scree where rock slid, grass where not.
        assert_eq!(at(15.0, 800.0, 0.0, 0.6), Material::Scree);
        assert_eq!(at(15.0, 800.0, 0.0, 0.1), Material::Grass);
        // Water does not hold soil past the rock slope, nor melt snow.
        assert_eq!(at(45.0, 800.0, 1.0, 0.0), Material::Rock);
        assert_eq!(at(10.0, 3000.0, 1.0, 1.0), Material::Snow);
        // Nothing known of the ground: the slope and altitude rules alone.
        assert_eq!(at(35.0, 500.0, 0.0, 0.0), r.material(35.0, 500.0));
    }
}
