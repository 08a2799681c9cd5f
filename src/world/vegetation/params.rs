//! The scene's `[vegetation]` table: the generator's grid and iterations,
//! the sun's day, the vegetation types (what each tolerates) and the
//! brushes (which types grow on which material, how dense and how big:
//! REDengine 3's "vegetation brush").

use serde::{Deserialize, Serialize};

use crate::world::error::{Result, WorldError};
use crate::world::hash::Fnv64;
use crate::world::payload::Material;

/// Most vegetation types a scene may name (grass types each get a bit in
/// the per-cell eligibility word).
pub const MAX_TYPES: usize = 16;

/// Generator cells a world may have (1.1 GB of working memory at the most).
pub const MAX_CELLS: u64 = 1 << 26;

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct VegetationParams {
    /// Side of a generator cell (m): at most one tree or bush per cell.
    pub cell_m: f64,
    /// Resource-flow iterations: resource travels at most a cell each.
    pub iterations: u32,
    /// Share of a cell's resource that leaves it downhill each iteration
    /// where its steepest drop is `flow_slope_deg` or more (gentler ground
    /// passes on proportionally less: flats keep their rain).
    pub flow: f64,
    pub flow_slope_deg: f64,
    /// Where the sun's day is taken: latitude (degrees, north positive)
    /// and day of the year (1..=365; 172: the June solstice).
    pub latitude_deg: f64,
    pub day_of_year: u32,
    /// Sun positions sampled between sunrise and sunset.
    pub sun_samples: u32,
    /// Farthest a shadow march looks towards the sun (m).
    pub reach_m: f64,
    /// Side of an occurrence-map cell (m; a whole number of generator cells).
    pub occurrence_cell_m: f64,
    pub seed: u32,
    pub types: Vec<VegetationType>,
    pub brushes: Vec<Brush>,
    /// A grey image over the world: white keeps vegetation out ([`super::MaskMap`]).
    pub mask_map: Option<std::path::PathBuf>,
}

/// What a vegetation type tolerates and likes.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VegetationType {
    pub name: String,
    /// `tree`, `bush` (instances) or `grass` (an occurrence map).
    pub kind: VegetationKind,
    /// Slopes it grows on (degrees, lo..=hi).
    pub slope_deg: [f64; 2],
    /// Altitudes it grows at (metres, lo..=hi; the tree line). Optional:
    /// any.
    #[serde(default = "any_altitude")]
    pub altitude_m: [f64; 2],
    /// Share of the day's sun samples the cell must see (lo..=hi, 0..1).
    pub sun: [f64; 2],
    /// Least resource (one cell's rain is 1) it needs.
    pub resource: f64,
    /// Its perfect conditions: resource and sun share where it grows
    /// largest.
    pub ideal_resource: f64,
    pub ideal_sun: f64,
}

fn any_altitude() -> [f64; 2] {
    [-1e6, 1e6]
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum VegetationKind {
    Tree,
    Bush,
    Grass,
}

/// A set of types with their densities and sizes, on the materials it is
/// assigned to.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Brush {
    pub name: String,
    /// Material names: grass, rock, snow, scree, sand.
    pub materials: Vec<String>,
    pub types: Vec<BrushEntry>,
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BrushEntry {
    #[serde(rename = "type")]
    pub type_name: String,
    /// Chance (0..1) that an eligible cell grows it; a cell's entries'
    /// chances add up to at most 1.
    pub density: f64,
    /// Scale at the worst and at perfect conditions.
    pub scale: [f64; 2],
    /// Random spread of the scale (0..1, a share of it either way).
    #[serde(default)]
    pub scale_var: f64,
}

impl Default for VegetationParams {
    /// A temperate mountain forest (the Alps' heights): spruce in the wet
    /// valleys and on shaded slopes up to 2 000 m, pine on dry sunny ground
    /// up to 2 200 m, juniper where trees give up (scree, up to 2 600 m),
    /// and meadow grass wherever water reaches, up to 2 800 m.
    fn default() -> Self {
        let ty = |name: &str, kind, slope_deg, top: f64, sun, resource, ideal_resource, ideal_sun| VegetationType {
            name: name.into(),
            kind,
            slope_deg,
            altitude_m: [-1e6, top],
            sun,
            resource,
            ideal_resource,
            ideal_sun,
        };
        let entry = |t: &str, density, scale| BrushEntry { type_name: t.into(), density, scale, scale_var: 0.15 };
        VegetationParams {
            cell_m: 5.0,
            iterations: 32,
            flow: 0.5,
            flow_slope_deg: 15.0,
            latitude_deg: 46.0,
            day_of_year: 172,
            sun_samples: 16,
            reach_m: 2000.0,
            occurrence_cell_m: 10.0,
            seed: 1,
            types: vec![
                ty("spruce", VegetationKind::Tree, [0.0, 35.0], 2000.0, [0.0, 0.8], 1.2, 3.0, 0.5),
                ty("pine", VegetationKind::Tree, [0.0, 38.0], 2200.0, [0.6, 1.0], 0.6, 1.5, 0.95),
                ty("juniper", VegetationKind::Bush, [0.0, 42.0], 2600.0, [0.3, 1.0], 0.3, 0.8, 0.8),
                ty("meadow", VegetationKind::Grass, [0.0, 35.0], 2800.0, [0.2, 1.0], 0.5, 2.0, 0.9),
            ],
            brushes: vec![
                Brush {
                    name: "forest".into(),
                    materials: vec!["grass".into()],
                    types: vec![
                        entry("spruce", 0.5, [0.6, 1.4]),
                        entry("pine", 0.3, [0.6, 1.2]),
                        entry("juniper", 0.1, [0.5, 1.0]),
                        entry("meadow", 1.0, [0.8, 1.2]),
                    ],
                },
                Brush {
                    name: "scree".into(),
                    materials: vec!["scree".into()],
                    types: vec![entry("juniper", 0.15, [0.4, 0.9]), entry("pine", 0.05, [0.4, 0.8])],
                },
            ],
            mask_map: None,
        }
    }
}

/// One checked brush entry, resolved: the type's index.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Entry {
    pub ty: usize,
    pub density: f64,
    pub scale: [f64; 2],
    pub scale_var: f64,
}

impl VegetationParams {
    /// One-line error for anything that cannot be meant.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(WorldError::Vegetation(m));
        let pos = |name: &str, v: f64, hi: f64| {
            if v.is_finite() && v > 0.0 && v <= hi {
                Ok(())
            } else {
                Err(WorldError::Vegetation(format!("{name} must be in (0, {hi}], got {v}")))
            }
        };
        pos("cell_m", self.cell_m, 1000.0)?;
        pos("reach_m", self.reach_m, 100_000.0)?;
        pos("occurrence_cell_m", self.occurrence_cell_m, 10_000.0)?;
        let ratio = self.occurrence_cell_m / self.cell_m;
        if (ratio - ratio.round()).abs() > 1e-9 || ratio.round() < 1.0 {
            return bad(format!(
                "occurrence_cell_m ({}) must be a whole number of cells of cell_m ({})",
                self.occurrence_cell_m, self.cell_m
            ));
        }
        let slope_ok = self.flow_slope_deg > 0.0 && self.flow_slope_deg < 90.0;
        if !((0.0..=1.0).contains(&self.flow) && slope_ok) {
            return bad(format!(
                "flow must be in 0..=1 (got {}) and flow_slope_deg in (0, 90) (got {})",
                self.flow, self.flow_slope_deg
            ));
        }
        if self.iterations > 10_000 || !(1..=1440).contains(&self.sun_samples) {
            return bad(format!(
                "iterations must be at most 10000 (got {}) and sun_samples 1..=1440 (got {})",
                self.iterations, self.sun_samples
            ));
        }
        if !(-90.0..=90.0).contains(&self.latitude_deg) || !(1..=365).contains(&self.day_of_year) {
            return bad(format!(
                "latitude_deg must be -90..=90 (got {}) and day_of_year 1..=365 (got {})",
                self.latitude_deg, self.day_of_year
            ));
        }
        self.validate_types()?;
        self.brush_entries().map(|_| ())
    }

    fn validate_types(&self) -> Result<()> {
        let bad = |m: String| Err(WorldError::Vegetation(m));
        if self.types.len() > MAX_TYPES {
            return bad(format!("{} types, at most {MAX_TYPES}", self.types.len()));
        }
        for (i, t) in self.types.iter().enumerate() {
            let at = format!("type \"{}\"", t.name);
            if self.types[..i].iter().any(|o| o.name == t.name) {
                return bad(format!("{at} is named twice"));
            }
            let [slo, shi] = t.slope_deg;
            if !(0.0..=90.0).contains(&slo) || !(slo..=90.0).contains(&shi) {
                return bad(format!("{at}: slope_deg must be lo <= hi within 0..=90, got [{slo}, {shi}]"));
            }
            let [alo, ahi] = t.altitude_m;
            if !(alo.is_finite() && ahi.is_finite() && alo <= ahi) {
                return bad(format!("{at}: altitude_m must be finite, lo <= hi, got [{alo}, {ahi}]"));
            }
            let [lo, hi] = t.sun;
            if !(0.0..=1.0).contains(&lo) || !(lo..=1.0).contains(&hi) || !(0.0..=1.0).contains(&t.ideal_sun) {
                return bad(format!("{at}: sun must be lo <= hi within 0..=1 and ideal_sun within 0..=1"));
            }
            if !(t.resource.is_finite() && t.resource >= 0.0 && t.ideal_resource.is_finite() && t.ideal_resource > 0.0)
            {
                return bad(format!("{at}: resource must be >= 0 and ideal_resource > 0"));
            }
        }
        Ok(())
    }

    /// Per material (by [`Material`] id), the entries of every brush
    /// assigned to it, types resolved; an unknown type or material, or
    /// densities over 1 on a material, is an error.
    pub fn brush_entries(&self) -> Result<[Vec<Entry>; 5]> {
        let bad = |m: String| Err(WorldError::Vegetation(m));
        let mut out: [Vec<Entry>; 5] = Default::default();
        for b in &self.brushes {
            let mut entries = Vec::new();
            for e in &b.types {
                let Some(ty) = self.types.iter().position(|t| t.name == e.type_name) else {
                    let names: Vec<&str> = self.types.iter().map(|t| t.name.as_str()).collect();
                    return bad(format!(
                        "brush \"{}\": type \"{}\" is not one of {}",
                        b.name,
                        e.type_name,
                        names.join(", ")
                    ));
                };
                let [s0, s1] = e.scale;
                let scale_ok = s0.is_finite() && s0 > 0.0 && s1 >= s0 && s1 <= 1000.0;
                if !((0.0..=1.0).contains(&e.density) && scale_ok && (0.0..=1.0).contains(&e.scale_var)) {
                    return bad(format!(
                        "brush \"{}\", type \"{}\": density and scale_var must be in 0..=1, scale 0 < lo <= hi",
                        b.name, e.type_name
                    ));
                }
                entries.push(Entry { ty, density: e.density, scale: e.scale, scale_var: e.scale_var });
            }
            for m in &b.materials {
                let Some(id) = material_id(m) else {
                    return bad(format!(
                        "brush \"{}\": material \"{m}\" is not one of grass, rock, snow, scree, sand",
                        b.name
                    ));
                };
                out[id as usize].extend(entries.iter().copied());
            }
        }
        for (id, entries) in out.iter().enumerate() {
            let instanced = |e: &&Entry| self.types[e.ty].kind != VegetationKind::Grass;
            let sum: f64 = entries.iter().filter(instanced).map(|e| e.density).sum();
            if sum > 1.0 + 1e-9 {
                return bad(format!("the tree and bush densities on {} add up to {sum}, over 1", MATERIAL_NAMES[id]));
            }
        }
        Ok(out)
    }

    /// Part of every tile's cache key.
    pub fn hash(&self) -> u64 {
        // The Debug form holds every field, in declaration order, with
        // floats written exactly (shortest round-trip).
        Fnv64::new().bytes(format!("{self:?}").as_bytes()).finish()
    }

    /// The resource flow's rule.
    pub fn flow_rule(&self) -> super::resource::Flow {
        super::resource::Flow { share: self.flow, full_slope_deg: self.flow_slope_deg }
    }

    /// Occurrence-map cells per side of generator cells.
    pub fn occurrence_ratio(&self) -> usize {
        (self.occurrence_cell_m / self.cell_m).round() as usize
    }
}

/// Material names by id ([`Material`] as u8).
pub const MATERIAL_NAMES: [&str; 5] = ["grass", "rock", "snow", "scree", "sand"];

fn material_id(name: &str) -> Option<Material> {
    let all = [Material::Grass, Material::Rock, Material::Snow, Material::Scree, Material::Sand];
    MATERIAL_NAMES.iter().position(|n| *n == name).map(|i| all[i])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_hold_and_mistakes_are_named() {
        let p = VegetationParams::default();
        p.validate().unwrap();
        let mut q = p.clone();
        q.brushes[0].types[0].type_name = "sprice".into();
        let e = q.validate().unwrap_err().to_string();
        assert!(e.contains("type \"sprice\" is not one of spruce, pine, juniper, meadow"), "{e}");
        let mut q = p.clone();
        q.brushes[0].materials[0] = "gras".into();
        assert!(q.validate().unwrap_err().to_string().contains("material \"gras\""));
        let mut q = p.clone();
        q.occurrence_cell_m = 7.0;
        assert!(q.validate().unwrap_err().to_string().contains("whole number of cells"));
        let mut q = p.clone();
        q.brushes[0].types[1].density = 0.9;
        assert!(q.validate().unwrap_err().to_string().contains("add up to"));
        let t: VegetationParams = toml::from_str("cell_m = 4\niterations = 8\n").unwrap();
        assert_eq!((t.cell_m, t.iterations, t.types.len()), (4.0, 8, 4));
        let e = toml::from_str::<VegetationParams>("cel_m = 4\n").unwrap_err().to_string();
        assert!(e.contains("unknown field `cel_m`"), "{e}");
    }
}
