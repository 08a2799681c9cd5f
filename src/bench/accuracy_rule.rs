//! What the per-triangle LOD rule (`reference::bintree_cut`) is expected
//! to draw for a view, counted as the floors count ([`super::accuracy_floor`]):
//! each visible point lies in one triangle of the rule's cut; a triangle
//! stands for its seen area over its own, and at least one.
//!
//! The saturated bounds of a vertex depend on every lattice point under
//! it, so the CPU computes the world's whole lattice: the finest one (down
//! to `REFINE_LEVELS` below the samples) up to [`MAX_FINEST_POINTS`], else
//! the samples' own (the rule then stops at LOD 0) up to
//! [`MAX_SAMPLE_POINTS`]; larger worlds get no figure here (the renderer
//! will bake the bounds with the nodes instead).

use super::accuracy_floor::{units_for, Seen};
use crate::reference::bintree_cut::{lattice, triangle_at, Tri, FINEST};
use crate::reference::finest::stored_post;
use crate::reference::FinestSurface;
use crate::scene::view::View;
use crate::world::bintree::{Bounds, Saturation, VertexErrors};
use crate::world::bintree_dense::DenseBounds;
use crate::world::{HeightSource, WorldDesc};
use glam::I64Vec2;
use serde::Serialize;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// Largest finest lattice walked vertex by vertex: 2049^2 points (a 512 m
/// world at 1 m samples).
pub const MAX_FINEST_POINTS: u64 = 2049 * 2049;
/// Largest sample lattice filled at once: 3 arrays of f32 a point, 6 GB.
pub const MAX_SAMPLE_POINTS: u64 = 1 << 29;

/// The rule's expected triangles per pixel, and down to which lattice.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RuleFigure {
    pub per_pixel: f64,
    /// Refinement levels below LOD 0 the rule could use (0: it stops at
    /// the samples, the world being too large for its finest lattice here).
    pub below: u32,
}

fn points(world: &WorldDesc, below: u32) -> u64 {
    let side = lattice(world, below).hi + I64Vec2::ONE;
    (side.x as u64).saturating_mul(side.y as u64)
}

/// Triangles of the rule's cut standing for `seen` (None: world too large).
pub(super) fn rule_triangles(
    seen: &[Seen],
    view: &View,
    world: &WorldDesc,
    source: &dyn HeightSource,
) -> Option<RuleFigure> {
    if points(world, FINEST) <= MAX_FINEST_POINTS {
        let finest = FinestSurface::new(world, source);
        let height = |v: I64Vec2| finest.at_lattice(v.x, v.y);
        let mut bounds = VertexErrors::new(&height, lattice(world, FINEST), Saturation::Measured);
        return Some(RuleFigure { per_pixel: count(seen, view, world, FINEST, &mut bounds), below: FINEST });
    }
    if points(world, 0) <= MAX_SAMPLE_POINTS {
        let dense = dense_bounds(world, source);
        let mut bounds = Shared(&dense);
        return Some(RuleFigure { per_pixel: count(seen, view, world, 0, &mut bounds), below: 0 });
    }
    None
}

/// The last world's filled lattice: a bench asks for every view and target
/// of one world in turn.
static LAST: Mutex<Option<(u64, Arc<DenseBounds>)>> = Mutex::new(None);

fn dense_bounds(world: &WorldDesc, source: &dyn HeightSource) -> Arc<DenseBounds> {
    let key = world.hash() ^ source.id_hash().rotate_left(17);
    let mut last = LAST.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((k, b)) = last.as_ref().filter(|(k, _)| *k == key) {
        debug_assert_eq!(*k, key);
        return b.clone();
    }
    // Drop the previous world's arrays before filling the next.
    *last = None;
    let b = Arc::new(DenseBounds::compute(lattice(world, 0), &|j, out: &mut [f32]| stored_row(world, source, j, out)));
    *last = Some((key, b.clone()));
    b
}

/// Row `j` of LOD-0 samples as the bake stores them ([`stored_post`], a
/// row at a time).
fn stored_row(world: &WorldDesc, source: &dyn HeightSource, j: i64, out: &mut [f32]) {
    let [ex, ey] = world.extent_m;
    let xs: Vec<f64> = (0..out.len() as i64).map(|i| world.sample_pos(i, j)[0].clamp(0.0, ex)).collect();
    source.sample_row(&xs, world.sample_pos(0, j)[1].clamp(0.0, ey), out);
    for h in out.iter_mut() {
        *h = world.decode_height(world.encode_height(*h));
    }
    debug_assert!(out.is_empty() || f64::from(out[0]) == stored_post(world, source, 0, j) || out[0].is_nan());
}

/// A shared filled lattice read as [`Bounds`].
struct Shared<'a>(&'a DenseBounds);

impl Bounds for Shared<'_> {
    fn bound(&mut self, v: I64Vec2) -> crate::world::bintree::VertexBound {
        self.0.get(v)
    }

    fn point(&mut self, v: I64Vec2) -> glam::DVec3 {
        self.0.at(v)
    }
}

/// Triangles (not yet per pixel) the cut on `bounds` stands for.
fn count(seen: &[Seen], view: &View, world: &WorldDesc, below: u32, bounds: &mut dyn Bounds) -> f64 {
    let cam = view.traverse_camera();
    let target = f64::from(view.target_error_px);
    let mut chosen: HashMap<Tri, (f64, u32)> = HashMap::new();
    for s in seen {
        let Some(t) = triangle_at(world, below, bounds, &cam, target, s.p.truncate()) else { continue };
        let c = chosen.entry(t).or_insert((0.0, 0));
        *c = (c.0 + s.area.unwrap_or(0.0), c.1 + 1);
    }
    let m2 = lattice(world, below).unit_m.powi(2);
    chosen.iter().map(|(t, &(seen_m2, points))| units_for(t.area2() as f64 * 0.5 * m2, points, seen_m2)).sum()
}
