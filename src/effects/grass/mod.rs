//! Effect `grass` (seed 000's GPU grass, seed 004's distribution by
//! material and pigment map): tufts placed on the GPU each frame from the
//! terrain's own data, one per world cell at most, kept with the
//! probability the cell's material gives, at a point the cell's hash
//! jitters, so nothing swims as the camera moves. `grass_pigment` renders
//! the near ground's albedo top-down, `grass_place` places and culls,
//! `grass_draw` draws every tuft kept in ONE indirect instanced draw into
//! the G-buffer. This module holds the scene parameters, the rule table
//! (the placement's CPU twin is `reference::grass`); `gpu` the resources.
//!
//! ```toml
//! [effects.grass]
//! radius_m = 40        # tufts within this distance of the camera
//! cell_m = 0.5         # one tuft per cell at most
//! density = { grass = 3.0, scree = 0.3 }  # tufts per m^2 by material
//! height = { scree = 0.6 }                # height scale by material
//! tint = { scree = [1.0, 0.9, 0.7] }      # pigment multiplier by material
//! vegetation = "veg"   # a `vista vegetate` folder: grass only where its occurrence
//!                      # maps let it, densities times its brushes' (seed 004)
//! ```

pub mod grass_draw;
pub mod grass_pigment;
pub mod grass_place;
pub mod kind;
pub mod occurrence;

pub mod frame;
pub mod gpu;

use crate::error::{Error, Result};
use crate::shaders::consts::{GRASS_MAX_SIDE, GRASS_RULES};
use crate::world::Material;
use occurrence::GrassOccurrence;
use serde::Serialize;
use std::path::Path;

/// The bake's materials by their scene names.
pub const MATERIAL_NAMES: [(&str, Material); 5] = [
    ("grass", Material::Grass),
    ("rock", Material::Rock),
    ("snow", Material::Snow),
    ("scree", Material::Scree),
    ("sand", Material::Sand),
];

/// What one material grows.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GrassRule {
    /// Tufts per square metre (0: none).
    pub density: f32,
    /// Scale of the blade height.
    pub height: f32,
    /// Linear multiplier of the pigment.
    pub tint: [f32; 3],
}

impl GrassRule {
    const NONE: GrassRule = GrassRule { density: 0.0, height: 1.0, tint: [1.0; 3] };
}

/// Effect `grass`'s parameters.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GrassParams {
    /// Tufts stand within this distance of the camera (horizontal).
    pub radius_m: f32,
    /// The world cell side: at most one tuft per cell.
    pub cell_m: f32,
    /// Tufts shrink to nothing over the radius' last `fade_m`.
    pub fade_m: f32,
    /// A tuft's height before its rule's scale and its own 0.75..1.25.
    pub blade_height_m: f32,
    /// A blade's width at its root.
    pub blade_width_m: f32,
    pub seed: u32,
    /// Per material, in [`MATERIAL_NAMES`] order.
    pub rules: [GrassRule; 5],
    /// A `vista vegetate` folder's occurrence maps and brush densities
    /// (scene key `vegetation`): grass grows only where a bit is set.
    pub occurrence: Option<GrassOccurrence>,
}

impl Default for GrassParams {
    fn default() -> Self {
        let mut rules = [GrassRule::NONE; 5];
        rules[Material::Grass as usize] = GrassRule { density: 3.0, height: 1.0, tint: [0.85, 1.0, 0.7] };
        rules[Material::Scree as usize] = GrassRule { density: 0.3, height: 0.6, tint: [1.0, 0.9, 0.7] };
        GrassParams {
            radius_m: 40.0,
            cell_m: 0.5,
            fade_m: 8.0,
            blade_height_m: 0.45,
            blade_width_m: 0.06,
            seed: 1,
            rules,
            occurrence: None,
        }
    }
}

/// The square of cells one frame considers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GrassGrid {
    /// Its first cell (world cell indices: cell i spans [i, i + 1) x cell_m).
    pub cell0: [i32; 2],
    pub side: u32,
}

/// Host twin of `GrassRule` (grass.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GrassRuleGpu {
    pub density: f32,
    pub height: f32,
    pub pad: [f32; 2],
    pub tint: [f32; 4],
}

impl GrassParams {
    /// Parameter names of `[effects.grass]` besides `enabled`.
    pub const PARAMETERS: [&'static str; 10] = [
        "radius_m",
        "cell_m",
        "fade_m",
        "blade_height_m",
        "blade_width_m",
        "hash_seed",
        "density",
        "height",
        "tint",
        "vegetation",
    ];

    /// Cells a side of the square around the camera.
    pub fn side(&self) -> u32 {
        (2.0 * self.radius_m / self.cell_m).ceil() as u32 + 1
    }

    /// One-line error for parameters that cannot be meant together.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::Scene(format!("effects.grass: {m}")));
        if self.fade_m > self.radius_m {
            return bad(format!("fade_m ({}) exceeds radius_m ({})", self.fade_m, self.radius_m));
        }
        if self.side() > GRASS_MAX_SIDE {
            return bad(format!(
                "radius_m {} over cell_m {} makes {} cells a side; at most {GRASS_MAX_SIDE} (a larger cell or a smaller radius)",
                self.radius_m,
                self.cell_m,
                self.side()
            ));
        }
        let area = self.cell_m * self.cell_m;
        for ((name, _), r) in MATERIAL_NAMES.iter().zip(&self.rules) {
            if r.density * area > 1.0 {
                return bad(format!(
                    "density.{name} = {} tufts per m^2 needs {:.2} per {} m cell, at most 1 (a smaller cell_m)",
                    r.density,
                    r.density * area,
                    self.cell_m
                ));
            }
        }
        Ok(())
    }

    /// Whether any material grows grass.
    pub fn grows(&self) -> bool {
        (0..5).any(|m| self.density(m) > 0.0)
    }

    /// Tufts per m^2 on material `m` (in [`MATERIAL_NAMES`] order): the
    /// rule's, times the vegetation's brushes' density when it has one.
    pub fn density(&self, m: usize) -> f32 {
        self.rules[m].density * self.occurrence.as_ref().map_or(1.0, |o| o.density[MATERIAL_NAMES[m].1 as usize])
    }

    /// The cells around the camera (world-relative metres, the f32 the GPU
    /// reads as `camera_world`).
    pub fn grid(&self, camera_xy: [f32; 2]) -> GrassGrid {
        let cell0 = camera_xy.map(|c| ((c - self.radius_m) / self.cell_m).floor() as i32);
        GrassGrid { cell0, side: self.side() }
    }

    /// The rule table the GPU reads (one entry per material id; ids the
    /// bake does not make grow nothing).
    pub fn rules_gpu(&self) -> Vec<GrassRuleGpu> {
        let area = self.cell_m * self.cell_m;
        let mut out =
            vec![GrassRuleGpu { height: 1.0, tint: [1.0; 4], ..GrassRuleGpu::default() }; GRASS_RULES as usize];
        for (k, ((_, m), r)) in MATERIAL_NAMES.iter().zip(&self.rules).enumerate() {
            let [tr, tg, tb] = r.tint;
            let density = self.density(k) * area;
            out[*m as usize] = GrassRuleGpu { density, height: r.height, pad: [0.0; 2], tint: [tr, tg, tb, 1.0] };
        }
        out
    }

    /// Reads one `[effects.grass]` parameter (`key`: its full name; a
    /// folder relative to `base`, the scene's).
    pub(crate) fn read(&mut self, key: &str, name: &str, v: &toml::Value, base: &Path) -> Result<()> {
        use crate::scene::params::{colour, number, seed, wrong};
        match name {
            "radius_m" => self.radius_m = number(key, v, 1.0, 1000.0)? as f32,
            "cell_m" => self.cell_m = number(key, v, 0.05, 10.0)? as f32,
            "fade_m" => self.fade_m = number(key, v, 0.0, 1000.0)? as f32,
            "blade_height_m" => self.blade_height_m = number(key, v, 0.01, 10.0)? as f32,
            "blade_width_m" => self.blade_width_m = number(key, v, 0.001, 1.0)? as f32,
            "hash_seed" => {
                self.seed = seed(key, v)?;
            }
            "vegetation" => {
                let dir = v.as_str().ok_or_else(|| wrong(key, "a folder written by `vista vegetate`", v))?;
                self.occurrence = Some(GrassOccurrence::load(&crate::world::resolve_relative(base, Path::new(dir)))?);
            }
            "density" | "height" | "tint" => {
                let t = v.as_table().ok_or_else(|| wrong(key, "a table by material name", v))?;
                for (m, x) in t {
                    let at = MATERIAL_NAMES.iter().position(|(n, _)| n == m).ok_or_else(|| {
                        let known: Vec<&str> = MATERIAL_NAMES.iter().map(|(n, _)| *n).collect();
                        Error::Scene(format!("{key}.{m}: no such material (known: {})", known.join(", ")))
                    })?;
                    let k = format!("{key}.{m}");
                    let rule = &mut self.rules[at];
                    match name {
                        "density" => rule.density = number(&k, x, 0.0, 400.0)? as f32,
                        "height" => rule.height = number(&k, x, 0.0, 10.0)? as f32,
                        _ => rule.tint = colour(&k, x)?,
                    }
                }
            }
            _ => unreachable!("{key} is a grass parameter but not read"),
        }
        Ok(())
    }
}

/// The grass counters of one frame (frames late, as data).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct GrassCounters {
    /// Cells within the radius.
    pub in_range: u32,
    /// Tufts standing on terrain that grows them (before culling).
    pub placed: u32,
    pub culled_frustum: u32,
    pub culled_hiz: u32,
    /// Cells in range the occurrence map skipped (no terrain read there).
    pub skipped_occurrence: u32,
    /// Tufts in the draw.
    pub drawn: u32,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn twins_have_the_shader_sizes() {
        use crate::shaders::structs;
        assert_eq!(std::mem::size_of::<GrassRuleGpu>(), structs::GRASS_RULE);
        assert_eq!(std::mem::size_of::<gpu::GrassInstanceGpu>(), structs::GRASS_INSTANCE);
        assert_eq!(std::mem::size_of::<gpu::GrassHeaderGpu>(), structs::GRASS_HEADER);
    }

    #[test]
    fn validation_names_the_problem() {
        let mut p = GrassParams::default();
        assert!(p.validate().is_ok());
        p.rules[0].density = 5.0;
        let e = p.validate().unwrap_err().to_string();
        assert!(e.contains("density.grass = 5") && e.contains("at most 1"), "{e}");
        let p = GrassParams { radius_m: 300.0, cell_m: 0.5, ..GrassParams::default() };
        assert!(p.validate().unwrap_err().to_string().contains("cells a side"));
        let p = GrassParams { fade_m: 50.0, ..GrassParams::default() };
        assert!(p.validate().unwrap_err().to_string().contains("fade_m"));
    }
}
