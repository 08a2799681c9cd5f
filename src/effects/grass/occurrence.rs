//! What `vista vegetate` leaves for grass (seed 004: "when a grass cell
//! comes into view, look up the prebaked occurrence map; if the bit is not
//! set, skip the cell"): the grass types' occurrence maps of a vegetation
//! folder, merged (a cell where any may grow), as the rows of 32-bit words
//! `grass_place` reads, and the brushes' density per material, which
//! multiplies the effect's own.

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::error::{Error, Result};

/// A vegetation folder's grass, ready for the GPU.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GrassOccurrence {
    /// The folder it was read from.
    pub folder: PathBuf,
    /// An occurrence cell's side (m); cell (i, j) spans [i, i + 1) x cell_m
    /// from the world's south-west corner.
    pub cell_m: f32,
    pub size: [u32; 2],
    /// Row `j` (south first) is `words[j * stride ..]`, bit `i % 32` of
    /// word `i / 32` the cell `i` ([`Self::stride`]).
    #[serde(skip)]
    pub words: Vec<u32>,
    /// Per material id (grass, rock, snow, scree, sand): the brushes'
    /// density, the largest over the grass types.
    pub density: [f32; 5],
    /// Cells whose bit is set.
    pub set: usize,
}

impl GrassOccurrence {
    /// Reads `folder` (what `vista vegetate --out` wrote): its
    /// `vegetation.json` and every grass type's occurrence map.
    pub fn load(folder: &Path) -> Result<Self> {
        let bad = |m: String| Error::Scene(format!("effects.grass.vegetation: {}: {m}", folder.display()));
        let s = crate::world::vegetation::read_summary(folder).map_err(bad)?;
        let [w, h] = s.occurrence_cells;
        if !(s.occurrence_cell_m.is_finite() && s.occurrence_cell_m > 0.0) || w == 0 || h == 0 || w * h > 1 << 30 {
            return Err(bad(format!(
                "vegetation.json: an occurrence grid of {w} x {h} cells of {} m",
                s.occurrence_cell_m
            )));
        }
        let stride = w.div_ceil(32);
        let mut words = vec![0u32; stride * h];
        let mut density = [0f32; 5];
        let grass: Vec<_> = s.types.iter().filter(|t| t.occurrence_file.is_some()).collect();
        if grass.is_empty() {
            return Err(bad("no grass type (kind = \"grass\") was generated: nothing to read".into()));
        }
        for t in grass {
            let file = t.occurrence_file.as_deref().expect("filtered");
            let bits = std::fs::read(folder.join(file)).map_err(|e| bad(format!("{file}: {e}")))?;
            if bits.len() != w.div_ceil(8) * h {
                return Err(bad(format!("{file}: {} bytes, a {w} x {h} map has {}", bits.len(), w.div_ceil(8) * h)));
            }
            merge(&mut words, &bits, [w, h]);
            let d = t.material_density.ok_or_else(|| bad(format!("type {}: no material_density", t.name)))?;
            for (o, v) in density.iter_mut().zip(d) {
                *o = o.max(v as f32);
            }
        }
        let set = words.iter().map(|w| w.count_ones() as usize).sum();
        let size = [w as u32, h as u32];
        Ok(GrassOccurrence {
            folder: folder.to_path_buf(),
            cell_m: s.occurrence_cell_m as f32,
            size,
            words,
            density,
            set,
        })
    }

    /// Words a row.
    pub fn stride(&self) -> usize {
        (self.size[0] as usize).div_ceil(32)
    }

    /// 1 / [`Self::cell_m`], as `grass_place` multiplies by it.
    pub fn per_m(&self) -> f32 {
        1.0 / self.cell_m
    }

    /// Whether grass may grow at `p` (world metres from the south-west
    /// corner, the f32 `grass_place` reads): outside the map, no. The same
    /// f32 product as the shader's, so the same cell.
    pub fn bit(&self, p: [f32; 2]) -> bool {
        let c = p.map(|v| (v * self.per_m()).floor());
        if c[0] < 0.0 || c[1] < 0.0 || c[0] >= self.size[0] as f32 || c[1] >= self.size[1] as f32 {
            return false;
        }
        let (i, j) = (c[0] as usize, c[1] as usize);
        self.words[j * self.stride() + i / 32] >> (i % 32) & 1 != 0
    }

    /// Metres the map covers each way.
    pub fn extent_m(&self) -> [f64; 2] {
        self.size.map(|s| f64::from(s) * f64::from(self.cell_m))
    }
}

/// ORs a byte-row map (`vista vegetate`'s) into 32-bit word rows.
fn merge(words: &mut [u32], bits: &[u8], [w, h]: [usize; 2]) {
    let (bytes, stride) = (w.div_ceil(8), w.div_ceil(32));
    for j in 0..h {
        for (k, b) in bits[j * bytes..(j + 1) * bytes].iter().enumerate() {
            words[j * stride + k / 4] |= u32::from(*b) << (8 * (k % 4));
        }
    }
}
