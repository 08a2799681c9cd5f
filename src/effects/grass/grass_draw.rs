//! `grass_draw` (effect `grass`): every tuft `grass_place` kept in ONE
//! instanced indirect draw (its header's arguments) into the G-buffer
//! `gbuffer_tiles` wrote, depth-tested and depth-writing against the
//! terrain, so `lighting_resolve` lights grass as it lights the ground.
//! Blades are made in the vertex shader from the vertex index: no vertex
//! or index buffer.

use crate::error::Result;
use crate::gpu::{vk, Buffer, Context, Image, Pipeline, Recorder, Resource, Sampler};
use crate::passes::gbuffer_tiles::GbufferTiles;
use crate::passes::terrain_geometry::RenderTargets;
use crate::shaders::{grass_draw_frag as fs, grass_draw_vert as vs, structs};
use crate::targets::gbuffer::GBuffer;
use crate::targets::GbufferLayout;

/// Host twin of `GrassDrawPush`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GrassDrawPush {
    pub pigment_origin_m: [f32; 2],
    pub pigment_size_m: f32,
    pub width_per_m: f32,
}

const _: () = assert!(std::mem::size_of::<GrassDrawPush>() == structs::GRASS_DRAW_PUSH);

/// What the draw reads.
pub struct DrawInputs<'a> {
    pub view: &'a Buffer,
    pub header: &'a Buffer,
    pub instances: &'a Buffer,
    pub rules: &'a Buffer,
    /// In GENERAL layout (grass_pigment's).
    pub pigment: &'a Image,
}

pub struct GrassDraw {
    pipeline: Pipeline,
    linear: Sampler,
}

impl GrassDraw {
    pub const NAME: &'static str = vs::PASS;

    /// `layout`: the engine's G-buffer (output `gbuffer`), else vista's.
    pub fn new(ctx: &Context, depth_format: vk::Format, layout: Option<&GbufferLayout>) -> Result<Self> {
        Ok(GrassDraw {
            pipeline: GbufferTiles::overlay_pipeline(
                ctx,
                Self::NAME,
                (&vs::SHADER, fs::variant(if layout.is_some() { fs::VARIANT_ENGINE_GBUFFER } else { 0 })),
                depth_format,
                // Blades are seen from both sides.
                vk::CullModeFlags::NONE,
                layout,
            )?,
            linear: crate::passes::cull_patches::linear_clamp_sampler(ctx, "grass_draw_linear")?,
        })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// Draws into the G-buffer's albedo, normal and material (colour
    /// attachments, as gbuffer_tiles leaves them) and the depth (read-only
    /// on entry and exit, as gbuffer_tiles leaves it and lighting_resolve
    /// expects it).
    pub fn record(
        &self,
        rec: &mut Recorder,
        targets: &RenderTargets,
        gbuffer: &GBuffer,
        inputs: &DrawInputs,
        push: GrassDrawPush,
    ) {
        GbufferTiles::begin_overlay(rec, targets, gbuffer);
        rec.bind_pipeline(&self.pipeline);
        rec.push_descriptors(
            &self.pipeline,
            &[
                (vs::VIEW, Resource::Buffer(inputs.view)),
                (vs::INSTANCES, Resource::Buffer(inputs.instances)),
                (vs::RULES, Resource::Buffer(inputs.rules)),
                (vs::PIGMENT, Resource::Image(inputs.pigment, vk::ImageLayout::GENERAL)),
                (vs::LINEAR_CLAMP, Resource::Sampler(self.linear.raw())),
            ],
        );
        rec.push_constants(&self.pipeline, &push);
        rec.draw_indirect(inputs.header, 0);
        GbufferTiles::end_overlay(rec, targets);
    }
}
