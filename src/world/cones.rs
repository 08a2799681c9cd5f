//! Per-patch normal cones for backface culling, computed on exactly the
//! triangles the GPU draws.

use super::layout::{NODE_SAMPLES, PATCH_QUADS};
use crate::shaders::consts::MAX_LOD_DELTA;

/// Angular padding (radians) covering f32 rounding of the stored axis and
/// of the GPU's own normal arithmetic.
const CONE_PAD_RAD: f64 = 1e-4;
/// Refinement steps of the Badoiu-Clarkson enclosing-cone iteration; 32
/// gets within a few percent of the minimal cone, which is plenty for culling.
const CONE_ITERATIONS: u32 = 32;

/// A cone of directions: unit axis and half-angle in radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalCone {
    pub axis: [f64; 3],
    pub half_angle: f64,
}

impl NormalCone {
    /// GPU form: axis xyz + sin(half-angle); a half-angle of 90 degrees or
    /// more cannot be expressed by its sine, so it becomes "never cull".
    pub fn to_gpu(&self) -> [f32; 4] {
        if self.half_angle >= std::f64::consts::FRAC_PI_2 {
            return [0.0, 0.0, 0.0, 1.0];
        }
        let a = self.axis.map(|v| v as f32);
        let s = self.half_angle.sin();
        // Round the sine up: rounding down would shrink the cone.
        let mut s32 = s as f32;
        if f64::from(s32) < s {
            s32 = f32::from_bits(s32.to_bits() + 1);
        }
        if s32 >= 1.0 {
            return [0.0, 0.0, 0.0, 1.0];
        }
        [a[0], a[1], a[2], s32]
    }
}

/// Unit normals of every triangle the GPU may draw for patch (px, py),
/// from `heights` (129x129 decoded metres, row 0 south) with `spacing`
/// metres between samples: its 2 x PATCH_QUADS^2 triangles, and those of
/// its edge quads under every stitching that stays within its corners (an
/// edge next to a coarser patch snaps its vertices to that patch's grid, 1
/// to log2(PATCH_QUADS) levels coarser, as `terrain_vertex.glsl` does), so
/// a patch is cone-tested whatever its neighbours' levels. Patches that
/// stitch further (up to `MAX_LOD_DELTA`) are never cone-tested
/// (`patch_cull.glsl`), so their cones need not hold those variants. Quads whose (x + y) is even are split along the
/// SW-NE diagonal, odd ones along SE-NW, so every odd/odd vertex is the
/// centre of 8 triangles: the diamond pattern the GPU index buffer uses.
/// Degenerate triangles (a snapped edge folds some to a line) draw nothing
/// and are left out.
pub fn patch_triangle_normals(heights: &[f32], spacing: f64, px: u32, py: u32) -> Vec<[f64; 3]> {
    assert_eq!(heights.len(), NODE_SAMPLES * NODE_SAMPLES, "not a node grid");
    let q = PATCH_QUADS;
    let mut out = Vec::with_capacity((q * q * 2) as usize);
    let h = |x: u32, y: u32| f64::from(heights[y as usize * NODE_SAMPLES + x as usize]);
    let deltas = 0..=q.trailing_zeros().min(MAX_LOD_DELTA);
    for qy in 0..q {
        for qx in 0..q {
            // Deltas of the edges this quad touches (west/east, south/north).
            let on_x = qx == 0 || qx == q - 1;
            let on_y = qy == 0 || qy == q - 1;
            for dx in deltas.clone().take(if on_x { usize::MAX } else { 1 }) {
                for dy in deltas.clone().take(if on_y { usize::MAX } else { 1 }) {
                    let p = |di: u32, dj: u32| {
                        let (i, j) = (qx + di, qy + dj);
                        let (x, y) = stitched([px * q + i, py * q + j], i, j, dx, dy, q);
                        [f64::from(x) * spacing, f64::from(y) * spacing, h(x, y)]
                    };
                    let (p00, p10, p01, p11) = (p(0, 0), p(1, 0), p(0, 1), p(1, 1));
                    let tris = if (qx + qy).is_multiple_of(2) {
                        [(p00, p10, p11), (p00, p11, p01)]
                    } else {
                        [(p00, p10, p01), (p10, p11, p01)]
                    };
                    out.extend(tris.iter().filter_map(|&(a, b, c)| tri_normal(a, b, c)));
                }
            }
        }
    }
    out
}

/// Where the vertex shader draws patch vertex (i, j), node sample `node`,
/// when the edges at i = 0 or q take delta `dx` and those at j = 0 or q
/// take `dy`: snapped in node coordinates, so a delta above log2(q) moves
/// it to a coarse vertex beyond the patch's corners (still in the node).
fn stitched(node: [u32; 2], i: u32, j: u32, dx: u32, dy: u32, q: u32) -> (u32, u32) {
    let snap = |v: u32, d: u32| if d == 0 { v } else { ((v + (1 << (d - 1)) - 1) >> d) << d };
    let x = if j == 0 || j == q { snap(node[0], dy) } else { node[0] };
    let y = if i == 0 || i == q { snap(node[1], dx) } else { node[1] };
    (x, y)
}

/// The unit normal, or `None` for a triangle of no area (drawn as nothing).
fn tri_normal(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> Option<[f64; 3]> {
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
    (n != [0.0; 3]).then(|| normalize(n))
}

fn normalize(v: [f64; 3]) -> [f64; 3] {
    let l = dot(v, v).sqrt();
    if l > 0.0 {
        v.map(|c| c / l)
    } else {
        [0.0, 0.0, 1.0]
    }
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Largest angle between `axis` and any of `normals`, radians.
fn max_angle(axis: [f64; 3], normals: &[[f64; 3]]) -> f64 {
    let min_dot = normals.iter().map(|&n| dot(axis, n)).fold(1.0f64, f64::min);
    min_dot.clamp(-1.0, 1.0).acos()
}

/// A small cone containing every normal: start from the mean direction, then
/// walk towards the farthest normal with shrinking steps (Badoiu-Clarkson on
/// the sphere) and keep the best axis seen. The result is padded so f32
/// storage never makes it miss a normal.
pub fn fit_cone(normals: &[[f64; 3]]) -> NormalCone {
    assert!(!normals.is_empty(), "cone of no normals");
    let sum = normals.iter().fold([0.0; 3], |s, n| [s[0] + n[0], s[1] + n[1], s[2] + n[2]]);
    let mut axis = normalize(sum);
    let mut best = (f64::INFINITY, axis);
    for it in 1..=CONE_ITERATIONS + 1 {
        // The farthest normal both measures this axis and steers the next.
        let (min_dot, far) =
            normals
                .iter()
                .map(|&n| (dot(axis, n), n))
                .fold((f64::INFINITY, axis), |a, b| if b.0 < a.0 { b } else { a });
        let angle = min_dot.clamp(-1.0, 1.0).acos();
        if angle < best.0 {
            best = (angle, axis);
        }
        let t = 1.0 / f64::from(it + 1);
        axis = normalize([0, 1, 2].map(|k| axis[k] + (far[k] - axis[k]) * t));
    }
    // Measure again with the axis as the GPU will see it (f32).
    let axis32 = normalize(best.1.map(|v| f64::from(v as f32)));
    NormalCone { axis: axis32, half_angle: max_angle(axis32, normals) + CONE_PAD_RAD }
}

/// Whether GPU cone `cone` (axis + sin half-angle) contains unit normal `n`.
pub fn cone_contains(cone: [f32; 4], n: [f64; 3]) -> bool {
    if cone[3] >= 1.0 {
        return true;
    }
    let axis = normalize([0, 1, 2].map(|k| f64::from(cone[k])));
    let half = f64::from(cone[3]).asin();
    dot(axis, n).clamp(-1.0, 1.0).acos() <= half
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cone_is_tight_and_conservative() {
        // Normals 30 degrees off z in four directions: minimal cone is z, 30.
        let t = 30f64.to_radians();
        let ns: Vec<[f64; 3]> = (0..4)
            .map(|k| {
                let a = f64::from(k) * std::f64::consts::FRAC_PI_2;
                [t.sin() * a.cos(), t.sin() * a.sin(), t.cos()]
            })
            .collect();
        let c = fit_cone(&ns);
        assert!((c.half_angle - t).abs() < 0.02, "{}", c.half_angle);
        let g = c.to_gpu();
        assert!(ns.iter().all(|&n| cone_contains(g, n)));
        // A half-angle of 90 degrees or more cannot be culled.
        let wide = NormalCone { axis: [0.0, 0.0, 1.0], half_angle: 1.6 };
        assert_eq!(wide.to_gpu(), [0.0, 0.0, 0.0, 1.0]);
    }
}
