//! CPU twin of `vt_feedback.comp`: the pages of the virtual texture a
//! frame's samples ask for, from the same depth, normals, classification,
//! view and state words. Position and footprint follow reconstruct.glsl
//! step by step in f32; where a sample sits within a rounding of a level
//! or page boundary (a GPU may fuse or order the arithmetic differently)
//! its requests are also given on the other side of that boundary as
//! `tolerated`, so a test can require every firm request and accept only
//! those alternatives.

use crate::effects::virtual_texture::vt_feedback::VtFeedbackPush;
use crate::scene::view::TerrainViewGpu;
use crate::shaders::consts::{
    FLAVOUR_VIRTUAL_TEXTURE, VT_NONE, VT_REQ_X_SHIFT, VT_REQ_Y_SHIFT, VT_STATE_HEADER, VT_SUB_K_SHIFT, VT_TILE_TEXELS,
};
use glam::{Mat4, Vec2, Vec3, Vec4};
use std::collections::BTreeSet;

/// cos(89.99 degrees), reconstruct.glsl's GRAZING_COS.
const GRAZING_COS: f32 = 1.745e-4;
/// How close (in levels, or in pages) to a boundary a sample's request is
/// taken as either side's.
const BOUNDARY: f32 = 1e-3;

/// One frame's G-buffer and view as the feedback pass read them.
pub struct FeedbackInputs<'a> {
    pub size: [u32; 2],
    /// Reversed-Z depth per pixel (0: no terrain).
    pub depth: &'a [f32],
    /// Geometric and triangle normal codes per pixel.
    pub normals: &'a [[u8; 4]],
    pub classification: &'a [u8],
    pub view: &'a TerrainViewGpu,
    /// The state buffer's words.
    pub state: &'a [u32],
    pub push: VtFeedbackPush,
}

/// The requests (region, level | x << 4 | y << 12): those every device
/// makes, and those a sample at a boundary may make instead.
#[derive(Debug, Default)]
pub struct TwinRequests {
    pub firm: BTreeSet<[u32; 2]>,
    pub tolerated: BTreeSet<[u32; 2]>,
    /// Samples with a boundary within the tolerance.
    pub boundary_samples: u32,
}

/// The octahedral normal code as `oct_decode8` (octahedral.glsl) reads it.
fn oct_decode8(c: [u8; 2]) -> Vec3 {
    Vec3::from(super::octahedral::oct_decode8(c.map(u32::from)).map(|x| x as f32))
}

struct Camera {
    inv: Mat4,
    viewport: Vec4,
}

impl Camera {
    fn ndc(&self, pixel: Vec2) -> Vec2 {
        pixel * Vec2::new(self.viewport.z, self.viewport.w) * 2.0 - 1.0
    }

    fn position(&self, pixel: Vec2, depth: f32) -> Vec3 {
        let h = self.inv * self.ndc(pixel).extend(depth).extend(1.0);
        h.truncate() / h.w
    }

    fn ray_plane(&self, pixel: Vec2, p: Vec3, n: Vec3) -> (Vec3, bool) {
        let d = (self.inv * self.ndc(pixel).extend(0.0).extend(1.0)).truncate();
        let len = d.length();
        let cosi = d.dot(n) / len;
        let parallel = cosi.abs() < GRAZING_COS;
        let guarded = if parallel { GRAZING_COS.copysign(if cosi < 0.0 { -1.0 } else { 1.0 }) } else { cosi };
        let t = p.dot(n) / (guarded * len);
        (d * t, !parallel && t > 0.0)
    }

    fn step(&self, pixel: Vec2, offset: Vec2, p: Vec3, n: Vec3) -> Vec3 {
        let (forward, hit) = self.ray_plane(pixel + offset, p, n);
        if hit {
            return forward - p;
        }
        let (backward, hit) = self.ray_plane(pixel - offset, p, n);
        if hit {
            p - backward
        } else {
            forward - p
        }
    }
}

/// The requests of `inp`'s frame.
pub fn page_requests(inp: &FeedbackInputs) -> TwinRequests {
    let cam =
        Camera { inv: Mat4::from_cols_array_2d(&inp.view.inv_view_proj), viewport: Vec4::from(inp.view.viewport) };
    let w = inp.state;
    let region_m = f32::from_bits(w[4]);
    let camera = Vec3::from_slice(&inp.view.camera_world[..3]);
    let mut out = TwinRequests::default();
    let stride = inp.push.stride;
    let cells = inp.size.map(|s| s.div_ceil(stride));
    for cy in 0..cells[1] {
        for cx in 0..cells[0] {
            let px = [cx * stride + inp.push.jitter[0], cy * stride + inp.push.jitter[1]];
            if px[0] >= inp.size[0] || px[1] >= inp.size[1] {
                continue;
            }
            let i = (px[1] * inp.size[0] + px[0]) as usize;
            let depth = inp.depth[i];
            if inp.classification[i] as u32 & FLAVOUR_VIRTUAL_TEXTURE == 0 || depth <= 0.0 {
                continue;
            }
            let nt = oct_decode8([inp.normals[i][2], inp.normals[i][3]]);
            let pixel = Vec2::new(px[0] as f32 + 0.5, px[1] as f32 + 0.5);
            let p = cam.position(pixel, depth);
            let ddx = cam.step(pixel, Vec2::X, p, nt);
            let ddy = cam.step(pixel, Vec2::Y, p, nt);
            let world = (camera + p).truncate();
            let footprint = ddx.truncate().length().max(ddy.truncate().length());
            let raw = (region_m / (VT_TILE_TEXELS as f32 * footprint.max(1e-9))).log2();
            // The sample's requests, and those of the same sample moved by
            // a rounding in position or level: equal everywhere, or the
            // sample is at a boundary.
            let base = requests_at(w, world, raw);
            let mut all = BTreeSet::new();
            let d = BOUNDARY * region_m;
            for (dx, dy, dl) in (0..27).map(|n| (n % 3, n / 3 % 3, n / 9)) {
                let moved = world + Vec2::new((dx as f32 - 1.0) * d, (dy as f32 - 1.0) * d);
                all.extend(requests_at(w, moved, raw + (dl as f32 - 1.0) * BOUNDARY));
            }
            if all.len() == base.len() && base.iter().all(|e| all.contains(e)) {
                out.firm.extend(base);
            } else {
                out.boundary_samples += 1;
                out.tolerated.extend(all);
            }
        }
    }
    out
}

/// The requests of a sample at `world` whose footprint asks for level
/// `raw` (vt_feedback.comp's `main` after the footprint).
fn requests_at(w: &[u32], world: Vec2, raw: f32) -> BTreeSet<[u32; 2]> {
    let regions = [w[0], w[1]];
    let region_m = f32::from_bits(w[4]);
    let mut out = BTreeSet::new();
    let c = (world / region_m).floor();
    if c.x < 0.0 || c.y < 0.0 || c.x >= regions[0] as f32 || c.y >= regions[1] as f32 {
        return out;
    }
    let region = c.x as u32 + c.y as u32 * regions[0];
    let window = w[7];
    let slot = c.x as u32 % window + (c.y as u32 % window) * window;
    let word = w[(VT_STATE_HEADER + slot) as usize];
    if word == VT_NONE || w[(VT_STATE_HEADER + window * window + slot) as usize] != region {
        return out;
    }
    let k = word >> VT_SUB_K_SHIFT;
    let level = raw.clamp(0.0, k as f32);
    let origin = c * region_m;
    let fine = level.ceil() as u32;
    let coarse = level.floor() as u32;
    for lv in [fine, coarse, 0] {
        let page_m = region_m / (1u32 << lv) as f32;
        let t = (world - origin) / page_m;
        let last = (1u32 << lv) - 1;
        let p = [t.x, t.y].map(|v| (v.floor().max(0.0) as u32).min(last));
        out.insert([region, lv | p[0] << VT_REQ_X_SHIFT | p[1] << VT_REQ_Y_SHIFT]);
    }
    out
}
