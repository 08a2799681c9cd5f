//! REDengine 3's offline vegetation generator (seed 004): where water
//! collects and the sun reaches decide what grows. Over a grid of the
//! world ([`HeightField`]): resource flows downhill for a number of
//! iterations (`resource.rs`), each cell's share of the day's sun is marched
//! (`sun.rs`), and the brushes of the cell's material offer the types that
//! tolerate those conditions (`spawn.rs`): at most one tree or bush a cell,
//! scaled by how perfect the conditions are, and for each grass type a bit
//! a cell, gathered into occurrence maps (a bit per occurrence cell).
//!
//! The work is split into tiles (`tiles.rs`) kept in the output folder
//! under a key of all they read: a rerun reuses what still holds, shards
//! take every N-th tile, and the outputs are written once every tile is
//! there (`outputs.rs`). Everything is deterministic per seed: no tile
//! depends on another's result or on the order they run in.

mod field;
mod maps;
mod masks;
mod outputs;
mod params;
mod resource;
mod spawn;
mod stamped;
mod sun;
mod tiles;

use std::path::Path;
use std::time::Instant;

use rayon::prelude::*;

pub use field::HeightField;
pub use maps::{hillshade, pictures};
pub use masks::{MaskMap, Masks};
pub use outputs::{read_summary, write_outputs, Occurrence, Summary, TypeSummary, OUTPUT_FILES};
pub use params::{
    Brush, BrushEntry, VegetationKind, VegetationParams, VegetationType, MATERIAL_NAMES, MAX_CELLS, MAX_TYPES,
};
pub use resource::{flow, Flow, Window};
pub use spawn::Instance;
pub use stamped::StampVegetation;
pub use sun::{lit, lit_share, trajectory, SunMarch};
pub use tiles::{Tile, TILE_CELLS};

use super::error::{Result, WorldError};
use super::holes::Hole;
use super::layout::WorldDesc;
use super::material_rules::MaterialRules;
use super::source::HeightSource;

/// What a run was given.
pub struct Request<'a> {
    pub world: &'a WorldDesc,
    pub source: &'a dyn HeightSource,
    pub holes: &'a [Hole],
    pub rules: &'a MaterialRules,
    pub params: &'a VegetationParams,
    /// Where nothing may grow.
    pub masks: &'a Masks,
    /// Stamps that carry their own vegetation, in the scene's order (a
    /// later one over an earlier one).
    pub stamps: &'a [StampVegetation],
    /// Shard `index` of `count`: the tiles whose row-major number is
    /// `index` modulo `count`.
    pub shard: Option<(u32, u32)>,
    /// World metres (min x, min y, max x, max y): only the tiles
    /// overlapping it (of the shard's), as `vista bake --region` bakes a
    /// region's nodes; the outputs wait for the rest.
    pub region: Option<[f64; 4]>,
    /// Marches the sun there (the GPU) instead of on this CPU.
    pub sun: Option<&'a (dyn SunMarch + Sync)>,
}

/// What a run did.
#[derive(Clone, Debug, Default)]
pub struct RunReport {
    pub cells: [usize; 2],
    pub tiles: usize,
    /// This run's tiles (its shard's), computed and found valid in the folder.
    pub computed: usize,
    pub reused: usize,
    /// Tiles of other shards not in the folder yet (the outputs wait for them).
    pub missing: usize,
    pub field_s: f64,
    pub tiles_s: f64,
    /// Of `tiles_s`, the sun marched elsewhere (`Request::sun`).
    pub sun_s: f64,
    /// The whole grid, when every tile was there (outputs written from it).
    pub result: Option<Generated>,
}

/// The whole grid's results, row-major, south row first.
#[derive(Clone, Debug, Default)]
pub struct Generated {
    pub cell_m: f64,
    pub size: [usize; 2],
    pub resource: Vec<f32>,
    pub sun: Vec<f32>,
    pub grass: Vec<u16>,
    pub instances: Vec<Instance>,
    /// For the maps: the hillshade and the ground's material.
    pub z: Vec<f32>,
    pub hole: Vec<bool>,
    pub material: Vec<u8>,
}

/// Checks the request before anything large is allocated.
pub fn check(req: &Request) -> Result<[usize; 2]> {
    req.params.validate()?;
    let size = req.world.extent_m.map(|e| (e / req.params.cell_m).ceil().max(1.0));
    if size[0] * size[1] > MAX_CELLS as f64 {
        return Err(WorldError::Vegetation(format!(
            "a grid of {} x {} cells of {} m is over {MAX_CELLS} cells; raise cell_m",
            size[0], size[1], req.params.cell_m
        )));
    }
    if let Some(r) = req.region {
        let [ex, ey] = req.world.extent_m;
        if !(r[0] < r[2] && r[1] < r[3] && r[0] < ex && r[1] < ey && r[2] > 0.0 && r[3] > 0.0) {
            return Err(WorldError::Vegetation(format!(
                "region {},{} .. {},{} m does not overlap the world (0..{ex} x 0..{ey} m)",
                r[0], r[1], r[2], r[3]
            )));
        }
    }
    if let Some((i, n)) = req.shard {
        if n == 0 || i >= n {
            return Err(WorldError::Vegetation(format!("shard {i}/{n}: the index must be below the count")));
        }
    }
    Ok(size.map(|s| s as usize))
}

/// Generates (or reuses) this run's tiles in `dir`, and when every tile
/// is there, gathers the whole grid.
pub fn generate(req: &Request, dir: &Path) -> Result<RunReport> {
    let cells = check(req)?;
    let p = req.params;
    let entries = p.brush_entries()?;
    let start = Instant::now();
    let field = HeightField::sample(req.world, req.source, req.holes, req.rules, p.cell_m);
    let field_s = start.elapsed().as_secs_f64();
    let sun_path = trajectory(p.latitude_deg, p.day_of_year, p.sun_samples);
    let inputs = tiles::Inputs { req, entries: &entries, sun_path: &sun_path };
    let all = tiles::tiles(&field);
    let (index, count) = req.shard.unwrap_or((0, 1));
    let cell = p.cell_m;
    let in_region = |w: &Window| {
        req.region.is_none_or(|r| {
            let lo = [w.lo[0] as f64 * cell, w.lo[1] as f64 * cell];
            let hi = [lo[0] + w.size[0] as f64 * cell, lo[1] + w.size[1] as f64 * cell];
            lo[0] < r[2] && r[0] < hi[0] && lo[1] < r[3] && r[1] < hi[1]
        })
    };
    let mine: Vec<usize> = (0..all.len()).filter(|k| *k as u32 % count == index && in_region(&all[*k])).collect();
    let start = Instant::now();
    let pending: Vec<(usize, u64)> = mine
        .par_iter()
        .map(|&k| (k, tiles::key(&inputs, &field, all[k])))
        .filter(|&(k, key)| tiles::read(dir, all[k], key).is_none())
        .collect();
    let windows: Vec<Window> = pending.iter().map(|&(k, _)| all[k]).collect();
    let sun_start = Instant::now();
    let marched = match req.sun {
        Some(m) if !windows.is_empty() => Some(m.march(&field, &windows, &sun_path, p.reach_m)?),
        _ => None,
    };
    let sun_s = if marched.is_some() { sun_start.elapsed().as_secs_f64() } else { 0.0 };
    pending
        .par_iter()
        .enumerate()
        .map(|(n, &(k, key))| {
            let sun = marched.as_ref().map(|m| &m[n][..]);
            tiles::write(dir, &tiles::compute(&inputs, &field, all[k], sun), key)
        })
        .collect::<Result<Vec<_>>>()?;
    let tiles_s = start.elapsed().as_secs_f64();
    let computed = pending.len();
    let found: Vec<Option<Tile>> =
        all.par_iter().map(|w| tiles::read(dir, *w, tiles::key(&inputs, &field, *w))).collect();
    let missing = found.iter().filter(|t| t.is_none()).count();
    let result = (missing == 0).then(|| gather(&field, found.into_iter().flatten().collect()));
    Ok(RunReport {
        cells,
        tiles: all.len(),
        computed,
        reused: mine.len() - computed,
        missing,
        field_s,
        tiles_s,
        sun_s,
        result,
    })
}

/// The tiles laid into one grid; instances in tile order.
fn gather(field: &HeightField, tiles: Vec<Tile>) -> Generated {
    let n = field.size[0] * field.size[1];
    let mut g = Generated {
        cell_m: field.cell_m,
        size: field.size,
        resource: vec![0.0; n],
        sun: vec![0.0; n],
        grass: vec![0; n],
        instances: Vec::new(),
        z: field.z.clone(),
        hole: field.hole.clone(),
        material: field.material.clone(),
    };
    for t in tiles {
        let w = t.window;
        for j in 0..w.size[1] {
            let (from, to) = (j * w.size[0], field.index(w.lo[0], w.lo[1] + j));
            g.resource[to..to + w.size[0]].copy_from_slice(&t.resource[from..from + w.size[0]]);
            g.sun[to..to + w.size[0]].copy_from_slice(&t.sun[from..from + w.size[0]]);
            g.grass[to..to + w.size[0]].copy_from_slice(&t.grass[from..from + w.size[0]]);
        }
        g.instances.extend(t.instances);
    }
    g
}
