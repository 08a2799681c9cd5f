//! The per-triangle rule's baked numbers (`world::vertex_bounds`) against
//! what they promise, each derived here another way:
//! - the error of every sample-grid vertex bounds its diamond's gap from
//!   the finest surface (measured point by point here), never falls under
//!   a child's, and never exceeds the walked bintree's own-plus-child sum
//!   (`world::bintree`, f64, vertex by vertex over the finest lattice);
//!   holes give an infinite error, all-hole diamonds none, and past the
//!   extent the lattice continues the edge (finite, not holes);
//! - the reach covers the finest surface over the vertex's diamond;
//! - every node holds the same bits for a point it shares with another
//!   (borders, and a coarser node's points), procedural and image worlds;
//! - every triangle of the twin's cut on the baked numbers lies within its
//!   split vertex's error of the finest surface, on terraces and a
//!   sawtooth ridge.

use glam::{DVec2, I64Vec2};
use std::collections::HashMap;
use vista::reference::bintree_cut::{cut, lattice, Tri, FINEST};
use vista::reference::FinestSurface;
use vista::render::{Camera, View, DEFAULT_NEAR_M};
use vista::world::bintree::{children, classify, diamond, Bounds, Saturation, VertexErrors};
use vista::world::vertex_bounds::VertexBoundsTree;
use vista::world::{GridSource, HeightSource, Hole, NodeId, ProceduralSource, WorldDesc, NODE_QUADS};

/// A height function of world metres as a source.
struct Analytic(fn(f64, f64) -> f32, u64);

impl HeightSource for Analytic {
    fn sample(&self, x: f64, y: f64) -> f32 {
        (self.0)(x, y)
    }
    fn id_hash(&self) -> u64 {
        self.1
    }
}

/// Rough ground: relief at 40, 9 and 2 m, and a hashed jitter per metre.
fn rough(x: f64, y: f64) -> f32 {
    let h = ((x.round() as i64).wrapping_mul(73856093) ^ (y.round() as i64).wrapping_mul(19349663)) as u64 % 1000;
    (100.0
        + 12.0 * (x / 40.0).sin() * (y / 33.0).cos()
        + 3.0 * (x / 9.0 + y / 13.0).sin()
        + 0.6 * (y / 2.1).sin()
        + h as f64 * 2e-3) as f32
}

/// Terraces: 4 m steps every 7.3 m along x, tilted along y.
fn terraces(x: f64, y: f64) -> f32 {
    (100.0 + 4.0 * (x / 7.3).floor() + 0.05 * y) as f32
}

/// A sawtooth ridge: 9 m teeth 5.5 m long along a diagonal.
fn sawtooth(x: f64, y: f64) -> f32 {
    let s = (x + 0.7 * y) / 5.5;
    (100.0 + 9.0 * (s - s.floor()) - 0.02 * (x - 128.0).abs()) as f32
}

fn world(extent: f64, lods: u32) -> WorldDesc {
    WorldDesc {
        extent_m: [extent, extent],
        height_range_m: [0.0, 400.0],
        spacing_m: 1.0,
        lod_count: lods,
        ..Default::default()
    }
}

/// Two hole shapes (a pit and a slot) over rough ground.
fn holes() -> Vec<Hole> {
    vec![
        Hole::Circle { center_m: [60.0, 190.0], radius_m: 9.0 },
        Hole::Polygon(vec![[300.0, 40.0], [306.0, 40.0], [306.0, 90.0], [300.0, 90.0]]),
    ]
}

/// The finest surface with the bake's holes: a lattice point takes its
/// nearest sample's (ties up); past the extent, the edge's nearest sample's
/// (the numbers continue the edge there: the GPU drops those triangles).
fn finest_with_holes<'a>(w: &'a WorldDesc, s: &'a FinestSurface, holes: &'a [Hole]) -> impl Fn(I64Vec2) -> f64 + 'a {
    move |v: I64Vec2| {
        let near = DVec2::from(w.sample_pos((v.x + 2) >> 2, (v.y + 2) >> 2)).min(DVec2::from(w.extent_m));
        if holes.iter().any(|h| h.contains(near.x, near.y)) {
            return f64::NAN;
        }
        s.at_lattice(v.x, v.y)
    }
}

#[test]
fn errors_bound_each_diamond_s_gap_never_above_the_walked_sum_across_fine_blocks_and_holes() {
    // 380 m: two LOD-0 nodes... of a 512-sample root, so the fine pass's
    // blocks (256 samples) meet inside it and the extent ends mid-root.
    let w = world(380.0, 3);
    let source = Analytic(rough, 1);
    let holes = holes();
    let mut tree = VertexBoundsTree::compute(&w, &source, &holes).unwrap();
    let finest = FinestSurface::new(&w, &source);
    let height = finest_with_holes(&w, &finest, &holes);
    let mut walked = VertexErrors::new(&height, lattice(&w, FINEST), Saturation::Nested);
    let last = lattice(&w, 0).hi;
    let (mut finite, mut infinite, mut empty, mut measured) = (0, 0, 0, 0);
    let mut ratios: Vec<(u32, f64)> = Vec::new();
    for y in 0..=last.y {
        for x in 0..=last.x {
            let s = I64Vec2::new(x, y);
            if s == I64Vec2::ZERO {
                continue;
            }
            let sum = walked.bound(s * 4).error_m;
            let (_, n) = tree.at(s);
            if !sum.is_finite() {
                assert!(n.error_m.is_infinite() || n.empty, "{s}: {n:?}, walked infinite");
                infinite += usize::from(!n.empty);
                empty += usize::from(n.empty);
                continue;
            }
            // Never looser than the walked sum (f32 rounded up once a half-level).
            assert!(!n.empty && n.error_m <= sum * (1.0 + 1e-5) + 1e-9, "{s}: {n:?} over the sum {sum}");
            // Saturated: never below a child's.
            for c in children(s * 4).into_iter().filter(|c| c.cmpge(I64Vec2::ZERO).all() && c.cmple(last * 4).all()) {
                if c.x % 4 == 0 && c.y % 4 == 0 {
                    let k = tree.at(c / 4).1;
                    assert!(k.empty || n.error_m >= k.error_m, "{s}: {} under child {c}'s {}", n.error_m, k.error_m);
                }
            }
            // A bound: every coarse diamond, and one fine one in 7, against
            // the finest surface measured point by point.
            let (t, _) = classify(s);
            if t >= 3 || (x * 31 + y * 17) % 7 == 0 {
                let gap = diamond_gap_m(s, last, &mut tree, &finest);
                assert!(n.error_m >= gap, "{s}: error {} under the diamond's gap {gap}", n.error_m);
                measured += 1;
            }
            ratios.push((t, n.error_m / sum.max(1e-12)));
            finite += 1;
        }
    }
    let coarse: Vec<f64> = ratios.iter().filter(|(t, _)| *t >= 4).map(|(_, r)| *r).collect();
    let mean = coarse.iter().sum::<f64>() / coarse.len() as f64;
    eprintln!("{finite} finite ({measured} measured), {infinite} infinite, {empty} empty vertices; coarse error / sum {mean:.3}");
    // Past the extent (380 of 512 m) the lattice continues the edge: only
    // the holes' vertices are infinite or empty.
    assert!(finite > 250_000 && infinite > 100 && empty > 100, "{finite} {infinite} {empty}");
    // The measured bound is what the rule is for: on rough ground the
    // coarse levels' sums add a term per half-level the gap does not have.
    assert!(mean < 0.8, "coarse levels' errors {mean:.3} of the sum: the measured bound is not used");
}

/// The largest gap between sample vertex `s`'s diamond drawn unsplit (its
/// halves inside the lattice) and the finest surface.
fn diamond_gap_m(s: I64Vec2, last: I64Vec2, tree: &mut VertexBoundsTree, finest: &FinestSurface) -> f64 {
    let ([a, b], parents) = diamond(s);
    let inside = |p: &I64Vec2| p.cmpge(I64Vec2::ZERO).all() && p.cmple(last).all();
    parents.iter().filter(|p| inside(p)).map(|p| gap_m(&Tri { apex: *p, b: a, c: b }, tree, finest)).fold(0.0, f64::max)
}

/// Lattice points (finest) of the diamond of fine vertex `v`: the two
/// triangles around its hypotenuse.
fn diamond_points(v: I64Vec2) -> Vec<I64Vec2> {
    let ([a, b], [p, q]) = diamond(v);
    let tris = [Tri { apex: p, b: a, c: b }, Tri { apex: q, b: a, c: b }];
    let lo = a.min(b).min(p).min(q);
    let hi = a.max(b).max(p).max(q);
    let mut out = Vec::new();
    for y in lo.y..=hi.y {
        for x in lo.x..=hi.x {
            let c = I64Vec2::new(x, y);
            let inside = |t: &Tri| {
                let [a, b, c2] = t.corners();
                let s = |u: I64Vec2, w: I64Vec2| (w - u).perp_dot(c - u);
                let (d0, d1, d2) = (s(a, b), s(b, c2), s(c2, a));
                (d0 >= 0 && d1 >= 0 && d2 >= 0) || (d0 <= 0 && d1 <= 0 && d2 <= 0)
            };
            if tris.iter().any(inside) {
                out.push(c);
            }
        }
    }
    out
}

#[test]
fn the_reach_covers_the_finest_surface_over_each_diamond() {
    let w = world(128.0, 1);
    let source = Analytic(sawtooth, 2);
    let tree = VertexBoundsTree::compute(&w, &source, &[]).unwrap();
    let finest = FinestSurface::new(&w, &source);
    let mut checked = 0;
    for y in 0..=128i64 {
        for x in 0..=128i64 {
            let s = I64Vec2::new(x, y);
            if s == I64Vec2::ZERO || (x % 128 == 0 && y % 128 == 0) {
                continue;
            }
            let (z, n) = tree.at(s);
            let far = diamond_points(s * 4)
                .into_iter()
                .filter(|p| p.cmpge(I64Vec2::ZERO).all() && p.cmple(I64Vec2::splat(512)).all())
                .map(|p| (finest.at_lattice(p.x, p.y) - f64::from(z)).abs())
                .fold(0.0, f64::max);
            assert!(n.reach_m >= far, "{s}: reach {} under the diamond's {far}", n.reach_m);
            checked += 1;
        }
    }
    assert_eq!(checked, 129 * 129 - 4);
}

/// Every node's values by the sample they stand at; the count of points
/// found in two nodes (all equal, or the test fails).
fn shared_points(tree: &VertexBoundsTree, w: &WorldDesc) -> usize {
    let mut seen: HashMap<I64Vec2, (u32, NodeId)> = HashMap::new();
    let mut shared = 0;
    let side = VertexBoundsTree::lattice_side(w);
    let last = I64Vec2::new(side[0] as i64 - 1, side[1] as i64 - 1);
    for lod in 0..w.lod_count as u8 {
        for id in w.nodes_at(lod) {
            let values = tree.node_values(id);
            let step = 1i64 << lod;
            // The heights' atlas layout: 132 x 132 texels, grid point -2 first.
            assert_eq!(values.len(), 132 * 132);
            let first = (I64Vec2::new(i64::from(id.x), i64::from(id.y)) * i64::from(NODE_QUADS) - 2) * step;
            for (k, v) in values.iter().enumerate() {
                let s = first + I64Vec2::new(k as i64 % 132, k as i64 / 132) * step;
                if s.cmplt(I64Vec2::ZERO).any() || s.cmpgt(last).any() {
                    // Past the lattice: infinite, so it never lowers a smaller-of-two.
                    assert_eq!(*v, 0x7C00_7C00, "{id} {s}");
                    continue;
                }
                // The f16 pair rounds the tree's numbers up.
                let (_, n) = tree.at(s);
                let err = half::f16::from_bits(*v as u16).to_f32();
                assert!(f64::from(err) >= if n.empty { 0.0 } else { n.error_m }, "{id} {s}");
                match seen.get(&s) {
                    Some((other, at)) => {
                        assert_eq!(other, v, "{s}: {at} and {id} differ");
                        shared += 1;
                    }
                    None => {
                        seen.insert(s, (*v, id));
                    }
                }
            }
        }
    }
    shared
}

#[test]
fn every_node_holds_the_same_bits_where_nodes_meet_procedural_and_image_worlds() {
    let w = world(512.0, 3);
    let procedural = ProceduralSource::new(3, w.extent_m, [0.0, 400.0]).unwrap();
    let posts: Vec<f32> = (0..65 * 65).map(|i| ((i * 7919) % 97) as f32 * 0.8 + 50.0).collect();
    let image = GridSource::new(65, 65, posts, w.extent_m);
    for source in [&procedural as &dyn HeightSource, &image] {
        let tree = VertexBoundsTree::compute(&w, source, &holes()).unwrap();
        let shared = shared_points(&tree, &w);
        // The root's 129^2 points are all LOD-1 points too, and so on down;
        // LOD-0 nodes share their borders (4 x 4 of them: 3 x 2 x 4 lines).
        assert!(shared > 2 * 129 * 129 + 24 * 129, "only {shared} points held twice");
    }
}

fn view(camera: Camera, target: f32) -> View {
    View { camera, fov_y_deg: 60.0, size: [256, 192], target_error_px: target, near_m: DEFAULT_NEAR_M }
}

/// Largest vertical gap (m) between triangle `t` (sample lattice) and the
/// finest surface at the finest lattice points inside it.
fn gap_m(t: &Tri, tree: &mut VertexBoundsTree, finest: &FinestSurface) -> f64 {
    let [a, b, c] = t.corners();
    let (za, zb, zc) = (tree.point(a).z, tree.point(b).z, tree.point(c).z);
    let (a4, b4, c4) = (a * 4, b * 4, c * 4);
    let (lo, hi) = (a4.min(b4).min(c4), a4.max(b4).max(c4));
    let area = (b4 - a4).perp_dot(c4 - a4) as f64;
    let mut worst = 0.0f64;
    for y in lo.y..=hi.y {
        for x in lo.x..=hi.x {
            let p = I64Vec2::new(x, y);
            let w = [(c4 - b4).perp_dot(p - b4), (a4 - c4).perp_dot(p - c4), (b4 - a4).perp_dot(p - a4)];
            let w = w.map(|k| k as f64 / area);
            if w.iter().any(|k| *k < 0.0) {
                continue;
            }
            let drawn = w[0] * za + w[1] * zb + w[2] * zc;
            worst = worst.max((drawn - finest.at_lattice(x, y)).abs());
        }
    }
    worst
}

#[test]
fn every_triangle_of_the_cut_lies_within_its_split_vertex_s_error_on_terraces_and_a_sawtooth() {
    let w = world(256.0, 2);
    let cameras = [
        Camera { position_m: [128.0, -30.0, 160.0], yaw_deg: 0.0, pitch_deg: -35.0 },
        Camera { position_m: [20.0, 200.0, 130.0], yaw_deg: 120.0, pitch_deg: -20.0 },
    ];
    for (name, f) in [("terraces", terraces as fn(f64, f64) -> f32), ("sawtooth", sawtooth)] {
        let source = Analytic(f, 3);
        let mut tree = VertexBoundsTree::compute(&w, &source, &[]).unwrap();
        let finest = FinestSurface::new(&w, &source);
        for target in [1.0f32, 4.0] {
            for c in cameras {
                let tris = cut(&w, 0, &mut tree, &view(c, target).traverse_camera(), f64::from(target));
                let mut worst_ratio = 0.0f64;
                for t in &tris {
                    let gap = gap_m(t, &mut tree, &finest);
                    let bound = match t.split() {
                        Some(m) => tree.bound(m).error_m,
                        // A sample quad's triangle: its node's quad centres bound it.
                        None => {
                            let lo = t.apex.min(t.b).min(t.c);
                            let n = (lo / NODE_QUADS as i64).min(I64Vec2::splat(1));
                            f64::from(tree.node_refine(NodeId::new(0, n.x as u32, n.y as u32)).error_m)
                        }
                    };
                    assert!(gap <= bound, "{name} {target} px: {t:?} {gap} m over its bound {bound} m");
                    worst_ratio = worst_ratio.max(gap / bound.max(1e-12));
                }
                let levels: Vec<u32> = tris.iter().filter_map(|t| t.split()).map(|m| classify(m).0).collect();
                eprintln!(
                    "{name} {target} px: {} triangles, worst gap / bound {worst_ratio:.3}, coarsest split level {:?}",
                    tris.len(),
                    levels.iter().max()
                );
                assert!(tris.len() < 2 * 256 * 256, "{name}: everything drawn finest");
            }
        }
    }
}
