//! Stamps (seed 004's copy-paste of terrain): a stamped world's heights
//! against a composition of its inputs written here from the definition
//! (rotation by glam, the map's values from the linear function they were
//! made of, the blend formulas), the ray-caster seeing a stamp, and the
//! range check.

use std::sync::Arc;

use glam::{DMat2, DVec2, DVec3};
use vista::reference::{RayCaster, RaycastConfig};
use vista::world::{
    GridSource, HeightSource, ProceduralSource, Stamp, StampBlend, StampPlacement, StampedSource, WorldDesc,
};

/// A stamp map whose pixel (i, j) (row 0 north) holds `a + b i + c j`:
/// Catmull-Rom reproduces a linear function exactly away from the border,
/// so its value anywhere inside is known without the resampler.
struct LinearMap {
    w: usize,
    h: usize,
    abc: [f64; 3],
}

impl LinearMap {
    fn grid(&self, size_m: f64) -> GridSource {
        let values = (0..self.w * self.h)
            .map(|k| (self.abc[0] + self.abc[1] * (k % self.w) as f64 + self.abc[2] * (k / self.w) as f64) as f32)
            .collect();
        GridSource::new(self.w, self.h, values, [size_m; 2])
    }

    /// The value at stamp-local metres (x east, y north from the square's
    /// south-west corner), or `None` within 1.5 pixels of the border, where
    /// the resampler's clamped taps leave the linear function.
    fn value(&self, x: f64, y: f64, size_m: f64) -> Option<f64> {
        let (dx, dy) = (size_m / self.w as f64, size_m / self.h as f64);
        let (i, j) = (x / dx - 0.5, (size_m - y) / dy - 0.5);
        let inside = |t: f64, n: usize| t >= 1.5 && t <= n as f64 - 2.5;
        (inside(i, self.w) && inside(j, self.h)).then(|| self.abc[0] + self.abc[1] * i + self.abc[2] * j)
    }
}

struct Case {
    placement: StampPlacement,
    map: LinearMap,
}

fn placement(center: [f64; 2], size: f64, rot: f64, height: f64, offset: f64, blend: StampBlend) -> StampPlacement {
    StampPlacement {
        center_m: center,
        size_m: size,
        rotation_deg: rot,
        height_m: height,
        offset_m: offset,
        blend,
        falloff_m: 0.2 * size,
    }
}

/// Four overlapping stamps, one per blend mode, rotated and of different
/// sizes and map shapes (non-square pixels), over a procedural world.
fn cases() -> Vec<Case> {
    let map = |w, h, abc| LinearMap { w, h, abc };
    vec![
        Case {
            placement: placement([900.0, 800.0], 700.0, 30.0, 120.0, 20.0, StampBlend::Replace),
            map: map(33, 17, [0.1, 0.02, 0.01]),
        },
        Case {
            placement: placement([1200.0, 1000.0], 500.0, -75.0, 90.0, -30.0, StampBlend::Add),
            map: map(20, 41, [0.9, -0.03, -0.005]),
        },
        Case {
            placement: placement([1000.0, 1300.0], 600.0, 200.0, 300.0, 150.0, StampBlend::Max),
            map: map(25, 25, [0.0, 0.02, 0.015]),
        },
        Case {
            placement: placement([700.0, 1150.0], 450.0, 123.0, 200.0, -20.0, StampBlend::Min),
            map: map(16, 30, [0.5, 0.02, -0.01]),
        },
    ]
}

fn world() -> (WorldDesc, Arc<dyn HeightSource>) {
    let world = WorldDesc {
        extent_m: [2048.0, 2048.0],
        height_range_m: [-400.0, 1000.0],
        spacing_m: 2.0,
        lod_count: 4,
        ..WorldDesc::default()
    };
    let base = ProceduralSource::new(3, world.extent_m, [0.0, 400.0]).unwrap();
    (world, Arc::new(base))
}

fn stamped(base: &Arc<dyn HeightSource>, cases: &[Case]) -> StampedSource {
    let stamps = cases.iter().map(|c| Stamp::new(c.placement, c.map.grid(c.placement.size_m)).unwrap()).collect();
    StampedSource::new(Arc::clone(base), stamps)
}

/// The composition by its definition: `None` where a stamp's map value is
/// not known exactly (near its border).
fn expected(base: f64, p: DVec2, cases: &[Case]) -> Option<(f64, Vec<(StampBlend, f64)>)> {
    let mut h = base;
    let mut applied = Vec::new();
    for c in cases {
        let s = &c.placement;
        let local = DMat2::from_angle(-s.rotation_deg.to_radians()) * (p - DVec2::from(s.center_m));
        let half = 0.5 * s.size_m;
        if local.x.abs() > half || local.y.abs() > half {
            continue;
        }
        let value = c.map.value(local.x + half, local.y + half, s.size_m)?;
        let stamp = s.offset_m + s.height_m * value;
        let edge = half - local.x.abs().max(local.y.abs());
        let t = (edge / s.falloff_m).min(1.0);
        let w = t * t * (3.0 - 2.0 * t);
        h = match s.blend {
            StampBlend::Replace => (1.0 - w) * h + w * stamp,
            StampBlend::Add => h + w * stamp,
            StampBlend::Max => (1.0 - w) * h + w * h.max(stamp),
            StampBlend::Min => (1.0 - w) * h + w * h.min(stamp),
        };
        applied.push((s.blend, w));
    }
    Some((h, applied))
}

#[test]
fn stamped_heights_equal_the_composition_of_their_inputs() {
    let (_, base) = world();
    let cases = cases();
    let source = stamped(&base, &cases);
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut rand = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let (mut checked, mut worst) = (0, 0f64);
    let mut seen = std::collections::HashSet::new();
    let mut ramps = 0;
    for _ in 0..20_000 {
        let p = DVec2::new(300.0 + 1300.0 * rand(), 300.0 + 1300.0 * rand());
        let h0 = f64::from(base.sample(p.x, p.y));
        let Some((want, applied)) = expected(h0, p, &cases) else { continue };
        let got = f64::from(source.sample(p.x, p.y));
        // The source composes in f64 and returns f32: half an f32 step of
        // heights under 1000 m is 3e-5 m.
        let err = (got - want).abs();
        worst = worst.max(err);
        assert!(err <= 1e-4, "at {p}: {got} against {want} (stamps {applied:?})");
        for (blend, w) in &applied {
            seen.insert(*blend as u8);
            ramps += usize::from(*w > 0.0 && *w < 1.0);
        }
        checked += 1;
    }
    println!("{checked} points, worst {worst:.2e} m, {ramps} in a falloff band");
    assert!(checked > 5000, "only {checked} points checked");
    assert_eq!(seen.len(), 4, "every blend mode applied somewhere");
    assert!(ramps > 500, "the falloff bands are exercised ({ramps})");
}

#[test]
fn rows_equal_single_samples_bit_for_bit() {
    let (_, base) = world();
    let source = stamped(&base, &cases());
    let xs: Vec<f64> = (0..700).map(|i| 400.0 + 1.37 * f64::from(i)).collect();
    for y in [200.0, 800.0, 1000.5, 1290.0] {
        let mut row = vec![0f32; xs.len()];
        source.sample_row(&xs, y, &mut row);
        for (x, v) in xs.iter().zip(&row) {
            assert_eq!(v.to_bits(), source.sample(*x, y).to_bits(), "at ({x}, {y})");
        }
    }
}

#[test]
fn the_ray_caster_sees_a_stamp() {
    // A flat 100 m world with a plateau stamped 150 m high (max, a flat map
    // at 1.0, no falloff): a ray straight down meets 150 m inside the
    // square and 100 m outside it.
    let world = WorldDesc {
        extent_m: [2048.0, 2048.0],
        height_range_m: [0.0, 400.0],
        spacing_m: 2.0,
        lod_count: 4,
        ..WorldDesc::default()
    };
    let base: Arc<dyn HeightSource> = Arc::new(GridSource::new(2, 2, vec![100.0; 4], world.extent_m));
    let flat = GridSource::new(4, 4, vec![1.0; 16], [200.0; 2]);
    let mut p = placement([1024.0, 1024.0], 200.0, 45.0, 50.0, 100.0, StampBlend::Max);
    p.falloff_m = 0.0;
    let source = StampedSource::new(base, vec![Stamp::new(p, flat).unwrap()]);
    let caster = RayCaster::new(&source, &world, RaycastConfig::default());
    let down = |x: f64, y: f64| caster.trace(DVec3::new(x, y, 1000.0), DVec3::NEG_Z, 1e-4).t.expect("a hit");
    // The square is rotated 45 degrees: (1024 + 90, 1024) is inside it,
    // (1024 + 90, 1024 + 90) outside (its corners point along the axes).
    for (x, y, z) in [(1024.0, 1024.0, 150.0), (1114.0, 1024.0, 150.0), (1114.0, 1114.0, 100.0), (1500.0, 600.0, 100.0)]
    {
        let hit = 1000.0 - down(x, y);
        assert!((hit - z).abs() < 1e-3, "ray at ({x}, {y}) met {hit} m, expected {z} m");
    }
}

#[test]
fn a_stamp_that_leaves_the_height_range_is_refused_naming_it() {
    let (world, base) = world();
    let ok = cases();
    stamped(&base, &ok).check_range(world.height_range_m).expect("the test stamps fit the range");
    let mut tall = cases();
    tall[2].placement.height_m = 3000.0;
    let e = stamped(&base, &tall).check_range(world.height_range_m).unwrap_err().to_string();
    assert!(e.starts_with("stamp 3 (max at 1000,1300)") && e.contains("height range -400..1000"), "{e}");
    assert!(!e.contains('\n'), "{e}");
}

#[test]
fn a_region_away_from_every_stamp_hashes_as_the_bare_source() {
    let (_, base) = world();
    let source = stamped(&base, &cases());
    let far = [1800.0, 1800.0, 2000.0, 2000.0];
    assert_eq!(source.region_hash(far), base.region_hash(far));
    let near = [850.0, 750.0, 950.0, 850.0];
    assert_ne!(source.region_hash(near), base.region_hash(near));
    // A grid's region hash follows its pixels there and nowhere else.
    let mut values = vec![0f32; 64 * 64];
    let a = GridSource::new(64, 64, values.clone(), [640.0; 2]);
    values[10 * 64 + 50] = 5.0; // pixel (50, 10): x 505 m, y 535 m
    let b = GridSource::new(64, 64, values, [640.0; 2]);
    assert_eq!(a.region_hash([0.0, 0.0, 200.0, 200.0]), b.region_hash([0.0, 0.0, 200.0, 200.0]));
    assert_ne!(a.region_hash([480.0, 500.0, 520.0, 540.0]), b.region_hash([480.0, 500.0, 520.0, 540.0]));
    assert_ne!(a.id_hash(), b.id_hash());
}

/// Adding a stamp to a baked world rebakes exactly the nodes whose bake
/// reads its area (their own area and the samples around it, so their
/// ancestors too) and recomputes only the error tile of the root under it;
/// the result equals a full bake of the stamped world byte for byte.
#[test]
fn adding_a_stamp_rebakes_exactly_the_nodes_it_touches() {
    use vista::world::{bake_world, BakeSettings, NodeId};
    // 4096 m at 2 m, 4 LODs: 2 x 2 roots of 2048 m, 340 nodes.
    let world = WorldDesc {
        extent_m: [4096.0, 4096.0],
        height_range_m: [-200.0, 800.0],
        spacing_m: 2.0,
        lod_count: 4,
        ..WorldDesc::default()
    };
    let base: Arc<dyn HeightSource> = Arc::new(ProceduralSource::new(5, world.extent_m, [0.0, 400.0]).unwrap());
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("stamp-rebake-{}", std::process::id()));
    let (edited, fresh) = (dir.join("edited"), dir.join("fresh"));
    let _ = std::fs::remove_dir_all(&dir);
    let settings = BakeSettings::default();
    let first = bake_world(Arc::clone(&base), &world, &[], &settings, None, &edited, false).unwrap();
    assert_eq!((first.baked, first.cached, first.errors.roots), (340, 0, 4));

    // A 300 m crater rotated 20 degrees inside the south-west root.
    let crater = LinearMap { w: 16, h: 16, abc: [0.2, 0.03, 0.02] };
    let p = placement([700.0, 900.0], 300.0, 20.0, 60.0, -40.0, StampBlend::Add);
    let stamp = Stamp::new(p, crater.grid(300.0)).unwrap();
    let sb = stamp.bounds_m();
    let stamped: Arc<dyn HeightSource> = Arc::new(StampedSource::new(Arc::clone(&base), vec![stamp]));
    let second = bake_world(Arc::clone(&stamped), &world, &[], &settings, None, &edited, false).unwrap();

    // The nodes it touches, from the layout: a node's bake reads its area
    // and 3 of its sample steps around it.
    let touched: std::collections::BTreeSet<NodeId> = (0..world.lod_count as u8)
        .flat_map(|l| world.nodes_at(l))
        .filter(|&id| {
            let b = world.bounds_m(id);
            let m = 3.0 * world.node_spacing_m(id.lod);
            b[0] - m <= sb[2] && b[2] + m >= sb[0] && b[1] - m <= sb[3] && b[3] + m >= sb[1]
        })
        .collect();
    let per_lod: Vec<usize> = (0..4).map(|l| touched.iter().filter(|n| n.lod == l).count()).collect();
    println!(
        "stamp edit: {} reused, {} rebaked ({per_lod:?} per LOD) in {:.2} s + {:.2} s error tree ({} of {} roots \
         computed); first bake {:.2} s + {:.2} s",
        second.cached,
        second.rebaked,
        second.seconds,
        second.errors.seconds,
        second.errors.roots - second.errors.read,
        second.errors.roots,
        first.seconds,
        first.errors.seconds
    );
    assert_eq!(per_lod[3], 1, "one root holds the stamp");
    assert!(per_lod[0] >= 4, "{per_lod:?}");
    assert_eq!((second.rebaked, second.baked, second.cached), (touched.len(), touched.len(), 340 - touched.len()));
    assert_eq!((second.errors.roots, second.errors.read), (4, 3), "only the stamped root's error tile is recomputed");
    let changed: std::collections::BTreeSet<NodeId> = first
        .files
        .iter()
        .zip(&second.files)
        .filter(|(a, b)| {
            assert_eq!(a.id, b.id);
            a.crc32 != b.crc32
        })
        .map(|(a, _)| a.id)
        .collect();
    assert_eq!(changed, touched, "the files that changed are those of the touched nodes");

    // A full bake of the stamped world: the same files, byte for byte.
    let full = bake_world(stamped, &world, &[], &settings, None, &fresh, false).unwrap();
    assert_eq!(full.baked, 340);
    for f in &full.files {
        let rel = format!("lod{}/{}_{}.vnode", f.id.lod, f.id.x, f.id.y);
        let (a, b) = (std::fs::read(edited.join(&rel)).unwrap(), std::fs::read(fresh.join(&rel)).unwrap());
        assert!(a == b, "{rel} differs between the edited and the full bake");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

mod common;

/// A running renderer takes an edited source: the resident nodes the stamp
/// touches reload (no frame between shows a gap: the old payloads stay
/// drawn until the new ones are swapped in), the others stay, and once
/// settled the picture is the one a renderer made with the stamped source
/// from the start draws.
#[test]
fn a_running_renderer_reloads_the_nodes_a_new_stamp_touches() {
    // A 200 m plateau raised in front of the camera (max, flat map).
    let mut p = placement([512.0, 420.0], 200.0, 25.0, 80.0, 380.0, StampBlend::Max);
    p.falloff_m = 30.0;
    common::gpu_test(|ctx| stamp_a_running_renderer(ctx, vista::effects::Effects::default(), p));
}

/// As above with the virtual texture (splat shading near the camera): the
/// pages made from the nodes before the edit are made again from the
/// reloaded ones (a reload at a page's own LOD drops it), so the settled
/// picture is again exactly a fresh renderer's.
#[test]
fn a_stamp_edit_renders_the_virtual_texture_pages_again() {
    use vista::effects::Effect;
    let mut fx = vista::effects::Effects::default().with(Effect::Splat, true).with(Effect::VirtualTexture, true);
    fx.shade.far_start_m = 300.0;
    fx.shade.far_end_m = 450.0;
    fx.virtual_texture.cache_mb = 16;
    fx.virtual_texture.indirection = 512;
    // A 4 m mound in the pages' band: the resident set stays, so only the
    // reload itself can tell the pages over it that they are stale.
    let p = placement([512.0, 330.0], 160.0, 25.0, 4.0, 0.0, StampBlend::Add);
    common::gpu_test(|ctx| stamp_a_running_renderer(ctx, fx, p));
}

fn stamp_a_running_renderer(ctx: &vista::gpu::Context, effects: vista::effects::Effects, p: StampPlacement) {
    use common::terrain::{small_world, view, Rig, Surface, MAGENTA_RGBA};
    use vista::passes::cull_patches::CullStages;
    use vista::render::RendererOptions;
    use vista::world::bake_region;
    let world = small_world();
    let base: Arc<dyn HeightSource> = Arc::new(Surface::Hills);
    let size = [160, 96];
    let v = view([512.0, 150.0, 520.0], 0.0, -25.0, size, 1.0);
    let options = RendererOptions { effects, ..RendererOptions::default() };
    let mut rig = Rig::with_source(ctx, world, Arc::clone(&base), vec![], size, false, options.clone());
    let before = rig.shot(ctx, &v, CullStages::ALL);
    let stamp = Stamp::new(p, GridSource::new(2, 2, vec![1.0; 4], [p.size_m; 2])).unwrap();
    let region = stamp.bounds_m();
    let stamped: Arc<dyn HeightSource> = Arc::new(StampedSource::new(Arc::clone(&base), vec![stamp]));
    let resident = rig.renderer.terrain.resident_nodes();
    let touched = resident
        .iter()
        .filter(|id| {
            let r = bake_region(&world, **id);
            r[0] <= region[2] && r[2] >= region[0] && r[1] <= region[3] && r[3] >= region[1]
        })
        .count();
    let reloaded = rig.renderer.replace_source(Arc::clone(&stamped), None, region).unwrap();
    println!("resident before the edit: {}", resident.len());
    assert_eq!(reloaded, touched, "every resident node whose bake reads the stamp, and only those");
    assert!(reloaded > 0 && reloaded < resident.len(), "{reloaded} of {}", resident.len());
    let terrain_before = before.rgba.chunks(4).filter(|p| *p != MAGENTA_RGBA).count();
    reload_without_gap_until_at_rest(ctx, &mut rig, &v, terrain_before);
    let after = rig.shot(ctx, &v, CullStages::ALL);
    assert_ne!(after.depth, before.depth, "the stamp shows");
    let mut fresh = Rig::with_source(ctx, world, stamped, vec![], size, false, options);
    let want = fresh.shot(ctx, &v, CullStages::ALL);
    assert_eq!(rig.renderer.terrain.resident_nodes(), fresh.renderer.terrain.resident_nodes());
    let differ = after.rgba.chunks(4).zip(want.rgba.chunks(4)).filter(|(a, b)| a != b).count();
    assert!(
        after.depth == want.depth && differ == 0,
        "the edited renderer draws the stamped world: {differ} pixels differ"
    );
    println!("{reloaded} of {} resident nodes reloaded; {} resident after", resident.len(), want_resident(&fresh));
}

fn want_resident(rig: &common::terrain::Rig) -> usize {
    rig.renderer.terrain.resident_nodes().len()
}

/// Frame by frame while the reloads come in: never a gap (the old payloads
/// stay drawn), and the first frame after which the renderer says settled
/// is at rest: the next one loads nothing and keeps the resident set (a
/// reload's taller ground may want children; settled waits until that is
/// weighed), so a picture taken once settled is final.
fn reload_without_gap_until_at_rest(
    ctx: &vista::gpu::Context,
    rig: &mut common::terrain::Rig,
    v: &vista::render::View,
    terrain_before: usize,
) {
    use common::terrain::MAGENTA_RGBA;
    use vista::passes::cull_patches::CullStages;
    for _ in 0..20_000 {
        let mid = rig.again(ctx, v, CullStages::ALL);
        let terrain = mid.rgba.chunks(4).filter(|p| *p != MAGENTA_RGBA).count();
        assert!(terrain >= terrain_before, "a gap while reloading: {terrain} terrain pixels, {terrain_before} before");
        if rig.renderer.settled() {
            let resident = rig.renderer.terrain.resident_nodes();
            rig.again(ctx, v, CullStages::ALL);
            assert_eq!(rig.renderer.terrain.stats().loading, 0, "settled, then the next frame asked for more nodes");
            assert_eq!(rig.renderer.terrain.resident_nodes(), resident, "settled, then the resident set changed");
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    panic!("streaming did not settle in 20 000 frames");
}
