//! The per-triangle LOD rule on the CPU: which triangles of the world's
//! bintree (`world::bintree`) a camera draws at a target error. A vertex
//! is split when its saturated error, projected from the nearest point of
//! its sphere, exceeds the target; the cut is every triangle reached from
//! the root nodes' two halves through split vertices. Also the checks the
//! rule promises: no T-junctions, the roots' area covered exactly, every
//! triangle's projected error within the target.

use crate::scene::view::View;
use crate::world::bintree::{Bounds, Lattice, VertexBound, VertexErrors};
use crate::world::{TraverseCamera, WorldDesc, NODE_QUADS};
use glam::{DVec2, DVec3, I64Vec2};
use std::collections::HashSet;

/// A right triangle of the bintree: the right angle, then the ends of its
/// hypotenuse (fine units).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Tri {
    pub apex: I64Vec2,
    pub b: I64Vec2,
    pub c: I64Vec2,
}

impl Tri {
    /// The vertex that splits it; None below the finest lattice.
    pub fn split(&self) -> Option<I64Vec2> {
        let s = self.b + self.c;
        (s.x % 2 == 0 && s.y % 2 == 0).then_some(s / 2)
    }

    /// Its two halves, each with the split vertex as its right angle.
    pub fn halves(&self, m: I64Vec2) -> [Tri; 2] {
        [Tri { apex: m, b: self.apex, c: self.b }, Tri { apex: m, b: self.c, c: self.apex }]
    }

    /// Twice its area (fine units squared).
    pub fn area2(&self) -> i64 {
        let (u, v) = (self.b - self.apex, self.c - self.apex);
        (u.x * v.y - u.y * v.x).abs()
    }

    pub fn corners(&self) -> [I64Vec2; 3] {
        [self.apex, self.b, self.c]
    }
}

/// The finest lattice: `REFINE_LEVELS` refinements below LOD 0.
pub const FINEST: u32 = crate::shaders::consts::REFINE_LEVELS;

/// Side of a root node in units of a lattice `below` levels under LOD 0.
fn root_side(world: &WorldDesc, below: u32) -> i64 {
    i64::from(NODE_QUADS) << (world.root_lod() as u32 + below)
}

/// The two triangles of a root node's square (lattice units), split along
/// the diagonal its level draws.
pub fn root_triangles(world: &WorldDesc, below: u32, x: u32, y: u32) -> [Tri; 2] {
    let side = root_side(world, below);
    let o = I64Vec2::new(i64::from(x), i64::from(y)) * side;
    let [sw, se, nw, ne] = [(0, 0), (side, 0), (0, side), (side, side)].map(|(a, b)| o + I64Vec2::new(a, b));
    if crate::world::bintree::slash(i64::from(x), i64::from(y)) {
        [Tri { apex: se, b: sw, c: ne }, Tri { apex: nw, b: ne, c: sw }]
    } else {
        [Tri { apex: sw, b: se, c: nw }, Tri { apex: ne, b: nw, c: se }]
    }
}

/// The lattice `below` levels under LOD 0 over the world's roots.
pub fn lattice(world: &WorldDesc, below: u32) -> Lattice {
    let side = root_side(world, below);
    let [gx, gy] = world.grid(world.root_lod());
    Lattice {
        lo: I64Vec2::ZERO,
        hi: I64Vec2::new(i64::from(gx), i64::from(gy)) * side,
        unit_m: world.spacing_m / f64::from(1u32 << below),
        origin_m: DVec2::from(world.grid_origin_m),
    }
}

/// Projected error (px) of `b` at vertex point `p` for `cam`: the error
/// over the distance from the eye to the sphere's nearest point, times
/// the largest 1 / cos^2 off the axis any of the sphere's points has.
pub fn projected_px(cam: &TraverseCamera, p: DVec3, b: &VertexBound) -> f64 {
    if !b.error_m.is_finite() {
        return f64::INFINITY;
    }
    let to = p - DVec3::from(cam.position_m);
    let dist = to.length();
    let near = (dist - b.radius_m).max(1e-3);
    let k = if dist <= b.radius_m {
        cam.widest
    } else {
        let cos = (to.dot(DVec3::from(cam.forward)) / dist).clamp(-1.0, 1.0);
        let angle = cos.acos() + (b.radius_m / dist).asin();
        if angle >= std::f64::consts::FRAC_PI_2 {
            cam.widest
        } else {
            (1.0 / angle.cos().powi(2)).min(cam.widest)
        }
    };
    b.error_m * cam.pixels_per_tan * k / near
}

/// The rule's cut for `cam` at `target_px` over the world's roots, on the
/// lattice `below` levels under LOD 0 that `bounds` covers.
pub fn cut(world: &WorldDesc, below: u32, bounds: &mut dyn Bounds, cam: &TraverseCamera, target_px: f64) -> Vec<Tri> {
    let mut out = Vec::new();
    let mut stack: Vec<Tri> = world.roots().iter().flat_map(|r| root_triangles(world, below, r.x, r.y)).collect();
    while let Some(t) = stack.pop() {
        match t.split().filter(|m| active(bounds, cam, target_px, *m)) {
            Some(m) => stack.extend(t.halves(m)),
            None => out.push(t),
        }
    }
    out
}

/// The triangle of the rule's cut holding world point `xy` (metres), or
/// None outside the roots.
pub fn triangle_at(
    world: &WorldDesc,
    below: u32,
    bounds: &mut dyn Bounds,
    cam: &TraverseCamera,
    target_px: f64,
    xy: DVec2,
) -> Option<Tri> {
    let l = lattice(world, below);
    let at = (xy - l.origin_m) / l.unit_m;
    let roots = world.roots();
    let mut t = roots.iter().flat_map(|r| root_triangles(world, below, r.x, r.y)).find(|t| weights(t, at).is_some())?;
    while let Some(m) = t.split().filter(|m| active(bounds, cam, target_px, *m)) {
        let [a, b] = t.halves(m);
        t = if weights(&a, at).is_some() { a } else { b };
    }
    Some(t)
}

/// The height the rule's cut draws at world point `xy` (metres),
/// interpolated in [`triangle_at`]'s triangle; None outside the roots.
pub fn drawn_z(
    world: &WorldDesc,
    below: u32,
    bounds: &mut dyn Bounds,
    cam: &TraverseCamera,
    target_px: f64,
    xy: DVec2,
) -> Option<f64> {
    let t = triangle_at(world, below, bounds, cam, target_px, xy)?;
    let l = lattice(world, below);
    let w = weights(&t, (xy - l.origin_m) / l.unit_m)?;
    Some(t.corners().iter().zip(w).map(|(v, w)| w * bounds.point(*v).z).sum())
}

/// Barycentric weights of `p` (lattice units) in `t`; None outside it.
fn weights(t: &Tri, p: DVec2) -> Option<[f64; 3]> {
    let [a, b, c] = t.corners().map(|v| v.as_dvec2());
    let area = (b - a).perp_dot(c - a);
    let w = [(c - b).perp_dot(p - b) / area, (a - c).perp_dot(p - c) / area, (b - a).perp_dot(p - a) / area];
    w.iter().all(|w| *w >= -1e-12).then_some(w)
}

/// Whether the rule splits `m`.
pub fn active(bounds: &mut dyn Bounds, cam: &TraverseCamera, target_px: f64, m: I64Vec2) -> bool {
    let b = bounds.bound(m);
    let p = bounds.point(m);
    projected_px(cam, if p.z.is_finite() { p } else { DVec3::new(p.x, p.y, 0.0) }, &b) > target_px
}

/// Lattice points of `tris` that lie inside one of their edges (a vertex
/// of a neighbour the triangle does not share): the cut's cracks.
pub fn t_junctions(tris: &[Tri]) -> usize {
    t_junctions_at(tris).len()
}

/// [`t_junctions`]' points, each with the triangle whose edge holds it.
pub fn t_junctions_at(tris: &[Tri]) -> Vec<(I64Vec2, Tri)> {
    let vertices: HashSet<I64Vec2> = tris.iter().flat_map(|t| t.corners()).collect();
    let mut found = Vec::new();
    for t in tris {
        let [a, b, c] = t.corners();
        for (p, q) in [(a, b), (b, c), (c, a)] {
            let d = q - p;
            let n = d.x.abs().max(d.y.abs());
            let step = d / n;
            found.extend((1..n).map(|k| p + step * k).filter(|v| vertices.contains(v)).map(|v| (v, *t)));
        }
    }
    found
}

/// Largest screen length (px) over `t`'s lattice points of the vertical
/// segment between the triangle and the finest surface, measured with the
/// view's own projection (not the rule's bound), where the segment is in
/// view (both ends on the image: the rule bounds what is seen; off the
/// image a segment may look longer than anywhere in the frustum).
pub fn measured_error_px(t: &Tri, errors: &mut VertexErrors, view: &View) -> f64 {
    let [a, b, c] = t.corners();
    let (za, zb, zc) = (errors.z(a), errors.z(b), errors.z(c));
    let lo = a.min(b).min(c);
    let hi = a.max(b).max(c);
    let area2 = t.area2() as f64;
    let mut worst = 0.0f64;
    for y in lo.y..=hi.y {
        for x in lo.x..=hi.x {
            let p = I64Vec2::new(x, y);
            let w = |u: I64Vec2, v: I64Vec2| {
                let (e, f) = (v - u, p - u);
                (e.x * f.y - e.y * f.x) as f64
            };
            // Barycentric weights (signed areas); outside when any is negative
            // against the triangle's orientation.
            let (wa, wb, wc) = (w(b, c), w(c, a), w(a, b));
            let sign = (wa + wb + wc).signum();
            if wa * sign < 0.0 || wb * sign < 0.0 || wc * sign < 0.0 {
                continue;
            }
            let drawn = (wa * za + wb * zb + wc * zc) / (sign * area2);
            let fine = errors.point(p);
            let top = [fine.x, fine.y, drawn];
            let (Some((s0, _)), Some((s1, _))) = (view.project(top), view.project(fine.to_array())) else { continue };
            let [w, h] = view.size.map(f64::from);
            let on = |s: [f64; 2]| (0.0..=w).contains(&s[0]) && (0.0..=h).contains(&s[1]);
            if !(on(s0) && on(s1)) {
                continue;
            }
            worst = worst.max((s0[0] - s1[0]).hypot(s0[1] - s1[1]));
        }
    }
    worst
}
