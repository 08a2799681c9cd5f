//! The outputs an engine chooses and the engine's depth: output `gbuffer`
//! writes into the engine's images exactly the surface vista's own
//! lighting shades (base colour, roughness and material bit for bit, the
//! normal within one 8-bit octahedral step), and an engine lighting it the
//! way `examples/embed` does gets vista's own picture; output `hdr` is the
//! lit path's linear radiance bit for bit; an sRGB or BGRA display target
//! shows the same picture; a loaded depth keeps the engine's occluder,
//! which hides terrain, culls patches, and leaves culled == unculled.

mod common;

use common::gpu_test;
use common::terrain::{small_world as world, view, Rig, Surface, MAGENTA};
use glam::{DVec3, Vec3};
use vista::gpu::vk;
use vista::passes::cull_patches::CullStages;
use vista::passes::terrain_geometry::DepthOptions;
use vista::reference::{flip_map, flip_stats};
use vista::render::offscreen::{Capture, EngineWall};
use vista::render::{Effect, Effects, Lighting, RendererOptions, View};
use vista::targets::gbuffer::GBufferCapture;
use vista::targets::gbuffer_layout::texel_bytes;
use vista::targets::{GbufferLayout, Output};

const SIZE: [u32; 2] = [96, 64];

/// Splat and cliff materials over the hills (so base colour, normal and
/// material vary), lit by the sun and the sky; thresholds scaled to this
/// small world as in tests/gbuffer.rs.
fn effects() -> Effects {
    let mut fx = Effects::default().with(Effect::Splat, true).with(Effect::Cliffs, true);
    fx.shade.cliff_slope_deg = 12.0;
    fx.shade.cliff_band_deg = 6.0;
    fx.shade.far_start_m = 300.0;
    fx.shade.far_end_m = 450.0;
    fx
}

fn over_the_hills() -> View {
    view([512.0, 120.0, 520.0], 10.0, -25.0, SIZE, 1.0)
}

fn rig(ctx: &vista::gpu::Context, fx: Effects, output: Output, depth: DepthOptions) -> Rig {
    let options = RendererOptions { effects: fx, output, depth, ..RendererOptions::default() };
    Rig::with_options(ctx, world(), Surface::Hills, vec![], SIZE, false, options)
}

fn own_gbuffer(ctx: &vista::gpu::Context, rig: &Rig) -> GBufferCapture {
    rig.renderer.gbuffer.as_ref().unwrap().capture(ctx).unwrap()
}

/// The texels of pixel `i` of each engine image.
fn texels<'a>(layout: &GbufferLayout, shot: &'a Capture, i: usize) -> Vec<&'a [u8]> {
    layout
        .attachments
        .iter()
        .zip(&shot.gbuffer)
        .map(|(a, bytes)| {
            let n = texel_bytes(a.format);
            &bytes[i * n..(i + 1) * n]
        })
        .collect()
}

/// Unit vector -> the octahedral map's [0, 1]^2 (the map of octahedral.glsl's
/// `oct_encode`, derived from its definition).
fn oct_unit(n: DVec3) -> [f64; 2] {
    let p = n / (n.x.abs() + n.y.abs() + n.z.abs());
    let sign = |v: f64| if v >= 0.0 { 1.0 } else { -1.0 };
    let e = if n.z < 0.0 { [(1.0 - p.y.abs()) * sign(p.x), (1.0 - p.x.abs()) * sign(p.y)] } else { [p.x, p.y] };
    e.map(|v| v * 0.5 + 0.5)
}

#[test]
fn gbuffer_output_holds_the_surface_the_lit_path_shades_with() {
    gpu_test(|ctx| {
        let v = over_the_hills();
        let mut lit = rig(ctx, effects(), Output::default(), DepthOptions::default());
        lit.shot(ctx, &v, CullStages::ALL);
        let own = own_gbuffer(ctx, &lit);
        for layout in [GbufferLayout::octahedral(), GbufferLayout::default()] {
            let mut engine = rig(ctx, effects(), Output::Gbuffer(layout.clone()), DepthOptions::default());
            let shot = engine.shot(ctx, &v, CullStages::ALL);
            assert!(engine.renderer.resolve.is_none(), "no lighting pass with output gbuffer");
            let classes = own_gbuffer(ctx, &engine).classification;
            assert_eq!(classes, own.classification, "the same geometry");
            let (mut compared, mut worst_e, mut worst_deg) = (0, 0.0f64, 0.0f64);
            let mut materials = std::collections::BTreeSet::new();
            for i in (0..classes.len()).filter(|&i| classes[i] != 0) {
                let t = texels(&layout, &shot, i);
                let s = layout.decode(&t);
                // Both presets keep base colour in RGBA8 sRGB: the same bytes.
                assert_eq!(&t[0][..3], &own.albedo[i][..3], "pixel {i}: base colour");
                let roughness = (s.roughness * 255.0).round() as u8;
                assert_eq!(roughness, own.normal[i][2], "pixel {i}: roughness");
                let lit_code = [own.normal[i][0], own.normal[i][1]].map(|c| f64::from(c) / 255.0);
                let lit_normal = vista::targets::gbuffer_layout::oct_decode(lit_code.map(|e| e * 2.0 - 1.0));
                let e = oct_unit(s.normal.as_dvec3().normalize());
                worst_e = worst_e.max((e[0] - lit_code[0]).abs().max((e[1] - lit_code[1]).abs()));
                worst_deg = worst_deg.max(s.normal.as_dvec3().normalize().angle_between(lit_normal).to_degrees());
                if layout.attachments.len() == 3 {
                    assert_eq!(s.material, u32::from(own.material[i][0]), "pixel {i}: material id");
                    materials.insert(s.material);
                }
                compared += 1;
            }
            // The lit path stores the octahedral map in 8 bits, the engine's
            // layouts in 16 bits (octahedral) or as a 10-bit vector: they
            // agree to half an 8-bit step, plus the 10-bit vector's step.
            let bound = if layout.attachments.len() == 3 { 0.5 / 255.0 + 1e-4 } else { 0.5 / 255.0 + 2.0 / 1023.0 };
            assert!(worst_e <= bound, "{layout:?}: normals differ by {worst_e} in the octahedral map (bound {bound})");
            assert!(compared > 4000, "only {compared} terrain pixels");
            if layout.attachments.len() == 3 {
                assert!(materials.len() >= 2, "one material in view: {materials:?}");
            }
            println!("{:?}: {compared} pixels, normals within {worst_e:.5} ({worst_deg:.3} deg)", layout.normal);
        }
    });
}

/// The example engine's lighting (examples/embed's `engine_light.frag`),
/// on the CPU: sun and sky ambient on the base colour, vista's tonemap.
fn engine_light(l: &Lighting, base: Vec3, n: Vec3) -> [u8; 3] {
    let (n, base) = (n.as_dvec3().normalize(), base.as_dvec3());
    let sun = DVec3::from(l.sun_color.map(f64::from)) * n.dot(l.sun_dir()).max(0.0);
    let sky = DVec3::from(l.sky_color.map(f64::from)) * (0.5 + 0.5 * n.z);
    let radiance = base * (sun + sky);
    vista::reference::tonemap::display_rgb8(l.tonemap, l.exposure_ev(), radiance.to_array())
}

#[test]
fn an_engine_lit_gbuffer_matches_vistas_lit_image() {
    gpu_test(|ctx| {
        let v = over_the_hills();
        let mut lit = rig(ctx, effects(), Output::default(), DepthOptions::default());
        let picture = lit.shot(ctx, &v, CullStages::ALL);
        let layout = GbufferLayout::octahedral();
        let mut engine = rig(ctx, effects(), Output::Gbuffer(layout.clone()), DepthOptions::default());
        let shot = engine.shot(ctx, &v, CullStages::ALL);
        let classes = own_gbuffer(ctx, &engine).classification;
        let lighting = Lighting::default();
        let mut engine_lit = picture.rgba.clone();
        for i in (0..classes.len()).filter(|&i| classes[i] != 0) {
            let s = layout.decode(&texels(&layout, &shot, i));
            engine_lit[4 * i..4 * i + 3].copy_from_slice(&engine_light(&lighting, s.base, s.normal));
        }
        let mut codes = [0usize; 4];
        for (a, b) in picture.rgba.iter().zip(&engine_lit) {
            codes[usize::from(a.abs_diff(*b).min(3))] += 1;
        }
        println!("channels differing by 0, 1, 2, 3+ codes: {codes:?}");
        let errors = flip_map(&picture.rgba, &engine_lit, SIZE);
        let terrain: Vec<f32> = (0..classes.len()).filter(|&i| classes[i] != 0).map(|i| errors[i]).collect();
        let stats = flip_stats(terrain);
        println!("engine-lit vs lit: FLIP {stats:?}");
        // The same formula on the same surface: what differs is the normal's
        // encoding (16-bit octahedral against vista's 8-bit one, up to a
        // third of a degree) and the CPU's f64 against the GPU's f32: a
        // channel moves by a code or two. FLIP scores such 1-code noise
        // about 0.02 on average, 0.03-0.04 at its worst (measured here:
        // mean 0.018, p99 0.031); a visible difference scores above 0.1.
        assert_eq!(codes[3], 0, "a channel differs by 3 codes or more: {codes:?}");
        assert!(codes[2] * 100 <= codes[1], "more than 1 % of the differences are 2 codes: {codes:?}");
        assert!(stats.mean <= 0.03 && stats.p99 <= 0.06, "{stats:?}");
        assert!(stats.pixels > 4000);
    });
}

#[test]
fn hdr_output_is_the_lit_paths_radiance() {
    gpu_test(|ctx| {
        let v = over_the_hills();
        let fx = effects().with(Effect::Atmosphere, true);
        let mut lit = rig(ctx, fx.clone(), Output::default(), DepthOptions::default());
        lit.shot(ctx, &v, CullStages::ALL);
        let radiance = own_gbuffer(ctx, &lit).hdr;
        let classes = own_gbuffer(ctx, &lit).classification;
        let sky = Output::Hdr { format: vk::Format::R16G16B16A16_SFLOAT, sky: true };
        let mut hdr = rig(ctx, fx.clone(), sky, DepthOptions::default());
        let got = hdr.shot(ctx, &v, CullStages::ALL).hdr;
        // The same shader arithmetic into the same f16 format.
        assert!(got == radiance, "output hdr differs from the lit path's radiance");
        let background = classes.iter().filter(|&&c| c == 0).count();
        assert!(background > 200, "the sky is in view ({background} pixels)");
        // Without the sky the background keeps what the target held.
        let no_sky = Output::Hdr { format: vk::Format::R16G16B16A16_SFLOAT, sky: false };
        let mut plain = rig(ctx, fx.clone(), no_sky, DepthOptions::default());
        let got = plain.shot(ctx, &v, CullStages::ALL).hdr;
        for (i, c) in classes.iter().enumerate() {
            let want = if *c == 0 { MAGENTA } else { radiance[i] };
            assert_eq!(got[i], want, "pixel {i} (class {c})");
        }
        // The packed float format: within one step of its mantissa (6 bits
        // for red and green, 5 for blue).
        let packed = Output::Hdr { format: vk::Format::B10G11R11_UFLOAT_PACK32, sky: true };
        let mut small = rig(ctx, fx, packed, DepthOptions::default());
        let got = small.shot(ctx, &v, CullStages::ALL).hdr;
        for (i, (g, r)) in got.iter().zip(&radiance).enumerate() {
            for c in 0..3 {
                // A device may round to nearest or toward zero: a whole step.
                let step = if c == 2 { 32.0 } else { 64.0 };
                let tolerance = r[c].abs() / step + 2f32.powi(-15);
                assert!((g[c] - r[c]).abs() <= tolerance, "pixel {i} channel {c}: {} vs {}", g[c], r[c]);
            }
        }
    });
}

#[test]
fn srgb_and_bgra_display_targets_show_the_same_picture() {
    gpu_test(|ctx| {
        let v = over_the_hills();
        let mut unorm = rig(ctx, effects(), Output::default(), DepthOptions::default());
        let want = unorm.shot(ctx, &v, CullStages::ALL).rgba;
        for format in [vk::Format::R8G8B8A8_SRGB, vk::Format::B8G8R8A8_UNORM, vk::Format::B8G8R8A8_SRGB] {
            let mut r = rig(ctx, effects(), Output::Lit { format }, DepthOptions::default());
            let got = r.shot(ctx, &v, CullStages::ALL).rgba;
            // An sRGB target re-encodes what the shader decoded: a code may
            // round to its neighbour.
            let worst = got.iter().zip(&want).map(|(a, b)| a.abs_diff(*b)).max().unwrap();
            assert!(worst <= 1, "{format:?}: differs by {worst}");
            // The picture is not trivially equal (the test reads it back).
            assert!(got.chunks_exact(4).any(|p| p[..3] != [255, 0, 255]));
        }
    });
}

/// An engine's wall 60 m ahead over the middle of the picture.
fn wall() -> EngineWall {
    EngineWall { rect: [16, 8, 80, 56], distance_m: 60.0, colour: [0.2, 0.9, 0.3, 1.0] }
}

fn in_wall(i: usize) -> bool {
    near_wall(i, 0)
}

/// Within `margin` pixels of the wall.
fn near_wall(i: usize, margin: u32) -> bool {
    let [x0, y0, x1, y1] = wall().rect;
    let (x, y) = ((i % SIZE[0] as usize) as u32, (i / SIZE[0] as usize) as u32);
    (x0.saturating_sub(margin)..x1 + margin).contains(&x) && (y0.saturating_sub(margin)..y1 + margin).contains(&y)
}

/// Terrain pixels next to the engine's own shade by a neighbourhood that
/// changed: the silhouette rule (silhouette.glsl) reads the 4-neighbours'
/// depth and the sources one step beyond them.
const SILHOUETTE_REACH: u32 = 2;

#[test]
fn a_loaded_depth_keeps_the_engines_occluder_which_hides_and_culls_terrain() {
    gpu_test(|ctx| {
        let v = over_the_hills();
        let load = DepthOptions { load: true, ..DepthOptions::default() };
        let mut r = rig(ctx, effects(), Output::default(), load);
        r.shot(ctx, &v, CullStages::ALL);
        // Each copy of the visibility bits (frame::per_frame) reaches its
        // steady state in two of its frames.
        let steady = |r: &mut Rig| (0..4).map(|_| r.again(ctx, &v, CullStages::ALL)).last().unwrap();
        let open = steady(&mut r);
        let open_k = r.renderer.read_counters(ctx).unwrap();
        r.off.wall = Some(wall());
        let walled = steady(&mut r);
        let walled_k = r.renderer.read_counters(ctx).unwrap();
        let wall_depth = wall().depth(v.near_m);
        let [x0, y0, ..] = wall().rect;
        let corner = 4 * (y0 * SIZE[0] + x0) as usize;
        // The engine's clear colour as the target stored it (0.3 * 255
        // may round either way).
        let wall_rgba = walled.rgba[corner..corner + 4].to_vec();
        let want = wall().colour.map(|c| c * 255.0);
        assert!(wall_rgba.iter().zip(want).all(|(&g, w)| (f32::from(g) - w).abs() <= 0.5), "{wall_rgba:?}");
        let mut hidden = 0;
        for i in 0..walled.depth.len() {
            if in_wall(i) {
                assert_eq!(walled.depth[i], wall_depth, "pixel {i}: the wall's depth");
                assert_eq!(walled.rgba[4 * i..4 * i + 4], wall_rgba, "pixel {i}: the wall's colour");
                hidden += usize::from(open.depth[i] > 0.0 && open.depth[i] < wall_depth);
            } else {
                assert_eq!(walled.depth[i], open.depth[i], "pixel {i}: depth outside the wall");
                if !near_wall(i, SILHOUETTE_REACH) {
                    assert_eq!(walled.rgba[4 * i..4 * i + 4], open.rgba[4 * i..4 * i + 4], "pixel {i}: colour");
                }
            }
        }
        assert!(hidden > 500, "only {hidden} terrain pixels lie behind the wall");
        let culled = |k: &vista::render::telemetry::FrameCounters| k.cull.occlusion_tested - k.cull.drawn_phase2;
        println!("patches culled by the pyramid: {} open, {} behind the wall", culled(&open_k), culled(&walled_k));
        assert!(culled(&walled_k) >= culled(&open_k) + 20, "the wall culled no patch");
        // Culling stays conservative with the engine's depth in the pyramid.
        let unculled = r.again(ctx, &v, CullStages::NONE);
        assert!(unculled.rgba == walled.rgba && unculled.depth == walled.depth, "culled != unculled");
    });
}

#[test]
fn gbuffer_output_over_a_loaded_depth_leaves_the_engines_pixels() {
    gpu_test(|ctx| {
        let v = over_the_hills();
        let layout = GbufferLayout::default();
        let load = DepthOptions { load: true, ..DepthOptions::default() };
        let mut r = rig(ctx, effects(), Output::Gbuffer(layout.clone()), load);
        r.shot(ctx, &v, CullStages::ALL);
        let steady = |r: &mut Rig| (0..4).map(|_| r.again(ctx, &v, CullStages::ALL)).last().unwrap();
        let open = steady(&mut r);
        r.off.wall = Some(wall());
        let walled = steady(&mut r);
        let [x0, y0, ..] = wall().rect;
        let corner = (y0 * SIZE[0] + x0) as usize;
        let mut changed = 0;
        for (k, a) in layout.attachments.iter().enumerate() {
            let n = texel_bytes(a.format);
            let texel = |shot: &Capture, i: usize| shot.gbuffer[k][i * n..(i + 1) * n].to_vec();
            // The engine's pass stored the wall's colour in every image.
            let engine = texel(&walled, corner);
            for i in 0..walled.depth.len() {
                if in_wall(i) {
                    assert_eq!(texel(&walled, i), engine, "attachment {k} pixel {i}: the engine's texel");
                    changed += usize::from(texel(&open, i) != engine);
                } else if !near_wall(i, SILHOUETTE_REACH) {
                    assert_eq!(texel(&walled, i), texel(&open, i), "attachment {k} pixel {i} outside the wall");
                }
            }
        }
        assert!(changed > 500, "the wall covers only {changed} texels vista drew");
    });
}
