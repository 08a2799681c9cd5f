//! Two-phase occlusion culling never removes a visible patch (images with
//! and without it are bit-identical in every frame, teleports and turns
//! included), its depth pyramid equals a CPU reduction bit for bit at
//! non-power-of-two sizes, its box test on the GPU makes the CPU twin's
//! choices, and behind a mountain it rejects most of what it tests.

mod common;

use common::terrain::{small_world as world, view, Rig, Surface};
use common::{gpu_test, Rng};
use glam::{Mat4, Vec3};
use vista::gpu::{
    vk, Buffer, BufferDesc, ComputePipelineDesc, Context, Image, ImageDesc, MemoryLocation, Pipeline, Resource,
    Sampler, SamplerDesc,
};
use vista::passes::cull_patches::CullStages;
use vista::reference::occlusion::{box_visible_cpu, level0_cpu, pyramid_cpu, reduce_cpu, Pyramid};
use vista::render::{Effect, Effects, RendererOptions, View};
use vista::shaders::occlusion_probe as probe_sh;

fn effects(occlusion: bool) -> RendererOptions {
    let mut fx = Effects::default();
    fx.set(Effect::Occlusion, occlusion);
    RendererOptions { effects: fx, ..RendererOptions::default() }
}

/// Two rigs, occlusion on and off, settled on the same resident set, then
/// streaming paused so the set stays the same while the camera moves.
fn twin_rigs(ctx: &Context, surface: Surface, size: [u32; 2], settle: &View) -> (Rig, Rig) {
    let mut on = Rig::with_options(ctx, world(), surface, vec![], size, true, effects(true));
    let mut off = Rig::with_options(ctx, world(), surface, vec![], size, true, effects(false));
    assert!(on.renderer.occlusion.is_some() && off.renderer.occlusion.is_none());
    on.shot(ctx, settle, CullStages::ALL);
    off.shot(ctx, settle, CullStages::ALL);
    assert_eq!(on.renderer.terrain.resident_nodes(), off.renderer.terrain.resident_nodes(), "same resident set");
    on.renderer.terrain.pause_streaming(true);
    off.renderer.terrain.pause_streaming(true);
    (on, off)
}

#[test]
fn occlusion_changes_no_pixel_over_100_poses_with_teleports_and_turns() {
    gpu_test(|ctx| {
        let size = [128, 96];
        // Settle high above the middle with a wide view: a rich resident set.
        let overview = view([512.0, 512.0, 900.0], 0.0, -89.0, size, 2.0);
        let (mut on, mut off) = twin_rigs(ctx, Surface::Hills, size, &overview);
        let mut rng = Rng(0x0cc1_u64);
        let (mut pos, mut yaw): ([f64; 3], f64) = ([512.0, 100.0, 330.0], 0.0);
        let (mut culled, mut phase2) = (0u64, 0u64);
        for i in 0..100 {
            match i % 5 {
                // Teleport anywhere, low over the hills (ridges occlude).
                0 => {
                    pos = [64.0 + 896.0 * rng.unit(), 64.0 + 896.0 * rng.unit(), 0.0];
                    pos[2] = Surface::Hills.height(pos[0], pos[1]) + 5.0 + 150.0 * rng.unit();
                    yaw = 360.0 * rng.unit();
                }
                // Turn around on the spot.
                2 => yaw += 180.0,
                // Walk a little.
                _ => {
                    let (s, c) = yaw.to_radians().sin_cos();
                    pos[0] = (pos[0] + 20.0 * s).clamp(10.0, 1014.0);
                    pos[1] = (pos[1] + 20.0 * c).clamp(10.0, 1014.0);
                    pos[2] = pos[2].max(Surface::Hills.height(pos[0], pos[1]) + 3.0);
                }
            }
            let v = view(pos, yaw, -5.0 - 20.0 * rng.unit(), size, 0.5);
            let a = on.again(ctx, &v, CullStages::ALL);
            let b = off.again(ctx, &v, CullStages::ALL);
            assert!(a.rgba == b.rgba, "pose {i} ({pos:?}, yaw {yaw}): colour differs with occlusion");
            assert!(
                a.depth.iter().zip(&b.depth).all(|(x, y)| x.to_bits() == y.to_bits()),
                "pose {i}: depth differs with occlusion"
            );
            let k = on.renderer.read_counters(ctx).unwrap().cull;
            culled += u64::from(k.occlusion_tested - k.drawn_phase2);
            phase2 += u64::from(k.drawn_phase2);
        }
        // Not vacuous: the pyramid culled patches and phase 2 drew some
        // (measured 292 culled on lavapipe at 0.5 px; floors below). Per-patch
        // LOD draws coarse ancestors' patches where they meet the target:
        // fewer, larger patches, which a ridge hides whole less often (997
        // culled when every patch was its node's, 363 when patches were
        // chosen by their largest error, not the promise).
        assert!(culled > 200, "occlusion culled only {culled} patches over 100 poses");
        assert!(phase2 > 100, "phase 2 drew only {phase2} patches over 100 poses");
    });
}

#[test]
fn pyramid_levels_equal_a_cpu_reduction_at_non_power_of_two_sizes() {
    gpu_test(|ctx| {
        for size in [[257, 131], [200, 150]] {
            let v = view([512.0, 60.0, 420.0], 10.0, -12.0, size, 4.0);
            let mut rig = Rig::with_options(ctx, world(), Surface::Hills, vec![], size, false, effects(true));
            rig.shot(ctx, &v, CullStages::ALL);
            // Phase 1 draws what its copy of the visibility bits (two
            // frames old, frame::per_frame) holds: one more frame and both
            // copies know the nodes the settle's last frame brought, so phase
            // 1 draws the whole picture and the pyramid is of the final depth.
            let capture = rig.again(ctx, &v, CullStages::ALL);
            let hiz = &rig.renderer.occlusion.as_ref().unwrap().hiz;
            let pyramid = hiz.pyramid().unwrap();
            let read =
                |mip: u32| -> Vec<f32> { bytemuck::pod_collect_to_vec(&ctx.read_image(pyramid, mip, 0, 4).unwrap()) };
            assert!(capture.depth.contains(&0.0) && capture.depth.iter().any(|&d| d > 0.0));
            let (l0, s0) = level0_cpu(&capture.depth, size);
            assert_eq!(s0, pyramid.extent);
            let gpu0 = read(0);
            assert!(gpu0 == l0, "{size:?}: level 0 differs from the CPU reduction");
            let (mut prev, mut prev_size) = (gpu0, s0);
            for mip in 1..pyramid.mip_levels {
                let (want, want_size) = reduce_cpu(&prev, prev_size);
                let got = read(mip);
                assert!(got == want, "{size:?}: level {mip} ({want_size:?}) differs from the CPU reduction");
                (prev, prev_size) = (got, want_size);
            }
            assert_eq!(prev_size, [1, 1]);
        }
    });
}

#[test]
fn occlusion_rejects_most_of_the_terrain_behind_a_mountain() {
    gpu_test(|ctx| {
        let size = [128, 96];
        // A 300 m cone between the camera and the north of the world.
        let mountain = Surface::Bump { z0: 150.0, c: [512.0, 400.0], r: 250.0, h: 300.0 };
        let v = view([512.0, 60.0, 165.0], 0.0, 2.0, size, 2.0);
        let mut rig = Rig::with_options(ctx, world(), mountain, vec![], size, false, effects(true));
        rig.shot(ctx, &v, CullStages::ALL);
        // Phase 2 rewrites the visibility bits: two more frames of each
        // copy of them (frame::per_frame) reach the steady state (the
        // settle may end right after new nodes arrived).
        for _ in 0..4 {
            rig.again(ctx, &v, CullStages::ALL);
        }
        let k = rig.renderer.read_counters(ctx).unwrap().cull;
        let rejected = k.after_hole - k.drawn;
        let share = f64::from(rejected) / f64::from(k.after_hole);
        eprintln!("behind the mountain: {rejected} of {} patches rejected ({share:.3}); {k:?}", k.after_hole);
        // Measured 162 of 332 (0.488) on lavapipe: the cone hides the plane
        // behind it, the plane beside it stays visible. The floor sits a
        // little below: the view and resident set are deterministic, the
        // margin covers LOD changes from small edits to the traversal.
        assert!(share >= 0.45, "phase 2 rejected {share:.3} of the patches in view");
    });
}

/// Uploads `p` into an R32F image with its mips (GENERAL, as the pass leaves it).
fn upload_pyramid(ctx: &Context, p: &Pyramid) -> Image {
    let img = Image::new(
        ctx,
        &ImageDesc {
            name: "test_pyramid",
            format: vk::Format::R32_SFLOAT,
            extent: p.sizes[0],
            mip_levels: p.levels.len() as u32,
            array_layers: 1,
            usage: vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
        },
    )
    .unwrap();
    let bytes: Vec<u8> = p.levels.iter().flat_map(|l| bytemuck::cast_slice::<f32, u8>(l).to_vec()).collect();
    let staging = host_buffer(ctx, "pyramid_staging", &bytes, vk::BufferUsageFlags::TRANSFER_SRC);
    ctx.submit_and_wait(|rec| {
        rec.discard_to(&img, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
        let mut off = 0;
        for (mip, l) in p.levels.iter().enumerate() {
            rec.copy_buffer_to_image(&staging, off, &img, mip as u32, 0);
            off += (l.len() * 4) as u64;
        }
        rec.transition(&img, vk::ImageLayout::GENERAL);
        Ok(())
    })
    .unwrap();
    img
}

fn host_buffer(ctx: &Context, name: &str, bytes: &[u8], usage: vk::BufferUsageFlags) -> Buffer {
    let mut b =
        Buffer::new(ctx, &BufferDesc { name, size: bytes.len() as u64, usage, location: MemoryLocation::CpuToGpu })
            .unwrap();
    b.mapped_mut().unwrap().copy_from_slice(bytes);
    b
}

#[test]
fn gpu_box_test_makes_the_cpu_twins_choices() {
    gpu_test(|ctx| {
        let mut rng = Rng(0xb0c5);
        // A random depth image of a non-power-of-two target, and its pyramid.
        let depth_size = [150u32, 90];
        let depth: Vec<f32> = (0..150 * 90).map(|_| (rng.unit() * 0.01) as f32).collect();
        let p = pyramid_cpu(&depth, depth_size);
        let img = upload_pyramid(ctx, &p);
        // The renderer's camera-relative projection, looking north (+y).
        let vp: Mat4 = view([0.0, 0.0, 0.0], 0.0, 0.0, depth_size, 1.0).view_proj().as_mat4();
        let boxes = random_boxes(&mut rng);
        let got = probe_on_the_gpu(ctx, &img, vp, depth_size, &boxes);
        let (mut near_plane, mut occluded, mut boundary, mut max_level) = (0, 0, 0, 0);
        for (i, ((lo, hi), g)) in boxes.iter().zip(&got).enumerate() {
            let t = box_visible_cpu(*lo, *hi, vp, depth_size, &p);
            // f32 rounding of the projection may differ by an ulp between
            // the GPU and the CPU: a decision within 1e-6 of its depth
            // threshold may flip (and is skipped); everything else must match.
            if t.footprint.is_some() && (t.z_nearest - t.farthest).abs() < 1e-6 {
                boundary += 1;
                continue;
            }
            assert_eq!((g[0] == 1, g[1]), (t.visible, t.level), "box {i}: {lo:?}..{hi:?} -> {t:?}");
            near_plane += usize::from(t.footprint.is_none() && t.visible);
            occluded += usize::from(!t.visible);
            max_level = max_level.max(t.level);
        }
        assert!(near_plane >= 300, "{near_plane} boxes crossed the near plane (counted visible)");
        assert!(occluded > 500 && boundary < 40, "{occluded} occluded, {boundary} at the threshold");
        assert!(max_level >= 5, "boxes reached level {max_level} only");
    });
}

/// Random boxes ahead (sizes from sub-pixel to most of the screen),
/// and boxes crossing the near plane (must be visible).
fn random_boxes(rng: &mut Rng) -> Vec<(Vec3, Vec3)> {
    let mut boxes = Vec::new();
    for i in 0..4000 {
        let c = Vec3::new(
            (rng.unit() as f32 - 0.5) * 120.0,
            if i % 10 == 0 { 0.3 } else { 2.0 + rng.unit() as f32 * 150.0 },
            (rng.unit() as f32 - 0.5) * 80.0,
        );
        let h = Vec3::new(rng.unit() as f32, rng.unit() as f32, rng.unit() as f32) * (0.05 + 20.0 * rng.unit() as f32);
        boxes.push((c - h, c + h));
    }
    boxes
}

/// The probe shader's (visible, level) of each box against the pyramid `img`.
fn probe_on_the_gpu(
    ctx: &Context,
    img: &Image,
    vp: Mat4,
    depth_size: [u32; 2],
    boxes: &[(Vec3, Vec3)],
) -> Vec<[u32; 2]> {
    let mut data: Vec<f32> = vp.to_cols_array().to_vec();
    data.extend(bytemuck::cast_slice::<u32, f32>(&[depth_size[0], depth_size[1], boxes.len() as u32, 0]));
    for (lo, hi) in boxes {
        data.extend([lo.x, lo.y, lo.z, 0.0, hi.x, hi.y, hi.z, 0.0]);
    }
    let probes = host_buffer(ctx, "probes", bytemuck::cast_slice(&data), vk::BufferUsageFlags::STORAGE_BUFFER);
    let results = Buffer::new(
        ctx,
        &BufferDesc {
            name: "probe_results",
            size: boxes.len() as u64 * 8,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
            location: MemoryLocation::GpuToCpu,
        },
    )
    .unwrap();
    let sampler = Sampler::new(
        ctx,
        &SamplerDesc {
            name: "probe_nearest",
            filter: vk::Filter::NEAREST,
            address_mode: vk::SamplerAddressMode::CLAMP_TO_EDGE,
        },
    )
    .unwrap();
    let pipeline = Pipeline::compute(
        ctx,
        &ComputePipelineDesc { name: "occlusion_probe", shader: &probe_sh::SHADER, specialization: &[] },
    )
    .unwrap();
    ctx.submit_and_wait(|rec| {
        rec.bind_pipeline(&pipeline);
        rec.push_descriptors(
            &pipeline,
            &[
                (probe_sh::PROBES, Resource::Buffer(&probes)),
                (probe_sh::OUT_, Resource::Buffer(&results)),
                (probe_sh::NEAREST, Resource::Sampler(sampler.raw())),
                (probe_sh::HIZ, Resource::Image(img, vk::ImageLayout::GENERAL)),
            ],
        );
        rec.dispatch((boxes.len() as u32).div_ceil(probe_sh::WORKGROUP_SIZE[0]), 1, 1);
        rec.barrier(vk::PipelineStageFlags2::COMPUTE_SHADER, vk::PipelineStageFlags2::HOST);
        Ok(())
    })
    .unwrap();
    bytemuck::pod_collect_to_vec(results.mapped().unwrap())
}
