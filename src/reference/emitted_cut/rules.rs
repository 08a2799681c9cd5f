//! The twin's projection (`projected_error.glsl`) and what it reads of
//! the nodes around: the LOD map across a node's borders
//! (`emit_triangles_borders.glsl`, `emit_triangles_fine.glsl`'s
//! `blocked`) and the patches' hole flags (`all_holes`).

use super::{EmitTwin, Numbers, SECTOR, UNITS};
use crate::reference::bintree_cut::Tri;
use crate::shaders::consts::NO_LOD;
use crate::world::{NodeId, PATCH_QUADS};
use glam::{DVec2, DVec3, I64Vec2};

impl EmitTwin<'_> {
    /// The largest projected error (px) of the numbers anywhere in their
    /// box: the smaller of the Jacobian bound and the vertical one
    /// (infinite for a hole, 0 for a vertex that splits nothing).
    pub(super) fn projected_px(&self, n: &Numbers) -> f64 {
        if n.e.is_infinite() {
            return f64::INFINITY;
        }
        if n.e <= 0.0 {
            return 0.0;
        }
        self.jacobian_px(n).min(self.vertical_px(n))
    }

    fn corners(n: &Numbers) -> [DVec3; 8] {
        std::array::from_fn(|i| {
            let pick = |bit: usize, lo: f64, hi: f64| if i & bit != 0 { hi } else { lo };
            DVec3::new(pick(1, n.lo.x, n.hi.x), pick(2, n.lo.y, n.hi.y), pick(4, n.lo.z, n.hi.z))
        })
    }

    /// The Jacobian bound: the traversal's own, on the box in world metres.
    fn jacobian_px(&self, n: &Numbers) -> f64 {
        let eye = self.terms.eye;
        self.terms.cam.projected_px(n.e, (n.lo + eye).to_array(), (n.hi + eye).to_array())
    }

    fn vertical_px(&self, n: &Numbers) -> f64 {
        let t = &self.terms;
        let (mut zmin, mut smin, mut smax, mut straddles) = (f64::MAX, DVec2::MAX, DVec2::MIN, false);
        for v in Self::corners(n) {
            let z = v.dot(t.forward);
            zmin = zmin.min(z);
            if z <= t.near {
                straddles = true;
            } else {
                let s = DVec2::new(v.dot(t.right), v.dot(t.up)) / z;
                (smin, smax) = (smin.min(s), smax.max(s));
            }
        }
        let (smin, smax) = if straddles {
            (-t.tan_half, t.tan_half)
        } else {
            (smin.clamp(-t.tan_half, t.tan_half), smax.clamp(-t.tan_half, t.tan_half))
        };
        let u = DVec3::new(t.right.z, t.up.z, t.forward.z);
        let g = [smin, DVec2::new(smax.x, smin.y), DVec2::new(smin.x, smax.y), smax]
            .map(|s| (u.truncate() - s * u.z).length())
            .into_iter()
            .fold(0.0, f64::max);
        n.e * t.pixels_per_tan * g / zmin.max(t.near)
    }

    /// Whether t is the half of one of the node's patches whose node
    /// samples are all holes.
    pub(super) fn all_holes(&self, node: NodeId, t: &Tri) -> bool {
        let step = UNITS << node.lod;
        let patch = i64::from(PATCH_QUADS) * step;
        let [a, b, c] = t.corners();
        let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
        if hi - lo != I64Vec2::splat(patch) {
            return false;
        }
        let q = i64::from(PATCH_QUADS) + 1;
        (0..q * q).all(|k| {
            let s = (lo + I64Vec2::new(k % q, k / q) * step) / UNITS;
            self.tree.at(s).0.is_nan()
        })
    }

    fn lod_at(&self, q: I64Vec2) -> u32 {
        self.map.at(q)
    }

    /// Whether the grid segment u-w (samples) lies on the node's border
    /// with a finer node's corner strictly inside it, across.
    pub(super) fn corner_across(&self, node: NodeId, u: I64Vec2, w: I64Vec2) -> bool {
        let Some((along, out_step)) = border_line(node, u, w) else { return false };
        let s0 = u.min(w);
        let len = (u - w).abs()[along];
        let mut q = s0 / SECTOR;
        q[1 - along] += out_step;
        let l = self.lod_at(q);
        l != NO_LOD && (SECTOR << l) < len
    }

    /// Whether every node across the node's borders through sample s holds
    /// it (true off the border).
    pub(super) fn held_across(&self, node: NodeId, s: I64Vec2) -> bool {
        let lo = I64Vec2::new(i64::from(node.x), i64::from(node.y)) * (SECTOR << node.lod);
        let hi = lo + I64Vec2::splat(SECTOR << node.lod);
        let mut ok = true;
        if s.x == lo.x || s.x == hi.x {
            ok = self.held_on_line(s, 1, if s.x == lo.x { -1 } else { 0 });
        }
        if s.y == lo.y || s.y == hi.y {
            ok = ok && self.held_on_line(s, 0, if s.y == lo.y { -1 } else { 0 });
        }
        ok
    }

    fn held_on_line(&self, s: I64Vec2, along: usize, out_step: i64) -> bool {
        let mut q = s / SECTOR;
        q[1 - along] += out_step;
        let mut before = q;
        before[along] -= 1;
        self.sector_holds(q, s) && (s[along] % SECTOR != 0 || self.sector_holds(before, s))
    }

    fn sector_holds(&self, q: I64Vec2, s: I64Vec2) -> bool {
        let l = self.lod_at(q);
        l == NO_LOD || (s.x | s.y) & ((1 << l) - 1) == 0
    }

    /// Whether a node across a LOD-0 node's border draws a coarser grid
    /// without lattice point g (below the samples).
    pub(super) fn blocked(&self, node: NodeId, g: I64Vec2) -> bool {
        let side = SECTOR * UNITS;
        let v = g - I64Vec2::new(i64::from(node.x), i64::from(node.y)) * side;
        if v.cmpgt(I64Vec2::ZERO).all() && v.cmplt(I64Vec2::splat(side)).all() {
            return false;
        }
        let q = g.div_euclid(I64Vec2::splat(side));
        let on = g - q * side;
        let lacks = |q: I64Vec2| {
            let l = self.lod_at(q);
            l != NO_LOD && l != 0 && (g.x | g.y) & ((UNITS << l) - 1) != 0
        };
        lacks(q)
            || (on.x == 0 && lacks(q - I64Vec2::X))
            || (on.y == 0 && lacks(q - I64Vec2::Y))
            || (on == I64Vec2::ZERO && lacks(q - I64Vec2::ONE))
    }
}

/// The axis a segment u-w on one of the node's border lines runs along,
/// and the step to the sector across (-1 west or south, 0 east or north).
fn border_line(node: NodeId, u: I64Vec2, w: I64Vec2) -> Option<(usize, i64)> {
    let lo = I64Vec2::new(i64::from(node.x), i64::from(node.y)) * (SECTOR << node.lod);
    let hi = lo + I64Vec2::splat(SECTOR << node.lod);
    if u.x == w.x && (u.x == lo.x || u.x == hi.x) {
        Some((1, if u.x == lo.x { -1 } else { 0 }))
    } else if u.y == w.y && (u.y == lo.y || u.y == hi.y) {
        Some((0, if u.y == lo.y { -1 } else { 0 }))
    } else {
        None
    }
}
