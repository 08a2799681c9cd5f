//! CPU reference of the GPU quadtree traversal, LOD map and sector data,
//! making the same f32 decisions as `traverse_common.glsl` (used by tests
//! and the debug CLI). No Vulkan.

use crate::quadtree::{QuadtreeShadow, EMPTY, INVALID};
use crate::world::{NodeId, WorldDesc};

/// Up to this many cameras refine one node list (traverse_common.glsl MAX_CAMERAS).
pub const MAX_CAMERAS: usize = 4;

/// A view that asks for detail: position in world metres and the projection
/// scale in pixels per unit of tangent (`viewport_height / (2 tan(fov_y / 2))`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraverseCamera {
    pub position_m: [f64; 3],
    pub pixels_per_tan: f64,
}

impl TraverseCamera {
    pub fn perspective(position_m: [f64; 3], fov_y_deg: f64, viewport_height_px: u32) -> Self {
        let pixels_per_tan = f64::from(viewport_height_px) / (2.0 * (fov_y_deg.to_radians() / 2.0).tan());
        TraverseCamera { position_m, pixels_per_tan }
    }
}

/// The accuracy knob and the views it applies to.
#[derive(Debug, Clone, PartialEq)]
pub struct TraverseParams {
    pub cameras: Vec<TraverseCamera>,
    /// Largest accepted projected vertical error, in pixels (default 1).
    pub target_error_px: f32,
}

/// f32 inputs exactly as the GPU sees them (the push constants).
#[derive(Debug, Clone, Copy)]
pub(crate) struct GpuInputs {
    pub cameras: [[f32; 4]; MAX_CAMERAS],
    pub camera_count: u32,
    pub target_error_px: f32,
    pub sector_size_m: f32,
    pub height_lo: f32,
    pub height_scale: f32,
}

impl GpuInputs {
    pub fn new(world: &WorldDesc, params: &TraverseParams) -> Self {
        assert!((1..=MAX_CAMERAS).contains(&params.cameras.len()), "1..={MAX_CAMERAS} cameras");
        let mut cameras = [[0.0; 4]; MAX_CAMERAS];
        for (c, cam) in cameras.iter_mut().zip(&params.cameras) {
            let p = cam.position_m;
            *c = [p[0] as f32, p[1] as f32, p[2] as f32, cam.pixels_per_tan as f32];
        }
        let [lo, hi] = world.height_range_m;
        GpuInputs {
            cameras,
            camera_count: params.cameras.len() as u32,
            target_error_px: params.target_error_px,
            sector_size_m: world.sector_size_m() as f32,
            height_lo: lo,
            height_scale: (hi - lo) / 65535.0,
        }
    }
}

#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TraverseResult {
    /// (node, slot), sorted.
    pub nodes: Vec<(NodeId, u32)>,
    pub lod_counts: [u32; 16],
    pub overflow: u32,
    pub missing_roots: u32,
}

fn value(t: &QuadtreeShadow, lod: u8, x: u32, y: u32) -> u16 {
    let w = t.extent()[0] >> lod;
    t.mips[lod as usize][(y * w + x) as usize]
}

/// Same operations, same order as `wants_refine` in traverse_common.glsl.
fn wants_refine(t: &QuadtreeShadow, g: &GpuInputs, n: NodeId, slot: u32) -> bool {
    let [w0, w1] = t.descs[slot as usize];
    let size = g.sector_size_m * (1u32 << n.lod) as f32;
    let bmin = [n.x as f32 * size, n.y as f32 * size, g.height_lo + (w0 & 0xFFFF) as f32 * g.height_scale];
    let bmax = [bmin[0] + size, bmin[1] + size, g.height_lo + (w0 >> 16) as f32 * g.height_scale];
    let bias = ((((w1 >> 14) & 0xF) as i32) << 28) >> 28;
    let err = t.errors[slot as usize] * 2f32.powi(bias);
    let target_sq = g.target_error_px * g.target_error_px;
    g.cameras[..g.camera_count as usize].iter().any(|c| {
        let o: Vec<f32> = (0..3).map(|i| (bmin[i] - c[i]).max(c[i] - bmax[i]).max(0.0)).collect();
        let d2 = (o[0] * o[0] + o[1] * o[1] + o[2] * o[2]).max(1e-6);
        let lhs = err * c[3];
        lhs * lhs > target_sq * d2
    })
}

/// Valid children to draw instead of `n`, or empty to keep `n`.
fn refinable_children(t: &QuadtreeShadow, g: &GpuInputs, n: NodeId, slot: u32) -> Vec<NodeId> {
    let Some(children) = n.children() else { return Vec::new() };
    let mut kids = Vec::new();
    for c in children {
        match value(t, c.lod, c.x, c.y) {
            EMPTY => return Vec::new(),
            INVALID => {}
            _ => kids.push(c),
        }
    }
    if kids.is_empty() || !wants_refine(t, g, n, slot) {
        return Vec::new();
    }
    kids
}

/// The final node list for the resident set in `tree`, with ample lists
/// (no overflow), as the GPU must produce it (as a set).
pub fn traverse_cpu(tree: &QuadtreeShadow, world: &WorldDesc, params: &TraverseParams) -> TraverseResult {
    let g = GpuInputs::new(world, params);
    let mut out = TraverseResult::default();
    let root = world.root_lod();
    let mut list = Vec::new();
    let [gx, gy] = world.grid(root);
    for y in 0..gy {
        for x in 0..gx {
            match value(tree, root, x, y) {
                EMPTY => out.missing_roots += 1,
                INVALID => {}
                _ => list.push(NodeId::new(root, x, y)),
            }
        }
    }
    while !list.is_empty() {
        let mut next = Vec::new();
        for n in list {
            let slot = u32::from(value(tree, n.lod, n.x, n.y));
            let kids = refinable_children(tree, &g, n, slot);
            if kids.is_empty() {
                out.lod_counts[n.lod as usize] += 1;
                out.nodes.push((n, slot));
            } else {
                next.extend(kids);
            }
        }
        list = next;
    }
    out.nodes.sort();
    out
}

/// Per LOD, the nodes of the final list that the camera wants finer but
/// whose children are not all resident (streaming has not caught up): the
/// gap between what is drawn and what the view asked for.
pub fn wanted_finer_cpu(tree: &QuadtreeShadow, world: &WorldDesc, params: &TraverseParams) -> [u32; 16] {
    let g = GpuInputs::new(world, params);
    let result = traverse_cpu(tree, world, params);
    let mut out = [0u32; 16];
    for (n, slot) in &result.nodes {
        let Some(children) = n.children() else { continue };
        let missing = children.iter().any(|c| world.is_valid(*c) && value(tree, c.lod, c.x, c.y) == EMPTY);
        if missing && wants_refine(tree, &g, *n, *slot) {
            out[n.lod as usize] += 1;
        }
    }
    out
}

/// The LOD map for a final node list: one byte per sector over the node
/// texture's padded extent, NO_LOD where no listed node covers it.
pub fn lod_map_cpu(result: &TraverseResult, world: &WorldDesc) -> Vec<u8> {
    let [w, h] = crate::quadtree::texture_extent(world);
    let mut map = vec![crate::passes::lod_map::NO_LOD; (w * h) as usize];
    for (n, _) in &result.nodes {
        let k = 1u32 << n.lod;
        for y in n.y * k..((n.y + 1) * k).min(h) {
            for x in n.x * k..((n.x + 1) * k).min(w) {
                map[(y * w + x) as usize] = n.lod;
            }
        }
    }
    map
}

/// Sector data: per sector of the padded extent, 10 bits per LOD (0-2 in
/// word 0, 3-5 in word 1) = the slot of the resident node covering it.
pub fn sector_data_cpu(tree: &QuadtreeShadow, world: &WorldDesc) -> Vec<[u32; 2]> {
    let [w, h] = tree.extent();
    let lods = world.lod_count.min(crate::passes::sector_data::SECTOR_DATA_LODS) as u8;
    let mut out = vec![[0u32; 2]; (w * h) as usize];
    for y in 0..h {
        for x in 0..w {
            let e = &mut out[(y * w + x) as usize];
            for k in 0..lods {
                let v = value(tree, k, x >> k, y >> k);
                let slot = if v == EMPTY || v == INVALID { 0 } else { u32::from(v) };
                e[usize::from(k / 3)] |= slot << (10 * u32::from(k % 3));
            }
        }
    }
    out
}

/// Height (m) at `p` from the finest resident node, bilinear over its R16
/// samples (what terrain_sample.glsl computes), or None where nothing is
/// resident. `heights(slot)` gives a resident node's 129x129 samples.
pub fn sample_height_cpu<'a>(
    tree: &QuadtreeShadow,
    world: &WorldDesc,
    heights: impl Fn(u32) -> &'a [u16],
    p: [f64; 2],
) -> Option<f32> {
    let sector = world.sector_size_m();
    let [w, h] = tree.extent();
    let sx = ((p[0] / sector).floor().max(0.0) as u32).min(w - 1);
    let sy = ((p[1] / sector).floor().max(0.0) as u32).min(h - 1);
    let lods = world.lod_count.min(crate::passes::sector_data::SECTOR_DATA_LODS) as u8;
    let (k, slot) = (0..lods).find_map(|k| {
        let v = value(tree, k, sx >> k, sy >> k);
        (v != EMPTY && v != INVALID).then_some((k, u32::from(v)))
    })?;
    let node = sector * f64::from(1u32 << k);
    let spacing = sector / crate::world::NODE_QUADS as f64 * f64::from(1u32 << k);
    let local = [0, 1].map(|i| ((p[i] - (p[i] / node).floor() * node) / spacing).clamp(0.0, 128.0));
    let i0 = local.map(|l| (l.floor() as usize).min(127));
    let f = [local[0] - i0[0] as f64, local[1] - i0[1] as f64];
    let hs = heights(slot);
    let s = |x: usize, y: usize| f64::from(hs[y * crate::world::NODE_SAMPLES + x]) / 65535.0;
    let a = s(i0[0], i0[1]) * (1.0 - f[0]) + s(i0[0] + 1, i0[1]) * f[0];
    let b = s(i0[0], i0[1] + 1) * (1.0 - f[0]) + s(i0[0] + 1, i0[1] + 1) * f[0];
    let [lo, hi] = world.height_range_m;
    Some((f64::from(lo) + (a * (1.0 - f[1]) + b * f[1]) * f64::from(hi - lo)) as f32)
}
