//! The headless frame loop of `vista render`, the benchmarks and the tests:
//! owns the targets of the renderer's output (a colour target, or the
//! G-buffer images of output `gbuffer`) and a depth target and a ring of
//! command buffers, records frames through [`TerrainRenderer`] exactly as
//! an engine would (with [`EngineWall`], drawing an "engine's" occluder
//! first into a depth the renderer loads), and reads the last frame back.

use crate::error::Result;
use crate::frame::FrameTimings;
use crate::gpu::{
    depth_layout, vk, ColorTarget, Context, DepthTarget, FrameCommands, FrameRing, Image, ImageDesc, QueueMode,
    Recorder,
};
use crate::passes::terrain_geometry::{RenderTargets, COLOR_FORMAT, DEPTH_FORMAT};
use crate::render::renderer::TerrainRenderer;
use crate::scene::view::{linear_depth, View};
use crate::targets::gbuffer_layout::texel_bytes;
use crate::targets::Output;
use std::time::{Duration, Instant};

/// Longest wait for a load between two frames of [`Offscreen::settle`]
/// when nothing else is under way (a frame then still comes this often).
pub const SETTLE_WAIT: Duration = Duration::from_millis(500);

/// Frames in a row the renderer reports settled before a picture counts as
/// final: the first draws the last set streamed, the second culls against
/// that frame's depth (occlusion culling sees the previous frame).
pub const CALM_FRAMES: u32 = 2;

/// A frame read back: the output's target(s) and the raw reversed-Z depth.
pub struct Capture {
    pub size: [u32; 2],
    /// Output `lit`: the display image, RGBA8 (row 0 at the top; a BGRA
    /// target swizzled); empty otherwise.
    pub rgba: Vec<u8>,
    /// Output `hdr`: the linear radiance, RGBA (alpha 1 for
    /// B10G11R11_UFLOAT); empty otherwise.
    pub hdr: Vec<[f32; 4]>,
    /// Output `gbuffer`: each engine image's texels as stored, in the
    /// layout's order; empty otherwise.
    pub gbuffer: Vec<Vec<u8>>,
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
    let color = colour_target(ctx, &format!("{prefix}_color"), size, COLOR_FORMAT)?;
    Ok((color, depth_target(ctx, &format!("{prefix}_depth"), size, depth_format)?))
}

/// A colour attachment of `format`, readable by transfers.
pub fn colour_target(ctx: &Context, name: &str, size: [u32; 2], format: vk::Format) -> Result<Image> {
    let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC;
    Image::new(ctx, &ImageDesc { name, format, extent: size, mip_levels: 1, array_layers: 1, usage })
}

/// A depth target of `format`, readable by transfers and sampled (the
/// tile shading reads it; occlusion culling reduces it into a pyramid).
pub fn depth_target(ctx: &Context, name: &str, size: [u32; 2], format: vk::Format) -> Result<Image> {
    let usage = vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
        | vk::ImageUsageFlags::TRANSFER_SRC
        | vk::ImageUsageFlags::SAMPLED;
    Image::new(ctx, &ImageDesc { name, format, extent: size, mip_levels: 1, array_layers: 1, usage })
}

/// An "engine's" occluder drawn before the terrain each frame by a
/// renderer that loads the engine's depth (`DepthOptions::load`; the
/// engine's pass clears the targets first, with or without a wall): a wall
/// facing the camera at `distance_m` over the pixels `rect` (x0, y0, x1,
/// y1), filling the colour target (or every G-buffer image) with `colour`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EngineWall {
    pub rect: [u32; 4],
    pub distance_m: f64,
    pub colour: [f32; 4],
}

impl EngineWall {
    /// Reversed-Z depth of a point `distance_m` ahead with an infinite far
    /// plane at near plane `near_m` (`View::projection`'s).
    pub fn depth(&self, near_m: f64) -> f32 {
        (near_m / self.distance_m) as f32
    }
}

/// What an [`Offscreen`] renders: the renderer's output and depth format,
/// and the submission mode.
#[derive(Debug, Clone)]
pub struct OffscreenDesc {
    pub size: [u32; 2],
    pub frames_in_flight: usize,
    /// The colour the targets are cleared to each frame (None: kept, for
    /// a renderer drawing over an engine's frame).
    pub clear: Option<[f32; 4]>,
    pub mode: QueueMode,
    pub depth_format: vk::Format,
    pub output: Output,
}

impl OffscreenDesc {
    pub fn new(size: [u32; 2], clear: [f32; 4]) -> Self {
        OffscreenDesc {
            size,
            frames_in_flight: 2,
            clear: Some(clear),
            mode: QueueMode::Single,
            depth_format: DEPTH_FORMAT,
            output: Output::default(),
        }
    }
}

pub struct Offscreen {
    /// Outputs `lit` and `hdr`: the colour target.
    pub color: Option<Image>,
    /// Output `gbuffer`: the G-buffer images, in the layout's order.
    pub gbuffer: Vec<Image>,
    pub depth: Image,
    ring: FrameRing,
    /// Set once the targets left UNDEFINED for their attachment layouts.
    initialised: bool,
    pub clear: Option<[f32; 4]>,
    /// Drawn before the terrain each frame (a renderer loading the depth).
    pub wall: Option<EngineWall>,
    output: Output,
}

impl Offscreen {
    pub fn new(ctx: &Context, size: [u32; 2], frames_in_flight: usize, clear: [f32; 4]) -> Result<Self> {
        Self::with_desc(ctx, &OffscreenDesc { frames_in_flight, ..OffscreenDesc::new(size, clear) })
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
        Self::with_desc(ctx, &OffscreenDesc { frames_in_flight, depth_format, ..OffscreenDesc::new(size, clear) })
    }

    /// Submitting in `mode` (split modes: a compute and a graphics command
    /// buffer per frame, joined by the ring's timeline semaphores).
    pub fn with_mode(
        ctx: &Context,
        size: [u32; 2],
        frames_in_flight: usize,
        clear: [f32; 4],
        mode: QueueMode,
    ) -> Result<Self> {
        Self::with_desc(ctx, &OffscreenDesc { frames_in_flight, mode, ..OffscreenDesc::new(size, clear) })
    }

    pub fn with_desc(ctx: &Context, d: &OffscreenDesc) -> Result<Self> {
        d.output.check().map_err(crate::Error::BadInput)?;
        let color = match d.output.color_format() {
            Some(format) => Some(colour_target(ctx, "offscreen_color", d.size, format)?),
            None => None,
        };
        let gbuffer = match &d.output {
            Output::Gbuffer(layout) => layout
                .attachments
                .iter()
                .map(|a| colour_target(ctx, &format!("offscreen_gbuffer_{}", a.name), d.size, a.format))
                .collect::<Result<Vec<_>>>()?,
            _ => Vec::new(),
        };
        let depth = depth_target(ctx, "offscreen_depth", d.size, d.depth_format)?;
        let ring = FrameRing::with_mode(ctx, d.frames_in_flight, d.mode)?;
        Ok(Offscreen {
            color,
            gbuffer,
            depth,
            ring,
            initialised: false,
            clear: d.clear,
            wall: None,
            output: d.output.clone(),
        })
    }

    pub fn mode(&self) -> QueueMode {
        self.ring.mode()
    }

    /// The frame's size.
    pub fn size(&self) -> [u32; 2] {
        self.depth.extent
    }

    /// Records and submits one frame (waits only for the ring slot's fence).
    pub fn frame(&mut self, ctx: &Context, renderer: &mut TerrainRenderer, view: &View) -> Result<()> {
        let init = !self.initialised;
        let mode = self.ring.mode();
        let gbuffer: Vec<&Image> = self.gbuffer.iter().collect();
        // A renderer loading the depth draws over the "engine's" frame,
        // which clears the targets (and draws its wall) first.
        let engine = renderer.depth().load;
        let clear = if engine { None } else { self.clear };
        let targets = RenderTargets { color: self.color.as_ref(), gbuffer: &gbuffer, depth: &self.depth, clear };
        let (wall, near_m, engine_clear) = (self.wall, view.near_m, self.clear.unwrap_or_default());
        self.ring.record_frame(ctx, |mut cmds| {
            let graphics = match &mut cmds {
                FrameCommands::One(r) => &mut **r,
                FrameCommands::Split { graphics, .. } => &mut **graphics,
            };
            if init {
                for img in targets.color.iter().chain(targets.gbuffer) {
                    graphics.discard_to(img, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
                }
                graphics.discard_to(targets.depth, depth_layout(targets.depth.format, false));
            }
            if engine {
                engine_pass(graphics, &targets, engine_clear, wall.map(|w| (w, near_m)));
            }
            renderer.record_frame(cmds, mode, view, &targets)
        })?;
        self.initialised = true;
        Ok(())
    }

    /// Renders until streaming is at rest ([`TerrainRenderer::settled`]
    /// after [`CALM_FRAMES`] frames in a row), or until `timeout`.
    pub fn settle(
        &mut self,
        ctx: &Context,
        renderer: &mut TerrainRenderer,
        view: &View,
        timeout: Duration,
    ) -> Result<Settle> {
        let start = Instant::now();
        let (mut frames, mut calm) = (0, 0u32);
        loop {
            self.frame(ctx, renderer, view)?;
            frames += 1;
            calm = if renderer.settled() { calm + 1 } else { 0 };
            if calm >= CALM_FRAMES {
                return Ok(Settle { frames, seconds: start.elapsed().as_secs_f64(), settled: true });
            }
            if start.elapsed() >= timeout {
                return Ok(Settle { frames, seconds: start.elapsed().as_secs_f64(), settled: false });
            }
            // Give the loader threads the cores while nodes are baking; where
            // only loads are under way, the next frame would draw this one
            // again: wait for a load instead (a root's error tile takes
            // seconds, and lavapipe's frames take the same cores).
            if renderer.only_loading() {
                renderer.terrain.wait_for_load(SETTLE_WAIT);
            } else if calm == 0 {
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
        let size = self.depth.extent;
        let raw = ctx.read_image(&self.depth, 0, 0, 4)?;
        let mut capture = Capture {
            size,
            rgba: Vec::new(),
            hdr: Vec::new(),
            gbuffer: Vec::new(),
            depth: bytemuck::pod_collect_to_vec(&raw),
        };
        match (&self.output, &self.color) {
            (Output::Lit { format }, Some(color)) => {
                capture.rgba = ctx.read_image(color, 0, 0, 4)?;
                if matches!(*format, vk::Format::B8G8R8A8_UNORM | vk::Format::B8G8R8A8_SRGB) {
                    capture.rgba.chunks_exact_mut(4).for_each(|p| p.swap(0, 2));
                }
            }
            (Output::Hdr { format, .. }, Some(color)) => {
                let bytes = ctx.read_image(color, 0, 0, texel_bytes_hdr(*format))?;
                capture.hdr = decode_hdr(*format, &bytes);
            }
            _ => {
                for img in &self.gbuffer {
                    capture.gbuffer.push(ctx.read_image(img, 0, 0, texel_bytes(img.format) as u64)?);
                }
            }
        }
        Ok(capture)
    }
}

/// The "engine's" pass before vista's: clears the frame's targets (colour
/// to `clear`, depth to far, stencil to 0) and draws the wall (at the
/// view's near plane `near_m`), leaving them in their frame layouts.
fn engine_pass(rec: &mut Recorder, targets: &RenderTargets, clear: [f32; 4], wall: Option<(EngineWall, f64)>) {
    let colours: Vec<ColorTarget> =
        targets.color.iter().chain(targets.gbuffer).map(|image| ColorTarget { image, clear: Some(clear) }).collect();
    let depth = DepthTarget { image: targets.depth, clear: Some(0.0), clear_stencil: true, read_only: false };
    rec.begin_rendering(&colours, Some(depth));
    if let Some((w, near_m)) = wall {
        rec.clear_rect(w.rect, w.colour, Some(w.depth(near_m)));
    }
    rec.end_rendering();
}

fn texel_bytes_hdr(format: vk::Format) -> u64 {
    if format == vk::Format::B10G11R11_UFLOAT_PACK32 {
        4
    } else {
        8
    }
}

/// The texels of an `hdr` target as RGBA floats.
pub fn decode_hdr(format: vk::Format, bytes: &[u8]) -> Vec<[f32; 4]> {
    if format == vk::Format::B10G11R11_UFLOAT_PACK32 {
        return bytes
            .chunks_exact(4)
            .map(|c| {
                let v = u32::from_le_bytes([c[0], c[1], c[2], c[3]]);
                [small_float(v & 0x7FF, 6), small_float((v >> 11) & 0x7FF, 6), small_float(v >> 22, 5), 1.0]
            })
            .collect();
    }
    let halves: Vec<u16> = bytemuck::pod_collect_to_vec(bytes);
    halves.chunks_exact(4).map(|c| [0, 1, 2, 3].map(|i| half::f16::from_bits(c[i]).to_f32())).collect()
}

/// An unsigned small float: a 5-bit exponent (bias 15) over `mantissa_bits`.
fn small_float(bits: u32, mantissa_bits: u32) -> f32 {
    let exponent = (bits >> mantissa_bits) as i32;
    let mantissa = (bits & ((1 << mantissa_bits) - 1)) as f32 / (1 << mantissa_bits) as f32;
    match exponent {
        0 => mantissa * 2f32.powi(-14),
        31 => f32::INFINITY,
        e => (1.0 + mantissa) * 2f32.powi(e - 15),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_floats_decode() {
        // 1.0: exponent 15, mantissa 0, in each field.
        let one = 15 << 6 | (15 << 6) << 11 | (15 << 5) << 22;
        assert_eq!(decode_hdr(vk::Format::B10G11R11_UFLOAT_PACK32, &(one as u32).to_le_bytes())[0], [1.0; 4]);
        assert_eq!(small_float(16 << 6 | 32, 6), 3.0);
        assert_eq!(small_float(1, 5), 2f32.powi(-14) / 32.0);
    }
}
