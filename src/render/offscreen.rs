//! The headless frame loop of `vista render`, the benchmarks and the tests:
//! owns a colour and a depth target and a ring of command buffers, records
//! frames through [`TerrainRenderer`] exactly as an engine would, and reads
//! the last picture back.

use crate::error::Result;
use crate::frame::FrameTimings;
use crate::gpu::{depth_layout, vk, Context, FrameCommands, FrameRing, Image, ImageDesc, QueueMode};
use crate::passes::terrain_geometry::{RenderTargets, COLOR_FORMAT, DEPTH_FORMAT};
use crate::render::renderer::TerrainRenderer;
use crate::render::view::{linear_depth, View};
use std::time::{Duration, Instant};

/// A frame read back: RGBA8 (row 0 at the top) and the raw reversed-Z depth.
pub struct Capture {
    pub size: [u32; 2],
    pub rgba: Vec<u8>,
    pub depth: Vec<f32>,
}

impl Capture {
    /// Linear view depth in metres along the forward axis, 0 where no terrain.
    pub fn linear_depth(&self, near_m: f64) -> Vec<f32> {
        self.depth.iter().map(|&d| linear_depth(d, near_m)).collect()
    }

    pub fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        let i = ((y * self.size[0] + x) * 4) as usize;
        [self.rgba[i], self.rgba[i + 1], self.rgba[i + 2], self.rgba[i + 3]]
    }
}

/// How long streaming took to settle before the measured frames.
#[derive(Debug, Clone, Copy, Default)]
pub struct Settle {
    pub frames: u32,
    pub seconds: f64,
    /// False when the timeout ended the wait with loads still outstanding.
    pub settled: bool,
}

/// A colour and a depth target (in `depth_format`) a frame of `size`
/// renders into, named `{prefix}_color` / `{prefix}_depth`, both readable
/// by transfers.
pub fn render_targets(ctx: &Context, prefix: &str, size: [u32; 2], depth_format: vk::Format) -> Result<(Image, Image)> {
    let image = |what: &str, format, usage| {
        let name = format!("{prefix}_{what}");
        Image::new(ctx, &ImageDesc { name: &name, format, extent: size, mip_levels: 1, array_layers: 1, usage })
    };
    let color =
        image("color", COLOR_FORMAT, vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC)?;
    let depth = image(
        "depth",
        depth_format,
        // Sampled: occlusion culling reduces it into a depth pyramid.
        vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
            | vk::ImageUsageFlags::TRANSFER_SRC
            | vk::ImageUsageFlags::SAMPLED,
    )?;
    Ok((color, depth))
}

pub struct Offscreen {
    pub color: Image,
    pub depth: Image,
    ring: FrameRing,
    /// Set once the targets left UNDEFINED for their attachment layouts.
    initialised: bool,
    pub clear: [f32; 4],
}

impl Offscreen {
    pub fn new(ctx: &Context, size: [u32; 2], frames_in_flight: usize, clear: [f32; 4]) -> Result<Self> {
        Self::with_mode(ctx, size, frames_in_flight, clear, QueueMode::Single)
    }

    /// As `new`, with a depth target in `depth_format` (a renderer built
    /// with those `DepthOptions`).
    pub fn with_depth_format(
        ctx: &Context,
        size: [u32; 2],
        frames_in_flight: usize,
        clear: [f32; 4],
        depth_format: vk::Format,
    ) -> Result<Self> {
        Self::make(ctx, size, frames_in_flight, clear, QueueMode::Single, depth_format)
    }

    /// Submitting in `mode` (split modes: a compute and a graphics command
    /// buffer per frame, joined by the ring's timeline semaphore).
    pub fn with_mode(
        ctx: &Context,
        size: [u32; 2],
        frames_in_flight: usize,
        clear: [f32; 4],
        mode: QueueMode,
    ) -> Result<Self> {
        Self::make(ctx, size, frames_in_flight, clear, mode, DEPTH_FORMAT)
    }

    fn make(
        ctx: &Context,
        size: [u32; 2],
        frames_in_flight: usize,
        clear: [f32; 4],
        mode: QueueMode,
        depth_format: vk::Format,
    ) -> Result<Self> {
        let (color, depth) = render_targets(ctx, "offscreen", size, depth_format)?;
        let ring = FrameRing::with_mode(ctx, frames_in_flight, mode)?;
        Ok(Offscreen { color, depth, ring, initialised: false, clear })
    }

    pub fn mode(&self) -> QueueMode {
        self.ring.mode()
    }

    /// Records and submits one frame (waits only for the ring slot's fence).
    pub fn frame(&mut self, ctx: &Context, renderer: &mut TerrainRenderer, view: &View) -> Result<()> {
        let (color, depth, clear, init) = (&self.color, &self.depth, self.clear, !self.initialised);
        let mode = self.ring.mode();
        self.ring.record_frame(ctx, |mut cmds| {
            if init {
                let graphics = match &mut cmds {
                    FrameCommands::One(r) => &mut **r,
                    FrameCommands::Split { graphics, .. } => &mut **graphics,
                };
                graphics.discard_to(color, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
                graphics.discard_to(depth, depth_layout(depth.format, false));
            }
            renderer.record_frame(cmds, mode, view, &RenderTargets { color, depth, clear })
        })?;
        self.initialised = true;
        Ok(())
    }

    /// Renders until streaming is at rest (nothing loading or waiting for
    /// upload after two frames in a row: the second shows that the first's
    /// arrivals asked for nothing more), or until `timeout`.
    pub fn settle(
        &mut self,
        ctx: &Context,
        renderer: &mut TerrainRenderer,
        view: &View,
        timeout: Duration,
    ) -> Result<Settle> {
        let start = Instant::now();
        let (mut frames, mut calm) = (0, 0);
        loop {
            self.frame(ctx, renderer, view)?;
            frames += 1;
            calm = if renderer.settled() { calm + 1 } else { 0 };
            if calm >= 2 {
                return Ok(Settle { frames, seconds: start.elapsed().as_secs_f64(), settled: true });
            }
            if start.elapsed() >= timeout {
                return Ok(Settle { frames, seconds: start.elapsed().as_secs_f64(), settled: false });
            }
            // Give the loader threads the cores while nodes are baking.
            if calm == 0 {
                std::thread::sleep(Duration::from_millis(10));
            }
        }
    }

    /// Renders `frames` frames and returns the timings of every frame that
    /// came back meanwhile (one frame late: the last frame's are not among
    /// them), oldest first.
    pub fn run(
        &mut self,
        ctx: &Context,
        renderer: &mut TerrainRenderer,
        view: &View,
        frames: u32,
    ) -> Result<Vec<FrameTimings>> {
        self.run_observed(ctx, renderer, view, frames, || {})
    }

    /// As [`Self::run`], calling `each` after every frame (progress).
    pub fn run_observed(
        &mut self,
        ctx: &Context,
        renderer: &mut TerrainRenderer,
        view: &View,
        frames: u32,
        mut each: impl FnMut(),
    ) -> Result<Vec<FrameTimings>> {
        let mut out: Vec<FrameTimings> = Vec::new();
        for _ in 0..frames {
            self.frame(ctx, renderer, view)?;
            each();
            if let Some(t) = renderer.latest_timings() {
                if out.last().is_none_or(|l| l.frame < t.frame) {
                    out.push(t.clone());
                }
            }
        }
        Ok(out)
    }

    /// Waits for every submitted frame and reads the targets back.
    pub fn capture(&self, ctx: &Context) -> Result<Capture> {
        self.ring.wait_all(ctx)?;
        let size = self.color.extent;
        let rgba = ctx.read_image(&self.color, 0, 0, 4)?;
        let raw = ctx.read_image(&self.depth, 0, 0, 4)?;
        Ok(Capture { size, rgba, depth: bytemuck::pod_collect_to_vec(&raw) })
    }
}
