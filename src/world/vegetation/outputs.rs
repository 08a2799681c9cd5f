//! The generator's files: the instances (32 bytes each, [`Instance`]'s
//! layout), an occurrence map per grass type (a bit per occurrence cell:
//! seed 004's "skip the cell if the bit is not set"), and
//! `vegetation.json` saying what each holds, with the maps' pictures, as
//! one set of files (all new or all old). Written only from a whole grid,
//! so two runs that agree on it write the same bytes.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::params::{VegetationKind, VegetationParams};
use super::spawn::Instance;
use super::Generated;
use crate::output::FileSet;
use crate::world::error::{Result, WorldError};
use image::ExtendedColorType::Rgb8;

/// The files every run writes (one `occurrence-NAME.bin` per grass type
/// besides).
pub const OUTPUT_FILES: [&str; 5] = ["instances.bin", "vegetation.json", "resource.png", "sun.png", "vegetation.png"];

/// A grass type's occurrence map: rows of bits, south row first, a row
/// `(size[0] + 7) / 8` bytes, bit `i % 8` of byte `i / 8` the cell `i`.
#[derive(Clone, Debug, PartialEq)]
pub struct Occurrence {
    pub ty: usize,
    pub size: [usize; 2],
    pub bits: Vec<u8>,
}

impl Occurrence {
    /// Type `ty`'s map over `g`: a cell's bit is set when the type may
    /// grow anywhere in its `ratio` x `ratio` generator cells.
    pub fn of(g: &Generated, ty: usize, ratio: usize) -> Self {
        let size = g.size.map(|s| s.div_ceil(ratio));
        let stride = size[0].div_ceil(8);
        let mut bits = vec![0u8; stride * size[1]];
        for j in 0..g.size[1] {
            for i in 0..g.size[0] {
                if g.grass[j * g.size[0] + i] & (1 << ty) != 0 {
                    let (oi, oj) = (i / ratio, j / ratio);
                    bits[oj * stride + oi / 8] |= 1 << (oi % 8);
                }
            }
        }
        Occurrence { ty, size, bits }
    }

    pub fn get(&self, i: usize, j: usize) -> bool {
        self.bits[j * self.size[0].div_ceil(8) + i / 8] & (1 << (i % 8)) != 0
    }

    pub fn set_cells(&self) -> usize {
        self.bits.iter().map(|b| b.count_ones() as usize).sum()
    }
}

/// `vegetation.json`: what a folder holds. Every reader of a folder (effect
/// grass's occurrence, effect vegetation, a stamp's vegetation) reads it
/// through [`read_summary`]; a field a hand-made file leaves out reads as
/// its default, and the readers' size checks catch what does not fit.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Summary {
    pub cell_m: f64,
    pub cells: [usize; 2],
    pub occurrence_cell_m: f64,
    pub occurrence_cells: [usize; 2],
    pub instances_file: String,
    pub instance_bytes: usize,
    pub instance_layout: String,
    pub instances: usize,
    pub types: Vec<TypeSummary>,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TypeSummary {
    pub name: String,
    pub kind: Option<VegetationKind>,
    pub instances: usize,
    pub occurrence_file: Option<String>,
    pub occurrence_set: Option<usize>,
    /// Grass: its brushes' density on each material (grass, rock, snow,
    /// scree, sand; the largest where several brushes offer it), which
    /// effect grass multiplies its own densities by.
    pub material_density: Option<[f64; 5]>,
}

/// Reads `folder`'s `vegetation.json`; the error is one line naming the
/// file and what `vista vegetate` command makes it.
pub fn read_summary(folder: &Path) -> std::result::Result<Summary, String> {
    let text = std::fs::read_to_string(folder.join("vegetation.json"))
        .map_err(|e| format!("vegetation.json: {e} (made by `vista vegetate --out {}`)", folder.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("vegetation.json: {e}"))
}

/// Writes the instances, the occurrence maps, the summary and the maps'
/// pictures into `dir`, as one set; gives the occurrence maps.
pub fn write_outputs(dir: &Path, params: &VegetationParams, g: &Generated) -> Result<Vec<Occurrence>> {
    let mut set = FileSet::new(dir);
    let mut put = |name: &str, bytes: &[u8]| set.add(name, bytes).map_err(|e| WorldError::io_write(&e.path, e.error));
    put("instances.bin", bytemuck::cast_slice(&g.instances))?;
    let ratio = params.occurrence_ratio();
    let entries = params.brush_entries()?;
    let mut maps = Vec::new();
    let mut types = Vec::new();
    for (ty, t) in params.types.iter().enumerate() {
        let mut s = TypeSummary {
            name: t.name.clone(),
            kind: Some(t.kind),
            instances: g.instances.iter().filter(|i| i.ty as usize == ty).count(),
            occurrence_file: None,
            occurrence_set: None,
            material_density: None,
        };
        if t.kind == VegetationKind::Grass {
            let m = Occurrence::of(g, ty, ratio);
            let file = format!("occurrence-{}.bin", t.name);
            put(&file, &m.bits)?;
            (s.occurrence_file, s.occurrence_set) = (Some(file), Some(m.set_cells()));
            let on = |es: &Vec<super::params::Entry>| {
                es.iter().filter(|e| e.ty == ty).map(|e| e.density).fold(0.0, f64::max)
            };
            s.material_density = Some([0, 1, 2, 3, 4].map(|m| on(&entries[m])));
            maps.push(m);
        }
        types.push(s);
    }
    let summary = Summary {
        cell_m: g.cell_m,
        cells: g.size,
        occurrence_cell_m: params.occurrence_cell_m,
        occurrence_cells: g.size.map(|s| s.div_ceil(ratio)),
        instances_file: "instances.bin".into(),
        instance_bytes: std::mem::size_of::<Instance>(),
        instance_layout: "x, y, z (f32 m), yaw (f32 rad), scale (f32), type (u32), tint (RGBA8), cell (u32)".into(),
        instances: g.instances.len(),
        types,
    };
    let json = serde_json::to_string_pretty(&summary).expect("the summary serializes");
    put("vegetation.json", json.as_bytes())?;
    for (name, img) in super::maps::pictures(params, g) {
        set.add_with(name, |w| crate::output::encode_png(w, img.as_raw(), [img.width(), img.height()], Rgb8))
            .map_err(|e| WorldError::io_write(&e.path, e.error))?;
    }
    set.commit().map_err(|e| WorldError::io_write(&e.path, e.error))?;
    Ok(maps)
}
