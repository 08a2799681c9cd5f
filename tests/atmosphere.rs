//! The `atmosphere` effect: on a flat world, every terrain pixel of the HDR
//! image is the unhazed pixel times the model's transmittance over its
//! distance plus the haze's in-scattering times the rest (the model of
//! effects/atmosphere, evaluated in f64 by reference::atmosphere), and
//! every background pixel is the model's sky; off, nothing is built and the
//! image is the one without it.

mod common;

use common::gpu_test;
use common::terrain::{small_world as world, view, Rig, Surface};
use glam::DVec3;
use vista::effects::atmosphere::AtmosphereParams;
use vista::passes::cull_patches::CullStages;
use vista::reference::atmosphere::{inscatter, sky, transmittance};
use vista::render::{linear_depth, Effect, Effects, RendererOptions, View};

const SIZE: [u32; 2] = [96, 64];
const GROUND: f64 = 200.0;

fn options(atmosphere: bool) -> RendererOptions {
    let mut fx = Effects::default().with(Effect::Atmosphere, atmosphere);
    fx.lighting.clay_albedo = Some(0.4);
    // Thick haze, so a 1 km view spans transmittances from 0.9 to 0.3.
    fx.atmosphere = AtmosphereParams { visibility_km: 2.0, scale_height_m: 300.0, ..AtmosphereParams::default() };
    RendererOptions { effects: fx, ..RendererOptions::default() }
}

/// Over the plane, looking down to the horizon: distances from ~150 m to
/// the world's edge, and sky above.
fn over_plane() -> View {
    view([512.0, 10.0, GROUND + 60.0], 0.0, -12.0, SIZE, 1.0)
}

/// (HDR image, depth) after settling.
fn shot(ctx: &vista::gpu::Context, atmosphere: bool) -> (Vec<[f32; 4]>, Vec<f32>, Vec<String>) {
    let mut rig = Rig::with_options(ctx, world(), Surface::Plane(GROUND), vec![], SIZE, false, options(atmosphere));
    let c = rig.shot(ctx, &over_plane(), CullStages::ALL);
    let g = rig.renderer.gbuffer.as_ref().unwrap().capture(ctx).unwrap();
    (g.hdr, c.depth, rig.renderer.pipelines())
}

#[test]
fn terrain_and_sky_follow_the_height_fog_model() {
    gpu_test(|ctx| {
        let (clear, depth_clear, plain) = shot(ctx, false);
        let (hazy, depth, pipelines) = shot(ctx, true);
        assert_eq!(depth, depth_clear, "the same terrain drawn");
        assert!(!plain.iter().any(|p| p.contains("ATMOSPHERE")), "off: no ATMOSPHERE variant {plain:?}");
        assert_eq!(plain.len(), pipelines.len(), "on: a variant of the same pipeline, nothing more");
        let v = over_plane();
        let o = options(true);
        let (fog, light) = (o.effects.atmosphere, o.effects.lighting);
        let eye = DVec3::from(v.camera.position_m);
        let forward = v.camera.basis()[0];
        let z_low = f64::from(world().height_range_m[0]);
        let (mut terrain, mut background, mut worst) = (0, 0, 0f64);
        let (mut t_min, mut t_max) = (1f64, 0f64);
        for (i, (&d, (h, c))) in depth.iter().zip(hazy.iter().zip(&clear)).enumerate() {
            let px = [(i as u32 % SIZE[0]) as f64 + 0.5, (i as u32 / SIZE[0]) as f64 + 0.5];
            let ray = v.ray(px);
            let want = if d == 0.0 {
                background += 1;
                sky(&fog, &light, z_low, eye, ray)
            } else {
                terrain += 1;
                let p = eye + ray * (f64::from(linear_depth(d, v.near_m)) / ray.dot(forward));
                let t = transmittance(&fog, z_low, eye, p);
                (t_min, t_max) = (t_min.min(t), t_max.max(t));
                let s = inscatter(&fog, &light, ray);
                // The pixel's measured transmittance, where the haze and
                // the surface differ enough to tell.
                let k =
                    (0..3).max_by(|&a, &b| (f64::from(c[a]) - s[a]).abs().total_cmp(&(f64::from(c[b]) - s[b]).abs()));
                let k = k.unwrap();
                if (f64::from(c[k]) - s[k]).abs() > 0.05 {
                    let measured = (f64::from(h[k]) - s[k]) / (f64::from(c[k]) - s[k]);
                    assert!((measured - t).abs() < 0.01, "pixel {i}: transmittance {measured}, the model's {t}");
                }
                [0, 1, 2].map(|k| f64::from(c[k]) * t + s[k] * (1.0 - t))
            };
            for k in 0..3 {
                worst = worst.max((f64::from(h[k]) - want[k]).abs() / want[k].max(0.05));
            }
        }
        assert!(terrain > 1000 && background > 500, "{terrain} terrain, {background} sky pixels");
        assert!(t_min < 0.5 && t_max > 0.85, "transmittances {t_min}..{t_max}: a range to test");
        // The HDR target is f16 (relative step 2^-11 = 0.05 %) and the
        // unhazed input is f16 too; the GPU evaluates exp and pow in f32.
        // 0.5 % relative is ten times those.
        assert!(worst < 5e-3, "a channel {worst} (relative) from the model");
    });
}

/// The overlay's toggle: a renderer built with the atmosphere, switched off
/// for a frame, draws exactly what a renderer built without it draws (the
/// variant without it, made on first use) and says so in its report.
#[test]
fn switching_the_atmosphere_off_for_a_frame_draws_the_clear_picture() {
    gpu_test(|ctx| {
        let (clear, _, _) = shot(ctx, false);
        let mut rig = Rig::with_options(ctx, world(), Surface::Plane(GROUND), vec![], SIZE, false, options(true));
        rig.shot(ctx, &over_plane(), CullStages::ALL);
        let built = rig.renderer.pipelines().len();
        rig.renderer.switches.atmosphere = false;
        rig.again(ctx, &over_plane(), CullStages::ALL);
        let hdr = rig.renderer.gbuffer.as_ref().unwrap().capture(ctx).unwrap().hdr;
        assert!(hdr == clear, "switched off, the picture is not the one without the atmosphere");
        assert_eq!(rig.renderer.pipelines().len(), built + 1, "one more variant of lighting_resolve");
        let report = vista::render::frame_report(ctx, &rig.renderer, None).unwrap();
        assert_eq!(report.switched_off, [Effect::Atmosphere]);
        assert!(report.pass("lighting_resolve").unwrap().reason.contains("without atmosphere"));
    });
}
