//! The GPU side of `vista view`: vista renders into its own colour and depth
//! targets, exactly as under `vista render`; the frame then blits the colour
//! into the acquired swapchain image, draws the overlay over it, and
//! presents. A screenshot copies the swapchain image in the same command
//! buffer, before it goes to the presentation engine.
//!
//! Field order is drop order: the overlay's renderer and pool, the
//! presenter (waits for the device), the ring, the targets, the terrain
//! renderer, and the context last.

use super::overlay::{Settings, Shown};
use crate::render_cmd::SKY_CLEAR;
use anyhow::{Context as _, Result};
use vista::gpu::present::{Acquired, Presenter};
use vista::gpu::{
    vk, Buffer, BufferDesc, ColorTarget, CommandPool, Context, FrameRing, Image, MemoryLocation, Recorder,
};
use vista::passes::terrain_geometry::{DepthOptions, RenderTargets};
use vista::render::{TerrainRenderer, View};

/// The overlay of one frame, tessellated.
pub struct OverlayFrame {
    pub primitives: Vec<egui::ClippedPrimitive>,
    pub pixels_per_point: f32,
}

pub struct Viewer {
    egui: egui_ash_renderer::Renderer<egui_ash_renderer::allocator::DefaultAllocator>,
    upload_pool: CommandPool,
    pub presenter: Presenter,
    ring: FrameRing,
    targets: Option<Targets>,
    pub renderer: TerrainRenderer,
    pub ctx: Context,
}

struct Targets {
    color: Image,
    depth: Image,
    /// Left UNDEFINED until the first frame's transitions.
    fresh: bool,
}

impl Targets {
    fn new(ctx: &Context, size: [u32; 2], depth: DepthOptions) -> Result<Targets> {
        let (color, depth) = vista::render::offscreen::render_targets(ctx, "view", size, depth.format)?;
        Ok(Targets { color, depth, fresh: true })
    }
}

/// Where a screenshot's texels go, and in what order they come.
pub struct Readback {
    buffer: Buffer,
    size: [u32; 2],
    bgra: bool,
}

impl Viewer {
    pub fn new(ctx: Context, renderer: TerrainRenderer, presenter: Presenter, frames_in_flight: usize) -> Result<Self> {
        let ring = FrameRing::new(&ctx, frames_in_flight)?;
        let upload_pool = CommandPool::new(&ctx, "overlay_uploads")?;
        let mode = egui_ash_renderer::RenderMode::DynamicRendering(egui_ash_renderer::DynamicRendering {
            color_attachment_format: presenter.format(),
            depth_attachment_format: None,
            stencil_attachment_format: None,
        });
        let options = egui_ash_renderer::Options { in_flight_frames: frames_in_flight, ..Default::default() };
        let egui = egui_ash_renderer::Renderer::with_default_allocator(
            ctx.instance(),
            ctx.physical_device(),
            ctx.device().clone(),
            mode,
            options,
        )
        .context("creating the overlay's renderer")?;
        Ok(Viewer { egui, upload_pool, presenter, ring, targets: None, renderer, ctx })
    }

    /// Uploads the overlay's new textures and frees its old ones (rare: the
    /// font atlas). egui-ash-renderer submits and waits on the queue
    /// itself; the viewer records and submits from this thread only.
    pub fn overlay_textures(&mut self, delta: &egui::TexturesDelta) -> Result<()> {
        if !delta.free.is_empty() {
            self.ring.wait_all(&self.ctx)?;
            for id in &delta.free {
                self.egui.free_texture(*id)?;
            }
        }
        let queue = self.ctx.graphics_queue().raw;
        for (id, changes) in &delta.set {
            for change in changes {
                self.egui.set_texture(queue, self.upload_pool.raw(), *id, change)?;
            }
        }
        Ok(())
    }

    /// A buffer for the next frame's screenshot.
    pub fn readback(&self) -> Result<Readback> {
        let [w, h] = self.presenter.extent();
        let buffer = Buffer::new(
            &self.ctx,
            &BufferDesc {
                name: "screenshot",
                size: u64::from(w) * u64::from(h) * 4,
                usage: vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuToCpu,
            },
        )?;
        Ok(Readback { buffer, size: [w, h], bgra: self.presenter.format() == vk::Format::B8G8R8A8_UNORM })
    }

    /// Renders, overlays and presents one frame of `view` (its size the
    /// swapchain's). False: the swapchain must be remade (resize, minimise,
    /// out of date); nothing was rendered or the picture was not shown.
    pub fn frame(&mut self, view: &View, overlay: Option<&OverlayFrame>, shot: Option<&Readback>) -> Result<bool> {
        self.ring.wait_next(&self.ctx)?;
        let Some(acquired) = self.presenter.acquire()? else {
            return Ok(false);
        };
        if self.targets.as_ref().is_none_or(|t| t.color.extent != view.size) {
            self.targets = Some(Targets::new(&self.ctx, view.size, self.renderer.depth())?);
        }
        let targets = self.targets.as_mut().expect("made above");
        let (renderer, egui, presenter) = (&mut self.renderer, &mut self.egui, &self.presenter);
        let swap = presenter.image(acquired.index);
        self.ring.record_synced(&self.ctx, acquired.sync, |rec| {
            if targets.fresh {
                rec.discard_to(&targets.color, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
                rec.discard_to(&targets.depth, renderer.depth().layout());
                targets.fresh = false;
            }
            let rt = RenderTargets::color(&targets.color, &targets.depth, SKY_CLEAR);
            renderer.record(rec, view, &rt)?;
            compose(rec, &targets.color, swap, egui, overlay, shot)
        })?;
        self.present(&acquired)
    }

    fn present(&mut self, acquired: &Acquired) -> Result<bool> {
        Ok(self.presenter.present(acquired)?)
    }

    /// Waits for the screenshot's frame and returns its RGBA8 texels.
    pub fn read(&self, shot: &Readback) -> Result<(Vec<u8>, [u32; 2])> {
        self.ring.wait_all(&self.ctx)?;
        let mut rgba = shot.buffer.mapped().context("the screenshot buffer is not mapped")?.to_vec();
        if shot.bgra {
            rgba.chunks_exact_mut(4).for_each(|p| p.swap(0, 2));
        }
        Ok((rgba, shot.size))
    }

    /// Remakes the swapchain for the window's new size.
    pub fn resize(&mut self, size: [u32; 2]) -> Result<()> {
        self.ring.wait_all(&self.ctx)?;
        Ok(self.presenter.resize(&self.ctx, size)?)
    }

    /// Destroys everything in order and returns the context with what is
    /// still alive of vista's objects (zero, or something leaked).
    pub fn close(self) -> Result<(Context, vista::gpu::LiveObjects)> {
        let Viewer { egui, upload_pool, presenter, ring, targets, renderer, ctx } = self;
        ring.wait_all(&ctx)?;
        drop((egui, upload_pool, presenter, ring, targets, renderer));
        ctx.wait_idle()?;
        let live = ctx.live_objects();
        Ok((ctx, live))
    }
}

/// Blits vista's colour target into the swapchain image, draws the overlay
/// over it, copies it for a screenshot, and leaves it ready to present.
fn compose(
    rec: &mut Recorder,
    color: &Image,
    swap: &Image,
    egui: &mut egui_ash_renderer::Renderer<egui_ash_renderer::allocator::DefaultAllocator>,
    overlay: Option<&OverlayFrame>,
    shot: Option<&Readback>,
) -> vista::error::Result<()> {
    rec.transition(color, vk::ImageLayout::TRANSFER_SRC_OPTIMAL);
    rec.discard_to(swap, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
    rec.blit(color, swap);
    rec.transition(color, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
    if let Some(o) = overlay.filter(|o| !o.primitives.is_empty()) {
        rec.transition(swap, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
        rec.begin_rendering(&[ColorTarget { image: swap, clear: None }], None);
        let extent = vk::Extent2D { width: swap.extent[0], height: swap.extent[1] };
        egui.cmd_draw(rec.raw(), extent, o.pixels_per_point, &o.primitives)
            .map_err(|e| vista::error::Error::Unsupported(format!("drawing the overlay: {e}")))?;
        rec.end_rendering();
    }
    if let Some(s) = shot {
        rec.transition(swap, vk::ImageLayout::TRANSFER_SRC_OPTIMAL);
        rec.copy_image_to_buffer(swap, 0, 0, &s.buffer);
        rec.transfer_to_host_barrier();
    }
    rec.transition(swap, vk::ImageLayout::PRESENT_SRC_KHR);
    Ok(())
}

pub struct Frame<'v> {
    pub view: &'v View,
    pub fps: f64,
    pub camera: String,
    pub speed_mps: f64,
    pub size: [u32; 2],
    pub slots: u32,
}

/// What the overlay shows now.
pub fn shown<'a>(v: &'a Viewer, f: Frame) -> Shown<'a> {
    let t = &v.renderer.terrain;
    let params = f.view.relative_to(v.renderer.origin_m).traverse_params();
    let wanted = vista::reference::wanted_finer_cpu(&t.tree.shadow, &t.world, &params);
    let r = &v.renderer;
    let built = vista::passes::cull_patches::CullStages {
        frustum: true,
        cone: r.cull.build.cone,
        hole: r.cull.build.holes,
        occlusion: r.cull.build.occlusion,
    };
    let memory: u64 = r.memory().iter().map(|(_, bytes, _)| bytes).sum();
    Shown {
        device: &v.ctx.info().name,
        fps: f.fps,
        camera: f.camera,
        speed_mps: f.speed_mps,
        size: f.size,
        timings: r.latest_timings(),
        counters: r.latest_counters(),
        stream: r.terrain.stats(),
        wanted_finer: wanted[..t.world.lod_count as usize].to_vec(),
        slots: f.slots,
        effects: r.effects(),
        built,
        switched_off: r.last_frame_log().map(|l| l.switched_off.clone()).unwrap_or_default(),
        memory_mb: memory as f64 / (1024.0 * 1024.0),
    }
}

/// Applies the overlay's switches to the next frame.
pub fn apply(renderer: &mut TerrainRenderer, settings: &Settings, view: &mut View) {
    view.target_error_px = settings.target_error_px;
    renderer.stages = settings.stages;
    renderer.switches = settings.switches;
    renderer.debug_view = settings.debug_view;
    renderer.effects.lighting = settings.lighting;
}
