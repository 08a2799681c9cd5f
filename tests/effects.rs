//! Scene effects gate what the renderer builds and runs: an effect that is
//! off has no pipeline, resource or pass (report and live-object counters);
//! an effect forced on where the world has no data for it changes no pixel;
//! a built pass with nothing to do is reported idle; the report's recorded
//! passes are exactly those that carried timestamps in the same frame.

mod common;

use common::gpu_test;
use common::terrain::{small_world as world, view, Rig, Surface, MAGENTA_RGBA};
use vista::gpu::{Context, LiveObjects};
use vista::passes::cull_patches::CullStages;
use vista::render::{frame_report, Effect, Effects, FrameReport, PassState, RendererOptions, View};
use vista::world::Hole;

const SIZE: [u32; 2] = [96, 64];

/// Looks over the hills toward the hole at (512, 600).
fn toward_hole() -> View {
    view([512.0, 250.0, 750.0], 0.0, -50.0, SIZE, 1.0)
}

fn hole() -> Vec<Hole> {
    vec![Hole::Circle { center_m: [512.0, 600.0], radius_m: 60.0 }]
}

/// Every effect this version implements off.
fn nothing() -> Effects {
    let mut fx = Effects::default();
    for e in Effect::ALL {
        fx.set(e, false);
    }
    fx
}

fn options(effects: Effects, force: bool) -> RendererOptions {
    RendererOptions { effects, force_content_gated: force, ..RendererOptions::default() }
}

fn diff(a: LiveObjects, b: LiveObjects) -> [i64; 4] {
    [b.pipelines - a.pipelines, b.images - a.images, b.buffers - a.buffers, b.samplers - a.samplers]
}

/// Renders `v` until settled; the capture's RGBA and the frame's report.
fn shot(ctx: &Context, rig: &mut Rig, v: &View) -> (Vec<u8>, FrameReport) {
    let c = rig.shot(ctx, v, CullStages::ALL);
    let timings = rig.renderer.poll_timings(ctx).cloned();
    (c.rgba, frame_report(ctx, &rig.renderer, timings.as_ref()).unwrap())
}

/// (effect, objects it adds, pipeline-label marker, its passes, its resources)
type Case = (Effect, [i64; 4], &'static str, &'static [&'static str], &'static [&'static str]);

#[test]
fn an_effect_that_is_off_builds_and_records_none_of_its_work() {
    // What each effect adds to a scene with none, derived from the design:
    // [pipelines, images, buffers, samplers], pipeline-label marker, passes
    // only it has, resources only it has.
    // An empty marker: no pipeline of its own; no resources: no memory.
    let cases: [Case; 7] = [
        // The hole list has a copy per frame parity (frame::per_frame).
        (Effect::Holes, [1, 1, 2, 0], "HOLE_CULL", &["terrain_holes"], &["atlas_patch_holes", "hole_patch_list"]),
        (Effect::ConeCull, [0, 1, 0, 0], "CONE_CULL", &[], &["atlas_patch_cones"]),
        // The lit variant of lighting_resolve replaces the unlit one.
        (Effect::Lighting, [0, 0, 0, 0], "LIGHTING", &[], &[]),
        // Sector data is core (the tile shading reads it): queries keep the
        // splat map for material queries.
        (Effect::Queries, [0, 1, 0, 0], "", &[], &["atlas_splat"]),
        // gbuffer_tiles variants splat and far_atlas+splat; the splat
        // atlas, three detail texture arrays and the material table.
        (Effect::Splat, [2, 4, 1, 0], "far_atlas+splat", &[], &["atlas_splat", "material_table"]),
        // Six variants with near and far cliffs; the same resources.
        (Effect::Cliffs, [6, 4, 1, 0], "near_cliff", &[], &["atlas_splat", "material_table"]),
        // Two pipelines and their samplers; phase 2's list and the
        // visibility bits (a copy per frame parity); the pyramid is made at
        // the first frame (its size is the target's), so it is not among the
        // objects at creation.
        (
            Effect::Occlusion,
            [2, 0, 3, 2],
            "OCCLUSION",
            &["hiz_build", "cull_occluded"],
            &["hiz_pyramid", "patch_visibility", "late_patch_list"],
        ),
    ];
    gpu_test(|ctx| {
        let v = toward_hole();
        let before = ctx.live_objects();
        let mut base = Rig::with_options(ctx, world(), Surface::Hills, hole(), SIZE, false, options(nothing(), false));
        let base_objects = diff(before, ctx.live_objects());
        let (_, base_report) = shot(ctx, &mut base, &v);
        drop(base);
        for (effect, added, marker, passes, resources) in cases {
            let before = ctx.live_objects();
            let fx = nothing().with(effect, true);
            let mut rig = Rig::with_options(ctx, world(), Surface::Hills, hole(), SIZE, false, options(fx, false));
            let objects = diff(before, ctx.live_objects());
            let delta: Vec<i64> = objects.iter().zip(base_objects).map(|(a, b)| a - b).collect();
            assert_eq!(delta, added, "{effect:?}: objects added over a scene with no effect");
            let (_, with) = shot(ctx, &mut rig, &v);
            for (report, on) in [(&with, true), (&base_report, false)] {
                let d = report.effects.iter().find(|d| d.effect == effect).unwrap();
                assert_eq!(d.on, on, "{effect:?}: {}", d.reason);
                if !marker.is_empty() {
                    assert_eq!(
                        report.pipelines.iter().any(|p| p.contains(marker)),
                        on,
                        "{effect:?}: {:?}",
                        report.pipelines
                    );
                }
                for pass in passes {
                    let p = report.pass(pass).unwrap();
                    assert_eq!(p.state == PassState::NotBuilt, !on, "{effect:?}: {pass} {:?}", p.state);
                    assert_eq!(p.recorded, on, "{effect:?}: {pass} recorded");
                }
                for name in resources {
                    let held = report.memory.iter().any(|m| m.name.starts_with(name) && m.bytes > 0);
                    assert_eq!(held, on, "{effect:?}: resource {name}");
                }
                if !resources.is_empty() {
                    assert_eq!(report.memory_of(effect) > 0, on, "{effect:?}: memory of its own");
                }
            }
            drop(rig);
        }
    });
}

#[test]
fn holes_forced_on_where_the_world_has_none_change_no_pixel() {
    gpu_test(|ctx| {
        let v = toward_hole();
        // The same world without hole regions: holes requested but off.
        let mut off =
            Rig::with_options(ctx, world(), Surface::Hills, vec![], SIZE, false, options(Effects::default(), false));
        let (image_off, report_off) = shot(ctx, &mut off, &v);
        let d = report_off.effects.iter().find(|d| d.effect == Effect::Holes).unwrap();
        assert!(!d.on && d.requested && d.reason.contains("no hole regions"), "{d:?}");
        drop(off);
        let mut forced =
            Rig::with_options(ctx, world(), Surface::Hills, vec![], SIZE, false, options(Effects::default(), true));
        let (image_on, report_on) = shot(ctx, &mut forced, &v);
        let holes = report_on.pass("terrain_holes").unwrap();
        assert_eq!(holes.state, PassState::Idle, "built, nothing to draw: {holes:?}");
        assert!(holes.recorded && holes.work.instances == Some(0), "{holes:?}");
        assert!(image_on == image_off, "the idle hole path changed pixels");
        // And with the hole in the world, the same pass draws.
        drop(forced);
        let mut real =
            Rig::with_options(ctx, world(), Surface::Hills, hole(), SIZE, false, options(Effects::default(), false));
        let (image_hole, report) = shot(ctx, &mut real, &v);
        let holes = report.pass("terrain_holes").unwrap();
        assert_eq!(holes.state, PassState::Ran, "{holes:?}");
        assert!(holes.work.instances.unwrap() > 0);
        // The hole shows the background (magenta) where the terrain was.
        let opened = image_hole
            .chunks_exact(4)
            .zip(image_off.chunks_exact(4))
            .filter(|(on, off)| *on == MAGENTA_RGBA && *off != MAGENTA_RGBA)
            .count();
        assert!(opened > 20, "the hole is in view: {opened} pixels opened");
    });
}

#[test]
fn cone_culling_on_or_off_gives_the_same_image() {
    gpu_test(|ctx| {
        // From the foot of a cone hill (300 m radius, 250 m high): its far
        // flank faces away, at the size of the patches the selection draws.
        let hill = Surface::Bump { z0: 150.0, c: [512.0, 512.0], r: 300.0, h: 250.0 };
        let v = view([112.0, 512.0, hill.height(112.0, 512.0) + 10.0], 90.0, 5.0, [160, 120], 0.5);
        let fx = Effects::default();
        let mut with = Rig::with_options(ctx, world(), hill, vec![], [160, 120], false, options(fx.clone(), false));
        let (a, report) = shot(ctx, &mut with, &v);
        let counters = with.renderer.read_counters(ctx).unwrap().cull;
        assert!(counters.after_cone < counters.after_frustum, "the cone stage had work: {counters:?}");
        assert!(report.pipelines.iter().any(|p| p.contains("CONE_CULL")));
        drop(with);
        let mut without = Rig::with_options(
            ctx,
            world(),
            hill,
            vec![],
            [160, 120],
            false,
            options(fx.with(Effect::ConeCull, false), false),
        );
        let (b, _) = shot(ctx, &mut without, &v);
        assert!(a == b, "cone culling changed pixels");
    });
}

#[test]
fn the_report_lists_exactly_the_passes_that_carried_timestamps() {
    gpu_test(|ctx| {
        let fx = Effects::default().with(Effect::Queries, true);
        let mut rig = Rig::with_options(ctx, world(), Surface::Hills, hole(), SIZE, false, options(fx, false));
        let v = toward_hole();
        rig.shot(ctx, &v, CullStages::ALL);
        for _ in 0..2 {
            rig.again(ctx, &v, CullStages::ALL);
            let timings = rig.renderer.poll_timings(ctx).cloned().expect("timings are back after the wait");
            let report = frame_report(ctx, &rig.renderer, Some(&timings)).unwrap();
            assert_eq!(report.frame, timings.frame, "the report and the timings are of the same frame");
            let stamped: Vec<String> =
                timings.passes.iter().map(|p| vista::frame::pass_label(p.name, p.late)).collect();
            assert_eq!(report.recorded_passes(), stamped);
            for p in &report.passes {
                assert_eq!(p.gpu_ms.is_some(), p.recorded, "{}: gpu time iff recorded", p.name);
            }
            // Settled: nothing to upload, so quadtree_update is idle, not recorded.
            let update = report.pass("quadtree_update").unwrap();
            assert!(update.state == PassState::Idle && !update.recorded, "{update:?}");
            assert!(report.pass("sector_data").unwrap().state == PassState::Ran);
        }
    });
}

#[test]
fn effects_that_cannot_run_are_reported_off_and_cost_nothing() {
    gpu_test(|ctx| {
        let v = toward_hole();
        let before = ctx.live_objects();
        let rig =
            Rig::with_options(ctx, world(), Surface::Hills, vec![], SIZE, false, options(Effects::default(), false));
        let plain = diff(before, ctx.live_objects());
        drop(rig);
        // Each lacks what it needs: splat's materials (off by default),
        // cliffs' flavours, the scene's assets or decals.
        let cannot = [
            (Effect::VirtualTexture, "effect splat is off"),
            (Effect::Grass, "effect splat is off"),
            (Effect::CliffMeshes, "effect cliffs is off"),
            (Effect::Assets, "no assets"),
            (Effect::Decals, "no decals"),
        ];
        let mut fx = Effects::default();
        for (e, _) in cannot {
            fx.set(e, true);
        }
        let before = ctx.live_objects();
        let mut rig = Rig::with_options(ctx, world(), Surface::Hills, vec![], SIZE, false, options(fx, false));
        assert_eq!(diff(before, ctx.live_objects()), plain, "asking for effects that cannot run builds nothing");
        let (_, report) = shot(ctx, &mut rig, &v);
        for (e, why) in cannot {
            let d = report.effects.iter().find(|d| d.effect == e).unwrap();
            assert!(d.requested && !d.on && d.reason.contains(why), "{d:?}");
        }
    });
}

/// The overlay's toggles (`FrameSwitches`): a renderer built with holes,
/// splat, cliffs and lighting, with one of them switched off for a frame,
/// draws exactly what a renderer built without it draws, says so in its
/// report, and draws its own picture again once the switch is back on.
#[test]
fn an_effect_switched_off_for_a_frame_draws_what_a_renderer_without_it_draws() {
    gpu_test(|ctx| {
        let v = toward_hole();
        let switchable = [Effect::Holes, Effect::Splat, Effect::Cliffs, Effect::Lighting];
        // With occlusion, so both phases' hole draws are switched.
        let all = switchable.iter().fold(nothing().with(Effect::Occlusion, true), |fx, &e| fx.with(e, true));
        let mut rig = Rig::with_options(ctx, world(), Surface::Hills, hole(), SIZE, false, options(all.clone(), false));
        let (own, _) = shot(ctx, &mut rig, &v);
        for effect in switchable {
            let fx = options(all.clone().with(effect, false), false);
            let mut without = Rig::with_options(ctx, world(), Surface::Hills, hole(), SIZE, false, fx);
            let (expected, _) = shot(ctx, &mut without, &v);
            drop(without);
            assert!(expected != own, "{effect:?} changes this view, or the test shows nothing");
            *rig.renderer.switches.get_mut(effect).unwrap() = false;
            let off = rig.again(ctx, &v, CullStages::ALL).rgba;
            let report = frame_report(ctx, &rig.renderer, None).unwrap();
            assert_eq!(report.switched_off, [effect]);
            let differ = off.chunks_exact(4).zip(expected.chunks_exact(4)).filter(|(a, b)| a != b).count();
            assert_eq!(differ, 0, "{effect:?} switched off: pixels unlike the renderer built without it");
            if effect == Effect::Holes {
                for p in [report.pass("terrain_holes").unwrap(), report.late_pass("terrain_holes").unwrap()] {
                    assert!(p.state == PassState::Idle && !p.recorded && p.reason.contains("switched off"), "{p:?}");
                }
            }
            *rig.renderer.switches.get_mut(effect).unwrap() = true;
            let back = rig.again(ctx, &v, CullStages::ALL).rgba;
            assert!(back == own, "{effect:?} switched back on: not the renderer's own picture");
        }
    });
}
