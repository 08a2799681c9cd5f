//! The world's surface as one restricted bintree (a 4-8 mesh, Lindstrom &
//! Pascucci 2001): every level of vista's grids is a diamond-split
//! triangulation, and the levels nest. Splitting a right triangle at the
//! midpoint of its hypotenuse gives two; twice over, a level's quad becomes
//! the next finer level's four (the quad's centre first, then its edge
//! midpoints), down to the finest surface (`REFINE_LEVELS` below LOD 0).
//!
//! Positions are points of the finest lattice, in fine units (a quarter of
//! a sample with two refinement levels), from the grid origin. A point
//! first appears at lattice level t (its coordinates' common trailing
//! zeros): at the centre of a quad of lattice t + 1 (both coordinates odd
//! multiples of 2^t), or at the midpoint of one of its edges. It splits the
//! two triangles whose hypotenuse it halves (its *diamond*); its parents
//! are the right-angle corners of those two, and it must be split before
//! any of its four children.
//!
//! Per vertex, [`VertexErrors`] gives a bound of how far its diamond, drawn
//! unsplit, lies from the finest surface (vertically), and a sphere holding
//! the diamond and the finest surface over it. Both are *saturated*: no
//! smaller than any child's (the error), and holding every child's sphere
//! (the radius). A rule that splits a vertex when its error, projected from
//! the nearest point of its sphere, exceeds a target then never splits a
//! child without its parents: the triangles it leaves conform (no
//! T-junctions), and each one's deviation is within its split vertex's
//! error, a strict bound. Everything is a function of the vertex's position
//! and the heights: the same in every node that holds it.

use glam::{DVec2, DVec3, I64Vec2};
use std::collections::HashMap;

/// How a vertex first appears.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// The centre of a quad of lattice level t + 1.
    Centre,
    /// The midpoint of an edge of lattice level t + 1.
    Edge,
}

/// Lattice level and kind of `v` (not the origin: every coordinate's
/// trailing zeros are counted, and the origin is a corner of every level).
pub fn classify(v: I64Vec2) -> (u32, Kind) {
    assert!(v != I64Vec2::ZERO, "the origin is a corner of every level");
    let t = v.x.trailing_zeros().min(v.y.trailing_zeros());
    let odd = |c: i64| (c >> t) & 1 == 1;
    (t, if odd(v.x) && odd(v.y) { Kind::Centre } else { Kind::Edge })
}

/// Whether a quad of a level's lattice (its index in that level's quads) is
/// split SW-NE: the diamond pattern every level draws.
pub fn slash(qx: i64, qy: i64) -> bool {
    (qx + qy).rem_euclid(2) == 0
}

/// The hypotenuse `v` halves (its two ends) and its parents (the right
/// angles of its diamond's two triangles).
pub fn diamond(v: I64Vec2) -> ([I64Vec2; 2], [I64Vec2; 2]) {
    let (t, kind) = classify(v);
    let d = 1i64 << t;
    match kind {
        Kind::Centre => {
            let (ne, se) = (I64Vec2::new(d, d), I64Vec2::new(d, -d));
            let q = (v - I64Vec2::splat(d)).div_euclid(I64Vec2::splat(2 * d));
            if slash(q.x, q.y) {
                ([v - ne, v + ne], [v + se, v - se])
            } else {
                ([v + se, v - se], [v - ne, v + ne])
            }
        }
        Kind::Edge => {
            let (x, y) = (I64Vec2::new(d, 0), I64Vec2::new(0, d));
            // On a horizontal edge when its x is the odd one.
            if (v.x >> t) & 1 == 1 {
                ([v - x, v + x], [v - y, v + y])
            } else {
                ([v - y, v + y], [v - x, v + x])
            }
        }
    }
}

/// The four vertices that split the triangles `v`'s split makes (none for
/// an edge midpoint of the finest lattice).
pub fn children(v: I64Vec2) -> Vec<I64Vec2> {
    let (t, kind) = classify(v);
    let d = 1i64 << t;
    match kind {
        Kind::Centre => [(d, 0), (-d, 0), (0, d), (0, -d)].iter().map(|&(x, y)| v + I64Vec2::new(x, y)).collect(),
        Kind::Edge if t == 0 => Vec::new(),
        Kind::Edge => {
            let h = d / 2;
            [(h, h), (-h, h), (h, -h), (-h, -h)].iter().map(|&(x, y)| v + I64Vec2::new(x, y)).collect()
        }
    }
}

/// A vertex's saturated numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VertexBound {
    /// Height (m) of the finest surface at the vertex.
    pub z_m: f64,
    /// Bound (m) of the vertical distance between its diamond drawn unsplit
    /// and the finest surface; infinite where a height is missing (a hole).
    pub error_m: f64,
    /// Radius (m) of a sphere about the vertex holding its diamond, the
    /// finest surface over it and every child's sphere.
    pub radius_m: f64,
}

/// Whether the numbers are saturated (the rule) or each vertex's own (to
/// show what saturation is for).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Saturation {
    /// Error: the vertex's own vertical error plus the largest child's
    /// (the diamond unsplit differs from its four halves by at most the
    /// own error, and each half lies within its child's bound); radius:
    /// holding every child's sphere.
    Nested,
    /// `Nested`, its error lowered to the diamond's largest vertical gap
    /// from the lattice's heights (measured point by point) where that is
    /// smaller, and raised to the largest child's: still a bound, still
    /// saturated, without a term per level (what the renderer bakes).
    Measured,
    /// The vertex's own vertical error and sphere only.
    Off,
}

/// Where a cut reads its vertices' bounds from.
pub trait Bounds {
    /// The saturated bounds of split vertex `v`.
    fn bound(&mut self, v: I64Vec2) -> VertexBound;
    /// `v` in world metres at its height.
    fn point(&mut self, v: I64Vec2) -> DVec3;
}

/// The lattice a set of bounds covers: inclusive corners, metres per unit
/// and the world position of point 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lattice {
    pub lo: I64Vec2,
    pub hi: I64Vec2,
    pub unit_m: f64,
    pub origin_m: DVec2,
}

impl Lattice {
    pub fn contains(&self, v: I64Vec2) -> bool {
        v.cmpge(self.lo).all() && v.cmple(self.hi).all()
    }

    pub fn point(&self, v: I64Vec2, z: f64) -> DVec3 {
        (self.origin_m + v.as_dvec2() * self.unit_m).extend(z)
    }
}

/// `v`'s own numbers: its vertical distance from its hypotenuse, and a
/// sphere holding its diamond's corners (and that distance about them).
/// `z` gives the heights (NaN: a hole, an infinite error).
pub fn own_bound(lattice: &Lattice, v: I64Vec2, z: &mut dyn FnMut(I64Vec2) -> f64) -> VertexBound {
    let ([a, b], parents) = diamond(v);
    let zv = z(v);
    let error_m = (zv - 0.5 * (z(a) + z(b))).abs();
    let mut reach = 0.0f64;
    for c in [a, b].into_iter().chain(parents).filter(|c| lattice.contains(*c)) {
        let dxy = (c - v).as_dvec2().length() * lattice.unit_m;
        reach = reach.max(dxy.hypot((z(c) - zv).abs() + error_m));
    }
    if !(error_m.is_finite() && reach.is_finite()) {
        return VertexBound { z_m: zv, error_m: f64::INFINITY, radius_m: 0.0 };
    }
    VertexBound { z_m: zv, error_m, radius_m: reach }
}

/// Saturates `own` with its children's bounds (`children`: each child's
/// point and bounds): the own error plus the largest child's, and a sphere
/// holding every finite child's.
pub fn nest(own: VertexBound, p: DVec3, children: &[(DVec3, VertexBound)]) -> VertexBound {
    let (mut worst, mut radius) = (0.0f64, own.radius_m);
    for (q, c) in children {
        worst = worst.max(c.error_m);
        if c.error_m.is_finite() {
            radius = radius.max(p.distance(*q) + c.radius_m);
        }
    }
    VertexBound { error_m: own.error_m + worst, radius_m: radius, ..own }
}

/// Per-vertex bounds over a lattice, computed on demand and kept (small
/// lattices: tests and the bench's expectations).
pub struct VertexErrors<'a> {
    /// Height of the surface at a lattice point (NaN: a hole).
    height: &'a dyn Fn(I64Vec2) -> f64,
    lattice: Lattice,
    saturation: Saturation,
    heights: HashMap<I64Vec2, f64>,
    bounds: HashMap<I64Vec2, VertexBound>,
}

impl<'a> VertexErrors<'a> {
    pub fn new(height: &'a dyn Fn(I64Vec2) -> f64, lattice: Lattice, s: Saturation) -> Self {
        assert!(lattice.lo.cmple(lattice.hi).all() && lattice.unit_m > 0.0, "an empty lattice");
        let (heights, bounds) = (HashMap::new(), HashMap::new());
        VertexErrors { height, lattice, saturation: s, heights, bounds }
    }

    pub fn contains(&self, v: I64Vec2) -> bool {
        self.lattice.contains(v)
    }

    /// The surface's height at `v`.
    pub fn z(&mut self, v: I64Vec2) -> f64 {
        let h = self.height;
        *self.heights.entry(v).or_insert_with(|| h(v))
    }
}

impl VertexErrors<'_> {
    /// The largest vertical gap between `v`'s diamond drawn unsplit (its
    /// halves whose apex is on the lattice) and the lattice points in it.
    fn measured_gap(&mut self, v: I64Vec2) -> f64 {
        let ([a, b], parents) = diamond(v);
        if !(self.contains(a) && self.contains(b)) {
            return f64::INFINITY;
        }
        let mut gap = 0.0f64;
        let lattice = self.lattice;
        for p in parents.into_iter().filter(|p| lattice.contains(*p)) {
            let corners = [a, b, p];
            let z = corners.map(|c| self.z(c));
            let area = (b - a).perp_dot(p - a) as f64;
            let (lo, hi) = (a.min(b).min(p), a.max(b).max(p));
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    let c = I64Vec2::new(x, y);
                    // Barycentric weights: all >= 0 inside (edges included).
                    let w = [(p - b).perp_dot(c - b), (a - p).perp_dot(c - p), (b - a).perp_dot(c - a)];
                    let w = w.map(|k| k as f64 / area);
                    if w.iter().all(|k| *k >= 0.0) {
                        let flat = w[0] * z[0] + w[1] * z[1] + w[2] * z[2];
                        gap = gap.max((self.z(c) - flat).abs());
                    }
                }
            }
        }
        gap
    }
}

impl Bounds for VertexErrors<'_> {
    fn point(&mut self, v: I64Vec2) -> DVec3 {
        let z = self.z(v);
        self.lattice.point(v, z)
    }

    fn bound(&mut self, v: I64Vec2) -> VertexBound {
        if let Some(b) = self.bounds.get(&v) {
            return *b;
        }
        assert!(self.contains(v), "{v} is outside the lattice");
        let lattice = self.lattice;
        let own = own_bound(&lattice, v, &mut |c| self.z(c));
        let b = match self.saturation {
            Saturation::Off => own,
            Saturation::Nested | Saturation::Measured => {
                let inside: Vec<I64Vec2> = children(v).into_iter().filter(|c| lattice.contains(*c)).collect();
                let kids: Vec<(DVec3, VertexBound)> =
                    inside.into_iter().map(|c| (self.point(c), self.bound(c))).collect();
                let p = self.point(v);
                let mut b = nest(own, p, &kids);
                if self.saturation == Saturation::Measured && b.error_m.is_finite() {
                    let floor = kids.iter().map(|(_, k)| k.error_m).fold(0.0, f64::max);
                    b.error_m = b.error_m.min(self.measured_gap(v)).max(floor);
                }
                b
            }
        };
        self.bounds.insert(v, b);
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_and_kinds_follow_the_trailing_zeros() {
        assert_eq!(classify(I64Vec2::new(1, 1)), (0, Kind::Centre));
        assert_eq!(classify(I64Vec2::new(1, 0)), (0, Kind::Edge));
        assert_eq!(classify(I64Vec2::new(2, 6)), (1, Kind::Centre));
        assert_eq!(classify(I64Vec2::new(4, 2)), (1, Kind::Edge));
        assert_eq!(classify(I64Vec2::new(-8, 24)), (3, Kind::Centre));
    }

    #[test]
    fn a_centre_halves_its_quads_diagonal_as_the_level_draws_it() {
        // Quad (0, 0) of lattice 1 is split SW-NE: its centre (1, 1) halves
        // (0, 0)-(2, 2), and its parents are the other two corners.
        let (h, p) = diamond(I64Vec2::new(1, 1));
        assert_eq!(h, [I64Vec2::new(0, 0), I64Vec2::new(2, 2)]);
        assert_eq!(p, [I64Vec2::new(2, 0), I64Vec2::new(0, 2)]);
        // Quad (1, 0) is split NW-SE.
        let (h, _) = diamond(I64Vec2::new(3, 1));
        assert_eq!(h, [I64Vec2::new(4, 0), I64Vec2::new(2, 2)]);
    }

    #[test]
    fn every_child_names_its_vertex_as_a_parent() {
        for x in -9..9 {
            for y in -9..9 {
                let v = I64Vec2::new(x, y);
                if v == I64Vec2::ZERO {
                    continue;
                }
                for c in children(v) {
                    assert!(diamond(c).1.contains(&v), "{c} does not depend on {v}");
                }
                for p in diamond(v).1.into_iter().filter(|p| *p != I64Vec2::ZERO) {
                    // Parents of a vertex are coarser by half a level.
                    let (tp, kp) = classify(p);
                    let (t, k) = classify(v);
                    let rank = |t: u32, k: Kind| 2 * t + u32::from(k == Kind::Centre);
                    assert!(rank(tp, kp) == rank(t, k) + 1 || tp > t + 1, "{p} of {v}");
                    assert!(children(p).contains(&v), "{v} missing among {p}'s children");
                }
            }
        }
    }
}
