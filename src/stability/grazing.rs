//! Case 4: grazing angles. The G-buffer shading reconstructs positions and
//! their screen derivatives from depth and 8-bit normal codes
//! (`reconstruct.glsl`), then samples materials with those gradients. Up
//! to 89.99 degrees incidence (and beyond the guard at 89.95) every
//! derivative stays finite and within the guard's bound, every one of the
//! 65 536 normal codes decodes to a finite unit vector, and the sampler's
//! mip never exceeds the last mip. `tests/derivatives.rs` checks the
//! accuracy from 0 to 89.9 degrees with the same probe.

use super::{CaseReport, Form};
use crate::error::Result;
use crate::gpu::{
    vk, Buffer, BufferDesc, ComputePipelineDesc, Context, Image, ImageDesc, MemoryLocation, Pipeline, Resource,
    Sampler, SamplerDesc,
};
use crate::render::{Camera, View, DEFAULT_NEAR_M};
use crate::shaders::derivative_probe as sh;
use glam::{DMat4, DVec3, DVec4};

pub const SIZE: [u32; 2] = [256, 144];
/// The probe's mip texture: 1024 texels, mips 0..=10, mip k holding k.
pub const TEXELS: u32 = 1024;
pub const LAST_MIP: f64 = 10.0;
/// Texture repeats per metre (a 20 m material): mip ~2 straight down from 10 m.
pub const UV_PER_M: f64 = 0.05;
/// The angle between neighbouring pixels' rays (60 degrees over 144 rows).
pub const ALPHA: f64 = 0.008_019;
/// reconstruct.glsl's guard.
pub const GRAZING_COS: f64 = 1.745e-4;

/// The unnormalised eye ray through pixel `px` (reconstruct.glsl's eye_ray).
pub fn eye_ray(inv: &DMat4, px: [f64; 2]) -> DVec3 {
    let ndc = [px[0] / f64::from(SIZE[0]) * 2.0 - 1.0, px[1] / f64::from(SIZE[1]) * 2.0 - 1.0];
    (*inv * DVec4::new(ndc[0], ndc[1], 0.0, 1.0)).truncate()
}

/// One pixel to reconstruct: position, stored depth, normal code.
pub struct Probe {
    pub px: [f64; 2],
    pub depth: f32,
    pub code: [u32; 2],
}

/// Runs the probe: per probe, (ddx, mip) and (ddy, 0).
pub fn probe_gpu(ctx: &Context, inv: &DMat4, probes: &[Probe]) -> Result<Vec<[[f32; 4]; 2]>> {
    let mut data: Vec<f32> = inv.as_mat4().to_cols_array().to_vec();
    let [w, h] = SIZE.map(|v| v as f32);
    data.extend([w, h, 1.0 / w, 1.0 / h, UV_PER_M as f32, 0.0, 0.0, 0.0]);
    data.extend(bytemuck::cast_slice::<u32, f32>(&[probes.len() as u32, 0, 0, 0]));
    for p in probes {
        data.extend([p.px[0] as f32, p.px[1] as f32, p.depth, f32::from_bits(p.code[0] | p.code[1] << 8)]);
    }
    let buffer = |name, size: u64, location| {
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
        Buffer::new(ctx, &BufferDesc { name, size, usage, location })
    };
    let mut input = buffer("derivative_probes", data.len() as u64 * 4, MemoryLocation::CpuToGpu)?;
    input.mapped_mut().expect("CpuToGpu buffers are mapped").copy_from_slice(bytemuck::cast_slice(&data));
    let results = buffer("derivative_results", probes.len() as u64 * 32, MemoryLocation::GpuToCpu)?;
    let mips = mip_texture(ctx)?;
    let sampler = Sampler::mipmapped(
        ctx,
        &SamplerDesc { name: "probe_mips", filter: vk::Filter::LINEAR, address_mode: vk::SamplerAddressMode::REPEAT },
    )?;
    let pipeline = Pipeline::compute(
        ctx,
        &ComputePipelineDesc { name: "derivative_probe", shader: &sh::SHADER, specialization: &[] },
    )?;
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
    })?;
    Ok(bytemuck::pod_collect_to_vec(results.mapped().expect("GpuToCpu buffers are mapped")))
}

/// R32F, mip k filled with k.
fn mip_texture(ctx: &Context) -> Result<Image> {
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
    )?;
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
    )?;
    staging.mapped_mut().expect("CpuToGpu buffers are mapped").copy_from_slice(bytemuck::cast_slice(&texels));
    ctx.submit_and_wait(|rec| {
        rec.discard_to(&img, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
        let mut off = 0;
        for k in 0..levels {
            rec.copy_buffer_to_image(&staging, off, &img, k, 0);
            off += u64::from((TEXELS >> k) * (TEXELS >> k)) * 4;
        }
        rec.transition(&img, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
        Ok(())
    })?;
    Ok(img)
}

/// A camera 10 m from the plane with normal `n` (camera-relative point
/// p0 = -10 n), its centre ray at `incidence` degrees from the normal;
/// `upside_down` flips the image rows (+y then leads away from the plane).
pub fn setup(n: DVec3, incidence: f64, upside_down: bool) -> (DMat4, DVec3) {
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

pub fn run(ctx: &Context, _form: Form) -> Result<CaseReport> {
    let mut r = CaseReport::new(4, "grazing angles");
    r.measured = "non-finite or out-of-bound derivatives and mips from 89 to 89.995 degrees incidence; probes over all 65 536 normal codes; largest mip chosen".into();
    r.bound = format!("0; 0; mip <= {LAST_MIP}");
    r.why = "reconstruct.glsl guards rays within 0.01 degrees of the plane (|cos| < 1.745e-4): a step is then at most |p| (1 + 1/1.745e-4); the sampler clamps to the last mip, which a NaN gradient would defeat".into();
    let n = DVec3::Z;
    let (mut bad, mut checked, mut top_mip) = (0usize, 0usize, 0.0f32);
    for incidence in [89.0, 89.9, 89.95, 89.99, 89.995] {
        for upside_down in [false, true] {
            let (vp, p0) = setup(n, incidence, upside_down);
            let inv = vp.inverse();
            let (mut probes, mut dist) = (Vec::new(), Vec::new());
            for i in [0.5, 128.5, 255.5] {
                // The centre rows: the pixel itself hits (or nearly).
                for j in [71.5, 72.5] {
                    let d = eye_ray(&inv, [i, j]);
                    let t = p0.dot(n) / d.dot(n);
                    if t > 0.0 {
                        let clip = vp * (d * t).extend(1.0);
                        probes.push(Probe { px: [i, j], depth: (clip.z / clip.w) as f32, code: [127, 127] });
                        dist.push((d * t).length());
                    }
                }
            }
            for (g, r_m) in probe_gpu(ctx, &inv, &probes)?.iter().zip(&dist) {
                let bound = r_m * (1.0 + 1.0 / GRAZING_COS) * 1.01;
                let steps = [&g[0], &g[1]].map(|v| DVec3::new(v[0].into(), v[1].into(), v[2].into()).length());
                let lod = g[0][3];
                bad += usize::from(!steps.iter().all(|s| s.is_finite() && *s <= bound) || !mip_ok(lod));
                top_mip = top_mip.max(lod);
                checked += 1;
            }
        }
    }
    r.details.push(format!("{checked} probes from 89 to 89.995 degrees (both image orientations)"));
    // Every normal code, each decoded by the shader and used for the
    // derivatives of the centre pixel of a 60 degree view of flat ground.
    let (vp, p0) = setup(n, 60.0, false);
    let inv = vp.inverse();
    let d = eye_ray(&inv, [128.0, 72.0]);
    let clip = vp * (d * (p0.dot(n) / d.dot(n))).extend(1.0);
    let depth = (clip.z / clip.w) as f32;
    let probes: Vec<Probe> =
        (0..65536u32).map(|c| Probe { px: [128.0, 72.0], depth, code: [c & 0xFF, c >> 8] }).collect();
    let mut code_bad = 0;
    for g in probe_gpu(ctx, &inv, &probes)? {
        let finite = g.iter().flatten().all(|v| v.is_finite());
        code_bad += usize::from(!finite || !mip_ok(g[0][3]));
        top_mip = top_mip.max(g[0][3]);
    }
    r.details
        .push(format!("65536 normal codes: {code_bad} gave a non-finite derivative or a mip outside 0..={LAST_MIP}"));
    r.worst = format!("{bad}; {code_bad}; mip {top_mip:.3}");
    r.pass = bad == 0 && code_bad == 0 && f64::from(top_mip) <= LAST_MIP;
    Ok(r)
}

fn mip_ok(lod: f32) -> bool {
    lod.is_finite() && (0.0..=LAST_MIP as f32).contains(&lod)
}
