//! Case 3: octahedral normal codes. The GLSL encoder (run by
//! `octahedral_probe.comp` on the device) and its CPU twin give identical
//! codes on a million random unit vectors (the quick form: 100 000) plus
//! the hard ones: the axes, the octant boundaries, signed zeros and the fold
//! (just below the equator). The codes' angular error is measured against
//! the input.

use super::{CaseReport, Form};
use crate::error::Result;
use crate::gpu::{vk, Buffer, BufferDesc, ComputePipelineDesc, Context, MemoryLocation, Pipeline, Resource};
use crate::reference::octahedral::{oct_decode8, oct_encode8};
use crate::shaders::octahedral_probe as sh;

/// 8+8 bits, 255 codes per axis: a code cell is 2/254 wide in the
/// octahedral square; the mapping stretches it by up to ~2x on the sphere,
/// so the worst error is about half a cell's diagonal there: under 1 degree.
const MAX_ERROR_DEG: f64 = 1.0;
/// The mean over uniformly random directions is about a third of that.
const MEAN_ERROR_DEG: f64 = 0.4;

fn unit(v: [f64; 3]) -> [f32; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|c| (c / l) as f32)
}

/// The axes, octant boundaries with signed zeros, diagonals and the fold.
fn hard_vectors() -> Vec<[f32; 3]> {
    let mut v = Vec::new();
    for &a in &[0.0f32, -0.0, 1.0, -1.0] {
        for &b in &[0.0f32, -0.0, 1.0, -1.0] {
            for &c in &[0.0f32, -0.0, 1.0, -1.0] {
                if a != 0.0 || b != 0.0 || c != 0.0 {
                    let l = (a * a + b * b + c * c).sqrt();
                    v.push([a / l, b / l, c / l]);
                }
            }
        }
    }
    // The fold: z just below and above 0, around the whole equator.
    for k in 0..3600 {
        let a = f64::from(k) * std::f64::consts::TAU / 3600.0;
        for z in [-1e-7, -1e-4, -0.01, 0.0, 1e-7, 0.01] {
            v.push(unit([a.cos(), a.sin(), z]));
        }
    }
    // Octant boundaries with one signed-zero component.
    for k in 0..360 {
        let a = f64::from(k).to_radians();
        let (s, c) = (a.sin() as f32, a.cos() as f32);
        v.extend([[0.0, s, c], [-0.0, s, c], [s, 0.0, c], [s, -0.0, c], [s, c, 0.0], [s, c, -0.0]]);
    }
    v
}

fn encode_gpu(ctx: &Context, vectors: &[[f32; 3]]) -> Result<Vec<[u32; 4]>> {
    let mut data: Vec<u32> = vec![vectors.len() as u32, 0, 0, 0];
    for v in vectors {
        data.extend([v[0].to_bits(), v[1].to_bits(), v[2].to_bits(), 0]);
    }
    let buffer = |name, size: u64, location| {
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        Buffer::new(ctx, &BufferDesc { name, size, usage, location })
    };
    let mut input = buffer("octahedral_probes", data.len() as u64 * 4, MemoryLocation::CpuToGpu)?;
    input.mapped_mut().expect("CpuToGpu buffers are mapped").copy_from_slice(bytemuck::cast_slice(&data));
    let results = buffer("octahedral_results", vectors.len() as u64 * 16, MemoryLocation::GpuToCpu)?;
    let pipeline = Pipeline::compute(
        ctx,
        &ComputePipelineDesc { name: "octahedral_probe", shader: &sh::SHADER, specialization: &[] },
    )?;
    ctx.submit_and_wait(|rec| {
        rec.bind_pipeline(&pipeline);
        rec.push_descriptors(&pipeline, &[(sh::IN_, Resource::Buffer(&input)), (sh::OUT_, Resource::Buffer(&results))]);
        rec.dispatch((vectors.len() as u32).div_ceil(sh::WORKGROUP_SIZE[0]), 1, 1);
        rec.barrier(vk::PipelineStageFlags2::COMPUTE_SHADER, vk::PipelineStageFlags2::HOST);
        Ok(())
    })?;
    Ok(bytemuck::pod_collect_to_vec(results.mapped().expect("GpuToCpu buffers are mapped")))
}

/// xorshift64*: a seeded stream, the same on every machine.
fn next_unit(state: &mut u64) -> f64 {
    *state ^= *state >> 12;
    *state ^= *state << 25;
    *state ^= *state >> 27;
    (state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
}

pub fn run(ctx: &Context, form: Form) -> Result<CaseReport> {
    let mut r = CaseReport::new(3, "octahedral normals");
    r.measured = "codes where the GLSL and CPU encoders differ; angular error of 8+8-bit codes (max, mean); GPU f32 decode against the f64 decode".into();
    r.bound = format!("0 codes; max < {MAX_ERROR_DEG} deg, mean < {MEAN_ERROR_DEG} deg; decode < 1e-6");
    r.why = "255 codes per axis make a cell 2/254 wide, stretched up to ~2x on the sphere: half a cell's diagonal is under 1 degree; the mean over random directions is about a third of it; f32 normalize is good to a few ulps".into();
    let random = form.pick(100_000, 1_000_000);
    let mut state = 0x0c7a_4ed0u64;
    let mut vectors = hard_vectors();
    let total = vectors.len() + random;
    while vectors.len() < total {
        // Uniform on the sphere: points of the unit ball, normalised.
        let v = [0, 1, 2].map(|_| next_unit(&mut state) * 2.0 - 1.0);
        let l2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        if l2 > 1e-6 && l2 <= 1.0 {
            vectors.push(unit(v));
        }
    }
    let gpu = encode_gpu(ctx, &vectors)?;
    let (mut differ, mut max_deg, mut sum_deg, mut decode_diff) = (0usize, 0f64, 0f64, 0f64);
    for (v, g) in vectors.iter().zip(&gpu) {
        let cpu = oct_encode8(*v);
        let gpu_code = [g[0] & 0xFF, g[0] >> 8];
        if cpu != gpu_code {
            differ += 1;
            if differ <= 3 {
                r.details.push(format!("{v:?}: CPU {cpu:?}, GPU {gpu_code:?}"));
            }
        }
        let d = oct_decode8(cpu);
        let cos = d.iter().zip(v).map(|(a, b)| a * f64::from(*b)).sum::<f64>();
        let deg = cos.clamp(-1.0, 1.0).acos().to_degrees();
        max_deg = max_deg.max(deg);
        sum_deg += deg;
        // The GPU's f32 decode against the CPU's.
        let gd = [g[1], g[2], g[3]].map(f32::from_bits);
        decode_diff = decode_diff.max(gd.iter().zip(d).map(|(a, b)| (f64::from(*a) - b).abs()).fold(0.0, f64::max));
    }
    let mean = sum_deg / vectors.len() as f64;
    r.details.push(format!(
        "{} vectors ({} hard ones): {differ} codes differ; angular error max {max_deg:.4} deg, mean {mean:.4} deg; GPU decode within {decode_diff:.2e}",
        vectors.len(),
        vectors.len() - random
    ));
    r.worst = format!("{differ} codes; max {max_deg:.3} deg, mean {mean:.3} deg; decode {decode_diff:.1e}");
    r.pass = differ == 0 && max_deg < MAX_ERROR_DEG && mean < MEAN_ERROR_DEG && decode_diff < 1e-6;
    Ok(r)
}
