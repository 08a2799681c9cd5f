//! `smoke_triangle`: one triangle with push-constant corners into an RGBA8
//! target: proves raster, dynamic rendering and readback.

use vista::gpu::{vk, ColorTarget, Context, GraphicsPipelineDesc, Image, Pipeline, Recorder};
use vista::shaders::{smoke_triangle_frag, smoke_triangle_vert};
use vista::Result;

/// Colour format of the smoke targets.
pub const TARGET_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SmokeTrianglePush {
    /// Clip-space corners (x, y, z, w).
    pub corners: [[f32; 4]; 3],
}

pub struct SmokeTriangle {
    pipeline: Pipeline,
}

impl SmokeTriangle {
    pub const NAME: &'static str = smoke_triangle_vert::PASS;

    pub fn new(ctx: &Context) -> Result<Self> {
        let desc = GraphicsPipelineDesc {
            name: Self::NAME,
            vertex: &smoke_triangle_vert::SHADER,
            fragment: &smoke_triangle_frag::SHADER,
            specialization: &[],
            color_formats: &[TARGET_FORMAT],
            depth_format: None,
            depth_compare: vk::CompareOp::ALWAYS,
            depth_write: true,
            stencil: None,
            cull_mode: vk::CullModeFlags::NONE,
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            blend: false,
        };
        Ok(SmokeTriangle { pipeline: Pipeline::graphics(ctx, &desc)? })
    }

    /// `target` must be in COLOR_ATTACHMENT_OPTIMAL; it is cleared first.
    pub fn record(&self, rec: &mut Recorder, target: &Image, corners: [[f32; 4]; 3]) {
        rec.begin_rendering(&[ColorTarget { image: target, clear: Some([0.0; 4]) }], None);
        rec.bind_pipeline(&self.pipeline);
        rec.push_constants(&self.pipeline, &SmokeTrianglePush { corners });
        rec.draw(3, 1);
        rec.end_rendering();
    }
}
