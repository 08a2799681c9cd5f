//! CPU twin of occlusion culling's depth pyramid (`hiz_build`) and box test
//! (`common/hiz_test.glsl`): the same integer texel arithmetic, written
//! from the shader's documented rules, so tests can check the GPU's
//! pyramid bit for bit and its decisions box for box.

use glam::{Mat4, Vec3, Vec4};

/// A depth pyramid: level 0 first, each row-major with its size.
#[derive(Debug, Clone, PartialEq)]
pub struct Pyramid {
    pub levels: Vec<Vec<f32>>,
    pub sizes: Vec<[u32; 2]>,
}

fn pow2_floor(v: u32) -> u32 {
    1 << v.max(1).ilog2()
}

/// Level 0 from a depth image: each side rounded down to a power of two,
/// each texel the minimum (reversed-Z: farthest) of the pixels
/// [i*W/w0, ceil((i+1)*W/w0)) it covers.
pub fn level0_cpu(depth: &[f32], size: [u32; 2]) -> (Vec<f32>, [u32; 2]) {
    let s0 = [pow2_floor(size[0]), pow2_floor(size[1])];
    let range = |i: u32, src: u32, dst: u32| (i * src / dst)..((i + 1) * src).div_ceil(dst);
    let mut out = Vec::with_capacity((s0[0] * s0[1]) as usize);
    for y in 0..s0[1] {
        for x in 0..s0[0] {
            let mut m = 1.0f32;
            for py in range(y, size[1], s0[1]) {
                for px in range(x, size[0], s0[0]) {
                    m = m.min(depth[(py * size[0] + px) as usize]);
                }
            }
            out.push(m);
        }
    }
    (out, s0)
}

/// The next level: exact 2x2 minima, clamped where a side is already 1.
pub fn reduce_cpu(prev: &[f32], prev_size: [u32; 2]) -> (Vec<f32>, [u32; 2]) {
    let size = prev_size.map(|s| (s / 2).max(1));
    let mut out = Vec::with_capacity((size[0] * size[1]) as usize);
    for y in 0..size[1] {
        for x in 0..size[0] {
            let mut m = 1.0f32;
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let qx = (2 * x + dx).min(prev_size[0] - 1);
                let qy = (2 * y + dy).min(prev_size[1] - 1);
                m = m.min(prev[(qy * prev_size[0] + qx) as usize]);
            }
            out.push(m);
        }
    }
    (out, size)
}

/// The whole pyramid of a depth image.
pub fn pyramid_cpu(depth: &[f32], size: [u32; 2]) -> Pyramid {
    let (l0, s0) = level0_cpu(depth, size);
    let mips = s0[0].max(s0[1]).ilog2() + 1;
    let mut p = Pyramid { levels: vec![l0], sizes: vec![s0] };
    for _ in 1..mips {
        let (l, s) = reduce_cpu(p.levels.last().expect("level 0"), *p.sizes.last().expect("level 0"));
        p.levels.push(l);
        p.sizes.push(s);
    }
    p
}

/// The box test's footprint: level-0 texel range [t0, t1] (inclusive).
pub fn level_for(t0: [u32; 2], t1: [u32; 2], mips: u32) -> u32 {
    let mut l = 0;
    while l + 1 < mips && ((t1[0] >> l) - (t0[0] >> l) > 1 || (t1[1] >> l) - (t0[1] >> l) > 1) {
        l += 1;
    }
    l
}

/// The level public implementations pick from the footprint's size,
/// `floor(log2(max extent))`: the negative control of the tests.
pub fn level_floor_log2(t0: [u32; 2], t1: [u32; 2]) -> u32 {
    let extent = (t1[0] - t0[0] + 1).max(t1[1] - t0[1] + 1);
    extent.ilog2()
}

/// What the box test decided: visible, the level read, and the footprint
/// (None when the box crosses the near plane or covers no pixel).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoxTest {
    pub visible: bool,
    pub level: u32,
    pub footprint: Option<([u32; 2], [u32; 2])>,
    /// Nearest depth of the box and the farthest depth read.
    pub z_nearest: f32,
    pub farthest: f32,
}

/// Twin of `hiz_box_visible` (camera-relative box, column-major matrix).
pub fn box_visible_cpu(lo: Vec3, hi: Vec3, view_proj: Mat4, depth_size: [u32; 2], p: &Pyramid) -> BoxTest {
    let mut t = BoxTest { visible: true, level: 0, footprint: None, z_nearest: 0.0, farthest: 1.0 };
    let (mut uv_lo, mut uv_hi) = ([3.0e38f32; 2], [-3.0e38f32; 2]);
    for c in 0..8u32 {
        let v = Vec3::new(
            if c & 1 != 0 { hi.x } else { lo.x },
            if c & 2 != 0 { hi.y } else { lo.y },
            if c & 4 != 0 { hi.z } else { lo.z },
        );
        let clip = view_proj * Vec4::new(v.x, v.y, v.z, 1.0);
        // As the shader: a NaN w counts as crossing (visible).
        if clip.w.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) || clip.z >= clip.w {
            return t;
        }
        let ndc = clip.truncate() / clip.w;
        for a in 0..2 {
            let uv = ndc[a] * 0.5 + 0.5;
            uv_lo[a] = uv_lo[a].min(uv);
            uv_hi[a] = uv_hi[a].max(uv);
        }
        t.z_nearest = t.z_nearest.max(ndc.z);
    }
    if uv_lo[0] > 1.0 || uv_lo[1] > 1.0 || uv_hi[0] < 0.0 || uv_hi[1] < 0.0 {
        t.visible = false;
        return t;
    }
    let px = |uv: f32, a: usize| (uv * depth_size[a] as f32).floor().clamp(0.0, depth_size[a] as f32 - 1.0) as u32;
    let s0 = p.sizes[0];
    let tex = |uv: f32, a: usize| px(uv, a) * s0[a] / depth_size[a];
    let t0 = [tex(uv_lo[0], 0), tex(uv_lo[1], 1)];
    let t1 = [tex(uv_hi[0], 0), tex(uv_hi[1], 1)];
    let l = level_for(t0, t1, p.levels.len() as u32);
    t.level = l;
    t.footprint = Some((t0, t1));
    let size = p.sizes[l as usize];
    for y in (t0[1] >> l)..=(t1[1] >> l) {
        for x in (t0[0] >> l)..=(t1[0] >> l) {
            t.farthest = t.farthest.min(p.levels[l as usize][(y * size[0] + x) as usize]);
        }
    }
    t.visible = t.z_nearest >= t.farthest;
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every level-0 texel of [t0, t1] lies in the texels read at `level`.
    fn covered(t0: [u32; 2], t1: [u32; 2], level: u32) -> bool {
        // Reading (t0 >> l ..= t1 >> l) covers everything; the question is
        // whether at most 2 texels a side are read.
        (0..2).all(|a| (t1[a] >> level) - (t0[a] >> level) <= 1)
    }

    #[test]
    fn chosen_level_reads_at_most_two_texels_a_side_and_floor_log2_does_not() {
        let mut floor_fails = 0;
        for a in 0..200u32 {
            for w in 1..40u32 {
                let (t0, t1) = ([a, a / 3], [a + w - 1, a / 3 + w / 2]);
                let l = level_for(t0, t1, 12);
                assert!(covered(t0, t1, l), "level {l} reads 3 texels for {t0:?}..{t1:?}");
                // Minimal: one level finer would read 3 a side.
                assert!(l == 0 || !covered(t0, t1, l - 1));
                if !covered(t0, t1, level_floor_log2(t0, t1)) {
                    floor_fails += 1;
                }
            }
        }
        // The pitfall the shader avoids: floor(log2) straddles 3 texels.
        assert!(floor_fails > 100, "floor(log2) straddled only {floor_fails} times");
    }

    #[test]
    fn level0_keeps_edge_pixels_of_non_power_of_two_targets() {
        // 5x3 pixels, the farthest in the last column and row.
        let mut depth = vec![0.5f32; 15];
        depth[4] = 0.1;
        depth[14] = 0.2;
        let (l0, s0) = level0_cpu(&depth, [5, 3]);
        assert_eq!(s0, [4, 2]);
        assert_eq!(l0[3], 0.1, "texel 3 covers pixels 3 and 4 of row 0");
        assert_eq!(l0[7], 0.2, "texel (3, 1) covers the last row and column");
        let p = pyramid_cpu(&depth, [5, 3]);
        assert_eq!(p.sizes, vec![[4, 2], [2, 1], [1, 1]]);
        assert_eq!(p.levels[2][0], 0.1);
    }
}
