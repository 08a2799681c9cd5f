//! The frame loop of `vista render`: streams the terrain (lazy baking,
//! upload, GPU quadtree passes) and, until terrain geometry exists, adds the
//! smoke passes (a prefix sum, a triangle, a holed diamond patch), all
//! through the frame executor so every pass is timed.

use crate::error::Result;
use crate::frame::{FrameExecutor, FrameTimings, QueueKind};
use crate::gpu::{vk, Buffer, BufferDesc, Context, FrameRing, Image, ImageDesc, MemoryLocation};
use crate::passes::diamond_patch::DiamondPatch;
use crate::passes::prefix_sum::PrefixSum;
use crate::passes::smoke_triangle::{SmokeTriangle, TARGET_FORMAT};
use crate::terrain::Terrain;
use crate::traverse_cpu::{TraverseCamera, TraverseParams};
use std::time::{Duration, Instant};

pub struct SmokeOutput {
    /// Timings of every frame that came back, oldest first.
    pub frames: Vec<FrameTimings>,
    /// RGBA8 of the last frame's diamond patch target.
    pub image: Vec<u8>,
    pub size: [u32; 2],
    /// Frames run before the timed ones while streaming settled.
    pub settle_frames: u32,
    pub settle_seconds: f64,
}

/// The render's view: one camera at `camera`, 60 degrees vertical field of
/// view over the target height, 1 px target error.
pub fn view_params(camera: [f64; 3], size: [u32; 2]) -> TraverseParams {
    TraverseParams { cameras: vec![TraverseCamera::perspective(camera, 60.0, size[1])], target_error_px: 1.0 }
}

/// Renders `frames` frames at `size` with two frames in flight.
pub fn render(ctx: &Context, size: [u32; 2], frames: u32) -> Result<SmokeOutput> {
    render_with(ctx, None, [0.0; 3], size, frames, Duration::ZERO)
}

/// As `render`, streaming `terrain` around `camera`: first frames until the
/// wanted set is resident (or `settle_timeout` passes), then `frames` timed
/// frames.
pub fn render_with(
    ctx: &Context,
    mut terrain: Option<&mut Terrain>,
    camera: [f64; 3],
    size: [u32; 2],
    frames: u32,
    settle_timeout: Duration,
) -> Result<SmokeOutput> {
    let scan = PrefixSum::new(ctx)?;
    let tri = SmokeTriangle::new(ctx)?;
    let patch = DiamondPatch::new(ctx, 16)?;
    let n = PrefixSum::capacity();
    let usage =
        vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::TRANSFER_SRC;
    let input = Buffer::new(
        ctx,
        &BufferDesc { name: "smoke_scan_input", size: u64::from(n) * 4, usage, location: MemoryLocation::GpuOnly },
    )?;
    let output = Buffer::new(
        ctx,
        &BufferDesc { name: "smoke_scan_output", size: u64::from(n) * 4, usage, location: MemoryLocation::GpuOnly },
    )?;
    ctx.upload(&input, bytemuck::cast_slice(&(0..n).collect::<Vec<u32>>()))?;
    let target_desc = |name| ImageDesc {
        name,
        format: TARGET_FORMAT,
        extent: size,
        mip_levels: 1,
        array_layers: 1,
        usage: vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC,
    };
    let tri_target = Image::new(ctx, &target_desc("smoke_triangle_target"))?;
    let patch_target = Image::new(ctx, &target_desc("diamond_patch_target"))?;
    let mut ring = FrameRing::new(ctx, 2)?;
    let mut exec = FrameExecutor::new(ctx, 2, 12)?;
    let mut out = Vec::new();
    let corners = [[-0.8, -0.7, 0.0, 1.0], [0.9, -0.2, 0.0, 1.0], [-0.1, 0.85, 0.0, 1.0]];
    // One view at `camera`, 60 degrees vertical field of view, 1 px target.
    let params =
        TraverseParams { cameras: vec![TraverseCamera::perspective(camera, 60.0, size[1])], target_error_px: 1.0 };
    let start = Instant::now();
    let mut settle_frames = 0;
    let mut settle_seconds = 0.0;
    let mut timed = 0;
    while timed < frames {
        let settling =
            terrain.as_ref().is_some_and(|t| settle_frames == 0 || !t.settled()) && start.elapsed() < settle_timeout;
        if settling {
            settle_frames += 1;
            // Give the loader threads the cores while nothing is resident yet.
            std::thread::sleep(Duration::from_millis(20));
        } else {
            if timed == 0 {
                settle_seconds = start.elapsed().as_secs_f64();
            }
            timed += 1;
        }
        ring.record(ctx, |rec| {
            rec.image_layout(&tri_target, vk::ImageLayout::UNDEFINED, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
            rec.image_layout(&patch_target, vk::ImageLayout::UNDEFINED, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
            let mut frame = exec.begin(rec);
            if let Some(t) = terrain.as_deref_mut() {
                t.record(&mut frame, &params)?;
            }
            frame.pass(PrefixSum::NAME, QueueKind::Compute, |r| scan.record(r, &input, &output, n))?;
            frame.pass(SmokeTriangle::NAME, QueueKind::Graphics, |r| tri.record(r, &tri_target, corners));
            frame.pass(DiamondPatch::NAME, QueueKind::Graphics, |r| {
                patch.record(r, &patch_target, Some(patch.vertex(5, 7)))
            });
            Ok(())
        })?;
        // Timings return once the GPU finished a frame: one frame late here.
        if let Some(t) = exec.latest().filter(|t| t.frame > u64::from(settle_frames)) {
            if out.last().is_none_or(|l: &FrameTimings| l.frame < t.frame) {
                out.push(t.clone());
            }
        }
    }
    ring.wait_all(ctx)?;
    let image = ctx.read_image(&patch_target, 0, 0, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, 4)?;
    Ok(SmokeOutput { frames: out, image, size, settle_frames, settle_seconds })
}
