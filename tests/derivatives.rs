//! Derivatives and mip levels of the G-buffer shading on a plane viewed
//! from 0 to 89.9 degrees incidence. The GPU runs `reconstruct.glsl` (the
//! code `gbuffer_tiles` runs) on depths and 8-bit normal codes; the CPU
//! intersects the same eye rays with the same plane in f64. Beyond the
//! guard (89.95 to 89.995 degrees) the results must stay finite and within
//! the guard's bound.

mod common;

use common::gpu_test;
use glam::{DMat4, DVec3, DVec4};
use vista::gpu::{
    vk, Buffer, BufferDesc, ComputePipelineDesc, Context, Image, ImageDesc, MemoryLocation, Pipeline, Resource,
    Sampler, SamplerDesc,
};
use vista::render::{Camera, View, DEFAULT_NEAR_M};
use vista::shaders::derivative_probe as sh;

const SIZE: [u32; 2] = [256, 144];
/// The probe's mip texture: 1024 texels, mips 0..=10, mip k holding k.
const TEXELS: u32 = 1024;
const LAST_MIP: f64 = 10.0;
/// Texture repeats per metre (a 20 m material): mip ~2 straight down from 10 m.
const UV_PER_M: f64 = 0.05;
/// The angle between neighbouring pixels' rays (60 degrees over 144 rows).
const ALPHA: f64 = 0.008_019;
/// reconstruct.glsl's guard.
const GRAZING_COS: f64 = 1.745e-4;

/// The CPU twin of `oct_decode8` (octahedral.glsl), in f64.
fn oct_decode8(code: [u32; 2]) -> DVec3 {
    DVec3::from(vista::reference::octahedral::oct_decode8(code))
}

/// The exact intersection of the eye ray through `px` with the plane
/// (p0, n): None where it runs parallel (within the guard) or meets the
/// plane behind the eye. Same definition as reconstruct.glsl, in f64.
fn hit(inv: &DMat4, px: [f64; 2], p0: DVec3, n: DVec3) -> Option<DVec3> {
    let d = eye_ray(inv, px);
    let cos = d.dot(n) / d.length();
    let t = p0.dot(n) / d.dot(n);
    (cos.abs() >= GRAZING_COS && t > 0.0).then_some(d * t)
}

/// The unnormalised eye ray through pixel `px` (reconstruct.glsl's eye_ray).
fn eye_ray(inv: &DMat4, px: [f64; 2]) -> DVec3 {
    let ndc = [px[0] / f64::from(SIZE[0]) * 2.0 - 1.0, px[1] / f64::from(SIZE[1]) * 2.0 - 1.0];
    (*inv * DVec4::new(ndc[0], ndc[1], 0.0, 1.0)).truncate()
}

/// The step to a neighbour, forward where it hits, else backward.
fn step(inv: &DMat4, px: [f64; 2], o: [f64; 2], p: DVec3, p0: DVec3, n: DVec3) -> Option<DVec3> {
    hit(inv, [px[0] + o[0], px[1] + o[1]], p0, n)
        .map(|q| q - p)
        .or_else(|| hit(inv, [px[0] - o[0], px[1] - o[1]], p0, n).map(|q| p - q))
}

struct Probe {
    px: [f64; 2],
    depth: f32,
    code: [u32; 2],
}

fn probe_gpu(ctx: &Context, inv: &DMat4, probes: &[Probe]) -> Vec<[[f32; 4]; 2]> {
    let mut data: Vec<f32> = inv.as_mat4().to_cols_array().to_vec();
    let [w, h] = SIZE.map(|v| v as f32);
    data.extend([w, h, 1.0 / w, 1.0 / h, UV_PER_M as f32, 0.0, 0.0, 0.0]);
    data.extend(bytemuck::cast_slice::<u32, f32>(&[probes.len() as u32, 0, 0, 0]));
    for p in probes {
        data.extend([p.px[0] as f32, p.px[1] as f32, p.depth, f32::from_bits(p.code[0] | p.code[1] << 8)]);
    }
    let buffer = |name, size: u64, location| {
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
        Buffer::new(ctx, &BufferDesc { name, size, usage, location }).unwrap()
    };
    let mut input = buffer("derivative_probes", data.len() as u64 * 4, MemoryLocation::CpuToGpu);
    input.mapped_mut().unwrap().copy_from_slice(bytemuck::cast_slice(&data));
    let results = buffer("derivative_results", probes.len() as u64 * 32, MemoryLocation::GpuToCpu);
    let mips = mip_texture(ctx);
    let sampler = Sampler::mipmapped(
        ctx,
        &SamplerDesc { name: "probe_mips", filter: vk::Filter::LINEAR, address_mode: vk::SamplerAddressMode::REPEAT },
    )
    .unwrap();
    let pipeline = Pipeline::compute(
        ctx,
        &ComputePipelineDesc { name: "derivative_probe", shader: &sh::SHADER, specialization: &[] },
    )
    .unwrap();
    ctx.submit_and_wait(|rec| {
        rec.bind_pipeline(&pipeline);
        rec.push_descriptors(
            &pipeline,
            &[
                (sh::IN_, Resource::Buffer(&input)),
                (sh::OUT_, Resource::Buffer(&results)),
                (sh::MIP_SAMPLER, Resource::Sampler(sampler.raw())),
                (sh::MIP_LEVELS, Resource::Image(&mips, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)),
            ],
        );
        rec.dispatch((probes.len() as u32).div_ceil(sh::WORKGROUP_SIZE[0]), 1, 1);
        rec.barrier(vk::PipelineStageFlags2::COMPUTE_SHADER, vk::PipelineStageFlags2::HOST);
        Ok(())
    })
    .unwrap();
    bytemuck::pod_collect_to_vec(results.mapped().unwrap())
}

/// R32F, mip k filled with k.
fn mip_texture(ctx: &Context) -> Image {
    let levels = LAST_MIP as u32 + 1;
    let img = Image::new(
        ctx,
        &ImageDesc {
            name: "probe_mip_levels",
            format: vk::Format::R32_SFLOAT,
            extent: [TEXELS, TEXELS],
            mip_levels: levels,
            array_layers: 1,
            usage: vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
        },
    )
    .unwrap();
    let texels: Vec<f32> =
        (0..levels).flat_map(|k| std::iter::repeat_n(k as f32, ((TEXELS >> k) * (TEXELS >> k)) as usize)).collect();
    let mut staging = Buffer::new(
        ctx,
        &BufferDesc {
            name: "probe_mip_staging",
            size: texels.len() as u64 * 4,
            usage: vk::BufferUsageFlags::TRANSFER_SRC,
            location: MemoryLocation::CpuToGpu,
        },
    )
    .unwrap();
    staging.mapped_mut().unwrap().copy_from_slice(bytemuck::cast_slice(&texels));
    ctx.submit_and_wait(|rec| {
        rec.discard_to(&img, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
        let mut off = 0;
        for k in 0..levels {
            rec.copy_buffer_to_image(&staging, off, &img, k, 0);
            off += u64::from((TEXELS >> k) * (TEXELS >> k)) * 4;
        }
        rec.transition(&img, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
        Ok(())
    })
    .unwrap();
    img
}

/// A camera 10 m from the plane with normal `n` (camera-relative point
/// p0 = -10 n), its centre ray at `incidence` degrees from the normal;
/// `upside_down` flips the image rows (+y then leads away from the plane).
fn setup(n: DVec3, incidence: f64, upside_down: bool) -> (DMat4, DVec3) {
    let tangent = n.cross(DVec3::Z).try_normalize().unwrap_or(DVec3::X);
    let t = tangent.cross(n).normalize();
    let (s, c) = incidence.to_radians().sin_cos();
    let forward = -n * c + t * s;
    let camera = Camera {
        position_m: [0.0; 3],
        yaw_deg: forward.x.atan2(forward.y).to_degrees(),
        pitch_deg: forward.z.clamp(-1.0, 1.0).asin().to_degrees(),
    };
    let view = View { camera, fov_y_deg: 60.0, size: SIZE, target_error_px: 1.0, near_m: DEFAULT_NEAR_M };
    let mut vp = view.view_proj();
    if upside_down {
        vp = DMat4::from_diagonal(DVec4::new(1.0, -1.0, 1.0, 1.0)) * vp;
    }
    (vp, -n * 10.0)
}

/// The mip range the Vulkan spec allows for position steps `gx`, `gy` (m per
/// pixel): rho per axis between the larger component and the sum of both.
fn mip_range(gx: DVec3, gy: DVec3) -> [f64; 2] {
    let t = f64::from(TEXELS) * UV_PER_M;
    let lo = (gx.x.abs().max(gx.y.abs())).max(gy.x.abs().max(gy.y.abs())) * t;
    let hi = (gx.x.abs() + gx.y.abs()).max(gy.x.abs() + gy.y.abs()) * t;
    [lo.log2().clamp(0.0, LAST_MIP), hi.log2().clamp(0.0, LAST_MIP)]
}

#[test]
fn derivatives_and_mips_on_a_plane_from_0_to_89_9_degrees() {
    gpu_test(|ctx| {
        // Flat ground (code 127,127 is exactly +z) and a plane tilted about
        // 33 degrees: each plane is the one its code decodes to.
        let planes = [[127u32, 127], [170, 150]];
        let angles = [0.0, 10.0, 30.0, 45.0, 60.0, 70.0, 80.0, 85.0, 88.0, 89.0, 89.5, 89.8, 89.9];
        let (mut checked, mut backward, mut worst_rel, mut worst_mip) = (0, 0, 0.0f64, 0.0f64);
        for code in planes {
            let n = oct_decode8(code);
            for upside_down in [false, true] {
                for &incidence in &angles {
                    let (vp, p0) = setup(n, incidence, upside_down);
                    let inv = vp.inverse();
                    // The centre pixel and a spread over the target.
                    let mut cases = Vec::new();
                    for j in [0.5, 36.5, 71.5, 72.5, 108.5, 143.5] {
                        for i in [0.5, 64.5, 128.5, 200.5, 255.5] {
                            let Some(p) = hit(&inv, [i, j], p0, n) else { continue };
                            let clip = vp * p.extend(1.0);
                            let (dx, dy) =
                                (step(&inv, [i, j], [1.0, 0.0], p, p0, n), step(&inv, [i, j], [0.0, 1.0], p, p0, n));
                            if let (Some(dx), Some(dy)) = (dx, dy) {
                                backward += usize::from(hit(&inv, [i, j + 1.0], p0, n).is_none());
                                cases.push((Probe { px: [i, j], depth: (clip.z / clip.w) as f32, code }, p, dx, dy));
                            }
                        }
                    }
                    assert!(!cases.is_empty() || incidence > 89.0, "{incidence}: no pixel on the plane");
                    let probes: Vec<Probe> = cases.iter().map(|c| Probe { ..c.0 }).collect();
                    let got = probe_gpu(ctx, &inv, &probes);
                    for ((probe, p, dx, dy), g) in cases.iter().zip(&got) {
                        let what =
                            format!("code {code:?} incidence {incidence} flipped {upside_down} pixel {:?}", probe.px);
                        let gx = DVec3::new(g[0][0].into(), g[0][1].into(), g[0][2].into());
                        let gy = DVec3::new(g[1][0].into(), g[1][1].into(), g[1][2].into());
                        // f32 rounding: the plane's offset p.n is found to
                        // about 2^-24 |p| (components of |p| cancel for a
                        // tilted plane); the neighbour's hit, at |p| away,
                        // moves by that relative amount times |p|; divided by
                        // the step (at least |p| times the pixel angle alpha)
                        // the relative error is about 2^-24 / (cos(i) alpha)
                        // with cos(i) = p0.n / |p| the pixel's own incidence:
                        // 1e-5 straight on, 0.5 % at 89.9 degrees. Bound:
                        // 16 times that, plus 1e-5.
                        let cos_i = p0.dot(n).abs() / p.length();
                        let bound = 16.0 * f64::from(f32::EPSILON) * 0.5 / (cos_i * ALPHA) + 1e-5;
                        for (gpu, exact, axis) in [(gx, *dx, "x"), (gy, *dy, "y")] {
                            let rel = (gpu - exact).length() / exact.length();
                            assert!(
                                rel.is_finite() && rel <= bound,
                                "{what}: d/d{axis} {gpu} vs {exact} (|p| {:.1}), {rel:.2e} over {bound:.2e}",
                                p.length()
                            );
                            worst_rel = worst_rel.max(rel / bound);
                        }
                        // The sampler's mip (mip k holds k, filtered
                        // linearly between mips) within the spec's range
                        // for the exact gradients, plus 1/16 mip for the
                        // driver's fixed-point level-of-detail.
                        let lod = f64::from(g[0][3]);
                        // Widened by what the derivative's bound moves it.
                        let [lo, hi] = mip_range(*dx, *dy);
                        let slack = 0.0625 + (1.0 + bound).log2();
                        assert!(
                            lod >= lo - slack && lod <= hi + slack,
                            "{what}: mip {lod} outside {lo}..{hi} (+-{slack})"
                        );
                        worst_mip = worst_mip.max((lo - lod).max(lod - hi));
                        checked += 1;
                    }
                }
            }
        }
        eprintln!("{checked} probes; worst derivative error {worst_rel:.3} of its bound; worst mip outside the spec's range {worst_mip:.4}; {backward} backward steps");
        assert!(checked > 600 && backward >= 20, "{checked} probes, {backward} took the backward step");
    });
}

#[test]
fn beyond_the_guard_derivatives_stay_finite_and_bounded() {
    gpu_test(|ctx| {
        let n = DVec3::Z;
        let mut checked = 0;
        for incidence in [89.95, 89.99, 89.995] {
            for upside_down in [false, true] {
                let (vp, p0) = setup(n, incidence, upside_down);
                let inv = vp.inverse();
                let mut probes = Vec::new();
                let mut dist = Vec::new();
                for i in [0.5, 128.5, 255.5] {
                    // The centre rows: the pixel itself hits (or nearly).
                    for j in [71.5, 72.5] {
                        let d = eye_ray(&inv, [i, j]);
                        let t = p0.dot(n) / d.dot(n);
                        if t <= 0.0 {
                            continue;
                        }
                        let clip = vp * (d * t).extend(1.0);
                        probes.push(Probe { px: [i, j], depth: (clip.z / clip.w) as f32, code: [127, 127] });
                        dist.push((d * t).length());
                    }
                }
                let got = probe_gpu(ctx, &inv, &probes);
                for ((probe, r), g) in probes.iter().zip(&dist).zip(&got) {
                    let bound = r * (1.0 + 1.0 / GRAZING_COS) * 1.01;
                    for v in [&g[0], &g[1]] {
                        let len = DVec3::new(v[0].into(), v[1].into(), v[2].into()).length();
                        assert!(len.is_finite() && len <= bound, "{incidence} {:?}: step {len} over {bound}", probe.px);
                    }
                    let lod = g[0][3];
                    assert!(lod.is_finite() && (0.0..=LAST_MIP as f32).contains(&lod), "{incidence}: mip {lod}");
                    checked += 1;
                }
            }
        }
        assert!(checked >= 12, "{checked} probes");
    });
}
