//! Terrain sun shadows (effect `shadows`): the shadow texture the GPU marches
//! equals its CPU twin (src/reference/sun_shadow.rs) and puts the shadow of a
//! cone on a plane where geometry puts it, at sun elevations 5 to 60
//! degrees; a sun that moves is caught up within the update budget and a
//! static one runs no shadow pass; the effect off builds nothing.

mod common;

use common::gpu_test;
use common::terrain::{view, Rig, Surface};
use glam::{DVec2, DVec3};
use vista::effects::shadows::sun_shadows::ShadowParams;
use vista::gpu::{Context, LiveObjects};
use vista::passes::cull_patches::CullStages;
use vista::reference::sun_shadow::{texel_position, March, NONE};
use vista::render::{frame_report, Effect, Effects, PassState, RendererOptions, View};
use vista::scene::graph::{Outcome, Skip};
use vista::world::{NodeId, WorldDesc};

const SIZE: [u32; 2] = [128, 128];
/// The cone: apex on a LOD-0 post inside one LOD-0 node (0..128 m square),
/// its flanks (74 degrees) steeper than any sun tested, so even at 60
/// degrees its shadow reaches past its base.
const CONE: Surface = Surface::Bump { z0: 100.0, c: [96.0, 96.0], r: 10.0, h: 36.0 };
/// The shadow falls towards azimuth 55 degrees, along no grid axis or diagonal.
const AZIMUTH: f64 = 235.0;

fn world() -> WorldDesc {
    common::terrain::shadow_world()
}

fn params() -> ShadowParams {
    // 1 m texels on LOD-0 nodes; dense steps, so a texel's march samples
    // the cone at least every 2 (457 - 1) / 256 = 3.6 m.
    ShadowParams { resolution: 129, steps: 256, softness_deg: 0.0, ..ShadowParams::default() }
}

fn options(elevation: f64, shadows: bool) -> RendererOptions {
    let mut fx = Effects::default().with(Effect::Shadows, shadows);
    fx.lighting.sun_azimuth_deg = AZIMUTH;
    fx.lighting.sun_elevation_deg = elevation;
    fx.shadows = params();
    RendererOptions { effects: fx, ..RendererOptions::default() }
}

/// From behind the cone, looking down the shadow: the cone's node is LOD 0.
fn over_cone() -> View {
    view([14.0, 39.0, 200.0], 55.0, -50.0, SIZE, 0.25)
}

/// Whether the plane point `q` lies in the cone's exact shadow: the shadow
/// is the union over heights s of the cross-section at s (a disc of radius
/// r (1 - s / h)) moved away from the sun by s / tan(elevation).
fn in_exact_shadow(q: DVec2, away: DVec2, rise: f64) -> bool {
    let Surface::Bump { c, r, h, .. } = CONE else { unreachable!() };
    let c = DVec2::from(c);
    (0..=2000).any(|i| {
        let f = f64::from(i) / 2000.0;
        (q - (c + away * (f * h / rise))).length() <= r * (1.0 - f)
    })
}

fn diff(a: LiveObjects, b: LiveObjects) -> [i64; 4] {
    [b.pipelines - a.pipelines, b.images - a.images, b.buffers - a.buffers, b.samplers - a.samplers]
}

/// The GPU's (threshold, distance) texels of `node`.
fn read_layer(ctx: &Context, rig: &Rig, node: NodeId) -> Vec<[f32; 2]> {
    let slot = rig.renderer.terrain.tree.shadow.slot_of(node).expect("resident");
    let atlas = &rig.renderer.effect::<vista::effects::shadows::frame::Shadows>().expect("built").pass.atlas;
    let bytes = ctx.read_image(atlas, 0, slot, 8).unwrap();
    bytemuck::cast_slice::<u8, [f32; 2]>(&bytes).to_vec()
}

fn lod0_height(p: DVec2) -> Option<f64> {
    common::terrain::shadow_world_height(CONE, p)
}

/// Checks every resident LOD-0 node's texture at `elevation`; returns the
/// plane texels in shadow on the GPU and exactly.
fn check_against_twin_and_geometry(ctx: &Context, rig: &Rig, elevation: f64, sun: DVec3) -> (usize, usize) {
    let w = world();
    let p = params();
    let march = March::new(sun, p.steps, f64::from(p.reach_m), f64::from(w.height_range_m[1]));
    let (away, rise) = (-march.dir, march.rise);
    let Surface::Bump { c, r, .. } = CONE else { unreachable!() };
    let nodes: Vec<NodeId> = rig.renderer.terrain.resident_nodes().into_iter().filter(|n| n.lod == 0).collect();
    assert!(nodes.contains(&NodeId::new(0, 0, 0)), "the cone's node is resident at LOD 0: {nodes:?}");
    let (mut shadowed, mut exact, mut worst, mut off_edge) = (0, 0, 0f64, Vec::new());
    let texel = w.node_spacing_m(0) * 128.0 / f64::from(p.resolution - 1);
    for node in nodes {
        let gpu = read_layer(ctx, rig, node);
        for (k, [h, d]) in gpu.iter().enumerate() {
            let t = [k as u32 % p.resolution, k as u32 / p.resolution];
            let q = texel_position(&w, node, p.resolution, t);
            let (h_cpu, d_cpu) = march.threshold(q, w.node_spacing_m(0), lod0_height);
            if h_cpu == NONE {
                assert_eq!(f64::from(*h), NONE as f32 as f64, "{elevation} deg, {node} texel {t:?}: nothing occludes");
                continue;
            }
            worst = worst.max((f64::from(*h) - h_cpu).abs());
            assert!((f64::from(*d) - d_cpu).abs() < 0.05 || (f64::from(*h) - h_cpu).abs() < 0.01, "{node} {t:?}");
            // The plane only: off the cone and its rim by a texel.
            if (q - DVec2::from(c)).length() < r + 2.0 * texel {
                continue;
            }
            // Relative to the ground: above it, the ground is in shadow.
            let gpu_dark = *h > 0.0;
            let exact_dark = in_exact_shadow(q, away, rise);
            shadowed += usize::from(gpu_dark);
            exact += usize::from(exact_dark);
            if gpu_dark != exact_dark {
                // Allowed only within a texel of the exact edge.
                let near_edge = (0..16).any(|i| {
                    let a = f64::from(i) * std::f64::consts::TAU / 16.0;
                    in_exact_shadow(q + DVec2::new(a.cos(), a.sin()) * texel, away, rise) == gpu_dark
                });
                if !near_edge {
                    off_edge.push((node, t));
                }
            }
        }
    }
    // R16 heights over the 40 m range (0.6 mm a step) and f32 positions
    // (under 0.1 mm at 512 m) against f64: 10 mm is ten times either.
    assert!(worst < 0.01, "{elevation} deg: GPU threshold {worst} m from the CPU twin");
    assert!(
        off_edge.is_empty(),
        "{elevation} deg: {} texels more than a texel from the exact edge: {:?}",
        off_edge.len(),
        &off_edge[..off_edge.len().min(8)]
    );
    (shadowed, exact)
}

#[test]
fn a_cones_shadow_matches_its_twin_and_geometry_from_5_to_60_degrees() {
    gpu_test(|ctx| {
        for elevation in [5.0, 15.0, 30.0, 45.0, 60.0] {
            let mut rig = Rig::with_options(ctx, world(), CONE, vec![], SIZE, false, options(elevation, true));
            rig.shot(ctx, &over_cone(), CullStages::ALL);
            let sun = rig.renderer.effects.lighting.sun_dir();
            let (shadowed, exact) = check_against_twin_and_geometry(ctx, &rig, elevation, sun);
            // Enough shadow to test: at 60 degrees it reaches 10.8 m past
            // the base, 8.8 m past the texels left out at the rim.
            assert!(exact >= 20, "{elevation} deg: only {exact} plane texels in the exact shadow");
            println!("{elevation} deg: {shadowed} plane texels in shadow on the GPU, {exact} exactly");
        }
    });
}

#[test]
fn a_moving_sun_is_caught_up_within_the_budget_and_a_static_one_is_idle() {
    gpu_test(|ctx| {
        let mut rig = Rig::with_options(ctx, world(), CONE, vec![], SIZE, false, options(30.0, true));
        let v = over_cone();
        rig.shot(ctx, &v, CullStages::ALL);
        let resident = rig.renderer.terrain.tree.shadow.resident_count();
        let budget = params().update_budget;
        let outcome = |rig: &Rig| {
            rig.renderer.last_frame_log().and_then(|l| l.outcome(vista::effects::shadows::frame::SUN_SHADOWS)).cloned()
        };
        // Settled and static: the pass is skipped, and the report says idle.
        rig.again(ctx, &v, CullStages::ALL);
        assert_eq!(outcome(&rig), Some(Outcome::Skipped(Skip::ShadowsCurrent)));
        let timings = rig.renderer.poll_timings(ctx).cloned();
        let report = frame_report(ctx, &rig.renderer, timings.as_ref()).unwrap();
        let pass = report.pass("sun_shadows").unwrap();
        assert!(pass.state == PassState::Idle && !pass.recorded, "{pass:?}");
        // One step of the sun: every resident node is redone within
        // ceil(resident / budget) frames, `budget` at a time, then idle.
        rig.renderer.effects.lighting.sun_elevation_deg = 15.0;
        let frames = resident.div_ceil(budget);
        let mut redone = 0;
        for f in 0..frames {
            rig.again(ctx, &v, CullStages::ALL);
            let Some(Outcome::Recorded { cpu_work: Some(n) }) = outcome(&rig) else { panic!("frame {f}: not run") };
            assert!(n <= u64::from(budget), "frame {f}: {n} nodes over the budget {budget}");
            redone += n;
        }
        assert_eq!(redone, u64::from(resident), "every resident node redone once");
        assert_eq!(rig.renderer.effect::<vista::effects::shadows::frame::Shadows>().unwrap().schedule.stale(), 0);
        rig.again(ctx, &v, CullStages::ALL);
        assert_eq!(outcome(&rig), Some(Outcome::Skipped(Skip::ShadowsCurrent)));
        // And what they hold is the new sun's shadow.
        let sun = rig.renderer.effects.lighting.sun_dir();
        check_against_twin_and_geometry(ctx, &rig, 15.0, sun);
    });
}

#[test]
fn shadows_off_build_nothing_and_on_darken_only_the_shadow() {
    gpu_test(|ctx| {
        let v = over_cone();
        let before = ctx.live_objects();
        let mut off = Rig::with_options(ctx, world(), CONE, vec![], SIZE, false, options(15.0, false));
        let objects_off = diff(before, ctx.live_objects());
        let a = off.shot(ctx, &v, CullStages::ALL);
        let timings = off.renderer.poll_timings(ctx).cloned();
        let report = frame_report(ctx, &off.renderer, timings.as_ref()).unwrap();
        assert_eq!(report.pass("sun_shadows").unwrap().state, PassState::NotBuilt);
        assert!(!report.memory.iter().any(|m| m.name.starts_with("sun_shadow")));
        drop(off);
        let before = ctx.live_objects();
        let mut on = Rig::with_options(ctx, world(), CONE, vec![], SIZE, false, options(15.0, true));
        let objects_on = diff(before, ctx.live_objects());
        let added: Vec<i64> = objects_on.iter().zip(objects_off).map(|(a, b)| a - b).collect();
        // The sun_shadows pipeline, its atlas, its job list and its sampler
        // (lighting_resolve's SHADOWS variant replaces the plain one).
        assert_eq!(added, [1, 1, 1, 1], "[pipelines, images, buffers, samplers]");
        let b = on.shot(ctx, &v, CullStages::ALL);
        // On: pixels only get darker, and some do: the cone's 15-degree
        // shadow (1180 m^2 on the plane) covers about 180 pixels here.
        let (mut darker, mut lighter) = (0, 0);
        let sum = |p: &[u8]| p[..3].iter().map(|&c| u32::from(c)).sum::<u32>();
        for (pa, pb) in a.rgba.chunks_exact(4).zip(b.rgba.chunks_exact(4)) {
            let (sa, sb) = (sum(pa), sum(pb));
            darker += usize::from(sb + 3 < sa);
            lighter += usize::from(sb > sa);
        }
        assert!(darker > 100 && lighter == 0, "{darker} darker, {lighter} lighter pixels");
    });
}

/// The overlay's toggle: shadows switched off for a frame skip their pass
/// (built, nothing destroyed) and the lighting goes without them; switched
/// back on, every resident node is marched again (its slot may hold another
/// node's texture by then) and the shadows show only once all are done.
#[test]
fn switched_off_shadows_skip_their_pass_and_return_once_every_node_is_redone() {
    use vista::effects::shadows::sun_shadows::MAX_UPDATE_BUDGET;
    gpu_test(|ctx| {
        let mut rig = Rig::with_options(ctx, world(), CONE, vec![], SIZE, false, options(15.0, true));
        let v = over_cone();
        let lit = rig.shot(ctx, &v, CullStages::ALL);
        let outcome = |rig: &Rig| {
            rig.renderer.last_frame_log().and_then(|l| l.outcome(vista::effects::shadows::frame::SUN_SHADOWS)).cloned()
        };
        let objects = ctx.live_objects();
        rig.renderer.switches.shadows = false;
        let off = rig.again(ctx, &v, CullStages::ALL);
        assert_eq!(outcome(&rig), Some(Outcome::Skipped(Skip::ShadowsOff)));
        let timings = rig.renderer.poll_timings(ctx).cloned();
        let report = frame_report(ctx, &rig.renderer, timings.as_ref()).unwrap();
        assert_eq!(report.switched_off, [Effect::Shadows]);
        let resolve = report.pass("lighting_resolve").unwrap();
        assert!(resolve.reason.contains("without shadows"), "{resolve:?}");
        assert!(report.to_text().contains("switched off this frame (built, FrameSwitches): shadows"));
        // Off: only the shadowed pixels change, and only get lighter.
        let sum = |p: &[u8]| p[..3].iter().map(|&c| u32::from(c)).sum::<u32>();
        let (mut darker, mut lighter) = (0, 0);
        for (a, b) in lit.rgba.chunks_exact(4).zip(off.rgba.chunks_exact(4)) {
            darker += usize::from(sum(b) < sum(a));
            lighter += usize::from(sum(b) > sum(a) + 3);
        }
        assert!(lighter > 100 && darker == 0, "{lighter} lighter, {darker} darker pixels");
        // The only new object: the lighting variant without shadows.
        let added = ctx.live_objects();
        assert_eq!((added.pipelines - objects.pipelines, added.images - objects.images), (1, 0));
        // Back on: every resident node redone, MAX_UPDATE_BUDGET a frame,
        // the lighting without shadows until the last one is done.
        rig.renderer.switches.shadows = true;
        let resident = rig.renderer.terrain.tree.shadow.resident_count();
        let (mut redone, mut frames) = (0, 0);
        let back = loop {
            let img = rig.again(ctx, &v, CullStages::ALL);
            frames += 1;
            let Some(Outcome::Recorded { cpu_work: Some(n) }) = outcome(&rig) else {
                panic!("frame {frames}: not run")
            };
            assert!(n <= u64::from(MAX_UPDATE_BUDGET), "{n} jobs");
            redone += n;
            let shown = !rig.renderer.last_frame_log().unwrap().switched_off.contains(&Effect::Shadows);
            if shown {
                break img;
            }
            assert!(frames < 100, "shadows never came back");
        };
        assert_eq!(redone, u64::from(resident), "every resident node redone once");
        assert_eq!(frames as u32, resident.div_ceil(MAX_UPDATE_BUDGET));
        // The same sun and nodes: the same picture as before the switch.
        assert!(back.rgba == lit.rgba, "shadows back on differ from before");
    });
}
