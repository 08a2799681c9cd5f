//! The smoke frame (tests only): a prefix sum, a triangle and a holed
//! diamond patch, through the frame executor so every pass is timed.

use super::diamond_patch::DiamondPatch;
use super::smoke_triangle::{SmokeTriangle, TARGET_FORMAT};
use vista::error::Result;
use vista::frame::{FrameExecutor, FrameTimings, QueueKind};
use vista::gpu::{vk, Buffer, BufferDesc, Context, FrameRing, Image, ImageDesc, MemoryLocation};
use vista::passes::prefix_sum::PrefixSum;

pub struct SmokeOutput {
    /// Timings of every frame that came back, oldest first.
    pub frames: Vec<FrameTimings>,
    /// RGBA8 of the last frame's diamond patch target.
    pub image: Vec<u8>,
    pub size: [u32; 2],
}

/// Renders `frames` smoke frames at `size` with two frames in flight.
pub fn render(ctx: &Context, size: [u32; 2], frames: u32) -> Result<SmokeOutput> {
    let scan = PrefixSum::new(ctx)?;
    let tri = SmokeTriangle::new(ctx)?;
    let patch = DiamondPatch::new(ctx, 16)?;
    let n = PrefixSum::capacity();
    let usage =
        vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::TRANSFER_SRC;
    let buffer =
        |name| Buffer::new(ctx, &BufferDesc { name, size: u64::from(n) * 4, usage, location: MemoryLocation::GpuOnly });
    let (input, output) = (buffer("smoke_scan_input")?, buffer("smoke_scan_output")?);
    ctx.upload(&input, bytemuck::cast_slice(&(0..n).collect::<Vec<u32>>()))?;
    let target = |name| {
        Image::new(
            ctx,
            &ImageDesc {
                name,
                format: TARGET_FORMAT,
                extent: size,
                mip_levels: 1,
                array_layers: 1,
                usage: vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC,
            },
        )
    };
    let (tri_target, patch_target) = (target("smoke_triangle_target")?, target("diamond_patch_target")?);
    let mut ring = FrameRing::new(ctx, 2)?;
    let mut exec = FrameExecutor::new(ctx, 2, 4, true)?;
    let mut out: Vec<FrameTimings> = Vec::new();
    let corners = [[-0.8, -0.7, 0.0, 1.0], [0.9, -0.2, 0.0, 1.0], [-0.1, 0.85, 0.0, 1.0]];
    for _ in 0..frames {
        ring.record(ctx, |rec| {
            rec.discard_to(&tri_target, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
            rec.discard_to(&patch_target, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
            let mut frame = exec.begin(vista::gpu::FrameCommands::One(rec), vista::gpu::QueueMode::Single);
            frame.pass(PrefixSum::NAME, false, QueueKind::Compute, |r| scan.record(r, &input, &output, n))?;
            frame.pass(SmokeTriangle::NAME, false, QueueKind::Graphics, |r| tri.record(r, &tri_target, corners));
            frame.pass(DiamondPatch::NAME, false, QueueKind::Graphics, |r| {
                patch.record(r, &patch_target, Some(patch.vertex(5, 7)))
            });
            Ok(())
        })?;
        // Timings return once the GPU finished a frame: one frame late here.
        if let Some(t) = exec.latest() {
            if out.last().is_none_or(|l| l.frame < t.frame) {
                out.push(t.clone());
            }
        }
    }
    ring.wait_all(ctx)?;
    let image = ctx.read_image(&patch_target, 0, 0, 4)?;
    Ok(SmokeOutput { frames: out, image, size })
}
