//! Every vertex's numbers for the per-triangle rule ([`super::vertex_rule`])
//! over a whole world, the way nodes carry them: per node, its 129 x 129
//! grid points' saturated error and vertical reach (f16 each, rounded up;
//! in the heights' atlas layout, with the points past the node around),
//! and a refinement bound (its quads' centres merged: what the traversal
//! tests before it draws the node's children).
//!
//! A vertex's numbers depend on every lattice point under it, across node
//! borders and up to the root's size, so they are computed for the whole
//! world at once, from the finest level up, and each node's are read out of
//! the one result: a point shared by two nodes (a border, or a coarser
//! node's grid point that a finer node holds too) has one value, the same
//! bits in every node that holds it.
//!
//! - the levels below the sample grid (Catmull-Rom refinement) in blocks of
//!   two LOD-0 nodes, in parallel (`vertex_bounds_fine`);
//! - the samples' own levels, one half-level at a time over the whole
//!   world, each in parallel, kept as f32 rounded up: the rule's sum
//!   lowered to the diamond's measured gap (`vertex_bounds_exact`),
//!   raised to the children's (14 bytes a sample kept, 2 more while the
//!   levels run).

use super::bintree::{classify, diamond, Bounds, Kind, VertexBound};
use super::holes::Hole;
use super::layout::{NodeId, WorldDesc, NODE_QUADS};
use super::payload::BakedNode;
use super::source::HeightSource;
use super::texels::{ATLAS_BORDER, ATLAS_SIDE};
use super::vertex_bounds_cache::{OwnedParts, Parts};
use super::vertex_bounds_exact::{diamond_gap, SampleGrid};
use super::vertex_bounds_fine::{block_numbers, Samples, BLOCK, UNITS};
use super::vertex_rule::{box_half_width, child_points, up_f16_bits, up_f32, vertex_numbers, VertexNumbers};
use super::WorldError;
use glam::{DVec3, I64Vec2};
use rayon::prelude::*;

/// Most samples a world's bounds are computed for at once (16 bytes each
/// at the peak: 8.6 GB). The default world (20 481^2) is under it.
pub const MAX_BOUNDS_SAMPLES: u64 = 1 << 29;

/// A node's refinement bound: its quads' centres merged (the largest
/// error, the lowest and highest point of their boxes); the traversal
/// draws its children when that error, projected from the box, is over the
/// target. Default: nothing to refine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeRefine {
    pub error_m: f32,
    pub z_lo_m: f32,
    pub z_hi_m: f32,
}

impl Default for NodeRefine {
    fn default() -> Self {
        NodeRefine { error_m: 0.0, z_lo_m: f32::INFINITY, z_hi_m: f32::NEG_INFINITY }
    }
}

impl NodeRefine {
    /// Takes in a centre at height `z` with numbers `n`, as the nodes
    /// store them (f16 rounded up): a test on the merged numbers never
    /// passes a vertex the same test on its own numbers refines.
    pub fn merge(&mut self, z: f64, n: &VertexNumbers) {
        if n.empty {
            return;
        }
        let f16 = |x: f64| half::f16::from_bits(up_f16_bits(up_f32(x))).to_f32();
        self.error_m = self.error_m.max(f16(n.error_m));
        if !z.is_nan() && n.error_m.is_finite() {
            let reach = f64::from(f16(n.reach_m));
            self.z_lo_m = self.z_lo_m.min(-up_f32(reach - z));
            self.z_hi_m = self.z_hi_m.max(up_f32(z + reach));
        }
    }
}

/// A world's per-vertex numbers on its LOD-0 sample lattice.
pub struct VertexBoundsTree {
    world: WorldDesc,
    /// Samples a row (and rows): the roots' grid, one more than its quads.
    side: [usize; 2],
    /// Stored heights (m), holes' too (the Catmull-Rom taps read them).
    z: Vec<f32>,
    hole: Vec<bool>,
    error: Vec<f32>,
    reach: Vec<f32>,
    empty: Vec<bool>,
    /// Per LOD-0 node (row-major over the roots' LOD-0 grid).
    lod0_refine: Vec<NodeRefine>,
}

impl VertexBoundsTree {
    /// Computes every vertex's numbers for `world` sampled from `source`
    /// with `holes` cut (a sample is a hole as the bake decides it).
    pub fn compute(world: &WorldDesc, source: &dyn HeightSource, holes: &[Hole]) -> Result<Self, WorldError> {
        let side = Self::lattice_side(world);
        let points = side[0] as u64 * side[1] as u64;
        if points > MAX_BOUNDS_SAMPLES {
            return Err(WorldError::InvalidConfig(format!(
                "per-vertex bounds of {} x {} samples need {:.1} GB at once; at most {MAX_BOUNDS_SAMPLES} samples",
                side[0],
                side[1],
                points as f64 * 16e-9
            )));
        }
        let last = I64Vec2::new(side[0] as i64 - 1, side[1] as i64 - 1);
        let (z, hole) = stored_rows(world, source, holes, side);
        let n = side[0] * side[1];
        let mut tree = VertexBoundsTree {
            world: *world,
            side,
            z,
            hole,
            error: vec![0.0; n],
            reach: vec![0.0; n],
            empty: vec![false; n],
            lod0_refine: vec![NodeRefine::default(); Self::lod0_nodes(world)],
        };
        let base = tree.fine_levels(source, holes, last);
        tree.sample_levels(last, &base);
        Ok(tree)
    }

    /// Samples a row and rows of `world`'s lattice: the roots' grid.
    pub fn lattice_side(world: &WorldDesc) -> [usize; 2] {
        let root = u64::from(NODE_QUADS) << world.root_lod();
        world.grid(world.root_lod()).map(|g| (u64::from(g) * root) as usize + 1)
    }

    /// LOD-0 nodes over the lattice.
    pub fn lod0_nodes(world: &WorldDesc) -> usize {
        Self::lattice_side(world).iter().map(|s| (s - 1) / NODE_QUADS as usize).product()
    }

    /// The arrays a cache file keeps.
    pub(super) fn parts(&self) -> Parts<'_> {
        Parts {
            side: self.side,
            z: &self.z,
            hole: &self.hole,
            error: &self.error,
            reach: &self.reach,
            empty: &self.empty,
            lod0_refine: &self.lod0_refine,
        }
    }

    /// The tree a cache file held (its lattice checked against `world`).
    pub(super) fn from_parts(world: WorldDesc, p: OwnedParts) -> Self {
        assert_eq!(p.side, Self::lattice_side(&world), "a cache file's lattice is checked before");
        let OwnedParts { side, z, hole, error, reach, empty, lod0_refine } = p;
        VertexBoundsTree { world, side, z, hole, error, reach, empty, lod0_refine }
    }

    fn index(&self, s: I64Vec2) -> usize {
        s.y as usize * self.side[0] + s.x as usize
    }

    /// The stored height of sample `s` (NaN: a hole).
    fn height(&self, s: I64Vec2) -> f64 {
        let i = self.index(s);
        if self.hole[i] {
            f64::NAN
        } else {
            f64::from(self.z[i])
        }
    }

    /// The samples `lo..lo + side` (each way) a block reads: from the
    /// world's arrays, or where the window passes the lattice's edge, from
    /// the source as the bake reads it.
    fn block_samples(&self, source: &dyn HeightSource, holes: &[Hole], lo: I64Vec2, side: i64) -> Samples {
        let last = I64Vec2::new(self.side[0] as i64 - 1, self.side[1] as i64 - 1);
        if lo.cmplt(I64Vec2::ZERO).any() || (lo + I64Vec2::splat(side - 1)).cmpgt(last).any() {
            return stored(&self.world, source, holes, lo, side, side);
        }
        let (mut z, mut hole) =
            (Vec::with_capacity((side * side) as usize), Vec::with_capacity((side * side) as usize));
        for j in 0..side {
            let i = self.index(lo + I64Vec2::new(0, j));
            z.extend(self.z[i..i + side as usize].iter().map(|h| f64::from(*h)));
            hole.extend_from_slice(&self.hole[i..i + side as usize]);
        }
        Samples { lo, size: I64Vec2::splat(side), z, hole }
    }

    fn numbers(&self, s: I64Vec2) -> VertexNumbers {
        let i = self.index(s);
        VertexNumbers { error_m: f64::from(self.error[i]), reach_m: f64::from(self.reach[i]), empty: self.empty[i] }
    }

    fn store(&mut self, s: I64Vec2, n: &VertexNumbers) {
        let i = self.index(s);
        (self.error[i], self.reach[i], self.empty[i]) = (up_f32(n.error_m), up_f32(n.reach_m), n.empty);
    }

    /// The levels below the sample grid, and the sample grid's finest;
    /// gives each sample's `base` ([`SampleGrid`]).
    fn fine_levels(&mut self, source: &dyn HeightSource, holes: &[Hole], last: I64Vec2) -> Vec<u16> {
        let mut base = vec![0u16; self.z.len()];
        let blocks: Vec<I64Vec2> = (0..=last.y / BLOCK)
            .flat_map(|by| (0..=last.x / BLOCK).map(move |bx| I64Vec2::new(bx, by) * BLOCK))
            .collect();
        let lod0_row = (last.x / i64::from(NODE_QUADS)) as usize;
        // Blocks in parallel, a few at a time (each holds ~10 MB of window).
        for chunk in blocks.chunks(rayon::current_num_threads() * 4) {
            let done: Vec<_> = chunk
                .par_iter()
                .map(|&o| {
                    let s = self.block_samples(source, holes, o - I64Vec2::splat(6), BLOCK + 13);
                    block_numbers(&s, o, last)
                })
                .collect();
            for b in done {
                for (s, n, below) in &b.samples {
                    self.store(*s, n);
                    self.spread_base(&mut base, *s, *below, last);
                }
                for (node, r) in b.nodes {
                    self.lod0_refine[node.y as usize * lod0_row + node.x as usize] = r;
                }
            }
        }
        base
    }

    /// Raises the `base` of edge-midpoint sample `s`'s diamond's samples to
    /// `below`: the halves drawn at the samples lie within it of the finest
    /// surface.
    fn spread_base(&self, base: &mut [u16], s: I64Vec2, below: f64, last: I64Vec2) {
        if classify(s * UNITS).1 != Kind::Edge {
            return;
        }
        let bits = up_f16_bits(up_f32(below));
        let ([a, b], [p, q]) = diamond(s * UNITS);
        for c in [s * UNITS, a, b, p, q].map(|c| c / UNITS) {
            if c.cmpge(I64Vec2::ZERO).all() && c.cmple(last).all() {
                let i = self.index(c);
                base[i] = base[i].max(bits);
            }
        }
    }

    /// The sample grid's coarser levels, a half-level at a time.
    fn sample_levels(&mut self, last: I64Vec2, base: &[u16]) {
        let top = 64 - (last.max_element() * UNITS).leading_zeros();
        let first = crate::shaders::consts::REFINE_LEVELS;
        for t in first..=top {
            for kind in [Kind::Edge, Kind::Centre] {
                if t == first && kind == Kind::Edge {
                    continue; // filled by the fine pass with the centres of its level
                }
                self.level(t, kind, last, base);
            }
        }
    }

    /// Level `t`'s vertices of `kind`, a band of rows at a time (their
    /// children are all stored; a band's results are kept until stored):
    /// the rule's numbers, the error lowered to the measured bound where
    /// that is smaller, never below a child's.
    fn level(&mut self, t: u32, kind: Kind, last: I64Vec2, base: &[u16]) {
        let d = (1i64 << t) / UNITS;
        let rows: Vec<i64> = (0..=last.y / d).collect();
        for band in rows.chunks(512) {
            let this = &*self;
            let inside = |p: I64Vec2| p.cmpge(I64Vec2::ZERO).all() && p.cmple(last * UNITS).all();
            let z = |p: I64Vec2| this.height(p / UNITS);
            let child = |p: I64Vec2| this.numbers(p / UNITS);
            let found: Vec<(I64Vec2, VertexNumbers)> = band
                .par_iter()
                .flat_map_iter(|&row| {
                    (0..=last.x / d).filter_map(move |col| {
                        let s = I64Vec2::new(col, row) * d;
                        let v = s * UNITS;
                        (v != I64Vec2::ZERO && classify(v) == (t, kind))
                            .then(|| (s, this.tightened(vertex_numbers(v, inside, z, child), v, base)))
                    })
                })
                .collect();
            for (s, n) in found {
                self.store(s, &n);
            }
        }
    }

    /// `n` (vertex `v`'s by the rule) with the smaller of its error and
    /// the measured bound ([`diamond_gap`]), raised to its children's.
    fn tightened(&self, mut n: VertexNumbers, v: I64Vec2, base: &[u16]) -> VertexNumbers {
        if n.empty || !n.error_m.is_finite() {
            return n;
        }
        let grid = SampleGrid { side: self.side, z: &self.z, hole: &self.hole, base, unit: UNITS };
        let last = I64Vec2::new(self.side[0] as i64 - 1, self.side[1] as i64 - 1) * UNITS;
        let kids =
            child_points(v).into_iter().flatten().filter(|c| c.cmpge(I64Vec2::ZERO).all() && c.cmple(last).all());
        let floor = kids.map(|c| self.numbers(c / UNITS)).filter(|c| !c.empty).map(|c| c.error_m).fold(0.0, f64::max);
        n.error_m = n.error_m.min(diamond_gap(&grid, v)).max(floor);
        n
    }
}

/// The whole lattice's stored heights (f32, as decoded) and hole flags,
/// a row at a time (no f64 copy of the world).
fn stored_rows(
    world: &WorldDesc,
    source: &dyn HeightSource,
    holes: &[Hole],
    side: [usize; 2],
) -> (Vec<f32>, Vec<bool>) {
    let (mut z, mut hole) = (vec![0f32; side[0] * side[1]], vec![false; side[0] * side[1]]);
    z.par_chunks_mut(side[0]).zip(hole.par_chunks_mut(side[0])).enumerate().for_each(|(j, (zr, hr))| {
        let s = stored(world, source, holes, I64Vec2::new(0, j as i64), side[0] as i64, 1);
        for (k, (h, o)) in s.z.iter().zip(&s.hole).enumerate() {
            (zr[k], hr[k]) = (*h as f32, *o);
        }
    });
    (z, hole)
}

/// Stored heights and hole flags of `w` x `h` samples from `lo`.
fn stored(world: &WorldDesc, source: &dyn HeightSource, holes: &[Hole], lo: I64Vec2, w: i64, h: i64) -> Samples {
    let [ex, ey] = world.extent_m;
    let xs: Vec<f64> = (0..w).map(|i| world.sample_pos(lo.x + i, 0)[0]).collect();
    let clamped: Vec<f64> = xs.iter().map(|x| x.clamp(0.0, ex)).collect();
    let rows: Vec<(Vec<f64>, Vec<bool>)> = (0..h)
        .into_par_iter()
        .map(|j| {
            let y = world.sample_pos(0, lo.y + j)[1];
            let mut raw = vec![0f32; w as usize];
            source.sample_row(&clamped, y.clamp(0.0, ey), &mut raw);
            let z = raw.iter().map(|r| f64::from(world.decode_height(world.encode_height(*r)))).collect();
            // Past the world's edge the lattice continues its edge's samples,
            // holes too: a vertex there neither forces splits towards the
            // edge nor hides an error (the bake makes those samples holes, so
            // the GPU drops the triangles that reach them).
            let yc = y.clamp(0.0, ey);
            let hole = clamped.iter().map(|x| super::bake::is_hole_at(world, source, holes, [*x, yc], world.spacing_m));
            let hole = hole.collect();
            (z, hole)
        })
        .collect();
    let (z, hole) = rows.into_iter().fold((Vec::new(), Vec::new()), |(mut z, mut hole), (zr, hr)| {
        z.extend(zr);
        hole.extend(hr);
        (z, hole)
    });
    Samples { lo, size: I64Vec2::new(w, h), z, hole }
}

impl VertexBoundsTree {
    pub fn world(&self) -> &WorldDesc {
        &self.world
    }

    /// Node `id`'s grid points in the heights' atlas layout (texel t holds
    /// grid point t - ATLAS_BORDER, row-major from the south-west): the
    /// error's f16 bits in the low half, the reach's in the high half (both
    /// rounded up; an empty diamond's are 0). The margin holds the points
    /// past the node (a LOD-0 node's vertices below its samples read their
    /// parents there); a point past the lattice is infinite, so it never
    /// lowers a number taken as the smaller of two.
    pub fn node_values(&self, id: NodeId) -> Vec<u32> {
        let step = 1i64 << id.lod;
        let border = ATLAS_BORDER as i64;
        let first = (I64Vec2::new(i64::from(id.x), i64::from(id.y)) * i64::from(NODE_QUADS) - border) * step;
        let last = I64Vec2::new(self.side[0] as i64 - 1, self.side[1] as i64 - 1);
        let inf = u32::from(half::f16::INFINITY.to_bits());
        let mut out = Vec::with_capacity(ATLAS_SIDE * ATLAS_SIDE);
        for j in 0..ATLAS_SIDE as i64 {
            for i in 0..ATLAS_SIDE as i64 {
                let s = first + I64Vec2::new(i, j) * step;
                if s.cmplt(I64Vec2::ZERO).any() || s.cmpgt(last).any() {
                    out.push(inf | inf << 16);
                    continue;
                }
                let k = self.index(s);
                out.push(u32::from(up_f16_bits(self.error[k])) | u32::from(up_f16_bits(self.reach[k])) << 16);
            }
        }
        out
    }

    /// Node `id`'s refinement bound: its quads' centres merged (at LOD 0,
    /// the centres below the samples, from the fine pass).
    pub fn node_refine(&self, id: NodeId) -> NodeRefine {
        if id.lod == 0 {
            let row = (self.side[0] - 1) / NODE_QUADS as usize;
            return self.lod0_refine[id.y as usize * row + id.x as usize];
        }
        let step = 1i64 << id.lod;
        let first = I64Vec2::new(i64::from(id.x), i64::from(id.y)) * i64::from(NODE_QUADS) * step;
        let mut r = NodeRefine::default();
        for qy in 0..i64::from(NODE_QUADS) {
            for qx in 0..i64::from(NODE_QUADS) {
                let c = first + I64Vec2::new(qx, qy) * step + I64Vec2::splat(step / 2);
                r.merge(self.height(c), &self.numbers(c));
            }
        }
        r
    }

    /// Gives `node` its grid points' numbers, and makes its LOD error and
    /// height range the refinement bound's: the traversal then draws a
    /// node's children exactly when one of their vertices may be split
    /// (a vertex's box lies within a cell of the node's square: the
    /// traversal pads it by that).
    pub fn attach(&self, node: &mut BakedNode) {
        node.vertex_bounds = self.node_values(node.id);
        let r = self.node_refine(node.id);
        node.max_error_m = r.error_m;
        if r.z_lo_m <= r.z_hi_m {
            let [lo, hi] = self.world.height_range_m;
            let steps = |z: f32| f64::from((z - lo) / (hi - lo)) * 65535.0;
            node.min_height = node.min_height.min((steps(r.z_lo_m).floor() - 1.0).clamp(0.0, 65535.0) as u16);
            node.max_height = node.max_height.max((steps(r.z_hi_m).ceil() + 1.0).clamp(0.0, 65535.0) as u16);
        }
    }

    /// Numbers of sample `s` (grid origin 0): height, error, reach, empty.
    pub fn at(&self, s: I64Vec2) -> (f32, VertexNumbers) {
        (self.height(s) as f32, self.numbers(s))
    }
}

/// The samples' lattice read as the CPU twin's bounds (lattice units =
/// samples: `reference::bintree_cut` with `below` 0): the box read as the
/// sphere about the vertex that holds it and nests like it (radius sqrt(2)
/// R + reach; see [`box_half_width`]).
impl Bounds for VertexBoundsTree {
    fn bound(&mut self, v: I64Vec2) -> VertexBound {
        let (z, n) = self.at(v);
        let (t, kind) = classify(v * UNITS);
        let r = box_half_width(t, kind) as f64 * self.world.spacing_m / UNITS as f64;
        let error_m = if n.empty { 0.0 } else { n.error_m };
        VertexBound { z_m: f64::from(z), error_m, radius_m: std::f64::consts::SQRT_2 * r + n.reach_m }
    }

    fn point(&mut self, v: I64Vec2) -> DVec3 {
        let [x, y] = self.world.sample_pos(v.x, v.y);
        DVec3::new(x, y, self.height(v))
    }
}
