//! One root's share of the error tree, computed from the LOD-0 samples
//! under it (see [`super::errors`] for what the numbers mean).
//!
//! The root is walked in blocks of at most 1024 x 1024 LOD-0 quads (a few
//! MiB each, in parallel). In a block:
//! - every LOD-0 sample is taken from the source exactly as the bake takes
//!   it (same position bits, same R16 rounding), plus one sample of border
//!   for the Catmull-Rom taps;
//! - every LOD-0 quad gets the 5 x 5 vertices of the finest surface (4x
//!   denser, Catmull-Rom of the samples, x then y as the vertex shader
//!   evaluates it), and from them: how far LOD 0's two triangles and the
//!   2x refinement's eight lie from it (exact: each triangulation nests in
//!   the next, so the largest gap is at a finest vertex), and its height
//!   range;
//! - for every coarser level k, how far level k's triangles lie from LOD 0
//!   at every sample (exact for the same reason), plus the quad's LOD-0
//!   gap: the triangle inequality bounds level k against the finest surface.
//!
//! Patches then take the largest value of their quads and a bound of their
//! 99th percentile ([`super::error_quantile`]), and the tree is made
//! monotone by construction: a patch's errors and height range cover those
//! of the four finer patches under it.

use rayon::prelude::*;

use super::error_quantile::Histogram;
use super::layout::{NodeId, WorldDesc, NODE_QUADS, PATCHES_PER_NODE, PATCHES_PER_NODE_SIDE, PATCH_QUADS};
use super::source::HeightSource;

/// Largest block side in LOD-0 quads: 1029^2 samples of f64 (8.5 MiB).
const MAX_BLOCK_QUADS: usize = 1024;

/// Catmull-Rom weights at t = 0, 1/4, 1/2, 3/4 and 1 (the finest surface's
/// vertices inside a LOD-0 quad).
const CR: [[f64; 4]; 5] = {
    let mut w = [[0.0; 4]; 5];
    let mut i = 0;
    while i < 5 {
        w[i] = super::source::catmull_rom(i as f64 / 4.0);
        i += 1;
    }
    w
};

/// Height at (u, v) in 0..=1 of a quad split along one diagonal: SW-NE
/// ("/") when `slash`, else NW-SE; the diamond pattern's choice is
/// `slash = (qx + qy) even` for quad (qx, qy) of its level's lattice.
pub fn diamond(h: [f64; 4], u: f64, v: f64, slash: bool) -> f64 {
    let [h00, h10, h01, h11] = h;
    if slash {
        if v <= u {
            h00 + u * (h10 - h00) + v * (h11 - h10)
        } else {
            h00 + v * (h01 - h00) + u * (h11 - h01)
        }
    } else if u + v <= 1.0 {
        h00 + u * (h10 - h00) + v * (h01 - h00)
    } else {
        h11 + (1.0 - u) * (h01 - h11) + (1.0 - v) * (h10 - h11)
    }
}

/// Per-patch numbers of one level of one root, row-major over the root's
/// patches of that level.
#[derive(Clone, Debug, Default)]
pub struct LevelPatches {
    pub side: usize,
    /// Error (m) of the level's own triangles against the finest surface.
    pub error: Vec<f32>,
    /// LOD 0 only: error of the 2x refinement; 0 elsewhere.
    pub refine: Vec<f32>,
    /// Upper bounds of the 99th percentile of `error` and `refine` over the
    /// patch's LOD-0 quads.
    pub error_q: Vec<f32>,
    pub refine_q: Vec<f32>,
    /// LOD-0 representation error (LOD 0 against the finest surface), the
    /// largest over the patch's area.
    pub repr: Vec<f32>,
    /// Height range of the finest surface over the patch, metres.
    pub lo: Vec<f64>,
    pub hi: Vec<f64>,
    /// While a root is computed: the error histograms of patches larger
    /// than a block, summed over their blocks (empty otherwise).
    pub partial: Vec<Histogram>,
}

impl LevelPatches {
    fn new(side: usize) -> Self {
        let n = side * side;
        LevelPatches {
            side,
            error: vec![0.0; n],
            refine: vec![0.0; n],
            error_q: vec![0.0; n],
            refine_q: vec![0.0; n],
            partial: Vec::new(),
            repr: vec![0.0; n],
            lo: vec![f64::INFINITY; n],
            hi: vec![f64::NEG_INFINITY; n],
        }
    }
}

/// Errors and bounds of every patch of every level under `root`, index =
/// LOD.
pub fn compute_root(world: &WorldDesc, source: &dyn HeightSource, root: NodeId) -> Vec<LevelPatches> {
    let r = usize::from(root.lod);
    let side_q = (NODE_QUADS as usize) << r;
    let block = side_q.min(MAX_BLOCK_QUADS);
    let per_side = side_q / block;
    let origin = [root.x as usize * side_q, root.y as usize * side_q];
    // Blocks holding at least one valid sector.
    let sectors = world.sectors();
    let blocks: Vec<[usize; 2]> = (0..per_side * per_side)
        .map(|b| [b % per_side, b / per_side])
        .filter(|b| (0..2).all(|a| origin[a] + b[a] * block < sectors[a] as usize * NODE_QUADS as usize))
        .collect();
    let results: Vec<([usize; 2], Vec<LevelPatches>)> = blocks
        .par_iter()
        .map(|&b| (b, Block::sample(world, source, [origin[0] + b[0] * block, origin[1] + b[1] * block], block).run(r)))
        .collect();
    let mut levels: Vec<LevelPatches> =
        (0..=r).map(|k| LevelPatches::new((PATCHES_PER_NODE_SIDE as usize) << (r - k))).collect();
    for (b, parts) in results {
        for (k, part) in parts.iter().enumerate() {
            merge(&mut levels[k], part, [b[0] * block, b[1] * block], (PATCH_QUADS as usize) << k);
        }
    }
    for l in &mut levels {
        for (p, h) in std::mem::take(&mut l.partial).iter().enumerate() {
            l.error_q[p] = h.quantile(l.error[p]);
        }
    }
    make_monotone(&mut levels);
    levels
}

/// Computes (and drops) one block of `quads` x `quads` LOD-0 quads at
/// LOD-0 sample `origin` with the levels of a root at `root_lod`: what the
/// plan times to estimate a whole tree (the cost is per LOD-0 quad).
pub fn compute_block(world: &WorldDesc, source: &dyn HeightSource, origin: [usize; 2], quads: usize, root_lod: u8) {
    std::hint::black_box(Block::sample(world, source, origin, quads).run(usize::from(root_lod)));
}

/// Folds a block's patches (at `offset` quads into the root, patches of
/// `patch_q` quads) into the root's.
fn merge(into: &mut LevelPatches, part: &LevelPatches, offset: [usize; 2], patch_q: usize) {
    let base = [offset[0] / patch_q, offset[1] / patch_q];
    for j in 0..part.side {
        for i in 0..part.side {
            let (s, d) = (j * part.side + i, (base[1] + j) * into.side + base[0] + i);
            into.error[d] = into.error[d].max(part.error[s]);
            into.refine[d] = into.refine[d].max(part.refine[s]);
            into.error_q[d] = into.error_q[d].max(part.error_q[s]);
            into.refine_q[d] = into.refine_q[d].max(part.refine_q[s]);
            if let Some(h) = part.partial.get(s) {
                if into.partial.is_empty() {
                    into.partial = vec![Histogram::default(); into.error.len()];
                }
                into.partial[d].merge(h);
            }
            into.repr[d] = into.repr[d].max(part.repr[s]);
            into.lo[d] = into.lo[d].min(part.lo[s]);
            into.hi[d] = into.hi[d].max(part.hi[s]);
        }
    }
}

/// Each patch covers the four finer patches under it: errors, LOD-0
/// representation error and height range; LOD 0 covers its refinement.
fn make_monotone(levels: &mut [LevelPatches]) {
    for p in 0..levels[0].error.len() {
        levels[0].error[p] = levels[0].error[p].max(levels[0].refine[p]);
        levels[0].error_q[p] = levels[0].error_q[p].max(levels[0].refine_q[p]);
    }
    for k in 1..levels.len() {
        let (fine, coarse) = levels.split_at_mut(k);
        let (fine, coarse) = (&fine[k - 1], &mut coarse[0]);
        for j in 0..coarse.side {
            for i in 0..coarse.side {
                let d = j * coarse.side + i;
                for c in 0..4 {
                    let s = (2 * j + c / 2) * fine.side + 2 * i + c % 2;
                    coarse.error[d] = coarse.error[d].max(fine.error[s]);
                    coarse.error_q[d] = coarse.error_q[d].max(fine.error_q[s]);
                    coarse.repr[d] = coarse.repr[d].max(fine.repr[s]);
                    coarse.lo[d] = coarse.lo[d].min(fine.lo[s]);
                    coarse.hi[d] = coarse.hi[d].max(fine.hi[s]);
                }
            }
        }
    }
}

/// The LOD-0 samples of one block, with one sample of border.
struct Block {
    quads: usize,
    /// Global LOD-0 index of the block's first sample (border excluded).
    origin: [usize; 2],
    /// (quads + 3)^2 decoded heights, row-major; sample (i, j) of the block
    /// (i, j in -1..=quads + 1) at [(j + 1) * side + i + 1].
    h: Vec<f64>,
    side: usize,
}

impl Block {
    fn sample(world: &WorldDesc, source: &dyn HeightSource, origin: [usize; 2], quads: usize) -> Block {
        let side = quads + 3;
        let [ex, ey] = world.extent_m;
        let mut h = vec![0.0; side * side];
        let xs: Vec<f64> = (0..side)
            .map(|i| world.grid_pos(0, origin[0] as i64 + i as i64 - 1, world.spacing_m).clamp(0.0, ex))
            .collect();
        h.par_chunks_exact_mut(side).enumerate().for_each_init(
            || vec![0f32; side],
            |raw, (j, row)| {
                let y = world.grid_pos(1, origin[1] as i64 + j as i64 - 1, world.spacing_m).clamp(0.0, ey);
                source.sample_row(&xs, y, raw);
                for (v, r) in row.iter_mut().zip(raw.iter()) {
                    *v = f64::from(world.decode_height(world.encode_height(*r)));
                }
            },
        );
        Block { quads, origin, h, side }
    }

    fn at(&self, i: usize, j: usize) -> f64 {
        self.h[(j + 1) * self.side + i + 1]
    }

    /// Per level 0..=r, the block's patches.
    fn run(&self, r: usize) -> Vec<LevelPatches> {
        let quads = self.quads;
        let patch0 = PATCH_QUADS as usize;
        let mut level0 = LevelPatches::new(quads / patch0);
        // Per quad: the LOD-0 gap to the finest surface (reused by every level).
        let mut gap0 = vec![0f32; quads * quads];
        let w4 = 4 * quads + 1;
        // Sample rows interpolated along x at every quarter point, for the
        // 4 rows qy - 1 ..= qy + 2 around the current quad row (a window).
        let mut xrows: Vec<Vec<f64>> = (0..4).map(|k| self.x_row(k)).collect();
        let mut fine = vec![[0.0; 5]; w4];
        let mut hists = vec![[Histogram::default(), Histogram::default()]; level0.error.len()];
        for qy in 0..quads {
            if qy > 0 {
                xrows.rotate_left(1);
                xrows[3] = self.x_row(qy + 3);
            }
            for (x4, f) in fine.iter_mut().enumerate() {
                for (fy, w) in CR.iter().enumerate() {
                    f[fy] = w[0] * xrows[0][x4] + w[1] * xrows[1][x4] + w[2] * xrows[2][x4] + w[3] * xrows[3][x4];
                }
            }
            for qx in 0..quads {
                let q = self.quad(qx, qy, &fine[4 * qx..=4 * qx + 4]);
                gap0[qy * quads + qx] = q.gap0 as f32;
                let p = (qy / patch0) * level0.side + qx / patch0;
                level0.error[p] = level0.error[p].max(q.gap0 as f32);
                level0.refine[p] = level0.refine[p].max(q.gap1 as f32);
                hists[p][0].add(q.gap0 as f32);
                hists[p][1].add(q.gap1 as f32);
                level0.lo[p] = level0.lo[p].min(q.lo);
                level0.hi[p] = level0.hi[p].max(q.hi);
            }
        }
        for (p, [h0, h1]) in hists.iter().enumerate() {
            level0.error_q[p] = h0.quantile(level0.error[p]);
            level0.refine_q[p] = h1.quantile(level0.refine[p]);
        }
        level0.repr.clone_from(&level0.error);
        let mut out = vec![level0];
        let mut dev = vec![0f32; (quads + 1) * (quads + 1)];
        for k in 1..=r {
            self.level_deviation(k, &mut dev);
            let patch_q = patch0 << k;
            let mut level = LevelPatches::new(quads.div_ceil(patch_q));
            let mut hists = vec![Histogram::default(); level.error.len()];
            for qy in 0..quads {
                for qx in 0..quads {
                    let d = |i: usize, j: usize| dev[j * (quads + 1) + i];
                    let m = d(qx, qy).max(d(qx + 1, qy)).max(d(qx, qy + 1)).max(d(qx + 1, qy + 1));
                    let p = (qy / patch_q) * level.side + qx / patch_q;
                    let e = m + gap0[qy * quads + qx];
                    level.error[p] = level.error[p].max(e);
                    hists[p].add(e);
                }
            }
            if patch_q <= quads {
                for (p, h) in hists.iter().enumerate() {
                    level.error_q[p] = h.quantile(level.error[p]);
                }
            } else {
                // Part of a patch larger than the block: summed in compute_root.
                level.partial = hists;
            }
            out.push(level);
        }
        out
    }

    /// |level k's surface - LOD 0| at every sample of the block (quads + 1
    /// per side): level k's vertices are the samples at multiples of 2^k,
    /// and the block is aligned to them.
    fn level_deviation(&self, k: usize, dev: &mut [f32]) {
        let (n, step) = (self.quads + 1, 1usize << k);
        for j in 0..n {
            for i in 0..n {
                let (ci, cj) = ((i / step).min(self.quads / step - 1), (j / step).min(self.quads / step - 1));
                let (i0, j0) = (ci * step, cj * step);
                let corners =
                    [self.at(i0, j0), self.at(i0 + step, j0), self.at(i0, j0 + step), self.at(i0 + step, j0 + step)];
                let (u, v) = ((i - i0) as f64 / step as f64, (j - j0) as f64 / step as f64);
                // Global level-k quad parity (the block origin is a multiple of 2^k).
                let g = (self.origin[0] >> k) + ci + (self.origin[1] >> k) + cj;
                let p = diamond(corners, u, v, g.is_multiple_of(2));
                dev[j * n + i] = (p - self.at(i, j)).abs() as f32;
            }
        }
    }

    /// Stored row `s` (sample row s - 1) interpolated along x at every
    /// quarter point of the block: Catmull-Rom over the 4 samples around
    /// each quad (its last point is the last quad's t = 1).
    fn x_row(&self, s: usize) -> Vec<f64> {
        let row = &self.h[s * self.side..(s + 1) * self.side];
        let mut out = Vec::with_capacity(4 * self.quads + 1);
        for qx in 0..self.quads {
            let t = [row[qx], row[qx + 1], row[qx + 2], row[qx + 3]];
            for w in &CR[..4] {
                out.push(w[0] * t[0] + w[1] * t[1] + w[2] * t[2] + w[3] * t[3]);
            }
        }
        out.push(row[self.quads + 1]);
        out
    }

    /// LOD-0 quad (qx, qy) against the finest surface, whose 5 x 5 vertices
    /// over it are `fine[fx][fy]` (x then y interpolated, as the vertex
    /// shader evaluates them): the gaps of LOD 0 and of the 2x refinement,
    /// and its height range.
    fn quad(&self, qx: usize, qy: usize, fine: &[[f64; 5]]) -> QuadStats {
        let g = [self.origin[0] + qx, self.origin[1] + qy];
        let lod0 = [self.at(qx, qy), self.at(qx + 1, qy), self.at(qx, qy + 1), self.at(qx + 1, qy + 1)];
        let slash0 = (g[0] + g[1]).is_multiple_of(2);
        let mut s = QuadStats { gap0: 0.0, gap1: 0.0, lo: f64::INFINITY, hi: f64::NEG_INFINITY };
        for (fx, col) in fine.iter().enumerate() {
            for (fy, &z) in col.iter().enumerate() {
                let (u, v) = (fx as f64 / 4.0, fy as f64 / 4.0);
                s.gap0 = s.gap0.max((diamond(lod0, u, v, slash0) - z).abs());
                // The 2x refinement's quad (half-sample lattice) holding this vertex.
                let (hx, hy) = ((fx / 2).min(1), (fy / 2).min(1));
                let c = |a: usize, b: usize| fine[2 * hx + 2 * a][2 * hy + 2 * b];
                let corners = [c(0, 0), c(1, 0), c(0, 1), c(1, 1)];
                let (u1, v1) = ((fx - 2 * hx) as f64 / 2.0, (fy - 2 * hy) as f64 / 2.0);
                let slash1 = (2 * g[0] + hx + 2 * g[1] + hy).is_multiple_of(2);
                s.gap1 = s.gap1.max((diamond(corners, u1, v1, slash1) - z).abs());
                s.lo = s.lo.min(z);
                s.hi = s.hi.max(z);
            }
        }
        s
    }
}

struct QuadStats {
    gap0: f64,
    gap1: f64,
    lo: f64,
    hi: f64,
}

/// Patches of one node in a level's root-wide arrays: 8 x 8 starting at the
/// node's offset in the root.
pub fn node_patches(levels: &[LevelPatches], root: NodeId, id: NodeId) -> impl Iterator<Item = usize> + '_ {
    let l = &levels[usize::from(id.lod)];
    let shift = root.lod - id.lod;
    let side = PATCHES_PER_NODE_SIDE as usize;
    let (x0, y0) = ((id.x - (root.x << shift)) as usize * side, (id.y - (root.y << shift)) as usize * side);
    (0..PATCHES_PER_NODE).map(move |p| (y0 + p / side) * l.side + x0 + p % side)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn diamond_interpolates_its_corners_and_splits_along_the_right_diagonal() {
        let h = [1.0, 2.0, 3.0, 10.0];
        for slash in [true, false] {
            assert_eq!(diamond(h, 0.0, 0.0, slash), 1.0);
            assert_eq!(diamond(h, 1.0, 0.0, slash), 2.0);
            assert_eq!(diamond(h, 0.0, 1.0, slash), 3.0);
            assert_eq!(diamond(h, 1.0, 1.0, slash), 10.0);
        }
        // Centre: mean of the diagonal's ends.
        assert_eq!(diamond(h, 0.5, 0.5, true), 5.5);
        assert_eq!(diamond(h, 0.5, 0.5, false), 2.5);
    }

    #[test]
    fn catmull_rom_weights_interpolate_the_samples() {
        assert_eq!(CR[0], [0.0, 1.0, 0.0, 0.0]);
        assert_eq!(CR[4], [0.0, 0.0, 1.0, 0.0]);
        for w in CR {
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        }
    }
}
