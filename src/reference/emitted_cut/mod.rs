//! The per-triangle rule as `emit_triangles` and `emit_fine` apply it to
//! the nodes a frame draws, on the CPU in f64: the triangles their list
//! holds with culling off (or with only the hole stage), from the world's
//! per-vertex numbers ([`VertexBoundsTree`]) and the frame's LOD map.
//!
//! [`super::bintree_cut`] is the rule over the whole world with spheres;
//! this is the renderer's form of it, which the list must equal:
//! - each drawn node starts from its own two halves, so its corners are
//!   drawn whatever their numbers say;
//! - a vertex's bound is a box (the sample's reach about its height, its
//!   descendants' square across), its projection the smaller of the
//!   Jacobian bound and the vertical direction's own;
//! - below the samples a vertex takes the smaller error of its two parents
//!   and the meet of their boxes with its own square;
//! - a segment on a node's border that a finer node across has a corner
//!   in is split whatever its vertex says (forced);
//! - a border vertex the node across lacks, or a vertex below the samples
//!   a coarser node across lacks, is not split (clamped);
//! - with the hole stage, a half of a patch whose node samples are all
//!   holes is dropped with everything under it.
//!
//! The GPU decides in f32. A vertex whose projected error is within
//! `tie` (relative) of the target is decided by the caller's `gpu_split`.

use super::bintree_cut::Tri;
use crate::scene::view::View;
use crate::shaders::consts::{NO_LOD, REFINE_LEVELS};
use crate::world::bintree::{classify, diamond, slash};
use crate::world::vertex_bounds::VertexBoundsTree;
use crate::world::vertex_rule::{box_half_width, up_f16_bits};
use crate::world::{NodeId, TraverseCamera, NODE_QUADS};
use glam::{DVec2, DVec3, I64Vec2};
use std::collections::BTreeSet;

/// Lattice units a sample step: the list's points are on this lattice.
const UNITS: i64 = 1 << REFINE_LEVELS;
/// LOD-0 samples a sector (a LOD-0 node) side.
const SECTOR: i64 = NODE_QUADS as i64;

/// A frame's LOD map read back (`lod_map`'s R8 image): per LOD-0 sector
/// the LOD of the drawn node covering it, or `NO_LOD`.
pub struct LodMapRead {
    pub width: u32,
    pub height: u32,
    pub lods: Vec<u8>,
}

impl LodMapRead {
    fn at(&self, q: I64Vec2) -> u32 {
        if q.x < 0 || q.y < 0 || q.x >= i64::from(self.width) || q.y >= i64::from(self.height) {
            return NO_LOD;
        }
        u32::from(self.lods[q.y as usize * self.width as usize + q.x as usize])
    }

    /// The drawn nodes (each once).
    pub fn nodes(&self) -> Vec<NodeId> {
        let mut set = BTreeSet::new();
        for (i, &l) in self.lods.iter().enumerate() {
            if u32::from(l) != NO_LOD {
                let (x, y) = (i as u32 % self.width, i as u32 / self.width);
                set.insert((l, x >> l, y >> l));
            }
        }
        set.into_iter().map(|(l, x, y)| NodeId::new(l, x, y)).collect()
    }
}

/// The twin's list and what it counted.
#[derive(Default)]
pub struct EmittedCut {
    /// Triangles, corners on the lattice `REFINE_LEVELS` below LOD 0.
    pub triangles: Vec<Tri>,
    /// Vertices within the tie of the target, decided by `gpu_split`.
    pub ties: usize,
    /// The ties `gpu_split` decided otherwise than the twin's own f64.
    pub overruled: usize,
    pub forced: usize,
    pub clamped: usize,
    /// Halves of all-hole patches the hole stage dropped.
    pub holes: usize,
}

enum Step {
    Draw,
    Split(I64Vec2),
    /// Dropped with everything under it (the hole stage).
    Drop,
}

/// A vertex's numbers as the rule reads them: its saturated error (m; 0
/// splits nothing; infinite: a hole) and its camera-relative box.
#[derive(Clone, Copy)]
struct Numbers {
    e: f64,
    lo: DVec3,
    hi: DVec3,
}

/// The camera terms `projected_error.glsl` reads (`TerrainView`'s lod_*):
/// the traversal's camera (its f64 Jacobian bound is the shader's first)
/// and what the vertical bound adds.
struct Terms {
    cam: TraverseCamera,
    eye: DVec3,
    forward: DVec3,
    right: DVec3,
    up: DVec3,
    pixels_per_tan: f64,
    tan_half: DVec2,
    near: f64,
    target: f64,
}

pub struct EmitTwin<'a> {
    tree: &'a VertexBoundsTree,
    map: &'a LodMapRead,
    terms: Terms,
    hole_stage: bool,
    tie: f64,
    lo_m: f64,
    hi_m: f64,
    /// The lattice's samples a row and rows.
    side: [i64; 2],
}

impl<'a> EmitTwin<'a> {
    /// The twin for `view`'s frame over `map`'s nodes; `hole_stage`: the
    /// list was made with the hole stage on; `tie`: the relative distance
    /// from the target within which the caller decides.
    pub fn new(tree: &'a VertexBoundsTree, map: &'a LodMapRead, view: &View, hole_stage: bool, tie: f64) -> Self {
        let cam = view.traverse_camera();
        let [_, right, up] = view.camera.basis();
        let tan_y = (view.fov_y_deg.to_radians() / 2.0).tan();
        let terms = Terms {
            eye: DVec3::from(view.camera.position_m),
            forward: DVec3::from(cam.forward),
            right,
            up,
            pixels_per_tan: cam.pixels_per_tan,
            tan_half: DVec2::new(tan_y * f64::from(view.size[0]) / f64::from(view.size[1]), tan_y),
            near: view.near_m,
            target: f64::from(view.target_error_px),
            cam,
        };
        let [lo_m, hi_m] = tree.world().height_range_m.map(f64::from);
        let side = VertexBoundsTree::lattice_side(tree.world()).map(|n| n as i64);
        EmitTwin { tree, map, terms, hole_stage, tie, lo_m, hi_m, side }
    }

    /// Every drawn node's triangles; `gpu_split(t)`: whether the GPU split
    /// triangle t (asked only for a tie).
    pub fn cut(&self, gpu_split: &dyn Fn(&Tri) -> bool) -> EmittedCut {
        let mut out = EmittedCut::default();
        for node in self.map.nodes() {
            self.walk(node, gpu_split, &mut out);
        }
        out
    }

    fn walk(&self, node: NodeId, gpu_split: &dyn Fn(&Tri) -> bool, out: &mut EmittedCut) {
        let side = (SECTOR * UNITS) << node.lod;
        let o = I64Vec2::new(i64::from(node.x), i64::from(node.y)) * side;
        let [sw, se, nw, ne] = [(0, 0), (side, 0), (0, side), (side, side)].map(|(a, b)| o + I64Vec2::new(a, b));
        let mut stack = if slash(i64::from(node.x), i64::from(node.y)) {
            vec![Tri { apex: se, b: sw, c: ne }, Tri { apex: nw, b: ne, c: sw }]
        } else {
            vec![Tri { apex: sw, b: se, c: nw }, Tri { apex: ne, b: nw, c: se }]
        };
        while let Some(t) = stack.pop() {
            match self.decide(node, &t, gpu_split, out) {
                Step::Split(m) => stack.extend(t.halves(m)),
                Step::Draw => out.triangles.push(t),
                Step::Drop => out.holes += 1,
            }
        }
    }

    /// What becomes of t (emit_triangles.comp's `decide`, in its order).
    fn decide(&self, node: NodeId, t: &Tri, gpu_split: &dyn Fn(&Tri) -> bool, out: &mut EmittedCut) -> Step {
        let step = UNITS << node.lod;
        let sum = t.b + t.c;
        if node.lod > 0 && (sum.x | sum.y) & (2 * step - 1) != 0 || (sum.x | sum.y) & 1 != 0 {
            return Step::Draw; // a cell half of the node's grid, or of the finest lattice
        }
        let m = sum / 2;
        if (m.x | m.y) & (UNITS - 1) != 0 {
            return self.decide_fine(node, t, m, gpu_split, out);
        }
        if self.hole_stage && self.all_holes(node, t) {
            return Step::Drop;
        }
        let [a, b, c] = t.corners().map(|p| p / UNITS);
        if self.corner_across(node, a, b) || self.corner_across(node, b, c) || self.corner_across(node, c, a) {
            out.forced += 1;
            return Step::Split(m);
        }
        if !self.over(&self.grid_numbers(m / UNITS), t, gpu_split, out) {
            return Step::Draw;
        }
        if !self.held_across(node, m / UNITS) {
            out.clamped += 1;
            return Step::Draw;
        }
        Step::Split(m)
    }

    /// `emit_fine`'s `decide_fine` for a vertex below the samples.
    fn decide_fine(
        &self,
        node: NodeId,
        t: &Tri,
        m: I64Vec2,
        gpu_split: &dyn Fn(&Tri) -> bool,
        out: &mut EmittedCut,
    ) -> Step {
        if !self.over(&self.fine_numbers(node, m), t, gpu_split, out) {
            return Step::Draw;
        }
        if self.blocked(node, m) {
            out.clamped += 1;
            return Step::Draw;
        }
        Step::Split(m)
    }

    /// Whether the numbers' projected error is over the target (a tie
    /// decided as the GPU did).
    fn over(&self, n: &Numbers, t: &Tri, gpu_split: &dyn Fn(&Tri) -> bool, out: &mut EmittedCut) -> bool {
        let px = self.projected_px(n);
        let target = self.terms.target;
        if px.is_finite() && (px - target).abs() <= self.tie * target {
            out.ties += 1;
            let split = gpu_split(t);
            out.overruled += usize::from(split != (px > target));
            return split;
        }
        px > target
    }

    /// Sample s's numbers (f16 rounded up, as the nodes carry them; past
    /// the lattice, as a node's margin holds them: infinite).
    fn grid_numbers(&self, s: I64Vec2) -> Numbers {
        let side = self.side;
        let f16 = |x: f64| f64::from(half::f16::from_bits(up_f16_bits(x as f32)).to_f32());
        let inside = s.cmpge(I64Vec2::ZERO).all() && s.x < side[0] && s.y < side[1];
        let (z, e, reach) = match inside.then(|| self.tree.at(s)) {
            Some((z, n)) => (f64::from(z), f16(n.error_m), f16(n.reach_m)),
            None => (f64::NAN, f64::INFINITY, f64::INFINITY),
        };
        let (lo, hi) = (self.lo_m, self.hi_m);
        // A hole's box (an infinite error) is the height range.
        let (zl, zh) = if e.is_infinite() || z.is_nan() {
            (lo, hi)
        } else {
            ((z - reach).clamp(lo, hi), (z + reach).clamp(lo, hi))
        };
        let (xy, r, eye) = (self.rel_xy(s * UNITS), self.half_width(s * UNITS), self.terms.eye.z);
        Numbers { e, lo: (xy - r).extend(zl - eye), hi: (xy + r).extend(zh - eye) }
    }

    /// Lattice point v's numbers below the samples: from its parents'.
    fn fine_numbers(&self, node: NodeId, v: I64Vec2) -> Numbers {
        let (_, [a, b]) = diamond(v);
        let parent = |p: I64Vec2| {
            let mut n =
                if (p.x | p.y) & (UNITS - 1) == 0 { self.grid_numbers(p / UNITS) } else { self.fine_numbers(node, p) };
            if self.blocked(node, p) {
                n.e = 0.0;
            }
            n
        };
        let (a, b) = (parent(a), parent(b));
        let (xy, r) = (self.rel_xy(v), self.half_width(v));
        let mut lo = a.lo.max(b.lo);
        let mut hi = a.hi.min(b.hi);
        lo = (lo.truncate().max(xy - r)).extend(lo.z);
        hi = (hi.truncate().min(xy + r)).extend(hi.z);
        Numbers { e: a.e.min(b.e), lo, hi }
    }

    fn rel_xy(&self, v: I64Vec2) -> DVec2 {
        let w = self.tree.world();
        let unit = w.spacing_m / UNITS as f64;
        DVec2::from(w.grid_origin_m) + v.as_dvec2() * unit - self.terms.eye.truncate()
    }

    /// Half the width (m) of lattice point v's box (its descendants' square).
    fn half_width(&self, v: I64Vec2) -> f64 {
        let (t, kind) = classify(v);
        box_half_width(t, kind) as f64 * self.tree.world().spacing_m / UNITS as f64
    }
}

mod rules;
