//! Stamps that carry vegetation (seed 004: "copy-paste with full package:
//! elevation, control map, colour map, vegetation"): a stamp's own
//! `vista vegetate` folder (made over the stamp's square as a world of its
//! own) is pasted where the stamp lands, rotated and scaled with it. Inside
//! the stamp's square (where its weight reaches one half) its instances
//! replace what the generator grew, and its grass types' occurrence bits
//! replace the cells' (by type name); the masks still hold.

use std::path::{Path, PathBuf};

use super::params::VegetationParams;
use super::spawn::Instance;
use crate::world::error::{Result, WorldError};
use crate::world::hash::Fnv64;
use crate::world::stamps::StampPlacement;

/// A grass type's occurrence map in the stamp: the scene's type index, its
/// cells, its rows of bits (`vista vegetate`'s layout).
#[derive(Clone, Debug, PartialEq)]
struct GrassMap {
    ty: usize,
    size: [usize; 2],
    bits: Vec<u8>,
}

/// One stamp's vegetation, ready to paste.
#[derive(Clone, Debug, PartialEq)]
pub struct StampVegetation {
    pub folder: PathBuf,
    pub placement: StampPlacement,
    /// Metres its folder's world spans (its cells times their side).
    pub extent_m: [f64; 2],
    /// Its instances in its own world's metres, their types the scene's.
    pub instances: Vec<Instance>,
    /// Per grass type of the scene (by index): its map, when the stamp has one.
    grass: Vec<Option<GrassMap>>,
    /// The occurrence cell of its maps (m, in its own world).
    occurrence_m: f64,
    hash: u64,
}

impl StampVegetation {
    /// Reads `folder` for the stamp at `placement`; its types are matched
    /// to `params`' by name (a type the scene lacks is an error).
    pub fn load(folder: &Path, placement: StampPlacement, params: &VegetationParams) -> Result<Self> {
        let bad = |m: String| WorldError::Vegetation(format!("stamp vegetation {}: {m}", folder.display()));
        let s = super::outputs::read_summary(folder).map_err(bad)?;
        let size = std::mem::size_of::<Instance>();
        let bytes = std::fs::read(folder.join("instances.bin")).map_err(|e| bad(format!("instances.bin: {e}")))?;
        if s.instance_bytes != size || bytes.len() != s.instances * size {
            return Err(bad(format!(
                "instances.bin holds {} bytes, not {} instances of {size}",
                bytes.len(),
                s.instances
            )));
        }
        let to_scene: Vec<usize> = s
            .types
            .iter()
            .map(|t| {
                params
                    .types
                    .iter()
                    .position(|p| p.name == t.name)
                    .ok_or_else(|| bad(format!("type \"{}\" is not the scene's", t.name)))
            })
            .collect::<Result<_>>()?;
        let mut instances: Vec<Instance> = bytes.chunks_exact(size).map(bytemuck::pod_read_unaligned).collect();
        for i in &mut instances {
            i.ty = *to_scene.get(i.ty as usize).ok_or_else(|| bad(format!("an instance of type {}", i.ty)))? as u32;
        }
        let mut grass = vec![None; params.types.len()];
        let [w, h] = s.occurrence_cells;
        for (t, scene) in s.types.iter().zip(&to_scene) {
            if let Some(file) = &t.occurrence_file {
                let bits = std::fs::read(folder.join(file)).map_err(|e| bad(format!("{file}: {e}")))?;
                if bits.len() != w.div_ceil(8) * h {
                    return Err(bad(format!("{file}: {} bytes for {w} x {h} cells", bits.len())));
                }
                grass[*scene] = Some(GrassMap { ty: *scene, size: [w, h], bits });
            }
        }
        let hash =
            Fnv64::new().bytes(&bytes).bytes(format!("{s:?}").as_bytes()).u64(placement_hash(&placement)).finish();
        let extent_m = s.cells.map(|c| c as f64 * s.cell_m);
        Ok(StampVegetation {
            folder: folder.to_path_buf(),
            placement,
            extent_m,
            instances,
            grass,
            occurrence_m: s.occurrence_cell_m,
            hash,
        })
    }

    /// Where `p` (world metres) lies in the stamp's own world, if inside
    /// the part it pastes (weight at least one half).
    fn own(&self, p: [f64; 2]) -> Option<[f64; 2]> {
        let (local, weight) = self.placement.local(p[0], p[1])?;
        (weight >= 0.5).then(|| [0, 1].map(|a| local[a] / self.placement.size_m * self.extent_m[a]))
    }

    /// Whether the stamp's vegetation replaces the generator's at `p`.
    pub fn covers(&self, p: [f64; 2]) -> bool {
        self.own(p).is_some()
    }

    /// The grass bits it gives the cell at `p` (it covers `p`).
    pub fn grass_bits(&self, p: [f64; 2]) -> u16 {
        let Some(q) = self.own(p) else { return 0 };
        self.grass.iter().flatten().fold(0, |bits, m| {
            let [w, h] = m.size;
            let (i, j) = ((q[0] / self.occurrence_m).floor(), (q[1] / self.occurrence_m).floor());
            let inside = i >= 0.0 && j >= 0.0 && (i as usize) < w && (j as usize) < h;
            let on = inside && m.bits[j as usize * w.div_ceil(8) + i as usize / 8] >> (i as usize % 8) & 1 != 0;
            if on {
                bits | 1 << m.ty
            } else {
                bits
            }
        })
    }

    /// Its instances in the world, turned and scaled with the stamp (z
    /// left for the caller: the ground there); only those it covers.
    pub fn placed(&self) -> Vec<Instance> {
        let p = &self.placement;
        let a = p.rotation_deg.to_radians();
        let (c, s) = (a.cos(), a.sin());
        let k = p.size_m / self.extent_m[0].max(self.extent_m[1]);
        self.instances
            .iter()
            .filter_map(|i| {
                let [u, v] = [0, 1].map(|ax| (f64::from(i.position[ax]) / self.extent_m[ax] - 0.5) * p.size_m);
                let at = [p.center_m[0] + c * u - s * v, p.center_m[1] + s * u + c * v];
                self.covers(at).then(|| Instance {
                    position: [at[0] as f32, at[1] as f32, 0.0],
                    yaw_rad: (f64::from(i.yaw_rad) + a) as f32,
                    scale: (f64::from(i.scale) * k) as f32,
                    ..*i
                })
            })
            .collect()
    }

    /// Part of the key of every tile it touches.
    pub fn hash(&self) -> u64 {
        self.hash
    }
}

fn placement_hash(p: &StampPlacement) -> u64 {
    Fnv64::new().f64(p.center_m[0]).f64(p.center_m[1]).f64(p.size_m).f64(p.rotation_deg).f64(p.falloff_m).finish()
}
