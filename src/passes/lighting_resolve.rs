//! `lighting_resolve`: the lit output of the tools and tests, from the
//! G-buffer: sun plus sky ambient (variant LIGHTING, the `lighting` effect)
//! or unlit albedo, into the caller's colour target (display-encoded: the
//! lit image exposed and through the scene's tonemapper, `render/tonemap.rs`;
//! unlit albedo clipped) and the renderer's HDR image, one full-screen triangle stencil-tested
//! against the terrain bit so the background keeps the clear colour. It
//! leaves the depth target in its frame layout. An engine lights the
//! G-buffer itself and can leave this pass out of its frame.

use crate::error::Result;
use crate::gpu::{
    depth_layout, vk, Buffer, ColorTarget, Context, DepthTarget, GraphicsPipelineDesc, Pipeline, Recorder, Resource,
    Sampler,
};
use crate::passes::cull_patches::nearest_sampler;
use crate::passes::terrain_geometry::{RenderTargets, COLOR_FORMAT, DEPTH_FORMAT, TERRAIN_ONLY};
use crate::render::gbuffer::{GBuffer, HDR_FORMAT};
use crate::shaders::{lighting_resolve_frag as fs, lighting_resolve_vert as vs};

pub struct LightingResolve {
    pipeline: Pipeline,
    nearest: Sampler,
}

impl LightingResolve {
    pub const NAME: &'static str = vs::PASS;

    pub fn new(ctx: &Context, lighting: bool) -> Result<Self> {
        let desc = GraphicsPipelineDesc {
            name: Self::NAME,
            vertex: &vs::SHADER,
            fragment: fs::variant(if lighting { fs::VARIANT_LIGHTING } else { 0 }),
            specialization: &[],
            color_formats: &[COLOR_FORMAT, HDR_FORMAT],
            depth_format: Some(DEPTH_FORMAT),
            depth_compare: vk::CompareOp::ALWAYS,
            depth_write: false,
            stencil: Some(TERRAIN_ONLY),
            cull_mode: vk::CullModeFlags::NONE,
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
        };
        Ok(LightingResolve {
            pipeline: Pipeline::graphics(ctx, &desc)?,
            nearest: nearest_sampler(ctx, "lighting_resolve_nearest")?,
        })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// Expects the depth target in DEPTH_STENCIL_READ_ONLY_OPTIMAL (after
    /// `gbuffer_tiles`); leaves it writable again.
    pub fn record(&self, rec: &mut Recorder, targets: &RenderTargets, gbuffer: &GBuffer, view: &Buffer) {
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        rec.transition(&gbuffer.albedo, read);
        rec.transition(&gbuffer.normal, read);
        rec.discard_to(&gbuffer.hdr, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
        rec.begin_rendering(
            &[
                ColorTarget { image: targets.color, clear: Some(targets.clear) },
                ColorTarget { image: &gbuffer.hdr, clear: Some(targets.clear) },
            ],
            Some(DepthTarget { image: targets.depth, clear: None, read_only: true }),
        );
        rec.bind_pipeline(&self.pipeline);
        rec.push_descriptors(
            &self.pipeline,
            &[
                (fs::VIEW, Resource::Buffer(view)),
                (fs::GB_ALBEDO, Resource::Image(&gbuffer.albedo, read)),
                (fs::GB_NORMAL, Resource::Image(&gbuffer.normal, read)),
                (fs::NEAREST, Resource::Sampler(self.nearest.raw())),
            ],
        );
        rec.draw(3, 1);
        rec.end_rendering();
        rec.transition(targets.depth, depth_layout(DEPTH_FORMAT, false));
    }
}
