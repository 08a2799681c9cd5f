//! The sub-sample pass of [`super::vertex_bounds`]: per block of 256 x 256
//! LOD-0 samples, the finest surface (Catmull-Rom of the stored samples,
//! `REFINE_LEVELS` below them, x then y as the vertex shader evaluates it)
//! on a window 4 samples wider on each side, and the numbers of every
//! vertex of the lattice levels below the sample grid's own (levels 0 to
//! `REFINE_LEVELS`, in lattice units). The window's margin is more than
//! the deepest reach of a kept vertex's children (10 lattice units), so the
//! kept numbers do not depend on where the block ends: a sample on a block
//! border gets the same bits from either side.

use super::bintree::{classify, Kind};
use super::layout::NODE_QUADS;
use super::vertex_rule::{child_points, vertex_numbers, VertexNumbers};
use crate::shaders::consts::REFINE_LEVELS;
use glam::I64Vec2;

/// Block side in samples (two LOD-0 nodes: blocks hold whole nodes).
pub const BLOCK: i64 = 2 * NODE_QUADS as i64;
/// Window margin in samples around a block.
const MARGIN: i64 = 4;
/// Lattice units a sample.
pub const UNITS: i64 = 1 << REFINE_LEVELS;

/// The stored samples a block reads: heights as the bake rounds them
/// (holes keep theirs: the Catmull-Rom taps read them), and hole flags.
pub struct Samples {
    /// First sample held (global index, may be negative).
    pub lo: I64Vec2,
    /// Samples a row, and rows.
    pub size: I64Vec2,
    pub z: Vec<f64>,
    pub hole: Vec<bool>,
}

impl Samples {
    fn index(&self, s: I64Vec2) -> usize {
        let l = s - self.lo;
        debug_assert!(l.cmpge(I64Vec2::ZERO).all() && l.cmplt(self.size).all(), "{s} not read");
        (l.y * self.size.x + l.x) as usize
    }

    pub fn z(&self, s: I64Vec2) -> f64 {
        self.z[self.index(s)]
    }

    pub fn hole(&self, s: I64Vec2) -> bool {
        self.hole[self.index(s)]
    }
}

/// What a block gives the samples' pass: the numbers of its samples whose
/// level is the sample grid's finest, and per LOD-0 node in it, the
/// numbers of its quads' centres merged (the node's refinement bound).
pub struct BlockNumbers {
    /// (sample index in the block, numbers, largest child error: how far
    /// the diamond's halves drawn at the samples lie from the finest
    /// surface), level-`REFINE_LEVELS` samples only.
    pub samples: Vec<(I64Vec2, VertexNumbers, f64)>,
    /// (LOD-0 node, merged quad-centre numbers).
    pub nodes: Vec<(I64Vec2, super::vertex_bounds::NodeRefine)>,
}

/// The window's lattice: heights and numbers of points `lo..=hi`.
struct Window {
    lo: I64Vec2,
    side: i64,
    /// The world lattice's last point (its first is 0).
    last: I64Vec2,
    z: Vec<f64>,
    numbers: Vec<VertexNumbers>,
}

impl Window {
    fn inside(&self, v: I64Vec2) -> bool {
        let l = v - self.lo;
        l.cmpge(I64Vec2::ZERO).all()
            && l.cmplt(I64Vec2::splat(self.side)).all()
            && v.cmpge(I64Vec2::ZERO).all()
            && v.cmple(self.last).all()
    }

    fn at(&self, v: I64Vec2) -> usize {
        let l = v - self.lo;
        (l.y * self.side + l.x) as usize
    }
}

/// Stored sample row `row` interpolated along x (Catmull-Rom) at lattice
/// columns `lo..lo + side`: the first half of the finest surface's
/// evaluation, shared by every point of those columns.
fn x_row(samples: &Samples, lo: i64, side: i64, row: i64) -> Vec<f64> {
    (lo..lo + side)
        .map(|u| {
            let c = u.div_euclid(UNITS);
            let wx = super::source::catmull_rom((u - c * UNITS) as f64 / UNITS as f64);
            (0..4).map(|a| wx[a] * samples.z(I64Vec2::new(c + a as i64 - 1, row))).sum::<f64>()
        })
        .collect()
}

/// The finest surface over the window `lo..lo + side` (NaN where a
/// point's nearest sample, ties up, is a hole: the vertex shader's rule
/// below LOD 0): along x over four rows, then along y, as
/// `reference::FinestSurface` sums it (the same operations in the same
/// order, so the same bits), each row's x pass done once.
fn window_heights(samples: &Samples, lo: I64Vec2, side: i64) -> Vec<f64> {
    let first = lo.y.div_euclid(UNITS) - 1;
    let last = (lo.y + side - 1).div_euclid(UNITS) + 2;
    let rows: Vec<Vec<f64>> = (first..=last).map(|r| x_row(samples, lo.x, side, r)).collect();
    let mut out = Vec::with_capacity((side * side) as usize);
    for j in 0..side {
        let v = lo.y + j;
        let cj = v.div_euclid(UNITS);
        let wy = super::source::catmull_rom((v - cj * UNITS) as f64 / UNITS as f64);
        for i in 0..side {
            let u = lo.x + i;
            let near = I64Vec2::new((u + UNITS / 2).div_euclid(UNITS), (v + UNITS / 2).div_euclid(UNITS));
            let on_post = u.rem_euclid(UNITS) == 0 && v.rem_euclid(UNITS) == 0;
            out.push(if samples.hole(near) {
                f64::NAN
            } else if on_post {
                samples.z(I64Vec2::new(u / UNITS, v / UNITS))
            } else {
                (0..4).map(|b| wy[b] * rows[(cj + b as i64 - 1 - first) as usize][i as usize]).sum()
            });
        }
    }
    out
}

/// The block of samples `origin..origin + BLOCK` (clipped to the lattice's
/// `last` sample): `samples` must hold `MARGIN + 2` samples around it.
/// Samples whose level is the grid's finest get their numbers here.
pub fn block_numbers(samples: &Samples, origin: I64Vec2, last: I64Vec2) -> BlockNumbers {
    let lo = (origin - I64Vec2::splat(MARGIN)) * UNITS;
    let side = (BLOCK + 2 * MARGIN) * UNITS + 1;
    let mut w = Window { lo, side, last: last * UNITS, z: Vec::new(), numbers: Vec::new() };
    w.z = window_heights(samples, lo, side);
    w.numbers = vec![VertexNumbers::EMPTY; (side * side) as usize];
    for t in 0..=REFINE_LEVELS {
        fill(&mut w, t, Kind::Edge);
        fill(&mut w, t, Kind::Centre);
    }
    let end = (origin + I64Vec2::splat(BLOCK - 1)).min(last);
    let mut out = BlockNumbers { samples: Vec::new(), nodes: Vec::new() };
    for y in origin.y..=end.y {
        for x in origin.x..=end.x {
            let s = I64Vec2::new(x, y);
            if s != I64Vec2::ZERO && classify(s * UNITS).0 == REFINE_LEVELS {
                out.samples.push((s, w.numbers[w.at(s * UNITS)], below(&w, s * UNITS)));
            }
        }
    }
    let node_side = i64::from(NODE_QUADS);
    for ny in (origin.y..=end.y.min(last.y - 1)).step_by(node_side as usize) {
        for nx in (origin.x..=end.x.min(last.x - 1)).step_by(node_side as usize) {
            out.nodes.push((I64Vec2::new(nx, ny) / node_side, node_refine(&w, I64Vec2::new(nx, ny))));
        }
    }
    out
}

/// The largest error among `v`'s children (none empty).
fn below(w: &Window, v: I64Vec2) -> f64 {
    let kids = child_points(v).into_iter().flatten().filter(|c| w.inside(*c));
    kids.map(|c| w.numbers[w.at(c)]).filter(|n| !n.empty).map(|n| n.error_m).fold(0.0, f64::max)
}

/// Numbers of every window vertex of level `t` and `kind`: only those
/// points are visited (a centre's coordinates are both odd multiples of
/// 2^t, an edge midpoint's one of them), and a vertex whose diamond and
/// children (all within 2^t each way) lie inside the window and the
/// lattice skips the bounds tests (the same numbers: every test passes).
/// A level's vertices read only finer levels' numbers (a centre's
/// children are its level's edge midpoints, filled first), so each is
/// stored as it is found.
fn fill(w: &mut Window, t: u32, kind: Kind) {
    let d = 1i64 << t;
    let to = (w.lo + I64Vec2::splat(w.side - 1)).min(w.last);
    let (safe_lo, safe_hi) = (w.lo.max(I64Vec2::ZERO) + I64Vec2::splat(d), to - I64Vec2::splat(d));
    // The first multiple of `step` past `offset` at or after `lo`.
    let first = |lo: i64, offset: i64, step: i64| lo.max(0) + (offset - lo.max(0)).rem_euclid(step);
    let grids: &[(i64, i64)] = match kind {
        Kind::Centre => &[(d, d)],
        Kind::Edge => &[(d, 0), (0, d)],
    };
    for &(ox, oy) in grids {
        for y in (first(w.lo.y, oy, 2 * d)..=to.y).step_by(2 * d as usize) {
            for x in (first(w.lo.x, ox, 2 * d)..=to.x).step_by(2 * d as usize) {
                let v = I64Vec2::new(x, y);
                if v == I64Vec2::ZERO {
                    continue;
                }
                debug_assert_eq!(classify(v), (t, kind));
                let interior = v.cmpge(safe_lo).all() && v.cmple(safe_hi).all();
                let n = if interior {
                    vertex_numbers(v, |_| true, |p| w.z[w.at(p)], |p| w.numbers[w.at(p)])
                } else {
                    vertex_numbers(v, |p| w.inside(p), |p| w.z[w.at(p)], |p| w.numbers[w.at(p)])
                };
                let i = w.at(v);
                w.numbers[i] = n;
            }
        }
    }
}

/// The quad centres of the LOD-0 node whose first sample is `first`
/// merged: the largest error, the lowest and highest box.
fn node_refine(w: &Window, first: I64Vec2) -> super::vertex_bounds::NodeRefine {
    let mut r = super::vertex_bounds::NodeRefine::default();
    for qy in 0..i64::from(NODE_QUADS) {
        for qx in 0..i64::from(NODE_QUADS) {
            let c = (first + I64Vec2::new(qx, qy)) * UNITS + I64Vec2::splat(UNITS / 2);
            if w.inside(c) {
                r.merge(w.z[w.at(c)], &w.numbers[w.at(c)]);
            }
        }
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `fill` with its interior shortcut gives every vertex the numbers
    /// the rule gives it visiting every point with the bounds tested, on
    /// a window across the lattice's corner with holes in it.
    #[test]
    fn fill_equals_the_rule_at_every_point() {
        let (lo, side, last) = (I64Vec2::new(-9, -5), 61, I64Vec2::new(40, 47));
        let z = (0..side * side)
            .map(|i| {
                let (x, y) = ((i % side) as f64, (i / side) as f64);
                let hole = (x - 30.0).hypot(y - 20.0) < 4.0;
                if hole {
                    f64::NAN
                } else {
                    (x * 0.37).sin() * 9.0 + (y * 0.21).cos() * 5.0 + (i * 7919 % 13) as f64 * 0.1
                }
            })
            .collect();
        let window = || Window {
            lo,
            side,
            last,
            z: Vec::clone(&z),
            numbers: vec![VertexNumbers::EMPTY; (side * side) as usize],
        };
        let (mut fast, mut slow) = (window(), window());
        for t in 0..=REFINE_LEVELS {
            for kind in [Kind::Edge, Kind::Centre] {
                fill(&mut fast, t, kind);
                let mut found = Vec::new();
                for k in 0..side * side {
                    let v = lo + I64Vec2::new(k % side, k / side);
                    if slow.inside(v) && v != I64Vec2::ZERO && classify(v) == (t, kind) {
                        let w = &slow;
                        found.push((
                            w.at(v),
                            vertex_numbers(v, |p| w.inside(p), |p| w.z[w.at(p)], |p| w.numbers[w.at(p)]),
                        ));
                    }
                }
                found.into_iter().for_each(|(i, n)| slow.numbers[i] = n);
            }
        }
        let bits = |n: &VertexNumbers| (n.error_m.to_bits(), n.reach_m.to_bits(), n.empty);
        let differ = fast.numbers.iter().zip(&slow.numbers).filter(|(a, b)| bits(a) != bits(b)).count();
        assert_eq!(differ, 0);
        assert!(
            slow.numbers.iter().any(|n| n.error_m.is_infinite())
                && slow.numbers.iter().filter(|n| !n.empty).count() > 1000
        );
    }
}
