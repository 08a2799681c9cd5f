//! Streaming residency, loader threads, the node cache and bake_world.

mod common;

use common::Rng;
use std::collections::HashSet;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use vista::world::*;

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("vista_world_{name}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Constant-height source: cheap to bake, hash set by the caller.
/// 2 x 2 roots of 1 024 m, three LODs.
fn small_world() -> WorldDesc {
    WorldDesc {
        extent_m: [2048.0, 2048.0],
        height_range_m: [0.0, 100.0],
        spacing_m: 1.0,
        lod_count: 3,
        ..WorldDesc::default()
    }
}

struct Flat(f32);

impl HeightSource for Flat {
    fn sample(&self, _: f64, _: f64) -> f32 {
        self.0
    }
    fn id_hash(&self) -> u64 {
        u64::from(self.0.to_bits())
    }
}

/// Invariants that must hold after every frame. Coverage can only hold
/// once the roots have arrived.
fn check_invariants(r: &Residency, rng: &mut Rng) {
    let w = *r.world();
    assert!(r.slots_used() <= r.config().budget, "budget exceeded");
    let resident: HashSet<NodeId> = r.resident().collect();
    for id in &resident {
        assert!(w.is_valid(*id));
        if u32::from(id.lod) + 1 < w.lod_count {
            assert!(resident.contains(&id.parent()), "{id} resident without its parent");
            // Families load and leave together: every sibling holds a slot.
            for sib in w.valid_children(id.parent()) {
                let held = r.is_resident(sib) || r.is_pending(sib) || r.is_failed(sib);
                assert!(held, "{id} held without its sibling {sib}");
            }
        }
    }
    if !w.roots().iter().all(|root| resident.contains(root)) {
        return;
    }
    // Every point of the extent lies in a resident valid node.
    for _ in 0..64 {
        let (x, y) = (rng.unit() * w.extent_m[0], rng.unit() * w.extent_m[1]);
        let covered = (0..w.lod_count as u8).filter_map(|l| w.node_at(l, x, y)).any(|n| resident.contains(&n));
        assert!(covered, "({x},{y}) not covered");
    }
}

#[test]
fn random_paths_keep_budget_roots_and_coverage() {
    let world = WorldDesc::default();
    for (seed, budget, lag) in [(1u64, 512usize, false), (2, 60, false), (3, 200, true), (4, 40, true)] {
        let config = ResidencyConfig { budget, ..ResidencyConfig::default() };
        let mut r = Residency::new(&world, config).unwrap();
        let mut rng = Rng(0x1234_5678 ^ seed.wrapping_mul(0x9e37_79b9));
        let mut pos = [5000.0, 5000.0, 300.0];
        let mut vel = [0.0, 0.0];
        let mut loading: Vec<NodeId> = Vec::new();
        let mut roots_seen = false;
        for frame in 0..400 {
            // Wandering walk with occasional teleports, sometimes off-world.
            if rng.next_u64().is_multiple_of(97) {
                pos = [rng.unit() * 12_000.0 - 1000.0, rng.unit() * 12_000.0 - 1000.0, 100.0];
            }
            vel = [vel[0] * 0.9 + (rng.unit() - 0.5) * 40.0, vel[1] * 0.9 + (rng.unit() - 0.5) * 40.0];
            pos = [pos[0] + vel[0], pos[1] + vel[1], pos[2]];
            let changes = r.update(pos);
            let resident_before: HashSet<NodeId> = r.resident().collect();
            for id in &changes.removes {
                assert!(!resident_before.contains(id), "removed node still resident");
            }
            loading.retain(|id| !changes.cancels.contains(id));
            loading.extend(changes.adds.iter().copied());
            // Deliver everything, or a random part when lagging.
            let mut still = Vec::new();
            for id in loading.drain(..) {
                if lag && rng.next_u64().is_multiple_of(3) {
                    still.push(id);
                    continue;
                }
                match r.on_loaded(id) {
                    Arrival::Defer => still.push(id),
                    Arrival::Accept | Arrival::Discard => {}
                }
            }
            loading = still;
            check_invariants(&r, &mut rng);
            if world.roots().iter().all(|&root| r.is_resident(root)) {
                roots_seen = true;
            }
            if !lag {
                // Instant loads: roots (and so coverage) from the first frame.
                assert!(roots_seen);
            }
            if roots_seen {
                for root in world.roots() {
                    assert!(r.is_resident(root), "root {root} lost in frame {frame}");
                }
            }
            if !lag && budget >= 512 {
                // Ample budget, instant loads: finest detail under the camera.
                if let Some(n) = world.node_at(0, pos[0], pos[1]) {
                    assert!(r.is_resident(n), "frame {frame}: {n} under camera missing");
                }
            }
        }
        assert!(roots_seen);
    }
}

#[test]
fn error_criterion_wants_the_families_the_camera_refines() {
    // A high camera over the middle: the rings alone never reach the far
    // corner root's children, but a large baked error on that resident root
    // makes its children wanted.
    let world = WorldDesc::default();
    let mut r = Residency::new(&world, ResidencyConfig::default()).unwrap();
    let cam = [5000.0, 5000.0, 20_000.0];
    // Looking straight down, with the off-axis factor capped at 1 (widest),
    // so the projection is error * 1000 / distance.
    let camera = TraverseCamera {
        position_m: cam,
        pixels_per_tan: 1000.0,
        forward: [0.0, 0.0, -1.0],
        widest: 1.0,
        frustum: None,
    };
    let want = RefineWant { camera, target_error_px: 1.0, prefetch: 1.0, ring_factor: 0.75, infinite_known: false };
    for id in r.update_with(cam, Some(&want)).adds {
        assert_eq!(r.on_loaded(id), Arrival::Accept);
    }
    let root = world.node_at(world.root_lod(), 10.0, 10.0).unwrap();
    let kids = world.valid_children(root);
    assert!(kids.iter().all(|k| !r.is_resident(*k) && !r.is_pending(*k)), "the rings reach the corner");
    // 30 m of error seen from ~20.3 km at 1000 px per unit tan: 1.47 px > 1.
    r.note_bounds(root, 30.0, [0.0, 100.0]);
    let adds = r.update_with(cam, Some(&want)).adds;
    assert_eq!(adds.iter().copied().collect::<HashSet<_>>(), kids.iter().copied().collect::<HashSet<_>>());
    // 10 m (0.49 px) is below target / hysteresis (0.8 px): the held
    // family is dropped (still loading here, so its loads are cancelled).
    r.note_bounds(root, 10.0, [0.0, 100.0]);
    let ch = r.update_with(cam, Some(&want));
    assert_eq!(ch.cancels.iter().copied().collect::<HashSet<_>>(), kids.iter().copied().collect::<HashSet<_>>());
}

#[test]
fn a_root_with_pending_errors_wants_its_family_only_in_view_nearest_first() {
    // Roots made on demand load with an unknown (infinite) error: their
    // families are wanted where the view holds the root, nearest first, and
    // never out of view (their tiles are what the family's load computes);
    // a known infinite error (a hole's) wants them everywhere.
    let world = small_world();
    let mut r = Residency::new(&world, ResidencyConfig::default()).unwrap();
    let cam = [900.0, 300.0, 500.0];
    // A view of the half-space x <= 1100 (every plane the same), looking -x.
    let camera = TraverseCamera {
        position_m: cam,
        pixels_per_tan: 1000.0,
        forward: [-1.0, 0.0, 0.0],
        widest: 2.0,
        frustum: Some([[-1.0, 0.0, 0.0, 1100.0]; 5]),
    };
    let want = RefineWant { camera, target_error_px: 1.0, prefetch: 1.0, ring_factor: 0.0, infinite_known: false };
    for id in r.update_with(cam, Some(&want)).adds {
        assert_eq!(r.on_loaded(id), Arrival::Accept);
    }
    for root in world.roots() {
        r.note_bounds(root, f32::INFINITY, [0.0, 100.0]);
    }
    let adds = r.update_with(cam, Some(&want)).adds;
    let seen: Vec<NodeId> = world.roots().into_iter().filter(|root| world.bounds_m(*root)[0] <= 1100.0).collect();
    assert!(!seen.is_empty() && seen.len() < world.roots().len());
    let expected: HashSet<NodeId> = seen.iter().flat_map(|root| world.valid_children(*root)).collect();
    assert_eq!(adds.iter().copied().collect::<HashSet<_>>(), expected, "the families of the roots in view");
    let distance = |id: &NodeId| {
        let b = world.bounds_m(id.parent());
        let (dx, dy) = ((b[0] - cam[0]).max(cam[0] - b[2]).max(0.0), (b[1] - cam[1]).max(cam[1] - b[3]).max(0.0));
        (dx * dx + dy * dy).sqrt()
    };
    let order: Vec<f64> = adds.iter().map(distance).collect();
    assert!(order.windows(2).all(|w| w[0] <= w[1]), "nearest root first: {order:?}");
    // Under the per-triangle rule an infinite error is a hole's, known:
    // the families out of view are wanted too.
    let known = RefineWant { infinite_known: true, ..want };
    let more = r.update_with(cam, Some(&known)).adds;
    let all: HashSet<NodeId> = world.roots().into_iter().flat_map(|root| world.valid_children(root)).collect();
    assert!(!more.is_empty() && more.iter().all(|id| !expected.contains(id)));
    assert_eq!(expected.union(&more.into_iter().collect()).copied().collect::<HashSet<_>>(), all);
}

#[test]
fn oscillating_camera_causes_no_churn() {
    let world = WorldDesc::default();
    let node = NodeId::new(0, 80, 80);
    let b = world.bounds_m(node);
    let centre = [(b[0] + b[2]) / 2.0, (b[1] + b[3]) / 2.0];
    for (hysteresis, expect_churn) in [(1.25, false), (1.0, true)] {
        let config = ResidencyConfig { hysteresis, ..ResidencyConfig::default() };
        let ring = config.ring_factor * world.node_size_m(0);
        let mut r = Residency::new(&world, config).unwrap();
        let mut churn = 0;
        for frame in 0..60u32 {
            // A few metres either side of the LOD-0 ring edge of `node`, on
            // the far side from its siblings (x = 80 is its family's west
            // column), so its family's nearest member is `node` itself.
            let dx = if frame.is_multiple_of(2) { ring - 3.0 } else { ring + 3.0 };
            let ch = r.update([centre[0] - dx, centre[1] + 0.1, 50.0]);
            for id in &ch.adds {
                assert_eq!(r.on_loaded(*id), Arrival::Accept);
            }
            if frame > 0 {
                churn += ch.adds.len() + ch.removes.len() + ch.cancels.len();
            }
        }
        assert_eq!(churn > 0, expect_churn, "hysteresis {hysteresis}: churn {churn}");
    }
}

#[test]
fn bad_residency_configs() {
    let world = WorldDesc::default();
    let small = ResidencyConfig { budget: 24, ..ResidencyConfig::default() };
    assert!(matches!(Residency::new(&world, small), Err(WorldError::BudgetTooSmall { roots: 25, budget: 24 })));
    for (ring_factor, hysteresis) in [(f64::NAN, 1.2), (0.1, 1.2), (2.0, 0.5)] {
        let c = ResidencyConfig { ring_factor, hysteresis, ..ResidencyConfig::default() };
        assert!(matches!(Residency::new(&world, c), Err(WorldError::InvalidConfig(_))));
    }
}

/// The retry schedule of the defaults (4 attempts, backoff 2 frames
/// doubling): a node failing every time is asked for at frames 1, 3, 7 and
/// 15, then never again; a root given up is reported.
#[test]
fn failed_loads_are_retried_with_doubling_backoff_then_given_up() {
    let world = WorldDesc {
        extent_m: [512.0, 512.0],
        height_range_m: [0.0, 100.0],
        spacing_m: 1.0,
        lod_count: 2,
        ..WorldDesc::default()
    };
    let config = ResidencyConfig::default();
    assert_eq!((config.max_load_attempts, config.retry_frames), (4, 2));
    let mut r = Residency::new(&world, config).unwrap();
    let cam = [60.0, 60.0, 10.0];
    let bad = world.node_at(0, cam[0], cam[1]).unwrap();
    let mut asked = Vec::new();
    let mut fates = Vec::new();
    for frame in 1..=40u64 {
        let changes = r.update(cam);
        for id in changes.adds {
            if id == bad {
                asked.push(frame);
                fates.push(r.on_failed(id));
            } else {
                assert_eq!(r.on_loaded(id), Arrival::Accept, "{id}");
            }
        }
        let waiting = fates.last().is_some_and(|f| matches!(f, LoadFate::Retry { .. }));
        assert_eq!(r.retry_waiting(), usize::from(waiting && !r.is_pending(bad)), "frame {frame}");
    }
    assert_eq!(asked, [1, 3, 7, 15]);
    assert_eq!(
        fates,
        [
            LoadFate::Retry { attempts: 1, at_frame: 3 },
            LoadFate::Retry { attempts: 2, at_frame: 7 },
            LoadFate::Retry { attempts: 3, at_frame: 15 },
            LoadFate::GaveUp { attempts: 4 },
        ]
    );
    assert!(r.gave_up(bad) && r.is_failed(bad) && r.root_given_up().is_none());
    assert_eq!(r.failure_counts(), FailureCounts { failures: 4, retries: 3, gave_up: 1 });
    // Its siblings are resident all along: the family minus the lost node.
    for sib in world.valid_children(bad.parent()).into_iter().filter(|s| *s != bad) {
        assert!(r.is_resident(sib), "{sib}");
    }

    // A root: one attempt, then it is given up and reported.
    let one = ResidencyConfig { max_load_attempts: 1, ..ResidencyConfig::default() };
    let mut r = Residency::new(&world, one).unwrap();
    let root = world.roots()[0];
    assert!(r.update(cam).adds.contains(&root));
    assert_eq!(r.on_failed(root), LoadFate::GaveUp { attempts: 1 });
    assert_eq!(r.root_given_up(), Some(root));
    assert!(r.update(cam).adds.is_empty(), "nothing below a lost root is wanted");
    let zero = ResidencyConfig { max_load_attempts: 0, ..ResidencyConfig::default() };
    assert!(matches!(Residency::new(&world, zero), Err(WorldError::InvalidConfig(_))));
}

#[test]
fn streamer_with_loader_threads() {
    let world = WorldDesc {
        extent_m: [4096.0, 4096.0],
        height_range_m: [0.0, 100.0],
        spacing_m: 1.0,
        lod_count: 4,
        ..WorldDesc::default()
    };
    // Next to the path's end, so it is still wanted when its load fails.
    let bad = NodeId::new(0, 29, 25);
    let w2 = world;
    let load: Arc<LoadFn> = Arc::new(move |id| {
        std::thread::sleep(Duration::from_millis(1 + u64::from(id.x % 3)));
        if id == bad {
            return Err(WorldError::InvalidNode(id));
        }
        Ok(bake_node(&Flat(10.0), &w2, &[], id))
    });
    let loader = Loader::new(3, load).unwrap();
    let residency = Residency::new(&world, ResidencyConfig::default()).unwrap();
    let mut s = Streamer::new(residency, loader);
    let mut on_gpu: HashSet<NodeId> = HashSet::new();
    let mut failed = Vec::new();
    let mut rng = Rng(99);
    for step in 0..400 {
        let t = step as f64 / 400.0;
        let pos = [200.0 + t * 3500.0, 300.0 + t * 3000.0, 10.0];
        let frame = s.frame(pos, None);
        for id in &frame.removed {
            assert!(on_gpu.remove(id), "removed {id} that never arrived");
        }
        for node in &frame.arrived {
            assert!(on_gpu.insert(node.id), "{} arrived twice", node.id);
        }
        failed.extend(frame.failed.into_iter().map(|(id, _)| id));
        let resident: HashSet<NodeId> = s.residency().resident().collect();
        assert_eq!(resident, on_gpu, "GPU view and residency disagree");
        check_invariants(s.residency(), &mut rng);
        std::thread::sleep(Duration::from_millis(2));
    }
    // Let the last requests land, then the path's end must be fully loaded.
    let end = [3700.0, 3300.0, 10.0];
    for _ in 0..500 {
        let frame = s.frame(end, None);
        frame.removed.iter().for_each(|id| assert!(on_gpu.remove(id)));
        frame.arrived.iter().for_each(|n| assert!(on_gpu.insert(n.id)));
        failed.extend(frame.failed.into_iter().map(|(id, _)| id));
        let under = world.node_at(0, end[0], end[1]).unwrap();
        if on_gpu.contains(&under) && failed.contains(&bad) {
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    assert!(on_gpu.contains(&world.node_at(0, end[0], end[1]).unwrap()));
    assert!(failed.contains(&bad), "the failing node was not reported");
    assert!(!on_gpu.contains(&bad));
    println!("streamer: {} resident at the end", on_gpu.len());
}

/// Frames never wait for loads, shown without a clock: every load is held
/// behind a gate while frames run, so a frame that waited on one could not
/// return. The loads are in flight meanwhile (started, none arrived), and
/// all land once the gate opens. The watchdog only turns a deadlock into a
/// failure instead of a hung test.
#[test]
fn frames_never_wait_for_loads() {
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    use std::sync::{Condvar, Mutex};
    let world = small_world();
    let gate = Arc::new((Mutex::new(false), Condvar::new()));
    let started = Arc::new(AtomicUsize::new(0));
    let (g, st, w2) = (Arc::clone(&gate), Arc::clone(&started), world);
    let load: Arc<LoadFn> = Arc::new(move |id| {
        st.fetch_add(1, Ordering::SeqCst);
        let (open, cv) = &*g;
        let _open = cv.wait_while(open.lock().unwrap(), |o| !*o).unwrap();
        Ok(bake_node(&Flat(10.0), &w2, &[], id))
    });
    let open_gate = |gate: &(Mutex<bool>, Condvar)| {
        *gate.0.lock().unwrap() = true;
        gate.1.notify_all();
    };
    let fired = Arc::new(AtomicBool::new(false));
    let (wg, wf) = (Arc::clone(&gate), Arc::clone(&fired));
    std::thread::spawn(move || {
        std::thread::sleep(Duration::from_secs(120));
        if !*wg.0.lock().unwrap() {
            wf.store(true, Ordering::SeqCst);
            open_gate(&wg);
        }
    });
    let loader = Loader::new(2, load).unwrap();
    let mut s = Streamer::new(Residency::new(&world, ResidencyConfig::default()).unwrap(), loader);
    let pos = [1000.0, 1000.0, 10.0];
    for frame in 0..50 {
        let f = s.frame(pos, None);
        assert!(f.arrived.is_empty() && f.failed.is_empty(), "frame {frame}: a gated load finished");
        // Let the loader threads pick requests up (no clock involved in the check).
        while frame == 0 && started.load(Ordering::SeqCst) == 0 {
            std::thread::yield_now();
        }
    }
    assert!(!fired.load(Ordering::SeqCst), "a frame waited for a load (watchdog opened the gate)");
    assert!(started.load(Ordering::SeqCst) >= 1, "no load was in flight");
    assert!(s.residency().pending_count() > 0, "requests are pending while gated");
    open_gate(&gate);
    let mut arrived = 0;
    while s.residency().pending_count() > 0 {
        arrived += s.frame(pos, None).arrived.len();
        std::thread::yield_now();
    }
    assert!(arrived > 0 && !fired.load(Ordering::SeqCst));
}

#[test]
fn cache_roundtrip_corruption_and_staleness() {
    let dir = temp_dir("cache");
    let world = WorldDesc {
        extent_m: [512.0, 512.0],
        height_range_m: [0.0, 100.0],
        spacing_m: 1.0,
        lod_count: 3,
        ..WorldDesc::default()
    };
    let id = NodeId::new(1, 1, 0);
    let cache = NodeCache::new(&dir, world, Arc::new(Flat(42.0)), vec![]).unwrap();
    let (baked, o) = cache.get_or_bake(id).unwrap();
    assert_eq!(o, CacheOutcome::Baked(MissReason::Missing));
    let mut expected = bake_node(&Flat(42.0), &world, &[], id);
    ErrorTree::new(&world, Arc::new(Flat(42.0)), None).unwrap().attach(&mut expected).unwrap();
    assert_eq!(baked, expected);
    let (read, o) = cache.get_or_bake(id).unwrap();
    assert_eq!(o, CacheOutcome::Hit);
    assert_eq!(read, baked);

    // Flip one byte anywhere: header (magic, version, keys, settings key,
    // node), the zstd frame or the checksum.
    let path = cache.path(id);
    let good = std::fs::read(&path).unwrap();
    // A flat node is mostly repeated bytes: zstd keeps a small part of it.
    assert!(good.len() * 10 < BakedNode::serialized_bytes(PayloadFormat::Bc, false), "{} bytes", good.len());
    for at in [0, 5, 20, 36, 44, 60, good.len() / 2, good.len() - 1] {
        let mut b = good.clone();
        b[at] ^= 0x10;
        std::fs::write(&path, &b).unwrap();
        let (n, o) = cache.get_or_bake(id).unwrap();
        assert_eq!(o, CacheOutcome::Baked(MissReason::Corrupt), "byte {at}");
        assert_eq!(n, baked);
        assert_eq!(std::fs::read(&path).unwrap(), good, "file not rewritten");
    }
    std::fs::write(&path, &good[..good.len() - 7]).unwrap();
    assert_eq!(cache.get_or_bake(id).unwrap().1, CacheOutcome::Baked(MissReason::Corrupt));
    std::fs::write(&path, b"garbage").unwrap();
    assert_eq!(cache.get_or_bake(id).unwrap().1, CacheOutcome::Baked(MissReason::Corrupt));

    // Another source (different id_hash) or hole set: stale, rebaked.
    let other = NodeCache::new(&dir, world, Arc::new(Flat(43.0)), vec![]).unwrap();
    let (n, o) = other.get_or_bake(id).unwrap();
    assert_eq!(o, CacheOutcome::Baked(MissReason::Stale));
    assert_ne!(n.heights, baked.heights);
    // A hole away from the node (it covers 256..512 x 0..256 m) leaves its
    // file current; one over it makes it stale.
    let far = vec![Hole::Circle { center_m: [10.0, 10.0], radius_m: 5.0 }];
    let unholed = NodeCache::new(&dir, world, Arc::new(Flat(43.0)), far).unwrap();
    assert_eq!(unholed.get_or_bake(id).unwrap().1, CacheOutcome::Hit);
    let holes = vec![Hole::Circle { center_m: [300.0, 100.0], radius_m: 5.0 }];
    let holed = NodeCache::new(&dir, world, Arc::new(Flat(43.0)), holes).unwrap();
    assert_eq!(holed.get_or_bake(id).unwrap().1, CacheOutcome::Baked(MissReason::Stale));
    assert_eq!(holed.get_or_bake(id).unwrap().1, CacheOutcome::Hit);
    // Other bake settings (payload format or material rules): stale too.
    for settings in [
        BakeSettings { format: PayloadFormat::Rgba8, ..BakeSettings::default() },
        BakeSettings {
            materials: MaterialRules { snow_line_m: 10.0, ..MaterialRules::default() },
            ..BakeSettings::default()
        },
    ] {
        let c = NodeCache::with_settings(&dir, world, Arc::new(Flat(43.0)), vec![], settings.clone()).unwrap();
        assert_eq!(c.get_or_bake(id).unwrap().1, CacheOutcome::Baked(MissReason::Stale));
        let (n, o) = c.get_or_bake(id).unwrap();
        assert_eq!((o, n.format), (CacheOutcome::Hit, settings.format));
    }

    assert!(matches!(cache.get_or_bake(NodeId::new(0, 4, 0)), Err(WorldError::InvalidNode(_))));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bake_world_region_and_timings() {
    let (world, src) = ProceduralSource::default_world(1);
    let src: Arc<dyn HeightSource> = Arc::new(src);

    let t = Instant::now();
    let node = bake_node(src.as_ref(), &world, &[], NodeId::new(0, 80, 80));
    let one = t.elapsed();
    // Errors come from the error tree, not the node's own bake.
    assert_eq!(node.max_error_m, f32::INFINITY);

    let dir = temp_dir("bake_world");
    let region = Some([5000.0, 5000.0, 5128.0, 5128.0]);
    let settings = BakeSettings::default();
    let stats = bake_world(Arc::clone(&src), &world, &[], &settings, region, &dir, false).unwrap();
    // Counted by hand, not by the bake's own region function: nodes of
    // side 64 * 2^lod m overlapping [5000, 5128) on each axis. LOD 0: 78..=80
    // (3); LOD 1 (128 m): 39..=40; LOD 2 (256 m): 19..=20; LOD 3 (512 m):
    // 9..=10; LOD 4 (1024 m): 4..=5 (5120 < 5128); LOD 5 (2048 m): 2 only.
    assert_eq!(stats.nodes_per_lod, [9, 4, 4, 4, 4, 1]);
    assert_eq!(stats.baked, 26);
    let expected = nodes_in_region(&world, region);
    assert_eq!(expected.len(), 26);
    // Compressed files differ in size: sum them one by one.
    let cache = NodeCache::new(&dir, world, Arc::clone(&src), vec![]).unwrap();
    let on_disk: u64 = expected.iter().map(|id| std::fs::metadata(cache.path(*id)).unwrap().len()).sum();
    assert_eq!(stats.bytes_on_disk, on_disk);
    let again = bake_world(Arc::clone(&src), &world, &[], &settings, region, &dir, false).unwrap();
    assert_eq!(again.cached, expected.len());

    let total_nodes: usize = (0..world.lod_count as u8).map(|l| world.nodes_at(l).len()).sum();
    let per_node_s = stats.seconds / expected.len() as f64;
    let per_node_bytes = stats.bytes_on_disk as f64 / expected.len() as f64;
    println!(
        "one LOD-0 bake: {one:?}; bake_world region: {} nodes {:?} in {:.3} s, {} bytes; \
         cached pass {:.3} s; full world: {total_nodes} nodes, ~{:.0} s on this machine, ~{:.2} GB",
        expected.len(),
        stats.nodes_per_lod,
        stats.seconds,
        stats.bytes_on_disk,
        again.seconds,
        per_node_s * total_nodes as f64,
        per_node_bytes * total_nodes as f64 / 1e9
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A second edit while the first's reloads are coming back: the ones
/// already back (held until all are) were made from the first edit's
/// source, so they are asked of the second's loader again; every node of
/// both edits is handed over once, together, from the last source.
#[test]
fn an_edit_during_anothers_reloads_reloads_both_from_the_last_source() {
    use std::sync::{Condvar, Mutex};
    type Gate = Arc<(Mutex<bool>, Condvar)>;
    let world = small_world();
    let flat = |h: f32, gated: Option<(NodeId, Gate)>| {
        let load: Arc<LoadFn> = Arc::new(move |id| {
            if let Some((g, gate)) = &gated {
                let (open, cv) = &**gate;
                let _open = cv.wait_while(open.lock().unwrap(), |o| *g == id && !*o).unwrap();
            }
            Ok(bake_node(&Flat(h), &world, &[], id))
        });
        Loader::new(2, load).unwrap()
    };
    let mut s = Streamer::new(Residency::new(&world, ResidencyConfig::default()).unwrap(), flat(10.0, None));
    let pos = [1000.0, 1000.0, 10.0];
    while s.residency().resident().count() < s.residency().roots().len() || s.residency().pending_count() > 0 {
        s.frame(pos, None);
        std::thread::yield_now();
    }
    let (a, b) = (s.residency().roots()[0], s.residency().roots()[1]);
    // Edit 1 touches a and b; b's load waits at the gate.
    let gate = Arc::new((Mutex::new(false), Condvar::new()));
    s.replace_loader(flat(20.0, Some((b, Arc::clone(&gate)))), |_| false);
    assert!(s.reload(a) && s.reload(b));
    while s.reloading() > 1 {
        assert!(s.frame(pos, None).reloaded.is_empty(), "a reload handed over before the others were back");
        std::thread::yield_now();
    }
    // Edit 2 touches b only; the gate opens so the old loader can finish.
    *gate.0.lock().unwrap() = true;
    gate.1.notify_all();
    s.replace_loader(flat(30.0, None), |_| false);
    assert!(s.reload(b));
    let mut handed = Vec::new();
    while handed.is_empty() {
        handed = s.frame(pos, None).reloaded;
        std::thread::yield_now();
    }
    let mut ids: Vec<NodeId> = handed.iter().map(|n| n.id).collect();
    ids.sort();
    let mut want = vec![a, b];
    want.sort();
    assert_eq!(ids, want, "both edits' nodes, together");
    let top = world.decode_height(handed[0].max_height);
    assert!(handed.iter().all(|n| world.decode_height(n.max_height) == top), "one source for all");
    assert!((top - 30.0).abs() < 0.01, "from the last edit's source: {top} m");
}
