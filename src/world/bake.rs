//! Baking node payloads from a height source.

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use rayon::prelude::*;

use super::cache::{CacheOutcome, NodeCache};
use super::cones::{fit_cone, patch_triangle_normals};
use super::error::Result;
use super::holes::Hole;
use super::layout::{NodeId, WorldDesc, NODE_SAMPLES, PATCHES_PER_NODE_SIDE, PATCH_QUADS, PATCH_SAMPLES, SPLAT_RES};
use super::payload::{BakedNode, Material, PATCH_HOLE_ALL, PATCH_HOLE_NONE, PATCH_HOLE_SOME};
use super::progress::{Progress, Reporter};
use super::source::HeightSource;

/// Samples per side of the 2x finer grid used for the LOD error (257) plus
/// a one-sample border on each side for central-difference normals.
const FINE: usize = 2 * (NODE_SAMPLES - 1) + 1 + 2;
/// Slope above which ground is bare rock (cliff), degrees.
const ROCK_SLOPE_DEG: f32 = 45.0;
/// Slope above which loose scree replaces grass, degrees.
const SCREE_SLOPE_DEG: f32 = 30.0;
/// Blue channel of the normal map: specular occlusion, 255 = unoccluded
/// (Far Cry 5 packs it there; nothing here computes occlusion yet).
const NO_OCCLUSION: u8 = 255;
/// Snow line as a fraction of the world's height range.
const SNOW_LINE: f32 = 0.72;

/// Bakes one node. `id` must be valid in `world` (programmer error
/// otherwise). Samples beyond the world extent take the edge's height (so
/// bounds and cones stay sane) and are holes, so a world whose extent is not
/// a multiple of the node size ends cleanly at its edge.
pub fn bake_node(source: &dyn HeightSource, world: &WorldDesc, holes: &[Hole], id: NodeId) -> BakedNode {
    assert!(world.is_valid(id), "bake_node on invalid node {id}");
    let b = world.bounds_m(id);
    let step = world.node_spacing_m(id.lod);
    let half = step / 2.0;
    let [ex, ey] = world.extent_m;

    // f[(j + 1) * FINE + (i + 1)] is the source at min + (i, j) * half.
    let mut f = vec![0f32; FINE * FINE];
    // Sampling dominates the bake; rows in parallel cut a single node's
    // latency for the streaming loader too.
    f.par_chunks_exact_mut(FINE).enumerate().for_each(|(j, row)| {
        let y = (b[1] + (j as f64 - 1.0) * half).clamp(0.0, ey);
        for (i, v) in row.iter_mut().enumerate() {
            let x = (b[0] + (i as f64 - 1.0) * half).clamp(0.0, ex);
            *v = source.sample(x, y);
        }
    });
    let fine = |i: usize, j: usize| f[(j + 1) * FINE + (i + 1)];
    let coarse = |i: usize, j: usize| fine(2 * i, 2 * j);

    let n = NODE_SAMPLES;
    let heights: Vec<u16> = (0..n * n).map(|k| world.encode_height(coarse(k % n, k / n))).collect();

    let hole_here = holes_near(holes, b, step);
    let [lo, hi] = world.height_range_m;
    let snow_m = lo + SNOW_LINE * (hi - lo);
    let mut normals = Vec::with_capacity(n * n);
    let mut albedo = Vec::with_capacity(n * n);
    let mut materials = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            // Central differences on the fine grid (spacing `half`).
            let (fi, fj) = (2 * i + 1, 2 * j + 1);
            let dx = (f[fj * FINE + fi + 1] - f[fj * FINE + fi - 1]) as f64 / step;
            let dy = (f[(fj + 1) * FINE + fi] - f[(fj - 1) * FINE + fi]) as f64 / step;
            let len = (dx * dx + dy * dy + 1.0).sqrt();
            let nrm = [-dx / len, -dy / len, 1.0 / len];
            let slope_deg = (nrm[2].clamp(-1.0, 1.0).acos() as f32).to_degrees();
            let mat = material(slope_deg, coarse(i, j), snow_m);
            let pos = [b[0] + i as f64 * step, b[1] + j as f64 * step];
            let solid =
                !beyond_extent(pos, world.extent_m, step) && !hole_here.iter().any(|h| h.contains(pos[0], pos[1]));
            let (rgb, smooth) = material_look(mat, slope_deg);
            normals.push([snorm8(nrm[0]), snorm8(nrm[1]), NO_OCCLUSION, smooth]);
            albedo.push([rgb[0], rgb[1], rgb[2], if solid { 255 } else { 0 }]);
            materials.push(mat);
        }
    }
    let splat =
        (0..SPLAT_RES * SPLAT_RES).map(|k| materials[(2 * (k / SPLAT_RES)) * n + 2 * (k % SPLAT_RES)] as u8).collect();

    let decoded: Vec<f32> = heights.iter().map(|&v| world.decode_height(v)).collect();
    let mut patch_min_max = Vec::new();
    let mut patch_cones = Vec::new();
    let mut patch_holes = Vec::new();
    for py in 0..PATCHES_PER_NODE_SIDE {
        for px in 0..PATCHES_PER_NODE_SIDE {
            let (mut mn, mut mx, mut holes_seen) = (u16::MAX, 0u16, 0usize);
            for j in 0..PATCH_SAMPLES {
                for i in 0..PATCH_SAMPLES {
                    let k = (py * PATCH_QUADS) as usize * n + j * n + (px * PATCH_QUADS) as usize + i;
                    mn = mn.min(heights[k]);
                    mx = mx.max(heights[k]);
                    holes_seen += usize::from(albedo[k][3] == 0);
                }
            }
            patch_min_max.push([mn, mx]);
            patch_holes.push(match holes_seen {
                0 => PATCH_HOLE_NONE,
                n if n == PATCH_SAMPLES * PATCH_SAMPLES => PATCH_HOLE_ALL,
                _ => PATCH_HOLE_SOME,
            });
            let tri = patch_triangle_normals(&decoded, step, px, py);
            patch_cones.push(fit_cone(&tri).to_gpu());
        }
    }
    let min_height = heights.iter().copied().min().unwrap_or(0);
    let max_height = heights.iter().copied().max().unwrap_or(0);
    let max_error_m = max_refinement_error(&fine);

    BakedNode {
        id,
        heights,
        normals,
        albedo,
        splat,
        patch_min_max,
        patch_cones,
        patch_holes,
        min_height,
        max_height,
        max_error_m,
    }
}

/// Max |finer surface - bilinear(this node's grid)| over the 257x257 finer
/// grid points. Unquantised heights, so a plane gives 0.
fn max_refinement_error(fine: &impl Fn(usize, usize) -> f32) -> f32 {
    let last = 2 * (NODE_SAMPLES - 1);
    let mut err = 0f64;
    for b in 0..=last {
        let (j0, j1) = (b / 2 * 2, b.div_ceil(2) * 2);
        for a in 0..=last {
            let (i0, i1) = (a / 2 * 2, a.div_ceil(2) * 2);
            let c = 0.25
                * (f64::from(fine(i0, j0))
                    + f64::from(fine(i1, j0))
                    + f64::from(fine(i0, j1))
                    + f64::from(fine(i1, j1)));
            err = err.max((f64::from(fine(a, b)) - c).abs());
        }
    }
    err as f32
}

/// A sample position past the world's extent (beyond rounding of the
/// sample grid) has no terrain.
fn beyond_extent(pos: [f64; 2], extent: [f64; 2], step: f64) -> bool {
    let slack = step * 1e-6;
    pos[0] > extent[0] + slack || pos[1] > extent[1] + slack
}

/// Holes whose bounds come within a sample of the node; usually none.
fn holes_near(holes: &[Hole], b: [f64; 4], step: f64) -> Vec<&Hole> {
    holes
        .iter()
        .filter(|h| {
            let hb = h.bounds();
            hb[0] <= b[2] + step && hb[2] >= b[0] - step && hb[1] <= b[3] + step && hb[3] >= b[1] - step
        })
        .collect()
}

fn snorm8(v: f64) -> u8 {
    (v * 127.5 + 127.5).round().clamp(0.0, 255.0) as u8
}

fn material(slope_deg: f32, h_m: f32, snow_m: f32) -> Material {
    if slope_deg > ROCK_SLOPE_DEG {
        Material::Rock
    } else if h_m > snow_m {
        Material::Snow
    } else if slope_deg > SCREE_SLOPE_DEG {
        Material::Scree
    } else {
        Material::Grass
    }
}

/// Baked albedo and smoothness per material; steeper ground is a little
/// darker so the far-away atlas keeps some relief.
fn material_look(m: Material, slope_deg: f32) -> ([u8; 3], u8) {
    let (rgb, smooth): ([f32; 3], u8) = match m {
        Material::Grass => ([0.30, 0.42, 0.18], 25),
        Material::Rock => ([0.42, 0.40, 0.38], 60),
        Material::Snow => ([0.92, 0.94, 0.97], 150),
        Material::Scree => ([0.50, 0.45, 0.38], 40),
    };
    let shade = 1.0 - 0.25 * (slope_deg / 90.0).clamp(0.0, 1.0);
    (rgb.map(|c| (c * shade * 255.0).round() as u8), smooth)
}

/// Valid nodes of every LOD overlapping `region` ([min x, min y, max x,
/// max y] metres; `None` = everything), coarsest LOD first.
pub fn nodes_in_region(world: &WorldDesc, region: Option<[f64; 4]>) -> Vec<NodeId> {
    let mut out = Vec::new();
    for lod in (0..world.lod_count as u8).rev() {
        let s = world.node_size_m(lod);
        let [gx, gy] = world.grid(lod);
        let (x0, y0, x1, y1) = match region {
            None => (0, 0, gx, gy),
            Some(r) => {
                let cell = |v: f64, g: u32| ((v / s).floor().max(0.0) as u32).min(g);
                let end = |v: f64, g: u32| ((v / s).ceil().max(0.0) as u32).min(g);
                (cell(r[0], gx), cell(r[1], gy), end(r[2], gx), end(r[3], gy))
            }
        };
        for y in y0..y1 {
            for x in x0..x1 {
                out.push(NodeId::new(lod, x, y));
            }
        }
    }
    out
}

/// What a [`bake_world`] run did.
#[derive(Clone, Debug, Default)]
pub struct BakeStats {
    /// Nodes per LOD (index = LOD).
    pub nodes_per_lod: Vec<usize>,
    /// Nodes baked now; the rest came from the cache.
    pub baked: usize,
    pub cached: usize,
    pub seconds: f64,
    /// Bytes of the node files of this region on disk.
    pub bytes_on_disk: u64,
}

/// Bakes (or validates from cache) every valid node of every LOD
/// overlapping `region` into `cache_dir`, in parallel.
pub fn bake_world(
    source: Arc<dyn HeightSource>,
    world: &WorldDesc,
    holes: &[Hole],
    region: Option<[f64; 4]>,
    cache_dir: &Path,
    progress: impl Into<Progress>,
) -> Result<BakeStats> {
    let start = Instant::now();
    let cache = NodeCache::new(cache_dir, *world, source, holes.to_vec())?;
    let nodes = nodes_in_region(world, region);
    let bar = Reporter::new(progress.into(), nodes.len() as u64);
    let outcomes = nodes
        .par_iter()
        .map(|&id| {
            let (_, outcome) = cache.get_or_bake(id)?;
            bar.inc();
            let bytes = std::fs::metadata(cache.path(id)).map(|m| m.len()).unwrap_or(0);
            Ok((id, outcome, bytes))
        })
        .collect::<Result<Vec<_>>>()?;
    bar.finish();
    let mut stats = BakeStats { nodes_per_lod: vec![0; world.lod_count as usize], ..BakeStats::default() };
    for (id, outcome, bytes) in outcomes {
        stats.nodes_per_lod[id.lod as usize] += 1;
        stats.bytes_on_disk += bytes;
        match outcome {
            CacheOutcome::Hit => stats.cached += 1,
            CacheOutcome::Baked(_) => stats.baked += 1,
        }
    }
    stats.seconds = start.elapsed().as_secs_f64();
    Ok(stats)
}
