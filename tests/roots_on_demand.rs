//! Roots made on demand (`ErrorTree::with_roots_on_demand`, what `vista
//! render` and `vista view` use): a root's error tile is computed only when
//! a view refines into it, the root drawn meanwhile says its bound is
//! unknown, and the settled picture is the one the whole tree gives.

mod common;

use common::gpu_test;
use common::terrain::{view, Rig, Surface};
use std::sync::Arc;
use vista::passes::cull_patches::CullStages;
use vista::render::{RendererOptions, View};
use vista::terrain::TerrainOptions;
use vista::world::{bake_node, ErrorTree, HeightSource, NodeCache, NodeId, WorldDesc};

/// Four 1 024 m roots in a row along x (LOD 3 at 1 m spacing).
fn world() -> WorldDesc {
    WorldDesc {
        extent_m: [4096.0, 1024.0],
        height_range_m: [100.0, 500.0],
        spacing_m: 1.0,
        lod_count: 4,
        ..WorldDesc::default()
    }
}

fn temp_dir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("vista-roots-on-demand-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn a_root_is_pending_until_a_child_makes_its_tile_then_gets_the_whole_trees_numbers() {
    let w = world();
    let source: Arc<dyn HeightSource> = Arc::new(Surface::Hills);
    let whole = ErrorTree::new(&w, Arc::clone(&source), None).unwrap();
    let lazy = ErrorTree::new(&w, Arc::clone(&source), None).unwrap().with_roots_on_demand();
    let root = NodeId::new(3, 1, 0);
    let mut pending = bake_node(source.as_ref(), &w, &[], root);
    lazy.attach(&mut pending).unwrap();
    assert!(pending.errors_pending(), "no tile yet: the root's error is unknown");
    assert_eq!([pending.min_height, pending.max_height], [0, u16::MAX], "culling sees the whole height range");
    assert!(pending.patch_min_max.iter().all(|p| *p == [0, u16::MAX]));
    assert_eq!(lazy.counts().computed, 0, "a pending root computes nothing");

    let mut child = bake_node(source.as_ref(), &w, &[], NodeId::new(2, 2, 1));
    lazy.attach(&mut child).unwrap();
    assert!(!child.errors_pending());
    assert_eq!(lazy.counts().computed, 1, "the child made its root's tile, and only that one");
    assert!(lazy.root_at_hand(root) && !lazy.root_at_hand(NodeId::new(3, 0, 0)));

    let mut made = bake_node(source.as_ref(), &w, &[], root);
    lazy.attach(&mut made).unwrap();
    let mut expected = bake_node(source.as_ref(), &w, &[], root);
    whole.attach(&mut expected).unwrap();
    assert_eq!(made, expected, "once made, the root's numbers are the whole tree's");
}

#[test]
fn a_node_cache_never_writes_a_pending_root() {
    let w = world();
    let dir = temp_dir("cache");
    let source: Arc<dyn HeightSource> = Arc::new(Surface::Hills);
    let tree = Arc::new(ErrorTree::new(&w, Arc::clone(&source), Some(&dir)).unwrap().with_roots_on_demand());
    let cache = NodeCache::new(&dir, w, Arc::clone(&source), vec![]).unwrap().with_errors(Arc::clone(&tree));
    let root = NodeId::new(3, 0, 0);
    let (node, _) = cache.get_or_bake_for_render(root).unwrap();
    assert!(node.errors_pending());
    let (again, outcome) = cache.get_or_bake_for_render(root).unwrap();
    assert!(again.errors_pending() && !matches!(outcome, vista::world::CacheOutcome::Hit), "nothing was written");
    let (child, _) = cache.get_or_bake_for_render(NodeId::new(2, 0, 0)).unwrap();
    assert!(!child.errors_pending());
    let (root_now, _) = cache.get_or_bake_for_render(root).unwrap();
    assert!(!root_now.errors_pending(), "the tile is at hand (in memory and in the folder)");
    // A new process finds the tile in the folder: the root is never pending.
    let fresh = ErrorTree::new(&w, Arc::clone(&source), Some(&dir)).unwrap().with_roots_on_demand();
    assert!(fresh.root_at_hand(root));
    let _ = std::fs::remove_dir_all(&dir);
}

fn shot(ctx: &vista::gpu::Context, errors: Arc<ErrorTree>, views: &[View]) -> (Vec<Vec<u8>>, Vec<f32>, Rig) {
    let options = RendererOptions {
        terrain: TerrainOptions { errors: Some(errors), ..TerrainOptions::default() },
        ..RendererOptions::default()
    };
    let mut rig = Rig::with_options(ctx, world(), Surface::Hills, vec![], [256, 144], false, options);
    let (mut pictures, mut bounds) = (Vec::new(), Vec::new());
    for v in views {
        pictures.push(rig.shot(ctx, v, CullStages::default()).rgba);
        bounds.push(vista::render::stats::collect(ctx, &rig.renderer, v).expect("stats").bound_px);
    }
    (pictures, bounds, rig)
}

/// Looking west from inside the first root, the three roots behind the
/// camera are never computed; turned east, all are, and both pictures are
/// the whole tree's, bit for bit (the nodes drawn have the same numbers;
/// a pending root is never drawn once its children are resident).
#[test]
fn only_the_roots_a_view_refines_into_are_computed_and_the_pictures_are_the_whole_trees() {
    gpu_test(|ctx| {
        let w = world();
        let source: Arc<dyn HeightSource> = Arc::new(Surface::Hills);
        let west = view([700.0, 512.0, 650.0], 270.0, -20.0, [256, 144], 1.0);
        let east = view([700.0, 512.0, 650.0], 90.0, -10.0, [256, 144], 1.0);

        let lazy = Arc::new(ErrorTree::new(&w, Arc::clone(&source), None).unwrap().with_roots_on_demand());
        let (first, first_bound, rig) = shot(ctx, Arc::clone(&lazy), std::slice::from_ref(&west));
        assert_eq!(lazy.counts().computed, 1, "looking west, only the camera's own root is refined into");
        assert_eq!(rig.renderer.terrain.pending_roots(), 3, "the roots behind the camera stay pending");
        assert!(first_bound[0].is_finite(), "settled, no pending root is drawn: bound {}", first_bound[0]);
        drop(rig);

        let lazy = Arc::new(ErrorTree::new(&w, Arc::clone(&source), None).unwrap().with_roots_on_demand());
        let (turned, turned_bounds, rig) = shot(ctx, Arc::clone(&lazy), &[west.clone(), east.clone()]);
        assert_eq!(lazy.counts().computed, 4, "looking east, every root is in view");
        assert_eq!(rig.renderer.terrain.pending_roots(), 0);
        assert!(turned_bounds.iter().all(|b| b.is_finite()));
        drop(rig);

        let whole = ErrorTree::new(&w, Arc::clone(&source), None).unwrap();
        whole.prepare(vista::world::Progress::Hidden);
        let (reference, reference_bounds, _) = shot(ctx, Arc::new(whole), &[west, east]);
        assert_eq!(first[0], reference[0], "west: the whole tree's picture");
        assert_eq!(turned[1], reference[1], "east: the whole tree's picture");
        assert_eq!(turned_bounds[1], reference_bounds[1], "east: the whole tree's bound");
    });
}
