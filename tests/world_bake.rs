//! World layout and node bakes checked against analytic surfaces.

use std::sync::Arc;
mod common;

use common::terrain::Surface;
use vista::world::*;

/// 512 m square, 1 m spacing, 3 LODs: 4x4 sectors, one root.
fn test_world() -> WorldDesc {
    WorldDesc {
        extent_m: [512.0, 512.0],
        height_range_m: [-100.0, 1400.0],
        spacing_m: 1.0,
        lod_count: 3,
        ..WorldDesc::default()
    }
}

fn all_nodes(w: &WorldDesc) -> Vec<NodeId> {
    (0..w.lod_count as u8).flat_map(|l| w.nodes_at(l)).collect()
}

const N: usize = NODE_SAMPLES;

/// Checks heights, patch min/max and node min/max against direct
/// computations on the u16 grid.
fn check_grids(src: &dyn HeightSource, w: &WorldDesc, node: &BakedNode) {
    let b = w.bounds_m(node.id);
    let step = w.node_spacing_m(node.id.lod);
    for j in 0..N {
        for i in 0..N {
            let x = (b[0] + i as f64 * step).min(w.extent_m[0]);
            let y = (b[1] + j as f64 * step).min(w.extent_m[1]);
            assert_eq!(node.height(i as isize, j as isize), w.encode_height(src.sample(x, y)));
        }
    }
    let (p, q) = (PATCHES_PER_NODE_SIDE as usize, PATCH_QUADS as usize);
    for py in 0..p {
        for px in 0..p {
            let mut mm = [u16::MAX, 0];
            for j in py * q..=py * q + q {
                for i in px * q..=px * q + q {
                    let v = node.height(i as isize, j as isize);
                    mm = [mm[0].min(v), mm[1].max(v)];
                }
            }
            assert_eq!(node.patch_min_max[py * p + px], mm, "patch {px},{py}");
        }
    }
    assert_eq!(node.min_height, *node.sample_heights().iter().min().unwrap());
    assert_eq!(node.max_height, *node.sample_heights().iter().max().unwrap());
}

/// Recomputes every triangle normal of every patch with an independent
/// diamond triangulation and checks the stored cone contains it.
fn check_cones(w: &WorldDesc, node: &BakedNode) -> f64 {
    let s = w.node_spacing_m(node.id.lod);
    let h = |i: usize, j: usize| w.decode_height(node.height(i as isize, j as isize)) as f64;
    let p = |i: usize, j: usize| [i as f64 * s, j as f64 * s, h(i, j)];
    let mut widest = 0f64;
    // One cone per block of CONE_BLOCK_PATCHES x CONE_BLOCK_PATCHES patches.
    let (blocks, q) = (CONE_BLOCKS_PER_NODE_SIDE as usize, NODE_QUADS as usize / CONE_BLOCKS_PER_NODE_SIDE as usize);
    for py in 0..blocks {
        for px in 0..blocks {
            let cone = node.patch_cones[py * blocks + px];
            if cone[3] >= 1.0 {
                assert_eq!(&cone[..3], &[0.0, 0.0, 0.0], "never-cull cone must have zero axis");
                widest = 90f64;
                continue;
            }
            let axis = glam::DVec3::new(cone[0] as f64, cone[1] as f64, cone[2] as f64).normalize();
            let half = (cone[3] as f64).asin();
            widest = widest.max(half.to_degrees());
            for qy in py * q..py * q + q {
                for qx in px * q..px * q + q {
                    // Diagonal through the odd/odd corner of the quad.
                    let tris = if (qx + qy).is_multiple_of(2) {
                        [[p(qx, qy), p(qx + 1, qy), p(qx + 1, qy + 1)], [p(qx, qy), p(qx + 1, qy + 1), p(qx, qy + 1)]]
                    } else {
                        [[p(qx, qy), p(qx + 1, qy), p(qx, qy + 1)], [p(qx + 1, qy), p(qx + 1, qy + 1), p(qx, qy + 1)]]
                    };
                    for t in tris {
                        let [a, b, c] = t.map(glam::DVec3::from_array);
                        let n = (b - a).cross(c - a).normalize();
                        assert!(n.z > 0.0, "triangle facing down: wrong winding");
                        let ang = n.dot(axis).clamp(-1.0, 1.0).acos();
                        assert!(ang <= half, "normal outside cone: {ang} > {half}");
                        assert!(cone_contains(cone, n.to_array()));
                    }
                }
            }
        }
    }
    widest
}

/// Brute force LOD error: the finer surface at every point of the 2x finer
#[test]
fn plane_and_tilted_plane() {
    let w = test_world();
    for src in [
        Surface::Plane(123.0),
        Surface::Tilted { z0: 200.0, gx: 0.3, gy: -0.2 },
        Surface::Tilted { z0: 0.0, gx: 2.0, gy: 0.5 },
    ] {
        let (big, tree) = error_world(src);
        // One R16 step of the height range.
        let step = f64::from(big.height_range_m[1] - big.height_range_m[0]) / 65535.0;
        for id in interior_nodes(&big) {
            // Rounding to R16 only: each level's triangles and the finest
            // surface stay within a step of the plane (Catmull-Rom's taps
            // sum to at most 1.25 per axis).
            let e = tree.node(id).unwrap();
            assert!(f64::from(e.node_m) < 3.0 * step, "{id}: plane error {} (step {step})", e.node_m);
        }
        for id in all_nodes(&w) {
            let node = bake_node(&src, &w, &[], id);
            check_grids(&src, &w, &node);
            let widest = check_cones(&w, &node);
            // Quantisation of the heights only: the cones stay narrow. The
            // R16 step (2.3 cm here) tilts a unit triangle's normal by up to
            // 1.3 degrees, and the cones also hold the stitched edge
            // triangles, slivers down to 1/7 of a quad across (an edge
            // vertex snapped 7 samples along a 16-sample coarser edge),
            // which magnify it as much: 9 degrees at most.
            assert!(widest < 10.0, "plane cone too wide: {widest} deg");
            assert!(node.patch_holes.iter().all(|&h| h == PATCH_HOLE_NONE));
            assert!(node.hole_mask().iter().all(|h| !h));
        }
    }
}

/// A 2 km world for the error tree's numbers: its edges clamp the
/// samples beyond them (a kink the finest surface bends over), so only
/// nodes away from them are compared with closed forms.
fn error_world(src: Surface) -> (WorldDesc, ErrorTree) {
    // A range that holds every test surface over 2 km: a clamped height is a kink too.
    let w = WorldDesc { extent_m: [2048.0, 2048.0], height_range_m: [-1500.0, 6000.0], ..test_world() };
    let tree = ErrorTree::new(&w, Arc::new(src), None).unwrap();
    (w, tree)
}

/// Nodes below the root at least 4 samples in from every edge.
fn interior_nodes(w: &WorldDesc) -> Vec<NodeId> {
    all_nodes(w)
        .into_iter()
        .filter(|id| {
            let b = w.bounds_m(*id);
            id.lod < w.root_lod()
                && b[0] >= 4.0
                && b[1] >= 4.0
                && b[2] <= w.extent_m[0] - 4.0
                && b[3] <= w.extent_m[1] - 4.0
        })
        .collect()
}

#[test]
fn paraboloid_error_matches_analytic_bound_and_brute_force() {
    let w = test_world();
    let a = 0.004;
    let src = Surface::Paraboloid { z0: 0.0, a, c: [256.0, 256.0] };
    for id in all_nodes(&w) {
        let node = bake_node(&src, &w, &[], id);
        check_grids(&src, &w, &node);
        check_cones(&w, &node);
    }
    let a = a / 10.0;
    let (big, tree) = error_world(Surface::Paraboloid { z0: 0.0, a, c: [1024.0, 1024.0] });
    let step = f64::from(big.height_range_m[1] - big.height_range_m[0]) / 65535.0;
    for id in interior_nodes(&big) {
        // Catmull-Rom reproduces a quadratic, so the finest surface is the
        // paraboloid itself. Linear interpolation of a(x^2 + y^2) over a
        // diamond's right triangle of legs h errs most at the hypotenuse's
        // middle: a (h sqrt 2)^2 / 4 = a h^2 / 2. The tree adds LOD 0's own
        // a s^2 / 2 (the triangle inequality through LOD 0) and rounding.
        let h = big.node_spacing_m(id.lod);
        let s = big.spacing_m;
        let (exact, lod0) = (a * h * h / 2.0, a * s * s / 2.0);
        let e = f64::from(tree.node(id).unwrap().node_m);
        let upper = if id.lod == 0 { exact } else { exact + lod0 };
        assert!(e >= exact - 2.0 * step && e <= upper + 2.0 * step, "{id}: {e} vs {exact}..{upper}");
    }
}

#[test]
fn steep_gorge_cones_hold_and_may_disable_culling() {
    let w = test_world();
    let src = Surface::Gorge { c: 100.3, slope: 40.0 };
    let node = bake_node(&src, &w, &[], NodeId::new(0, 0, 0));
    check_grids(&src, &w, &node);
    let widest = check_cones(&w, &node);
    assert!(widest > 80.0, "gorge patch should have a wide cone, got {widest}");
    // The rock rule: walls steeper than 45 degrees are cliffs.
    assert!(node.splat.contains(&(Material::Rock as u8)));
}

#[test]
fn samples_outside_extent_clamp_to_edge_and_are_holes() {
    // 300 m is not a multiple of the 128 m sector: the last column of
    // nodes is partial and its samples past 300 m repeat the edge's height
    // and are holes (the world ends at its extent, no streaks).
    let w = WorldDesc { extent_m: [300.0, 300.0], ..test_world() };
    assert_eq!(w.sectors(), [3, 3]);
    let src = Surface::Tilted { z0: 10.0, gx: 1.0, gy: 0.0 };
    let node = bake_node(&src, &w, &[], NodeId::new(0, 2, 0));
    let mask = node.hole_mask();
    let edge = w.encode_height(310.0);
    for (i, (&height, &hole)) in node.sample_heights().iter().zip(&mask).take(N).enumerate() {
        let x = 256.0 + i as f64;
        let expect = if x >= 300.0 { edge } else { w.encode_height(10.0 + x as f32) };
        assert_eq!(height, expect);
        assert_eq!(hole, x > 300.0, "hole flag at x = {x}");
    }
    // Patches whose samples (x 256 + q k ..= 256 + q (k + 1) m) all lie at or
    // before 300 m are inside, the one holding 300 m is cut, the rest lie
    // wholly beyond the extent.
    let q = PATCH_QUADS as f64;
    let row: Vec<u8> = (0..PATCHES_PER_NODE_SIDE as usize).map(|px| node.patch_holes[px]).collect();
    let expect: Vec<u8> = (0..PATCHES_PER_NODE_SIDE)
        .map(|k| {
            let (lo, hi) = (256.0 + q * f64::from(k), 256.0 + q * f64::from(k + 1));
            if hi <= 300.0 {
                PATCH_HOLE_NONE
            } else if lo > 300.0 {
                PATCH_HOLE_ALL
            } else {
                PATCH_HOLE_SOME
            }
        })
        .collect();
    assert_eq!(row, expect);
    assert!(expect.contains(&PATCH_HOLE_SOME) && expect.contains(&PATCH_HOLE_ALL));
}

#[test]
fn holes_clear_alpha_and_flag_patches() {
    let w = test_world();
    let holes = vec![
        Hole::Circle { center_m: [64.0, 64.0], radius_m: 30.0 },
        Hole::Polygon(vec![[0.0, 100.0], [20.0, 100.0], [20.0, 128.0], [0.0, 128.0]]),
    ];
    let node = bake_node(&Surface::Plane(0.0), &w, &holes, NodeId::new(0, 0, 0));
    let mask = node.hole_mask();
    for j in 0..N {
        for i in 0..N {
            let (x, y) = (i as f64, j as f64);
            let inside = holes.iter().any(|h| h.contains(x, y));
            assert_eq!(mask[j * N + i], inside, "({x},{y})");
        }
    }
    // The patch holding (64, 64) lies well inside the circle (30 m radius;
    // patches are at most 16 m); patch (0,0) is untouched; the one holding
    // (34, 64) straddles the rim (its west edge at 32 m lies 32 m out).
    let patch =
        |x: usize, y: usize| y / PATCH_QUADS as usize * PATCHES_PER_NODE_SIDE as usize + x / PATCH_QUADS as usize;
    const { assert!(PATCH_QUADS <= 16) };
    assert_eq!(node.patch_holes[patch(64, 64)], PATCH_HOLE_ALL);
    assert_eq!(node.patch_holes[0], PATCH_HOLE_NONE);
    assert_eq!(node.patch_holes[patch(34, 64)], PATCH_HOLE_SOME);
    assert_ne!(holes_hash(&holes), holes_hash(&holes[..1]));
}

#[test]
fn layout_rules() {
    let d = WorldDesc::default();
    d.validate().unwrap();
    assert_eq!(d.sectors(), [160, 160]);
    assert_eq!(d.node_size_m(5), 2048.0);
    assert_eq!(d.roots().len(), 25);

    // Mont Blanc at 8 m: 59 sectors of 1024 m, not a multiple of 2^k.
    let mb = WorldDesc {
        extent_m: [60_000.0, 60_000.0],
        height_range_m: [454.0, 4810.0],
        spacing_m: 8.0,
        lod_count: 6,
        ..WorldDesc::default()
    };
    mb.validate().unwrap();
    assert_eq!(mb.sectors(), [59, 59]);
    assert_eq!(mb.grid(1), [30, 30]);
    assert_eq!(mb.roots().len(), 4);
    assert!(mb.is_valid(NodeId::new(0, 58, 58)));
    assert!(!mb.is_valid(NodeId::new(0, 59, 0)));
    assert!(mb.is_valid(NodeId::new(1, 29, 0)));
    assert_eq!(mb.valid_children(NodeId::new(1, 29, 29)), vec![NodeId::new(0, 58, 58)]);
    assert!(!mb.is_valid(NodeId::new(6, 0, 0)));
    let root = NodeId::new(5, 1, 1);
    assert_eq!(mb.bounds_m(root), [32768.0, 32768.0, 65536.0, 65536.0]);
    for c in root.children().unwrap() {
        assert_eq!(c.parent(), root);
        assert!(c.is_within(&root));
    }
    assert!(NodeId::new(0, 3, 3).children().is_none());

    let bad = [
        WorldDesc { extent_m: [f64::NAN, 1.0], ..d },
        WorldDesc { extent_m: [0.0, 1.0], ..d },
        WorldDesc { spacing_m: -1.0, ..d },
        WorldDesc { spacing_m: f64::INFINITY, ..d },
        WorldDesc { height_range_m: [5.0, 5.0], ..d },
        WorldDesc { height_range_m: [0.0, f32::NAN], ..d },
        WorldDesc { lod_count: 0, ..d },
        WorldDesc { lod_count: 11, ..d },
        WorldDesc { extent_m: [1e12, 1.0], ..d },
    ];
    for b in bad {
        assert!(matches!(b.validate(), Err(WorldError::InvalidDesc(_))), "{b:?}");
    }

    let r = [-50.0f32, 1000.0];
    for h in [-50.0f32, 0.0, 1.234, 999.99, 1000.0] {
        let back = decode_height(encode_height(h, r), r);
        assert!((back - h).abs() <= 1050.0 / 65535.0 * 0.51, "{h} -> {back}");
    }
    assert_eq!(encode_height(-1e9, r), 0);
    assert_eq!(encode_height(1e9, r), 65535);
    assert_eq!(encode_height(f32::NAN, r), 0);
}

#[test]
fn payload_roundtrip_and_memory_report() {
    let w = test_world();
    let src = Surface::Paraboloid { z0: 0.0, a: 0.004, c: [100.0, 50.0] };
    let node = bake_node(&src, &w, &[], NodeId::new(1, 1, 0));
    let bytes = node.to_bytes();
    assert_eq!(bytes.len(), BakedNode::serialized_bytes(PayloadFormat::Bc, false));
    assert_eq!(BakedNode::from_bytes(&bytes), Some(node.clone()));
    assert_eq!(BakedNode::from_bytes(&bytes[1..]), None);

    let report = MemoryReport::new(512);
    assert_eq!(report.cpu_bytes_per_node() - report.kinds.last().unwrap().cpu_bytes, node_cpu_bytes(&node));
    let text = report.to_string();
    assert!(text.contains("R16_UNORM 132x132") && text.contains("total for 512 nodes"));
    println!("{report}");
}

#[test]
fn procedural_world_is_deterministic_and_has_cliffs() {
    // Terraced: the option that cuts cliffs (tests/procedural_world.rs
    // checks the eroded default).
    let (w, src) = ProceduralSource::default_world(7);
    let src = src.with_terraces(true);
    let same = ProceduralSource::default_world(7).1.with_terraces(true);
    let (_, other) = ProceduralSource::default_world(8);
    assert_eq!(src.id_hash(), same.id_hash());
    assert_ne!(src.id_hash(), other.id_hash());
    let mut steepest = 0f64;
    let (mut lo, mut hi) = (f32::MAX, f32::MIN);
    // Sparse probe of the whole world at 0.5 m offsets for slope.
    for j in 0..200 {
        for i in 0..200 {
            let (x, y) = (i as f64 * 51.2 + 3.0, j as f64 * 51.2 + 7.0);
            let h = src.sample(x, y);
            assert_eq!(h, same.sample(x, y));
            assert!(h.is_finite() && (0.0..=1600.0).contains(&h));
            lo = lo.min(h);
            hi = hi.max(h);
            let dx = (src.sample(x + 0.5, y) - h) as f64 / 0.5;
            let dy = (src.sample(x, y + 0.5) - h) as f64 / 0.5;
            steepest = steepest.max(dx.hypot(dy).atan().to_degrees());
        }
    }
    println!("procedural heights {lo}..{hi} m, steepest probe {steepest:.1} deg");
    assert!(hi - lo > 600.0, "too flat: {lo}..{hi}");
    assert!(steepest > 60.0, "no cliffs: steepest {steepest}");
    assert!(w.validate().is_ok());
    let _: Arc<dyn HeightSource> = Arc::new(src);
}

#[test]
fn procedural_rejects_bad_params() {
    assert!(ProceduralSource::new(1, [f64::NAN, 1.0], [0.0, 1.0]).is_err());
    assert!(ProceduralSource::new(1, [10.0, 10.0], [1.0, 1.0]).is_err());
    assert!(ProceduralSource::new(1, [10.0, 10.0], [0.0, 1.0]).is_ok());
}

#[test]
fn material_rules_are_absolute_whatever_the_height_range() {
    // Splat ids of a node of a plane at `z0` tilted by `slope_deg` east.
    let splat = |range: [f32; 2], z0: f64, slope_deg: f64, rules: MaterialRules| {
        let w = WorldDesc { height_range_m: range, ..test_world() };
        let gx = slope_deg.to_radians().tan();
        let src = Surface::Tilted { z0, gx, gy: 0.0 };
        let settings = BakeSettings { materials: rules, ..BakeSettings::default() };
        // An inner node: at the world's edge the source clamps, flattening
        // the first samples' slope.
        let node = bake_node_with(&src, &w, &[], &settings, NodeId::new(0, 1, 1));
        let mut ids = node.splat.clone();
        ids.sort_unstable();
        ids.dedup();
        ids
    };
    let alps = MaterialRules::default();
    let id = |m: Material| vec![m as u8];
    // A gentle 1 km hill in a world that tops out at 1.1 km: grass (a rule
    // relative to the range put snow on its top 28 %). Heights climb 128 m
    // to the node's start and 11 m across it at 5 degrees.
    assert_eq!(splat([0.0, 1100.0], 850.0, 5.0, alps), id(Material::Grass));
    // The same slope at 3 km, above the 2 800 m snow line: snow.
    assert_eq!(splat([0.0, 4000.0], 3000.0, 5.0, alps), id(Material::Snow));
    // 50 degrees is rock at any altitude; 35 degrees is scree below the
    // snow line.
    assert_eq!(splat([0.0, 4000.0], 3000.0, 50.0, alps), id(Material::Rock));
    assert_eq!(splat([-500.0, 1100.0], 200.0, 35.0, alps), id(Material::Scree));
    // A sea floor at -40 m is sand, not grass; so is a beach 1 m above sea.
    assert_eq!(splat([-100.0, 100.0], -40.0, 0.0, alps), id(Material::Sand));
    assert_eq!(splat([-100.0, 100.0], 50.0, 0.0, alps), id(Material::Grass));
    assert_eq!(splat([-100.0, 100.0], 1.0, 0.0, alps), id(Material::Sand));
    // A scene's own snow line moves it.
    let low_snow = MaterialRules { snow_line_m: 800.0, ..alps };
    assert_eq!(splat([0.0, 1100.0], 850.0, 5.0, low_snow), id(Material::Snow));
}
