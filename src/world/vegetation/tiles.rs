//! The generator's unit of work and of reuse: a tile of 64 x 64 cells,
//! computed from a window of the field around it (the resource's
//! iterations, the sun's reach) and kept in a file named by its position
//! and keyed by a hash of everything it reads. A rerun keeps every tile
//! whose key still matches (a stamp regenerates the tiles within reach of
//! it, no others), and shards split the tiles among processes.

use std::path::{Path, PathBuf};

use super::field::HeightField;
use super::params::Entry;
use super::resource::{flow, Window};
use super::spawn::{grass_bits, instance, Conditions, Instance};
use super::stamped::StampVegetation;
use super::sun::lit_share;
use crate::world::error::{Result, WorldError};
use crate::world::hash::Fnv64;
use crate::world::holes::{holes_hash, Hole};

/// Cells a tile side.
pub const TILE_CELLS: usize = 64;
const MAGIC: &[u8; 4] = b"VVEG";
/// Bumped when what a tile holds or how it is computed changes.
const VERSION: u32 = 3;

/// One tile's results, row-major over its cells (south row first).
#[derive(Clone, Debug, PartialEq)]
pub struct Tile {
    pub window: Window,
    pub resource: Vec<f32>,
    /// Share of the day's sun samples the cell sees.
    pub sun: Vec<f32>,
    /// Grass types eligible in the cell (bit = type index).
    pub grass: Vec<u16>,
    pub instances: Vec<Instance>,
}

/// Everything a tile is computed from, but the field itself: the run's
/// request, the brushes by material, the sun's positions.
pub struct Inputs<'a> {
    pub req: &'a super::Request<'a>,
    pub entries: &'a [Vec<Entry>; 5],
    pub sun_path: &'a [glam::DVec3],
}

/// The tiles over `field`, row-major.
pub fn tiles(field: &HeightField) -> Vec<Window> {
    let [tx, ty] = field.size.map(|s| s.div_ceil(TILE_CELLS));
    (0..ty)
        .flat_map(|j| (0..tx).map(move |i| (i, j)))
        .map(|(i, j)| {
            let lo = [i * TILE_CELLS, j * TILE_CELLS];
            Window { lo, size: [0, 1].map(|a| TILE_CELLS.min(field.size[a] - lo[a])) }
        })
        .collect()
}

/// The tile's cache key: the parameters, the world, its rules and holes,
/// and the source over the window the tile reads.
pub fn key(inputs: &Inputs, field: &HeightField, tile: Window) -> u64 {
    let c = field.cell_m;
    let reach = inputs.req.params.reach_m.max(f64::from(inputs.req.params.iterations) * c) + 2.0 * c;
    let bounds = [
        tile.lo[0] as f64 * c - reach,
        tile.lo[1] as f64 * c - reach,
        (tile.lo[0] + tile.size[0]) as f64 * c + reach,
        (tile.lo[1] + tile.size[1]) as f64 * c + reach,
    ];
    // Only the holes the window reads: one cut elsewhere changes nothing here.
    let touches = |b: [f64; 4]| b[0] <= bounds[2] && b[2] >= bounds[0] && b[1] <= bounds[3] && b[3] >= bounds[1];
    let near: Vec<Hole> = inputs.req.holes.iter().filter(|h| touches(h.bounds())).cloned().collect();
    Fnv64::new()
        .u64(u64::from(VERSION))
        .u64(inputs.req.params.hash())
        .u64(inputs.req.world.hash())
        .u64(inputs.req.rules.hash())
        .u64(holes_hash(&near))
        .u64(inputs.req.source.region_hash(bounds))
        .u64(inputs.req.masks.region_hash(bounds))
        .u64(stamps_hash(inputs, tile_bounds(field, tile)))
        .u64(tile.lo[0] as u64)
        .u64(tile.lo[1] as u64)
        .bytes(inputs.req.sun.map(|m| m.name()).unwrap_or_default().as_bytes())
        .finish()
}

/// The tile's own square (m), grown by a cell.
fn tile_bounds(field: &HeightField, tile: Window) -> [f64; 4] {
    let c = field.cell_m;
    let lo = tile.lo.map(|v| (v as f64 - 1.0) * c);
    [lo[0], lo[1], (tile.lo[0] + tile.size[0] + 1) as f64 * c, (tile.lo[1] + tile.size[1] + 1) as f64 * c]
}

fn touching<'a>(inputs: &'a Inputs, b: [f64; 4]) -> impl Iterator<Item = &'a StampVegetation> + 'a {
    inputs.req.stamps.iter().filter(move |s| {
        let sb = s.placement.bounds_m();
        sb[0] <= b[2] && sb[2] >= b[0] && sb[1] <= b[3] && sb[3] >= b[1]
    })
}

/// The stamps' vegetation the tile's cells may take.
fn stamps_hash(inputs: &Inputs, b: [f64; 4]) -> u64 {
    touching(inputs, b).fold(Fnv64::new(), |h, s| h.u64(s.hash())).finish()
}

/// The stamps' own instances whose point lies in `tile`'s cells and no
/// mask (on the ground there).
fn pasted(inputs: &Inputs, field: &HeightField, tile: Window) -> Vec<Instance> {
    let mut out = Vec::new();
    for s in touching(inputs, tile_bounds(field, tile)) {
        for mut t in s.placed() {
            let (x, y) = (f64::from(t.position[0]), f64::from(t.position[1]));
            let (i, j) = ((x / field.cell_m).floor() as i64, (y / field.cell_m).floor() as i64);
            let inside = tile.contains(i as isize, j as isize) && i >= 0 && j >= 0;
            if inside && !inputs.req.masks.masked([x, y]) {
                t.position[2] = inputs.req.source.sample(x, y);
                t.cell = field.index(i as usize, j as usize) as u32;
                out.push(t);
            }
        }
    }
    out
}

/// Computes `tile` of `field`; its cells' sun shares when marched
/// elsewhere (row-major), else here.
pub fn compute(inputs: &Inputs, field: &HeightField, tile: Window, marched: Option<&[f32]>) -> Tile {
    let p = inputs.req.params;
    let wide = Window::around(tile, p.iterations as usize, field.size);
    let water = flow(field, wide, p.iterations, p.flow_rule());
    let n = tile.size[0] * tile.size[1];
    let mut out = Tile {
        window: tile,
        resource: Vec::with_capacity(n),
        sun: Vec::with_capacity(n),
        grass: Vec::with_capacity(n),
        instances: Vec::new(),
    };
    for j in tile.lo[1]..tile.lo[1] + tile.size[1] {
        for i in tile.lo[0]..tile.lo[0] + tile.size[0] {
            let k = field.index(i, j);
            let r = water[(j - wide.lo[1]) * wide.size[0] + (i - wide.lo[0])];
            if field.hole[k] {
                out.resource.push(0.0);
                out.sun.push(0.0);
                out.grass.push(0);
                continue;
            }
            let sun = match marched {
                Some(s) => s[(j - tile.lo[1]) * tile.size[0] + (i - tile.lo[0])],
                None => lit_share(field, i, j, inputs.sun_path, p.reach_m),
            };
            let c = Conditions {
                slope_deg: field.slope_deg(i, j),
                altitude_m: f64::from(field.z[k]),
                sun: f64::from(sun),
                resource: r,
            };
            let entries = &inputs.entries[field.material[k] as usize];
            out.resource.push(r as f32);
            out.sun.push(sun);
            // A mask removes what grows, not the water or the sun; a
            // stamp's vegetation replaces the generator's (the last stamp
            // over the cell).
            let centre = [(i as f64 + 0.5) * field.cell_m, (j as f64 + 0.5) * field.cell_m];
            let stamp = inputs.req.stamps.iter().rev().find(|s| s.covers(centre));
            if inputs.req.masks.masked(centre) || stamp.is_some() {
                out.grass.push(stamp.filter(|_| !inputs.req.masks.masked(centre)).map_or(0, |s| s.grass_bits(centre)));
                continue;
            }
            out.grass.push(grass_bits(p, entries, &c));
            let grown = instance(p, field, entries, (i, j), &c);
            let at = |t: &Instance| [f64::from(t.position[0]), f64::from(t.position[1])];
            let covered = |t: &Instance| inputs.req.stamps.iter().any(|s| s.covers(at(t)));
            if let Some(mut t) = grown.filter(|t| !inputs.req.masks.masked(at(t)) && !covered(t)) {
                t.position[2] = inputs.req.source.sample(f64::from(t.position[0]), f64::from(t.position[1]));
                out.instances.push(t);
            }
        }
    }
    out.instances.extend(pasted(inputs, field, tile));
    out
}

/// Where tile `w`'s file lies in `dir`.
pub fn tile_path(dir: &Path, w: Window) -> PathBuf {
    dir.join("tiles").join(format!("{}_{}.vveg", w.lo[0] / TILE_CELLS, w.lo[1] / TILE_CELLS))
}

/// Writes `tile` under `key`, whole or not at all (a reader, another
/// shard, never sees half a file).
pub fn write(dir: &Path, tile: &Tile, key: u64) -> Result<()> {
    let path = tile_path(dir, tile.window);
    let folder = path.parent().expect("a tile's folder");
    std::fs::create_dir_all(folder).map_err(|e| WorldError::io_write(folder, e))?;
    let mut bytes = Vec::new();
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&VERSION.to_le_bytes());
    bytes.extend_from_slice(&key.to_le_bytes());
    for v in tile.window.lo.iter().chain(&tile.window.size) {
        bytes.extend_from_slice(&(*v as u32).to_le_bytes());
    }
    bytes.extend_from_slice(bytemuck::cast_slice(&tile.resource));
    bytes.extend_from_slice(bytemuck::cast_slice(&tile.sun));
    bytes.extend_from_slice(bytemuck::cast_slice(&tile.grass));
    bytes.extend_from_slice(&(tile.instances.len() as u32).to_le_bytes());
    bytes.extend_from_slice(bytemuck::cast_slice(&tile.instances));
    crate::output::write(&path, &bytes).map_err(|e| WorldError::io_write(&path, e.error))
}

/// Reads tile `w`'s file if it exists and was made under `key`; `None`
/// for a missing, stale or damaged file (it is then recomputed).
pub fn read(dir: &Path, w: Window, key: u64) -> Option<Tile> {
    let bytes = std::fs::read(tile_path(dir, w)).ok()?;
    let mut at = 0usize;
    let mut take = |n: usize| {
        let s = bytes.get(at..at + n);
        at += n;
        s
    };
    let word = |s: Option<&[u8]>| s.map(|s| u32::from_le_bytes(s.try_into().expect("4 bytes")));
    if take(4)? != MAGIC || word(take(4))? != VERSION || u64::from_le_bytes(take(8)?.try_into().ok()?) != key {
        return None;
    }
    let dims: Vec<usize> = (0..4).map(|_| word(take(4)).map(|v| v as usize)).collect::<Option<_>>()?;
    if dims != [w.lo[0], w.lo[1], w.size[0], w.size[1]] {
        return None;
    }
    let n = w.size[0] * w.size[1];
    let floats = |s: &[u8]| s.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().expect("4"))).collect();
    let resource = floats(take(4 * n)?);
    let sun = floats(take(4 * n)?);
    let grass = take(2 * n)?.chunks_exact(2).map(|c| u16::from_le_bytes([c[0], c[1]])).collect();
    let count = word(take(4))? as usize;
    let size = std::mem::size_of::<Instance>();
    let instances = take(count.checked_mul(size)?)?.chunks_exact(size).map(bytemuck::pod_read_unaligned).collect();
    (take(1).is_none()).then_some(Tile { window: w, resource, sun, grass, instances })
}
