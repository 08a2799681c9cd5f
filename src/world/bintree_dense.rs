//! Every vertex's saturated bounds over a whole lattice at once
//! ([`super::bintree`]), for lattices too large to walk vertex by vertex:
//! one array per number, filled a half-level at a time from the finest
//! (the edge midpoints of lattice level t, then the quad centres of level
//! t, whose children are all finer), each half-level in parallel. Values
//! are stored as f32 rounded away from zero, so a bound stays a bound.
//! Errors are the rule's sum lowered to the diamond's gap measured against
//! the lattice (`vertex_bounds_exact`), as the renderer bakes them.

use super::bintree::{children, nest, own_bound, Bounds, Kind, Lattice, VertexBound};
use super::vertex_bounds_exact::{diamond_gap, SampleGrid};
use glam::{DVec3, I64Vec2};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

/// Bounds of every point of a lattice whose low corner is 0.
pub struct DenseBounds {
    lattice: Lattice,
    /// Points per row.
    width: usize,
    z: Vec<f32>,
    error: Vec<AtomicU32>,
    radius: Vec<AtomicU32>,
}

/// `x` as f32, no smaller in magnitude.
fn up(x: f64) -> f32 {
    let f = x as f32;
    if f.is_finite() && f64::from(f).abs() < x.abs() {
        f32::from_bits(f.to_bits() + 1)
    } else {
        f
    }
}

impl DenseBounds {
    /// Heights a row at a time from `row` (its y and the row to fill;
    /// NaN: a hole), then every vertex's bounds.
    pub fn compute(lattice: Lattice, row: &(dyn Fn(i64, &mut [f32]) + Sync)) -> Self {
        assert!(lattice.lo == I64Vec2::ZERO && lattice.hi.cmpgt(I64Vec2::ZERO).all(), "lattice from 0");
        let width = lattice.hi.x as usize + 1;
        let rows = lattice.hi.y as usize + 1;
        let mut z = vec![0.0f32; width * rows];
        z.par_chunks_mut(width).enumerate().for_each(|(y, out)| row(y as i64, out));
        let zeros = || (0..width * rows).map(|_| AtomicU32::new(0)).collect::<Vec<_>>();
        let d = DenseBounds { lattice, width, z, error: zeros(), radius: zeros() };
        let top = 64 - lattice.hi.max_element().leading_zeros();
        for t in 0..top {
            d.fill(t, Kind::Edge);
            d.fill(t, Kind::Centre);
        }
        d
    }

    fn index(&self, v: I64Vec2) -> usize {
        v.y as usize * self.width + v.x as usize
    }

    fn height(&self, v: I64Vec2) -> f64 {
        f64::from(self.z[self.index(v)])
    }

    fn stored(&self, v: I64Vec2) -> VertexBound {
        let i = self.index(v);
        let f = |a: &AtomicU32| f64::from(f32::from_bits(a.load(Ordering::Relaxed)));
        VertexBound { z_m: self.height(v), error_m: f(&self.error[i]), radius_m: f(&self.radius[i]) }
    }

    /// Bounds of the vertices of lattice level `t` of `kind`: their children
    /// were filled before.
    fn fill(&self, t: u32, kind: Kind) {
        let d = 1i64 << t;
        let hi = self.lattice.hi;
        (0..=hi.y / d).into_par_iter().for_each(|row| {
            let y = row * d;
            for x in (0..=hi.x).step_by(d as usize) {
                let v = I64Vec2::new(x, y);
                let odd = [(x >> t) & 1 == 1, (y >> t) & 1 == 1];
                let here = match kind {
                    Kind::Centre => odd[0] && odd[1],
                    Kind::Edge => odd[0] != odd[1],
                };
                if here {
                    self.store(v);
                }
            }
        });
    }

    fn store(&self, v: I64Vec2) {
        let lattice = self.lattice;
        let own = own_bound(&lattice, v, &mut |c| if lattice.contains(c) { self.height(c) } else { f64::NAN });
        let kids: Vec<(DVec3, VertexBound)> = children(v)
            .into_iter()
            .filter(|c| lattice.contains(*c))
            .map(|c| (lattice.point(c, self.height(c)), self.stored(c)))
            .collect();
        let mut b = nest(own, lattice.point(v, own.z_m), &kids);
        if b.error_m.is_finite() {
            // The rule's sum lowered to the measured gap, never under a child's.
            let rows = self.z.len() / self.width;
            let grid = SampleGrid { side: [self.width, rows], z: &self.z, hole: &[], base: &[], unit: 1 };
            let floor = kids.iter().map(|(_, k)| k.error_m).fold(0.0, f64::max);
            b.error_m = b.error_m.min(diamond_gap(&grid, v)).max(floor);
        }
        let i = self.index(v);
        self.error[i].store(up(b.error_m).to_bits(), Ordering::Relaxed);
        self.radius[i].store(up(b.radius_m).to_bits(), Ordering::Relaxed);
    }
}

impl DenseBounds {
    /// The bounds of split vertex `v`.
    pub fn get(&self, v: I64Vec2) -> VertexBound {
        self.stored(v)
    }

    /// `v` in world metres at its height.
    pub fn at(&self, v: I64Vec2) -> DVec3 {
        self.lattice.point(v, self.height(v))
    }
}

impl Bounds for DenseBounds {
    fn bound(&mut self, v: I64Vec2) -> VertexBound {
        self.get(v)
    }

    fn point(&mut self, v: I64Vec2) -> DVec3 {
        self.at(v)
    }
}
