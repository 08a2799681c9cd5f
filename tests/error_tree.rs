//! The error tree is monotone over a whole world (every patch covers the
//! four finer patches under it, in error and height range) and
//! conservative: brute force over the finest surface, evaluated here
//! independently (a direct 4 x 4 Catmull-Rom sum over the source's LOD-0
//! samples), never finds a node's triangles farther from it than the
//! stored error.

mod common;

use common::Rng;
use std::collections::HashMap;
use std::sync::Arc;
use vista::world::{
    bake_node, diamond, ErrorTree, GridSource, HeightSource, NodeErrors, NodeId, ProceduralSource, WorldDesc,
    NODE_QUADS, PATCHES_PER_NODE, PATCHES_PER_NODE_SIDE, PATCH_QUADS,
};

/// Patches per node side and quads per patch side.
const SIDE: usize = PATCHES_PER_NODE_SIDE as usize;
const QUADS: usize = PATCH_QUADS as usize;

fn procedural() -> (WorldDesc, Arc<dyn HeightSource>) {
    let w = WorldDesc {
        extent_m: [1024.0, 896.0],
        height_range_m: [0.0, 1600.0],
        spacing_m: 1.0,
        lod_count: 4,
        ..WorldDesc::default()
    };
    let src = ProceduralSource::new(5, [10_240.0, 10_240.0], [0.0, 1600.0]).unwrap();
    // The default world's generator over a mountainous 1 km corner.
    (w, Arc::new(Offset(src, [4800.0, 6400.0])))
}

/// A 300 x 260 map of rough random heights at its own pixel size: the
/// vertices sit on its posts.
fn posts() -> (WorldDesc, Arc<dyn HeightSource>) {
    let (w, h) = (300, 260);
    let mut rng = Rng(77);
    let heights: Vec<f32> = (0..w * h)
        .map(|k| {
            let (x, y) = ((k % w) as f32, (k / w) as f32);
            40.0 * (x * 0.05).sin() * (y * 0.07).cos() + rng.unit() as f32 * 6.0
        })
        .collect();
    let extent = [w as f64 * 2.0, h as f64 * 2.0];
    let world = WorldDesc {
        extent_m: extent,
        height_range_m: [-60.0, 60.0],
        spacing_m: 2.0,
        lod_count: 3,
        ..WorldDesc::default()
    }
    .with_posts([2.0, 2.0]);
    assert!(world.on_posts());
    (world, Arc::new(GridSource::new(w, h, heights, extent)))
}

struct Offset(ProceduralSource, [f64; 2]);

impl HeightSource for Offset {
    fn sample(&self, x: f64, y: f64) -> f32 {
        self.0.sample(x + self.1[0], y + self.1[1])
    }
    fn id_hash(&self) -> u64 {
        self.0.id_hash() ^ 0x5eed
    }
}

fn every_node(w: &WorldDesc) -> Vec<NodeId> {
    (0..w.lod_count as u8).flat_map(|l| w.nodes_at(l)).collect()
}

#[test]
fn errors_and_bounds_are_monotone_over_whole_trees() {
    for (world, source) in [procedural(), posts()] {
        let tree = ErrorTree::new(&world, source, None).unwrap();
        let errors: HashMap<NodeId, NodeErrors> =
            every_node(&world).into_iter().map(|n| (n, tree.node(n).unwrap())).collect();
        let mut checked = 0;
        for (id, e) in &errors {
            assert_eq!(e.node_m, e.patch_m.iter().map(|p| p[0]).fold(0.0, f32::max), "{id}");
            for p in &e.patch_m {
                assert!(p[0].is_finite() && p[0] >= p[1], "{id}: {p:?}");
            }
            for child in world.valid_children(*id) {
                let c = &errors[&child];
                assert!(e.node_m >= c.node_m, "{id} {} < {child} {}", e.node_m, c.node_m);
                assert!(e.repr_m >= c.repr_m, "{id} repr");
                // Child patch (i, j) lies under parent patch ((i + side * cx) / 2, ...).
                let (cx, cy) = ((child.x & 1) as usize, (child.y & 1) as usize);
                for (k, (cp, cb)) in c.patch_m.iter().zip(&c.bounds).enumerate() {
                    let (i, j) = (k % SIDE + SIDE * cx, k / SIDE + SIDE * cy);
                    let pk = (j / 2) * SIDE + i / 2;
                    assert!(e.patch_m[pk][0] >= cp[0], "{id} patch {pk} < {child} patch {k}");
                    assert!(e.patch_max_m[pk][0] >= c.patch_max_m[k][0], "{id} patch {pk} max < {child} patch {k}");
                    assert!(e.bounds[pk][0] <= cb[0] && e.bounds[pk][1] >= cb[1], "{id} bounds");
                    checked += 1;
                }
            }
        }
        assert!(checked >= 13 * PATCHES_PER_NODE, "{checked}");
    }
}

/// The finest surface at LOD-0 sample coordinates (x, y): 4 x 4
/// Catmull-Rom taps of the R16-rounded samples, summed directly.
fn finest(world: &WorldDesc, src: &dyn HeightSource, cache: &mut HashMap<(i64, i64), f64>, x: f64, y: f64) -> f64 {
    let cr = |t: f64| {
        let (t2, t3) = (t * t, t * t * t);
        [
            0.5 * (-t3 + 2.0 * t2 - t),
            0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
            0.5 * (-3.0 * t3 + 4.0 * t2 + t),
            0.5 * (t3 - t2),
        ]
    };
    let (i0, j0) = (x.floor() as i64, y.floor() as i64);
    let (wx, wy) = (cr(x - i0 as f64), cr(y - j0 as f64));
    let mut sum = 0.0;
    for (b, wyb) in wy.iter().enumerate() {
        for (a, wxa) in wx.iter().enumerate() {
            let (i, j) = (i0 + a as i64 - 1, j0 + b as i64 - 1);
            let h = *cache.entry((i, j)).or_insert_with(|| {
                let [px, py] = world.sample_pos(i, j);
                let v = src.sample(px.clamp(0.0, world.extent_m[0]), py.clamp(0.0, world.extent_m[1]));
                f64::from(world.decode_height(world.encode_height(v)))
            });
            sum += wxa * wyb * h;
        }
    }
    sum
}

#[test]
fn no_triangle_lies_farther_from_the_finest_surface_than_its_patch_error() {
    for (world, source) in [procedural(), posts()] {
        let tree = ErrorTree::new(&world, Arc::clone(&source), None).unwrap();
        let mut rng = Rng(9);
        let mut cache = HashMap::new();
        for lod in 0..world.lod_count as u8 {
            let nodes = world.nodes_at(lod);
            for _ in 0..3 {
                let id = nodes[rng.index(nodes.len())];
                let node = bake_node(source.as_ref(), &world, &[], id);
                let e = tree.node(id).unwrap();
                let patch = rng.index(PATCHES_PER_NODE);
                let (px, py) = (patch % SIDE, patch / SIDE);
                let step = 1usize << lod;
                // The finest surface's vertices: a quarter of a LOD-0 sample apart.
                let n = QUADS * step * 4;
                let mut worst = 0f64;
                // Exact gap at every finest vertex, row-major over (n + 1)^2.
                let mut gaps = vec![0f64; (n + 1) * (n + 1)];
                let (ox, oy) = (id.x as usize * NODE_QUADS as usize * step, id.y as usize * NODE_QUADS as usize * step);
                for b in 0..=n {
                    for a in 0..=n {
                        // LOD-0 sample coordinates of the vertex.
                        let x = (ox + px * QUADS * step) as f64 + a as f64 / 4.0;
                        let y = (oy + py * QUADS * step) as f64 + b as f64 / 4.0;
                        let f = finest(&world, source.as_ref(), &mut cache, x, y);
                        // The node's own triangle there: node-local sample units.
                        let (lx, ly) = ((x - ox as f64) / step as f64, (y - oy as f64) / step as f64);
                        let (qx, qy) = ((lx.floor() as isize).min(127), (ly.floor() as isize).min(127));
                        let h = |i: isize, j: isize| f64::from(world.decode_height(node.height(i, j)));
                        let corners = [h(qx, qy), h(qx + 1, qy), h(qx, qy + 1), h(qx + 1, qy + 1)];
                        let slash = (qx + qy) % 2 == 0;
                        let p = diamond(corners, lx - qx as f64, ly - qy as f64, slash);
                        worst = worst.max((p - f).abs());
                        gaps[b * (n + 1) + a] = (p - f).abs();
                        let z = world.decode_height(e.bounds[patch][0]) as f64 - 1e-9;
                        let zmax = world.decode_height(e.bounds[patch][1]) as f64 + 1e-9;
                        assert!((z..=zmax).contains(&f), "{id} patch {patch}: {f} outside {z}..{zmax}");
                    }
                }
                let stored = f64::from(e.patch_max_m[patch][0]);
                assert!(worst <= stored + 1e-4, "{id} patch {patch}: {worst} m > stored {stored} m");
                // The selection error: at least half the largest, and at
                // most 1 % of the patch's LOD-0 quads reach above it.
                let sel = f64::from(e.patch_m[patch][0]);
                assert!(sel >= 0.5 * stored && sel <= stored, "{id} patch {patch}: selection {sel}, max {stored}");
                let quads = n / 4;
                let above = (0..quads * quads)
                    .filter(|&q| {
                        let (qx, qy) = (q % quads, q / quads);
                        let m = (0..=4)
                            .flat_map(|b| (0..=4).map(move |a| (4 * qx + a, 4 * qy + b)))
                            .map(|(a, b)| gaps[b * (n + 1) + a])
                            .fold(0.0, f64::max);
                        m > sel + 1e-4
                    })
                    .count();
                assert!(
                    above * 100 <= quads * quads,
                    "{id} patch {patch}: {above} of {} quads above {sel}",
                    quads * quads
                );
                println!("{id} patch {patch}: brute force {worst:.4} m, stored {stored:.4} m, selection {sel:.4} m");
            }
        }
    }
}

/// A tree with a cache folder keeps at most its held budget of root tiles
/// in memory (and the tile in use); the others are read back from their
/// files when a node asks, with the numbers a tree holding everything gives.
#[test]
fn a_cached_tree_holds_its_budget_and_reads_dropped_tiles_back() {
    let (w, source) = procedural();
    // 8 x 7 sectors of 128 m at 2 LODs: 4 x 4 roots.
    let world = WorldDesc { lod_count: 2, ..w };
    assert_eq!(world.roots().len(), 16);
    // A LOD-1 root: 32 x 32 patches at LOD 0 and 16 x 16 at LOD 1, each
    // five f32 and two f64 in memory.
    let per_root = (32 * 32 + 16 * 16) * (5 * 4 + 2 * 8);
    assert_eq!(ErrorTree::root_tile_bytes(&world), per_root);
    let whole = ErrorTree::new(&world, Arc::clone(&source), None).unwrap();
    let p = whole.prepare(vista::world::Progress::Hidden);
    assert_eq!((p.roots, p.read), (16, 0));
    assert_eq!(whole.memory_bytes(), 16 * per_root, "without a folder every tile stays");
    let dir = std::env::temp_dir().join(format!("vista-held-tiles-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let budget = 3 * per_root;
    for pass in 0..2 {
        let held = ErrorTree::new(&world, Arc::clone(&source), Some(&dir)).unwrap().with_held_bytes(budget);
        let p = held.prepare(vista::world::Progress::Hidden);
        assert_eq!(p.read, if pass == 0 { 0 } else { 16 }, "pass {pass}: the second reads the first's files");
        assert!(held.memory_bytes() <= budget, "pass {pass}: {} held", held.memory_bytes());
        // Every node in an order that crosses roots back and forth.
        let mut nodes = every_node(&world);
        nodes.sort_by_key(|n| (n.x % 2, n.y, n.x, n.lod));
        for n in nodes {
            assert_eq!(held.node(n).unwrap(), whole.node(n).unwrap(), "pass {pass}: {n}");
            assert!(held.memory_bytes() <= budget, "pass {pass}: {} held after {n}", held.memory_bytes());
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
