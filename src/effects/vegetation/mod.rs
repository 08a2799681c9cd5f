//! Effect `vegetation`: the trees and bushes `vista vegetate` placed
//! (seed 004's generator, `world::vegetation`), drawn as instanced meshes
//! with three LODs (the last two crossed triangles: a far billboard) into
//! the G-buffer. `vegetation_cull` culls on the GPU each frame, clusters
//! of instances (a grid's cells) first, then the instances of those that
//! may show (by their type's draw distance, the frustum, with effect
//! `occlusion` the depth pyramid) into six indexed indirect draws (two mesh kinds x
//! three LODs) that `vegetation_draw` records; near the ground their
//! vertices blend into the terrain (terrain_blend.glsl, as the assets').
//! With effect `shadows` on they cast into the terrain's sun shadows as a
//! height field over the ground (`canopy.rs`).
//!
//! ```toml
//! [effects.vegetation]
//! folder = "veg"        # what `vista vegetate --out veg` wrote (relative to the scene)
//! lod_m = [60, 250]     # LOD 0 within 60 m, LOD 1 within 250 m, the billboards beyond
//! tree_draw_m = 1500    # trees drawn within this distance, bushes within bush_draw_m
//! bush_draw_m = 300
//! tree_height_m = 16    # a scale-1 tree's and bush's height
//! bush_height_m = 2
//! cluster_m = 64       # the culling tests clusters of instances in cells of this side or larger first
//! canopy_cell_m = 1     # the canopy the sun's shadows march over: cells of this side or larger
//! ```

pub mod canopy;
pub mod clusters;
pub mod frame;
pub mod kind;
pub mod meshes;
pub mod vegetation_cull;
pub mod vegetation_draw;
pub mod vegetation_sun;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::Serialize;

use crate::error::{Error, Result};
use crate::shaders::consts::VEG_TYPES;
use crate::world::vegetation::{Instance, VegetationKind};

/// Most instances one renderer draws (its visible list: three LODs' words
/// an instance, 48 MiB at most).
pub const MAX_INSTANCES: usize = 65_535 * 64;

/// Effect `vegetation`'s parameters.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VegetationDrawParams {
    /// The folder `vista vegetate` wrote, and what was read from it.
    pub folder: Option<PathBuf>,
    #[serde(skip)]
    pub set: Option<Arc<VegetationSet>>,
    /// LOD 0 within `lod_m[0]` of the camera, LOD 1 within `lod_m[1]`.
    pub lod_m: [f32; 2],
    pub tree_draw_m: f32,
    pub bush_draw_m: f32,
    pub tree_height_m: f32,
    pub bush_height_m: f32,
    /// The blend into the terrain fades out over this height above it.
    pub blend_height_m: f32,
    /// Cells of the canopy (`canopy::CanopyGrid`) are this side or larger.
    pub canopy_cell_m: f32,
    /// Cells of the culling's clusters (`clusters.rs`) are this side or larger.
    pub cluster_m: f32,
}

impl Default for VegetationDrawParams {
    fn default() -> Self {
        VegetationDrawParams {
            folder: None,
            set: None,
            lod_m: [60.0, 250.0],
            tree_draw_m: 1500.0,
            bush_draw_m: 300.0,
            tree_height_m: 16.0,
            bush_height_m: 2.0,
            blend_height_m: 0.5,
            canopy_cell_m: 1.0,
            cluster_m: 64.0,
        }
    }
}

/// A vegetation folder's trees and bushes.
#[derive(Debug, PartialEq, Serialize)]
pub struct VegetationSet {
    pub folder: PathBuf,
    /// Each type's name and kind, in the generator's order.
    pub types: Vec<(String, VegetationKind)>,
    #[serde(skip)]
    pub instances: Vec<Instance>,
}

impl VegetationSet {
    /// Reads `folder`'s `vegetation.json` and `instances.bin`, each
    /// instance checked (a known tree or bush type, finite numbers).
    pub fn load(folder: &Path) -> Result<Self> {
        let bad = |m: String| Error::Scene(format!("effects.vegetation.folder: {}: {m}", folder.display()));
        let s = crate::world::vegetation::read_summary(folder).map_err(bad)?;
        let size = std::mem::size_of::<Instance>();
        if s.instance_bytes != size || s.instances > MAX_INSTANCES || s.types.len() > VEG_TYPES as usize {
            return Err(bad(format!(
                "{} instances of {} bytes and {} types; this build reads at most {MAX_INSTANCES} of {size} bytes and \
                 {VEG_TYPES} types",
                s.instances,
                s.instance_bytes,
                s.types.len()
            )));
        }
        let bytes = std::fs::read(folder.join("instances.bin")).map_err(|e| bad(format!("instances.bin: {e}")))?;
        if bytes.len() != s.instances * size {
            return Err(bad(format!(
                "instances.bin: {} bytes, {} instances need {}",
                bytes.len(),
                s.instances,
                s.instances * size
            )));
        }
        let instances: Vec<Instance> = bytes.chunks_exact(size).map(bytemuck::pod_read_unaligned).collect();
        let kind = |t: &crate::world::vegetation::TypeSummary| {
            t.kind.ok_or_else(|| bad(format!("vegetation.json: type \"{}\" has no kind", t.name)))
        };
        let types: Vec<(String, VegetationKind)> =
            s.types.iter().map(|t| Ok((t.name.clone(), kind(t)?))).collect::<Result<_>>()?;
        for (k, i) in instances.iter().enumerate() {
            let known = types.get(i.ty as usize).is_some_and(|t| t.1 != VegetationKind::Grass);
            let finite = i.position.iter().chain([&i.yaw_rad, &i.scale]).all(|v| v.is_finite());
            if !(known && finite && i.scale > 0.0 && i.scale < 100.0) {
                return Err(bad(format!("instances.bin: instance {k} has type {} or numbers not drawable", i.ty)));
            }
        }
        Ok(VegetationSet { folder: folder.to_path_buf(), types, instances })
    }
}

/// Host twin of `VegetationType` (vegetation.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VegetationTypeGpu {
    pub crown: [f32; 4],
    pub height_m: f32,
    /// 0 tree, 1 bush.
    pub kind: u32,
    pub draw_m: f32,
    pub pad: f32,
}

/// Crown colours (linear): the trees' from dark spruce to a lighter
/// green, the bushes' olive; by type within its kind.
const TREE_CROWNS: [[f32; 3]; 3] = [[0.035, 0.075, 0.035], [0.06, 0.11, 0.04], [0.08, 0.13, 0.05]];
const BUSH_CROWNS: [[f32; 3]; 2] = [[0.11, 0.12, 0.05], [0.09, 0.1, 0.06]];

impl VegetationDrawParams {
    /// The type table the GPU reads (grass types: never drawn, a bush's
    /// numbers for completeness).
    pub fn types_gpu(&self, set: &VegetationSet) -> Vec<VegetationTypeGpu> {
        let (mut trees, mut bushes) = (0, 0);
        set.types
            .iter()
            .map(|(_, kind)| {
                let tree = *kind == VegetationKind::Tree;
                let crown = if tree { TREE_CROWNS[trees % 3] } else { BUSH_CROWNS[bushes % 2] };
                (trees, bushes) = if tree { (trees + 1, bushes) } else { (trees, bushes + 1) };
                VegetationTypeGpu {
                    crown: [crown[0], crown[1], crown[2], 1.0],
                    height_m: if tree { self.tree_height_m } else { self.bush_height_m },
                    kind: u32::from(!tree),
                    draw_m: if tree { self.tree_draw_m } else { self.bush_draw_m },
                    pad: 0.0,
                }
            })
            .collect()
    }

    /// Reads one `[effects.vegetation]` parameter (`key`: its full name; a
    /// folder relative to `base`, the scene's).
    pub(crate) fn read(&mut self, key: &str, name: &str, v: &toml::Value, base: &Path) -> Result<()> {
        use crate::scene::params::{number, wrong};
        let metres = |v: &toml::Value, k: &str| number(k, v, 0.1, 100_000.0).map(|x| x as f32);
        match name {
            "folder" => {
                let dir = v.as_str().ok_or_else(|| wrong(key, "a folder written by `vista vegetate`", v))?;
                let folder = crate::world::resolve_relative(base, Path::new(dir));
                self.set = Some(Arc::new(VegetationSet::load(&folder)?));
                self.folder = Some(folder);
            }
            "lod_m" => {
                let a = v.as_array().filter(|a| a.len() == 2).ok_or_else(|| wrong(key, "[lod0, lod1] metres", v))?;
                self.lod_m = [metres(&a[0], key)?, metres(&a[1], key)?];
                if self.lod_m[0] > self.lod_m[1] {
                    return Err(Error::Scene(format!("{key}: {:?} must rise", self.lod_m)));
                }
            }
            "tree_draw_m" => self.tree_draw_m = metres(v, key)?,
            "bush_draw_m" => self.bush_draw_m = metres(v, key)?,
            "tree_height_m" => self.tree_height_m = metres(v, key)?,
            "bush_height_m" => self.bush_height_m = metres(v, key)?,
            "blend_height_m" => self.blend_height_m = number(key, v, 0.0, 100.0)? as f32,
            "canopy_cell_m" => self.canopy_cell_m = number(key, v, 0.25, 1000.0)? as f32,
            "cluster_m" => self.cluster_m = number(key, v, 1.0, 100_000.0)? as f32,
            _ => unreachable!("{key} is a vegetation parameter but not read"),
        }
        Ok(())
    }
}
