//! One vertex's baked numbers for the per-triangle rule ([`super::bintree`]),
//! in the form the renderer keeps them: a saturated error and a vertical
//! reach, nested in boxes whose horizontal size is a function of the
//! vertex's level alone. Shared by the sub-sample pass and the pass over
//! the samples ([`super::vertex_bounds`]) so both apply the same rule.
//!
//! - **error**: the vertical distance of the vertex from the hypotenuse it
//!   halves, plus the largest child's error (the diamond drawn unsplit
//!   differs from its halves by the first, each half from the finest
//!   surface by its child's bound): a bound of the unsplit diamond's
//!   distance from the finest surface, never below a child's;
//! - **reach**: the largest |z - z_v| over the diamond's corners and every
//!   descendant's box, so the box `[v - R, v + R] x [z_v - reach, z_v +
//!   reach]` holds every box under it ([`box_half_width`] gives R);
//! - **holes**: a diamond with a hole among its own three heights, or under
//!   a child whose error is infinite, has an infinite error (split down to
//!   the holes, whose triangles the GPU drops); one whose every lattice
//!   point is a hole is *empty*: error 0, nothing to refine, its unsplit
//!   triangles all dropped.

use super::bintree::{classify, diamond, Kind};
use glam::I64Vec2;

/// A vertex's numbers (metres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VertexNumbers {
    pub error_m: f64,
    pub reach_m: f64,
    /// Every lattice point of its diamond is a hole.
    pub empty: bool,
}

impl VertexNumbers {
    pub const EMPTY: VertexNumbers = VertexNumbers { error_m: 0.0, reach_m: 0.0, empty: true };
}

/// Half the side (lattice units) of the square holding every descendant
/// diamond of a vertex of level `t`: an edge midpoint's diamond reaches
/// 2^t, each child (a centre half a level down, 2^(t-1) away) adds its
/// own; a centre's children are edge midpoints 2^t away. Summed down to
/// the finest edge (1): 2^(t+1) - 1 and 3 * 2^t - 1.
pub fn box_half_width(t: u32, kind: Kind) -> i64 {
    match kind {
        Kind::Edge => (2i64 << t) - 1,
        Kind::Centre => 3 * (1i64 << t) - 1,
    }
}

/// The rule for vertex `v`: `z` gives lattice heights (NaN: a hole),
/// `inside` whether a point is on the lattice, `child` the numbers of a
/// child already computed.
pub fn vertex_numbers(
    v: I64Vec2,
    inside: impl Fn(I64Vec2) -> bool,
    z: impl Fn(I64Vec2) -> f64,
    child: impl Fn(I64Vec2) -> VertexNumbers,
) -> VertexNumbers {
    let ([a, b], parents) = diamond(v);
    let zv = z(v);
    let (mut reach, mut any_height) = (0.0f64, !zv.is_nan());
    for c in [a, b, parents[0], parents[1]] {
        let h = if inside(c) { z(c) } else { f64::NAN };
        if !h.is_nan() {
            any_height = true;
            reach = reach.max((h - zv).abs());
        }
    }
    let (mut worst, mut all_empty) = (0.0f64, true);
    for c in child_points(v).into_iter().flatten().filter(|c| inside(*c)) {
        let n = child(c);
        if n.empty {
            continue;
        }
        all_empty = false;
        worst = worst.max(n.error_m);
        let zc = z(c);
        if !zc.is_nan() {
            reach = reach.max((zc - zv).abs() + n.reach_m);
        }
    }
    if !any_height && all_empty {
        return VertexNumbers::EMPTY;
    }
    // Ends off the lattice only above the roots' level: never split.
    let end = |p: I64Vec2| if inside(p) { z(p) } else { f64::NAN };
    let own = (zv - 0.5 * (end(a) + end(b))).abs();
    let error_m = if own.is_nan() { f64::INFINITY } else { own + worst };
    if !(error_m.is_finite() && reach.is_finite()) {
        return VertexNumbers { error_m: f64::INFINITY, reach_m: 0.0, empty: false };
    }
    VertexNumbers { error_m, reach_m: reach, empty: false }
}

/// [`children`] without a heap allocation (the passes call this for every
/// lattice point).
pub(super) fn child_points(v: I64Vec2) -> [Option<I64Vec2>; 4] {
    let (t, kind) = classify(v);
    let d = 1i64 << t;
    let offsets = match kind {
        Kind::Centre => [(d, 0), (-d, 0), (0, d), (0, -d)],
        Kind::Edge if t == 0 => return [None; 4],
        Kind::Edge => {
            let h = d / 2;
            [(h, h), (-h, h), (h, -h), (-h, -h)]
        }
    };
    offsets.map(|(x, y)| Some(v + I64Vec2::new(x, y)))
}

/// `x` as f32, no smaller (a bound stays a bound).
pub fn up_f32(x: f64) -> f32 {
    let f = x as f32;
    if f.is_finite() && f64::from(f) < x {
        f32::from_bits(f.to_bits() + 1)
    } else {
        f
    }
}

/// `x` (>= 0) as f16 bits, no smaller; infinite past f16's range.
pub fn up_f16_bits(x: f32) -> u16 {
    let h = half::f16::from_f32(x);
    if h.is_finite() && h.to_f32() < x {
        h.to_bits() + 1
    } else {
        h.to_bits()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::bintree::children;

    fn descendants(v: I64Vec2, out: &mut Vec<I64Vec2>) {
        for c in children(v) {
            out.push(c);
            descendants(c, out);
        }
    }

    #[test]
    fn every_descendant_diamond_lies_in_the_box() {
        for v in [I64Vec2::new(16, 0), I64Vec2::new(8, 8), I64Vec2::new(24, 8), I64Vec2::new(4, 12), I64Vec2::new(2, 0)]
        {
            let (t, kind) = classify(v);
            let mut all = Vec::new();
            descendants(v, &mut all);
            let corners = all.iter().flat_map(|d| {
                let ([a, b], p) = diamond(*d);
                [a, b, p[0], p[1]]
            });
            let reach = corners.map(|c| (c - v).abs().max_element()).max().unwrap_or(0);
            assert_eq!(reach, box_half_width(t, kind), "{v}: level {t} {kind:?}");
        }
    }

    #[test]
    fn the_unallocated_children_are_bintree_s() {
        for x in -9..9 {
            for y in -9..9 {
                let v = I64Vec2::new(x, y);
                if v != I64Vec2::ZERO {
                    assert_eq!(child_points(v).into_iter().flatten().collect::<Vec<_>>(), children(v), "{v}");
                }
            }
        }
    }

    #[test]
    fn rounding_up_never_shrinks_a_bound() {
        for x in [0.0, 1e-7, 0.1, 1.0 / 3.0, 123.456, 70000.0] {
            assert!(f64::from(up_f32(x)) >= x);
            let h = half::f16::from_bits(up_f16_bits(up_f32(x)));
            assert!(f64::from(h.to_f32()) >= x, "{x} -> {h}");
        }
        assert!(half::f16::from_bits(up_f16_bits(70000.0)).is_infinite());
    }
}
