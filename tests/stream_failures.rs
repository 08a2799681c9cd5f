//! Failed node loads through the renderer: retried with backoff and counted
//! in the stats; a node given up leaves its parent drawing and the world
//! still settles; a root given up is an error from the frame call. Every
//! loop is bounded by a frame count, never by a clock.

mod common;

use common::gpu_test;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use vista::gpu::Context;
use vista::render::offscreen::Offscreen;
use vista::render::{Camera, RendererOptions, TerrainRenderer, View, DEFAULT_NEAR_M};
use vista::terrain::{CustomLoad, TerrainOptions};
use vista::world::{bake_node, HeightSource, LoadFn, NodeId, WorldDesc, WorldError};
use vista::Error;

/// 512 m, 3 LODs: one root (LOD 2, 512 m), 4 x 4 LOD-0 nodes of 128 m.
fn world() -> WorldDesc {
    WorldDesc {
        extent_m: [512.0, 512.0],
        height_range_m: [0.0, 100.0],
        spacing_m: 1.0,
        lod_count: 3,
        ..WorldDesc::default()
    }
}

const ATTEMPTS: u32 = 3;
/// Far more frames than streaming the 21 nodes of this world needs.
const FRAME_LIMIT: usize = 3000;

struct Flat;

impl HeightSource for Flat {
    fn sample(&self, x: f64, y: f64) -> f32 {
        10.0 + (x * 0.01).sin() as f32 + (y * 0.013).cos() as f32
    }
    fn id_hash(&self) -> u64 {
        7
    }
}

/// Loads that fail for the nodes of `fail` (the first `n` times each; `u32::MAX`:
/// always), counting every attempt per node.
struct Faulty {
    attempts: Arc<Mutex<HashMap<NodeId, u32>>>,
}

impl Faulty {
    fn load(fail: Vec<(NodeId, u32)>) -> (Faulty, CustomLoad) {
        let attempts = Arc::new(Mutex::new(HashMap::new()));
        let seen = Arc::clone(&attempts);
        let w = world();
        let load: Arc<LoadFn> = Arc::new(move |id| {
            let n = {
                let mut a = seen.lock().unwrap();
                let n = a.entry(id).or_insert(0u32);
                *n += 1;
                *n
            };
            if fail.iter().any(|(f, times)| *f == id && n <= *times) {
                return Err(WorldError::Corrupt { path: format!("injected/{id}").into(), detail: "injected".into() });
            }
            Ok(bake_node(&Flat, &w, &[], id))
        });
        (Faulty { attempts }, CustomLoad(load))
    }

    fn attempts(&self, id: NodeId) -> u32 {
        self.attempts.lock().unwrap().get(&id).copied().unwrap_or(0)
    }
}

fn renderer(ctx: &Context, load: CustomLoad) -> (TerrainRenderer, Offscreen) {
    let options = RendererOptions {
        terrain: TerrainOptions {
            slots: 64,
            loader_threads: 1,
            load: Some(load),
            max_load_attempts: ATTEMPTS,
            retry_frames: 1,
            ..TerrainOptions::default()
        },
        ..RendererOptions::default()
    };
    let r = TerrainRenderer::new(ctx, &world(), Arc::new(Flat), vec![], &options).expect("renderer");
    (r, Offscreen::new(ctx, [64, 64], 2, [1.0, 0.0, 1.0, 1.0]).expect("targets"))
}

/// Low over (100, 100), looking down: wants LOD 0 there.
fn view() -> View {
    View {
        camera: Camera { position_m: [100.0, 100.0, 40.0], yaw_deg: 45.0, pitch_deg: -60.0 },
        fov_y_deg: 60.0,
        size: [64, 64],
        target_error_px: 1.0,
        near_m: DEFAULT_NEAR_M,
    }
}

/// Frames until streaming rests (two settled frames in a row), at most
/// FRAME_LIMIT; the first frame error is returned.
fn settle(ctx: &Context, r: &mut TerrainRenderer, off: &mut Offscreen) -> Result<usize, Error> {
    let (v, mut calm) = (view(), 0);
    for frame in 1..=FRAME_LIMIT {
        off.frame(ctx, r, &v)?;
        calm = if r.terrain.settled() { calm + 1 } else { 0 };
        if calm >= 2 {
            return Ok(frame);
        }
        // Let the loader thread run; the bound stays the frame count.
        std::thread::yield_now();
    }
    panic!("not settled after {FRAME_LIMIT} frames: {:?}", r.terrain.stats());
}

/// A root, and separately a node below it, failing twice then loading:
/// (each on its own, as a root's retries also cancel and reload the
/// families below it, which would blur the counts).
#[test]
fn loads_that_fail_then_succeed_are_retried_and_counted() {
    gpu_test(|ctx| {
        let w = world();
        for node in [w.roots()[0], w.node_at(1, 100.0, 100.0).unwrap()] {
            let (faulty, load) = Faulty::load(vec![(node, 2)]);
            let (mut r, mut off) = renderer(ctx, load);
            settle(ctx, &mut r, &mut off).expect("no error: every node loads in the end");
            let resident = r.terrain.resident_nodes();
            assert!(resident.contains(&node), "{node}: retried until resident");
            assert!(resident.contains(&w.node_at(0, 100.0, 100.0).unwrap()), "{node}: the refinement below came");
            assert_eq!(faulty.attempts(node), 3, "{node}: two failures, then the load that worked");
            let st = r.terrain.stats();
            assert_eq!((st.failed, st.retried, st.gave_up, st.retry_waiting), (2, 2, 0, 0), "{node}: {st:?}");
            let stats = vista::render::stats::collect(ctx, &r, &view()).unwrap();
            assert_eq!((stats.streaming.failed, stats.streaming.retried, stats.streaming.gave_up), (2, 2, 0));
        }
    });
}

#[test]
fn a_root_that_keeps_failing_is_an_error_not_a_hang() {
    gpu_test(|ctx| {
        let root = world().roots()[0];
        let (faulty, load) = Faulty::load(vec![(root, u32::MAX)]);
        let (mut r, mut off) = renderer(ctx, load);
        let e = settle(ctx, &mut r, &mut off).expect_err("a root that never loads must fail the frame");
        match &e {
            Error::World(WorldError::RootUnavailable { node, attempts, cause }) => {
                assert_eq!((*node, *attempts), (root, ATTEMPTS));
                assert!(cause.contains("injected"), "the cause is the load's error: {cause}");
            }
            e => panic!("unexpected error {e}"),
        }
        let msg = e.to_string();
        assert!(msg.contains(&root.to_string()) && msg.contains("injected"), "names node and cause: {msg}");
        assert_eq!(faulty.attempts(root), ATTEMPTS, "gave up after the configured attempts");
        assert!(!r.terrain.settled());
        assert!(off.frame(ctx, &mut r, &view()).is_err(), "every later frame reports it too");
        let st = r.terrain.stats();
        assert_eq!((st.failed, st.retried, st.gave_up), (ATTEMPTS as usize, ATTEMPTS as usize - 1, 1));
    });
}

#[test]
fn a_leaf_that_keeps_failing_is_given_up_and_the_world_settles() {
    gpu_test(|ctx| {
        let w = world();
        let leaf = w.node_at(0, 100.0, 100.0).unwrap();
        let (faulty, load) = Faulty::load(vec![(leaf, u32::MAX)]);
        let (mut r, mut off) = renderer(ctx, load);
        settle(ctx, &mut r, &mut off).expect("a leaf failing is no error");
        assert_eq!(faulty.attempts(leaf), ATTEMPTS);
        let resident = r.terrain.resident_nodes();
        assert!(!resident.contains(&leaf));
        assert!(resident.contains(&leaf.parent()), "its parent stays to draw there");
        let st = r.terrain.stats();
        assert_eq!((st.failed, st.retried, st.gave_up, st.retry_waiting), (3, 2, 1, 0), "{st:?}");
        // It stays given up: more frames request it no more.
        for _ in 0..10 {
            off.frame(ctx, &mut r, &view()).unwrap();
        }
        assert_eq!(faulty.attempts(leaf), ATTEMPTS);
    });
}
