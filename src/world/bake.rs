//! Baking node payloads from a height source.

use rayon::prelude::*;

use super::cones::{fit_cone, patch_triangle_normals};
use super::control_map::{slope01, ControlBake};
use super::hash::Fnv64;
use super::holes::Hole;
use super::layout::{
    NodeId, WorldDesc, CONE_BLOCKS_PER_NODE_SIDE, NODE_QUADS, NODE_SAMPLES, PATCHES_PER_NODE, PATCHES_PER_NODE_SIDE,
    PATCH_QUADS, PATCH_SAMPLES, SPLAT_RES,
};
use super::material_rules::{MaterialRules, Site};
use super::payload::{BakedNode, Material, PATCH_HOLE_ALL, PATCH_HOLE_NONE, PATCH_HOLE_SOME};
use super::source::HeightSource;
use super::texels::{pack_normal, texel_index, PayloadFormat, TexelKind, ATLAS_BORDER, ATLAS_SIDE, ATLAS_TEXELS};

/// The grid a node is sampled on: `sub` points per sample step (2 above
/// LOD 0, for the refinement error against the next finer level; 1 at LOD
/// 0, which has none), covering the normal layer's samples -2..=129 plus
/// one grid point on either side for central differences.
struct Grid {
    sub: usize,
    /// Samples a row (and rows).
    width: usize,
    values: Vec<f32>,
}

impl Grid {
    /// Grid index of texel `t` (sample `t - 2`) along one axis.
    fn at(&self, t: usize) -> usize {
        self.sub * t + 1
    }
}
/// Blue channel of the normal map: specular occlusion, 255 = unoccluded
/// (Far Cry 5 packs it there; nothing here computes occlusion yet).
const NO_OCCLUSION: u8 = 255;

/// What a bake makes besides the geometry: the texel formats, the
/// material rules and, for a control-map world, its control words. Part of
/// the cache key.
#[derive(Clone, Debug, Default)]
pub struct BakeSettings {
    pub format: PayloadFormat,
    pub materials: MaterialRules,
    /// Control-map materials (seed 004): a word per splat texel in the
    /// payload's `control` layer, and the baked albedo from its textures.
    pub control: Option<ControlBake>,
}

impl PartialEq for BakeSettings {
    fn eq(&self, other: &Self) -> bool {
        self.hash() == other.hash()
    }
}

impl BakeSettings {
    pub fn hash(&self) -> u64 {
        let h = Fnv64::new().u64(u64::from(self.format.tag())).u64(self.materials.hash());
        h.u64(self.control.as_ref().map_or(0, ControlBake::hash)).finish()
    }
}

/// Bakes one node with the default [`BakeSettings`]; see [`bake_node_with`].
pub fn bake_node(source: &dyn HeightSource, world: &WorldDesc, holes: &[Hole], id: NodeId) -> BakedNode {
    bake_node_with(source, world, holes, &BakeSettings::default(), id)
}

/// Bakes one node. `id` must be valid in `world` (programmer error
/// otherwise). Samples beyond the world extent take the edge's height (so
/// bounds and cones stay sane) and are holes, so a world whose extent is not
/// a multiple of the node size ends cleanly at its edge.
pub fn bake_node_with(
    source: &dyn HeightSource,
    world: &WorldDesc,
    holes: &[Hole],
    settings: &BakeSettings,
    id: NodeId,
) -> BakedNode {
    assert!(world.is_valid(id), "bake_node on invalid node {id}");
    let b = world.bounds_m(id);
    let step = world.node_spacing_m(id.lod);

    let (g, gstep) = sample_grid(source, world, id);
    let width = g.width;
    let f = &g.values;
    // Sample (i, j), i and j from -2 on, counted from 0 here.
    let texel_height = |t: usize, u: usize| f[g.at(u) * width + g.at(t)];
    let coarse = |i: usize, j: usize| texel_height(i + ATLAS_BORDER, j + ATLAS_BORDER);

    let n = NODE_SAMPLES;
    let samples: Vec<u16> = (0..n * n).map(|k| world.encode_height(coarse(k % n, k / n))).collect();
    let heights: Vec<u16> =
        (0..ATLAS_TEXELS).map(|k| world.encode_height(texel_height(k % ATLAS_SIDE, k / ATLAS_SIDE))).collect();

    let place = Placement { world, holes: holes_near(holes, b, step), id, step, gstep };
    let Texels { normals, albedo, materials, words } = texels(source, settings, &g, &place);
    let at_splat = |k: usize| texel_index(2 * (k % SPLAT_RES) as isize, 2 * (k / SPLAT_RES) as isize);
    let splat = (0..SPLAT_RES * SPLAT_RES).map(|k| materials[at_splat(k)] as u8).collect();
    let control = match settings.control {
        Some(_) => (0..SPLAT_RES * SPLAT_RES).map(|k| words[at_splat(k)]).collect(),
        None => Vec::new(),
    };

    let decoded: Vec<f32> = samples.iter().map(|&v| world.decode_height(v)).collect();
    let (patch_min_max, patch_holes) = patch_bounds(&samples, &albedo);
    let patch_cones = patch_cones(&decoded, step);
    let min_height = samples.iter().copied().min().unwrap_or(0);
    let max_height = samples.iter().copied().max().unwrap_or(0);
    BakedNode {
        id,
        heights,
        format: settings.format,
        normals: settings.format.encode(TexelKind::Normal, &normals),
        albedo: settings.format.encode(TexelKind::Albedo, &albedo),
        splat,
        control,
        patch_min_max,
        patch_cones,
        patch_holes,
        min_height,
        max_height,
        // Errors need every LOD-0 sample under the node: ErrorTree::attach.
        max_error_m: f32::INFINITY,
        patch_errors: vec![[f32::INFINITY; 2]; PATCHES_PER_NODE],
        repr_error_m: f32::INFINITY,
        vertex_bounds: Vec::new(),
    }
}

/// The node's samples on a grid of `sub` points per LOD step (2 above LOD
/// 0: the normals see the finer slope), with the border the atlases and
/// the central differences need; and the grid's step (m).
fn sample_grid(source: &dyn HeightSource, world: &WorldDesc, id: NodeId) -> (Grid, f64) {
    let step = world.node_spacing_m(id.lod);
    let [ex, ey] = world.extent_m;
    let sub = if id.lod == 0 { 1 } else { 2 };
    let width = sub * (ATLAS_SIDE - 1) + 3;
    // Grid point (i, j) is grid line (origin + i - first, origin + j - first)
    // of the world's grid of step / sub metres (WorldDesc::grid_pos).
    let first = (sub * ATLAS_BORDER + 1) as i64;
    let gstep = step / sub as f64;
    let per_node = i64::from(NODE_QUADS) * sub as i64;
    let origin = [i64::from(id.x) * per_node - first, i64::from(id.y) * per_node - first];
    let mut g = Grid { sub, width, values: vec![0f32; width * width] };
    // Sampling dominates the bake; rows in parallel cut a single node's
    // latency for the streaming loader too.
    let xs: Vec<f64> = (0..width).map(|i| world.grid_pos(0, origin[0] + i as i64, gstep).clamp(0.0, ex)).collect();
    g.values.par_chunks_exact_mut(width).enumerate().for_each(|(j, row)| {
        let y = world.grid_pos(1, origin[1] + j as i64, gstep).clamp(0.0, ey);
        source.sample_row(&xs, y, row);
    });
    (g, gstep)
}

/// Where a node's texels lie: its world, the holes near it, its id, its
/// LOD step and its sample grid's step (m).
struct Placement<'a> {
    world: &'a WorldDesc,
    holes: Vec<&'a Hole>,
    id: NodeId,
    step: f64,
    gstep: f64,
}

/// Per atlas texel: the packed normal, the albedo (alpha 0: a hole), the
/// material and the control word.
struct Texels {
    normals: Vec<[u8; 4]>,
    albedo: Vec<[u8; 4]>,
    materials: Vec<Material>,
    words: Vec<u16>,
}

fn texels(source: &dyn HeightSource, settings: &BakeSettings, g: &Grid, p: &Placement) -> Texels {
    let (f, width, world, gstep) = (&g.values, g.width, p.world, p.gstep);
    let mut out = Texels {
        normals: Vec::with_capacity(ATLAS_TEXELS),
        albedo: Vec::with_capacity(ATLAS_TEXELS),
        materials: Vec::with_capacity(ATLAS_TEXELS),
        words: Vec::with_capacity(ATLAS_TEXELS),
    };
    for u in 0..ATLAS_SIDE {
        for t in 0..ATLAS_SIDE {
            // Texel (t, u) is sample (t - 2, u - 2).
            let (fi, fj) = (g.at(t), g.at(u));
            let dx = (f[fj * width + fi + 1] - f[fj * width + fi - 1]) as f64 / (2.0 * gstep);
            let dy = (f[(fj + 1) * width + fi] - f[(fj - 1) * width + fi]) as f64 / (2.0 * gstep);
            let len = (dx * dx + dy * dy + 1.0).sqrt();
            let nrm = [-dx / len, -dy / len, 1.0 / len];
            let slope_deg = (nrm[2].clamp(-1.0, 1.0).acos() as f32).to_degrees();
            let s = [t as i64 - ATLAS_BORDER as i64, u as i64 - ATLAS_BORDER as i64];
            let n0 = [i64::from(p.id.x), i64::from(p.id.y)].map(|c| c * i64::from(NODE_QUADS));
            let pos = [world.grid_pos(0, n0[0] + s[0], p.step), world.grid_pos(1, n0[1] + s[1], p.step)];
            let solid = !is_hole_at(world, source, p.holes.iter().copied(), pos, p.step);
            let site = Site { slope_deg, altitude_m: f[fj * width + fi], ground: source.ground(pos[0], pos[1]) };
            let mat = settings.materials.material_at(&site);
            let word = settings.control.as_ref().map(|c| c.word(pos[0], pos[1], &site));
            let (rgb, smooth) = match (&settings.control, word) {
                (Some(c), Some(w)) => c.looks.look(w, slope01(nrm[2])),
                _ => material_look(mat, slope_deg),
            };
            out.normals.push(pack_normal(nrm, NO_OCCLUSION, smooth));
            out.albedo.push([rgb[0], rgb[1], rgb[2], if solid { 255 } else { 0 }]);
            out.materials.push(mat);
            out.words.push(word.unwrap_or(0));
        }
    }
    out
}

/// Per patch: the min and max encoded height and whether it has holes.
fn patch_bounds(samples: &[u16], albedo: &[[u8; 4]]) -> (Vec<[u16; 2]>, Vec<u8>) {
    let n = NODE_SAMPLES;
    let (mut min_max, mut holes) = (Vec::new(), Vec::new());
    for py in 0..PATCHES_PER_NODE_SIDE {
        for px in 0..PATCHES_PER_NODE_SIDE {
            let (mut mn, mut mx, mut holes_seen) = (u16::MAX, 0u16, 0usize);
            for j in 0..PATCH_SAMPLES {
                for i in 0..PATCH_SAMPLES {
                    let (si, sj) = ((px * PATCH_QUADS) as usize + i, (py * PATCH_QUADS) as usize + j);
                    let k = sj * n + si;
                    mn = mn.min(samples[k]);
                    mx = mx.max(samples[k]);
                    holes_seen += usize::from(albedo[texel_index(si as isize, sj as isize)][3] == 0);
                }
            }
            min_max.push([mn, mx]);
            holes.push(match holes_seen {
                0 => PATCH_HOLE_NONE,
                n if n == PATCH_SAMPLES * PATCH_SAMPLES => PATCH_HOLE_ALL,
                _ => PATCH_HOLE_SOME,
            });
        }
    }
    (min_max, holes)
}

/// One cone per block of patches holds every triangle any of them draws.
fn patch_cones(decoded: &[f32], step: f64) -> Vec<[f32; 4]> {
    let b = crate::shaders::consts::CONE_BLOCK_PATCHES;
    let mut cones = Vec::new();
    for by in 0..CONE_BLOCKS_PER_NODE_SIDE {
        for bx in 0..CONE_BLOCKS_PER_NODE_SIDE {
            let tri: Vec<[f64; 3]> = (0..b * b)
                .flat_map(|k| patch_triangle_normals(decoded, step, bx * b + k % b, by * b + k / b))
                .collect();
            cones.push(fit_cone(&tri).to_gpu());
        }
    }
    cones
}

/// Whether the sample at `pos` is a hole: outside the extent, in a hole
/// shape, or a source's no-data (`step`: the grid's spacing, for the
/// extent's rounding slack). The per-vertex bounds ask the same.
pub(super) fn is_hole_at<'a>(
    world: &WorldDesc,
    source: &dyn HeightSource,
    holes: impl IntoIterator<Item = &'a Hole>,
    pos: [f64; 2],
    step: f64,
) -> bool {
    outside_extent(pos, world.extent_m, step)
        || holes.into_iter().any(|h| h.contains(pos[0], pos[1]))
        || source.is_hole(pos[0], pos[1])
}

/// A sample position outside the world's extent (beyond rounding of the
/// sample grid) has no terrain; border texels west or south of the world
/// lie before 0.
fn outside_extent(pos: [f64; 2], extent: [f64; 2], step: f64) -> bool {
    let slack = step * 1e-6;
    pos[0] > extent[0] + slack || pos[1] > extent[1] + slack || pos[0] < -slack || pos[1] < -slack
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

/// Baked albedo and smoothness per material; steeper ground is a little
/// darker so the far-away atlas keeps some relief.
fn material_look(m: Material, slope_deg: f32) -> ([u8; 3], u8) {
    let (rgb, smooth): ([f32; 3], u8) = match m {
        Material::Grass => ([0.30, 0.42, 0.18], 25),
        Material::Rock => ([0.42, 0.40, 0.38], 60),
        Material::Snow => ([0.92, 0.94, 0.97], 150),
        Material::Scree => ([0.50, 0.45, 0.38], 40),
        Material::Sand => ([0.76, 0.70, 0.50], 30),
    };
    let shade = 1.0 - 0.25 * (slope_deg / 90.0).clamp(0.0, 1.0);
    (rgb.map(|c| (c * shade * 255.0).round() as u8), smooth)
}
