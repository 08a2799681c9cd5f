//! The tight bound of a sample-level vertex ([`super::vertex_bounds`]):
//! its diamond drawn unsplit, measured against every sample under it.
//!
//! The rule's own-plus-largest-child sum ([`super::vertex_rule`]) is a
//! bound, but it adds one term a half-level: over the 20-odd levels of a
//! large world it reaches several times the real gap, and the cut refines
//! what is already flat enough. Measured instead: the largest vertical gap
//! between the diamond's two triangles and the samples' surface (both are
//! linear between samples, and the diamond's edges are the samples'
//! triangulation's, so the largest gap is at a sample), plus the largest
//! gap of that surface from the finest one under the diamond (`base`: per
//! sample, the largest child error of the finest sample-level diamonds
//! that hold it). The sum bounds the diamond's distance from the finest
//! surface; the caller keeps the smaller of it and the rule's, raised to
//! the children's (saturated: a vertex never errs less than a child).

use super::bintree::diamond;
use glam::I64Vec2;

/// The samples' lattice as the measure reads it (row-major, `side[0]` a row).
pub struct SampleGrid<'a> {
    pub side: [usize; 2],
    pub z: &'a [f32],
    /// Per sample, or empty: none.
    pub hole: &'a [bool],
    /// f16 bits (>= 0: their order is the values'), per sample, or empty: 0.
    pub base: &'a [u16],
    /// Lattice units a sample (the vertices' coordinates over the samples').
    pub unit: i64,
}

impl SampleGrid<'_> {
    fn last(&self) -> I64Vec2 {
        I64Vec2::new(self.side[0] as i64 - 1, self.side[1] as i64 - 1)
    }

    fn inside(&self, s: I64Vec2) -> bool {
        s.cmpge(I64Vec2::ZERO).all() && s.cmple(self.last()).all()
    }

    fn z(&self, s: I64Vec2) -> f64 {
        f64::from(self.z[s.y as usize * self.side[0] + s.x as usize])
    }
}

/// The measured bound (m) of lattice vertex `v` (a sample-level vertex, in
/// lattice units): infinite where a hole lies under the diamond or its
/// hypotenuse leaves the lattice. Halves whose apex leaves the lattice lie
/// outside it (the world's edge runs along the hypotenuse) and are skipped.
pub fn diamond_gap(grid: &SampleGrid, v: I64Vec2) -> f64 {
    let ([a, b], parents) = diamond(v);
    let [a, b] = [a, b].map(|p| p / grid.unit);
    if !(grid.inside(a) && grid.inside(b)) {
        return f64::INFINITY;
    }
    let (mut gap, mut base) = (0.0f64, 0u16);
    for p in parents.map(|p| p / grid.unit).into_iter().filter(|p| grid.inside(*p)) {
        let Some((g, h)) = triangle_gap(grid, [a, b, p]) else { return f64::INFINITY };
        (gap, base) = (gap.max(g), base.max(h));
    }
    gap + f64::from(half::f16::from_bits(base).to_f32())
}

/// The largest gap between triangle `t` (sample coordinates) drawn flat and
/// the samples in it (edges included), and their largest `base` bits;
/// None on a hole.
fn triangle_gap(grid: &SampleGrid, t: [I64Vec2; 3]) -> Option<(f64, u16)> {
    let [a, b, p] = t;
    let (za, zb, zp) = (grid.z(a), grid.z(b), grid.z(p));
    let (u, w) = ((b - a).as_dvec2(), (p - a).as_dvec2());
    let det = u.perp_dot(w);
    let gx = ((zb - za) * w.y - (zp - za) * u.y) / det;
    let gy = (u.x * (zp - za) - w.x * (zb - za)) / det;
    let lo = a.min(b).min(p).max(I64Vec2::ZERO);
    let hi = a.max(b).max(p).min(grid.last());
    let (mut gap, mut base) = (0.0f64, 0u16);
    for y in lo.y..=hi.y {
        let Some((x0, x1)) = row_span(t, y, lo.x, hi.x) else { continue };
        let row = y as usize * grid.side[0];
        let c0 = za + gx * (-a.x as f64) + gy * (y - a.y) as f64;
        for x in x0..=x1 {
            let i = row + x as usize;
            if grid.hole.get(i) == Some(&true) {
                return None;
            }
            gap = gap.max((f64::from(grid.z[i]) - (c0 + gx * x as f64)).abs());
            base = base.max(grid.base.get(i).copied().unwrap_or(0));
        }
    }
    Some((gap, base))
}

/// The columns of row `y` inside triangle `t` (closed), within `lo..=hi`.
fn row_span(t: [I64Vec2; 3], y: i64, mut lo: i64, mut hi: i64) -> Option<(i64, i64)> {
    for k in 0..3 {
        let (p, q, r) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
        let e = q - p;
        // e x (s - p) = a * x + c, on r's side: >= 0 once signed.
        let sign = e.perp_dot(r - p).signum();
        let (a, c) = (-e.y * sign, (e.x * (y - p.y) + e.y * p.x) * sign);
        match a.signum() {
            1 => lo = lo.max(-(c.div_euclid(a))),
            -1 => hi = hi.min(c.div_euclid(-a)),
            _ if c < 0 => return None,
            _ => {}
        }
    }
    (lo <= hi).then_some((lo, hi))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::vertex_bounds_fine::UNITS;

    #[test]
    fn a_row_span_holds_exactly_the_triangle_s_points() {
        let t = [I64Vec2::new(0, 0), I64Vec2::new(4, 0), I64Vec2::new(2, 2)];
        assert_eq!(row_span(t, 0, -9, 9), Some((0, 4)));
        assert_eq!(row_span(t, 1, -9, 9), Some((1, 3)));
        assert_eq!(row_span(t, 2, -9, 9), Some((2, 2)));
        assert_eq!(row_span(t, 3, -9, 9), None);
        let s = [I64Vec2::new(0, 0), I64Vec2::new(2, 2), I64Vec2::new(0, 2)];
        assert_eq!(row_span(s, 1, -9, 9), Some((0, 1)));
        assert_eq!(row_span(s, 1, 1, 9), Some((1, 1)));
    }

    #[test]
    fn a_flat_diamond_measures_only_its_base_and_a_bump_its_height() {
        let side = [9usize, 9];
        let mut z: Vec<f32> = (0..81).map(|i| (i % 9) as f32 * 0.5 + (i / 9) as f32).collect();
        let hole = vec![false; 81];
        let mut base = vec![0u16; 81];
        base[4 * 9 + 5] = half::f16::from_f32(0.25).to_bits();
        // Centre vertex (4, 4) samples, level 4 in lattice units: the square 0..8.
        let v = I64Vec2::new(4, 4) * UNITS;
        let grid = SampleGrid { side, z: &z, hole: &hole, base: &base, unit: UNITS };
        assert!((diamond_gap(&grid, v) - 0.25).abs() < 1e-9);
        z[3 * 9 + 3] += 2.0;
        let grid = SampleGrid { side, z: &z, hole: &hole, base: &base, unit: UNITS };
        assert!((diamond_gap(&grid, v) - 2.25).abs() < 1e-6);
    }
}
