//! CPU reference of the GPU quadtree traversal, making the same f32
//! decisions in the same order as `traverse_common.glsl`. Tests compare the
//! `traverse` pass against it; the stats and the CLI use it to explain a
//! frame. No Vulkan.

use crate::shaders::consts as k;
use crate::terrain::quadtree::{QuadtreeShadow, EMPTY, INVALID};
use crate::terrain::selection::{GpuInputs, TraverseParams, TraverseResult};
use crate::world::{NodeId, WorldDesc};

/// Same operations, same order as `wants_refine` in traverse_common.glsl.
fn wants_refine(t: &QuadtreeShadow, g: &GpuInputs, n: NodeId, slot: u32) -> bool {
    let [w0, w1] = t.descs[slot as usize];
    let size = g.sector_size_m * (1u32 << n.lod) as f32;
    let grow = g.box_pad * size;
    let corner = [n.x as f32 * size, n.y as f32 * size];
    let bmin = [corner[0] - grow, corner[1] - grow, g.height_lo + (w0 & 0xFFFF) as f32 * g.height_scale];
    let bmax =
        [corner[0] + size + grow, corner[1] + size + grow, g.height_lo + (w0 >> k::HALF_BITS) as f32 * g.height_scale];
    // Sign-extend the 4-bit bias.
    let spare = 32 - k::DESC_BIAS_BITS;
    let bias = (((w1 >> k::DESC_BIAS_SHIFT) as i32) << spare) >> spare;
    let err = t.errors[slot as usize] * 2f32.powi(bias);
    let target_sq = g.target_error_px * g.target_error_px;
    let n = g.camera_count as usize;
    g.cameras[..n].iter().zip(&g.forwards[..n]).any(|(c, f)| {
        let o: Vec<f32> = (0..3).map(|i| (bmin[i] - c[i]).max(c[i] - bmax[i]).max(0.0)).collect();
        let d2 = (o[0] * o[0] + o[1] * o[1] + o[2] * o[2]).max(1e-6);
        let lhs = err * c[3];
        let widest = lhs * f[3];
        if widest * widest <= target_sq * d2 {
            return false;
        }
        (0..8).any(|k| {
            let v: Vec<f32> = (0..3).map(|i| if k & (1 << i) != 0 { bmax[i] } else { bmin[i] } - c[i]).collect();
            let z = v[0] * f[0] + v[1] * f[1] + v[2] * f[2];
            let l2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            let a = lhs * l2;
            let zz = z * z;
            z <= 0.0 || a * a > target_sq * d2 * (zz * zz)
        })
    })
}

/// Valid children to draw instead of `n`, or empty to keep `n`.
fn refinable_children(t: &QuadtreeShadow, g: &GpuInputs, n: NodeId, slot: u32) -> Vec<NodeId> {
    let Some(children) = n.children() else { return Vec::new() };
    let mut kids = Vec::new();
    for c in children {
        match t.texel(c.lod, c.x, c.y) {
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
            match tree.texel(root, x, y) {
                EMPTY => out.missing_roots += 1,
                INVALID => {}
                _ => list.push(NodeId::new(root, x, y)),
            }
        }
    }
    while !list.is_empty() {
        let mut next = Vec::new();
        for n in list {
            let slot = u32::from(tree.texel(n.lod, n.x, n.y));
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
        let missing = children.iter().any(|c| world.is_valid(*c) && tree.texel(c.lod, c.x, c.y) == EMPTY);
        if missing && wants_refine(tree, &g, *n, *slot) {
            out[n.lod as usize] += 1;
        }
    }
    out
}
