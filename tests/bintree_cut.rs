//! The per-triangle LOD rule's promises, on its CPU twin
//! (`reference::bintree_cut` over `world::bintree`): a conforming cut that
//! covers the world, bounds that do not depend on the node asking, and a
//! strict error bound on adversarial surfaces.

use glam::I64Vec2;
use vista::reference::bintree_cut::{cut, lattice, measured_error_px, t_junctions, Tri, FINEST};
use vista::reference::FinestSurface;
use vista::render::{Camera, View, DEFAULT_NEAR_M};
use vista::world::bintree::{Bounds, Saturation, VertexBound, VertexErrors};
use vista::world::{GridSource, HeightSource, NodeId, ProceduralSource, WorldDesc, NODE_QUADS};

/// 256 m at 1 m samples, two LODs: one root of 256 m over four LOD-0
/// nodes; the finest lattice is 1025 points a side.
fn world() -> WorldDesc {
    WorldDesc {
        extent_m: [256.0, 256.0],
        height_range_m: [0.0, 400.0],
        spacing_m: 1.0,
        lod_count: 2,
        ..Default::default()
    }
}

/// A small deterministic generator (tests need no crate for it).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

/// Rough ground (metres of relief at 40, 9 and 2 m wavelengths, and a
/// hashed jitter per point) with two holes (NaN).
fn rough(v: I64Vec2) -> f64 {
    let (x, y) = (v.x as f64 * 0.25, v.y as f64 * 0.25);
    let hole = |cx: f64, cy: f64, r: f64| (x - cx).hypot(y - cy) < r;
    if hole(60.0, 190.0, 9.0) || hole(170.0, 80.0, 4.5) {
        return f64::NAN;
    }
    let h = (v.x.wrapping_mul(73856093) ^ v.y.wrapping_mul(19349663)) as u64 % 1000;
    100.0
        + 12.0 * (x / 40.0).sin() * (y / 33.0).cos()
        + 3.0 * (x / 9.0 + y / 13.0).sin()
        + 0.6 * (y / 2.1).sin()
        + h as f64 * 2e-4
}

fn view(camera: Camera, target: f32) -> View {
    View { camera, fov_y_deg: 60.0, size: [256, 192], target_error_px: target, near_m: DEFAULT_NEAR_M }
}

fn random_view(rng: &mut Lcg, target: f32) -> View {
    let camera = Camera {
        position_m: [rng.range(-40.0, 296.0), rng.range(-40.0, 296.0), rng.range(115.0, 260.0)],
        yaw_deg: rng.range(0.0, 360.0),
        pitch_deg: rng.range(-80.0, -5.0),
    };
    view(camera, target)
}

fn errors<'a>(w: &WorldDesc, height: &'a dyn Fn(I64Vec2) -> f64, s: Saturation) -> VertexErrors<'a> {
    VertexErrors::new(height, lattice(w, FINEST), s)
}

fn covered(tris: &[Tri]) -> i64 {
    tris.iter().map(Tri::area2).sum()
}

#[test]
fn the_cut_conforms_and_covers_the_world_over_100_views_of_rough_ground_with_holes() {
    let w = world();
    let l = lattice(&w, FINEST);
    let whole = 2 * (l.hi - l.lo).x * (l.hi - l.lo).y;
    let mut rng = Lcg(7);
    let (mut rule, mut off) = (errors(&w, &rough, Saturation::Measured), errors(&w, &rough, Saturation::Off));
    let mut cracked_without_saturation = 0;
    for i in 0..100 {
        let v = random_view(&mut rng, if i % 2 == 0 { 1.0 } else { 4.0 });
        let cam = v.traverse_camera();
        let tris = cut(&w, FINEST, &mut rule, &cam, f64::from(v.target_error_px));
        assert_eq!(t_junctions(&tris), 0, "view {i}: {:?}", v.camera);
        // The triangles tile the roots: no gap a background pixel could
        // show through (they never overlap: bintree leaves).
        assert_eq!(covered(&tris), whole, "view {i}");
        let unsaturated = cut(&w, FINEST, &mut off, &cam, f64::from(v.target_error_px));
        cracked_without_saturation += usize::from(t_junctions(&unsaturated) > 0);
    }
    // Without saturation a child can split while its parent does not.
    assert!(cracked_without_saturation > 10, "only {cracked_without_saturation} views cracked without saturation");
}

/// Every vertex of every node of `w`'s tree (at the node's own sample
/// spacing), each node computed from a fresh set of bounds.
fn per_node_bounds(w: &WorldDesc, height: &dyn Fn(I64Vec2) -> f64) -> usize {
    let mut seen: std::collections::HashMap<I64Vec2, (NodeId, VertexBound)> = Default::default();
    let mut shared = 0;
    let nodes: Vec<NodeId> = (0..w.lod_count as u8).flat_map(|l| w.nodes_at(l)).collect();
    for n in nodes {
        let mut e = errors(w, height, Saturation::Measured);
        let step = 4i64 << n.lod;
        let base = I64Vec2::new(i64::from(n.x), i64::from(n.y)) * step * i64::from(NODE_QUADS);
        for j in 0..=i64::from(NODE_QUADS) {
            for i in 0..=i64::from(NODE_QUADS) {
                let v = base + I64Vec2::new(i, j) * step;
                if v == I64Vec2::ZERO {
                    continue;
                }
                let b = e.bound(v);
                if let Some((other, was)) = seen.insert(v, (n, b)) {
                    let same = |a: f64, b: f64| a.to_bits() == b.to_bits();
                    assert!(
                        same(was.error_m, b.error_m) && same(was.radius_m, b.radius_m) && same(was.z_m, b.z_m),
                        "{v}: {was:?} in {other:?}, {b:?} in {n:?}"
                    );
                    shared += 1;
                }
            }
        }
    }
    shared
}

#[test]
fn saturated_bounds_are_the_same_in_every_node_that_holds_the_vertex() {
    let w = world();
    // A procedural world and an image world (a 65 x 65 grid of posts),
    // both through the finest surface the renderer draws.
    let procedural = ProceduralSource::new(3, w.extent_m, [0.0, 400.0]).unwrap();
    let posts: Vec<f32> = (0..65 * 65).map(|i| ((i * 7919) % 97) as f32 * 0.8 + 50.0).collect();
    let image = GridSource::new(65, 65, posts, w.extent_m);
    for source in [&procedural as &dyn HeightSource, &image] {
        let finest = FinestSurface::new(&w, source);
        let height = |v: I64Vec2| finest.at_lattice(v.x, v.y);
        let shared = per_node_bounds(&w, &height);
        // Every vertex of the root is also one of a LOD-0 node's, and the
        // LOD-0 nodes share their borders.
        assert!(shared > 129 * 129, "only {shared} vertices held twice");
    }
}

/// Terraces: 4 m steps every 7.3 m along x, tilted along y.
fn terraces(v: I64Vec2) -> f64 {
    let (x, y) = (v.x as f64 * 0.25, v.y as f64 * 0.25);
    100.0 + 4.0 * (x / 7.3).floor() + 0.05 * y
}

/// A sawtooth ridge: 9 m teeth 5.5 m long running along a diagonal.
fn sawtooth(v: I64Vec2) -> f64 {
    let (x, y) = (v.x as f64 * 0.25, v.y as f64 * 0.25);
    let s = (x + 0.7 * y) / 5.5;
    100.0 + 9.0 * (s - s.floor()) - 0.02 * (x - 128.0).abs()
}

#[test]
fn every_drawn_triangle_keeps_the_target_on_terraces_and_a_sawtooth() {
    let w = world();
    let cameras = [
        Camera { position_m: [128.0, -30.0, 160.0], yaw_deg: 0.0, pitch_deg: -35.0 },
        Camera { position_m: [20.0, 200.0, 130.0], yaw_deg: 120.0, pitch_deg: -20.0 },
        Camera { position_m: [128.0, 128.0, 400.0], yaw_deg: 45.0, pitch_deg: -89.0 },
    ];
    for (name, surface) in [("terraces", &terraces as &dyn Fn(I64Vec2) -> f64), ("sawtooth", &sawtooth)] {
        let mut e = errors(&w, surface, Saturation::Measured);
        for target in [1.0f32, 4.0] {
            for c in cameras {
                let v = view(c, target);
                let tris = cut(&w, FINEST, &mut e, &v.traverse_camera(), f64::from(target));
                let worst = tris.iter().map(|t| measured_error_px(t, &mut e, &v)).fold(0.0, f64::max);
                eprintln!("{name} {target} {:?}: worst {worst:.3} px, {} triangles", c.position_m, tris.len());
                assert!(worst <= f64::from(target), "{name} at {target} px from {c:?}: {worst} px");
                // The bound is not met by drawing everything finest.
                assert!(tris.len() < 2 * 1024 * 1024 / 4, "{name}: {} triangles", tris.len());
            }
        }
    }
}

#[test]
fn bounds_filled_at_once_equal_those_walked_vertex_by_vertex() {
    // The samples' lattice of the small world (257 points a side).
    let w = world();
    let l = lattice(&w, 0);
    // Heights as the bake stores them (f32), as the filled lattice keeps them.
    let height = |v: I64Vec2| f64::from(rough(v * 4) as f32);
    let mut walked = VertexErrors::new(&height, l, Saturation::Measured);
    let row = |y: i64, out: &mut [f32]| {
        for (x, h) in out.iter_mut().enumerate() {
            *h = height(I64Vec2::new(x as i64, y)) as f32;
        }
    };
    let mut dense = vista::world::bintree_dense::DenseBounds::compute(l, &row);
    let mut checked = 0;
    for y in 0..=l.hi.y {
        for x in 0..=l.hi.x {
            let v = I64Vec2::new(x, y);
            if v == I64Vec2::ZERO || (x % 256 == 0 && y % 256 == 0) {
                // The root's corners split nothing.
                continue;
            }
            let (a, b) = (walked.bound(v), dense.bound(v));
            // Stored as f32 rounded outwards: no smaller, within an f32 step.
            let close = |exact: f64, stored: f64| {
                (exact.is_infinite() && stored.is_infinite())
                    || (stored >= exact && stored <= exact * (1.0 + 1e-6) + 1e-30)
            };
            assert!(close(a.error_m, b.error_m) && close(a.radius_m, b.radius_m), "{v}: {a:?} walked, {b:?} filled");
            checked += 1;
        }
    }
    assert_eq!(checked, 257 * 257 - 4);
}

/// Largest screen jumps (px) of visible points that the rule's LOD changes
/// cause along a slow flight (not the camera's move): at every frame's
/// visible ground, the height the last frame's cut drew against this
/// frame's, both seen from this frame's camera. p99 and max.
fn popping(w: &WorldDesc, e: &mut VertexErrors, height: &dyn Fn(I64Vec2) -> f64, target: f32) -> (f64, f64) {
    let mut jumps = Vec::new();
    let mut last: Option<vista::world::TraverseCamera> = None;
    for frame in 0..16 {
        // 2 m a frame at 60 m above a 100 m base, across the rough hills.
        let c = Camera { position_m: [60.0 + 2.0 * f64::from(frame), 20.0, 160.0], yaw_deg: 30.0, pitch_deg: -30.0 };
        let v = View { size: [96, 72], ..view(c, target) };
        let cam = v.traverse_camera();
        if let Some(prev) = &last {
            for py in 0..72 {
                for px in 0..96 {
                    // The ground this pixel sees: marched along its ray on the finest surface.
                    let Some(p) = hit(&v, [f64::from(px) + 0.5, f64::from(py) + 0.5], height) else { continue };
                    let xy = p.truncate();
                    let target = f64::from(target);
                    let (Some(z0), Some(z1)) = (
                        vista::reference::bintree_cut::drawn_z(w, FINEST, e, prev, target, xy),
                        vista::reference::bintree_cut::drawn_z(w, FINEST, e, &cam, target, xy),
                    ) else {
                        continue;
                    };
                    let (Some((a, _)), Some((b, _))) = (v.project([xy.x, xy.y, z0]), v.project([xy.x, xy.y, z1]))
                    else {
                        continue;
                    };
                    jumps.push((a[0] - b[0]).hypot(a[1] - b[1]));
                }
            }
        }
        last = Some(cam);
    }
    jumps.sort_by(f64::total_cmp);
    (jumps[jumps.len() * 99 / 100], *jumps.last().unwrap())
}

/// The first point of the finest surface along pixel `px`'s ray (25 cm steps).
fn hit(v: &View, px: [f64; 2], height: &dyn Fn(I64Vec2) -> f64) -> Option<glam::DVec3> {
    let (o, d) = (glam::DVec3::from(v.camera.position_m), v.ray(px));
    (1..2400).map(|k| o + d * (f64::from(k) * 0.25)).find(|p| {
        let l = (p.truncate() * 4.0).round().as_i64vec2();
        (0..=1024).contains(&l.x) && (0..=1024).contains(&l.y) && p.z <= height(l)
    })
}

#[test]
fn the_rule_s_popping_along_a_slow_flight_is_measured() {
    let w = world();
    let height = |v: I64Vec2| f64::from(rough(v) as f32);
    let height = |v: I64Vec2| if height(v).is_nan() { 100.0 } else { height(v) };
    let mut e = errors(&w, &height, Saturation::Measured);
    for target in [1.0f32, 4.0] {
        let (p99, max) = popping(&w, &mut e, &height, target);
        eprintln!("popping at {target} px: p99 {p99:.3} px, max {max:.3} px");
        // A vertex that splits this frame was within the target last
        // frame, and the finer surface is within it now: a jump is at most
        // about twice the target.
        assert!(max <= 2.0 * f64::from(target) * 1.1, "{target} px: max jump {max}");
        assert!(p99 <= f64::from(target), "{target} px: p99 jump {p99}");
    }
}
