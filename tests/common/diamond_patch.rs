//! `diamond_patch`: an n x n quad patch covering the target, drawn with the
//! diamond index pattern; one vertex may be made NaN at run time to cut a
//! hole (the terrain hole mechanism, tested in isolation).

use super::smoke_triangle::TARGET_FORMAT;
use vista::gpu::{
    vk, Buffer, BufferDesc, ColorTarget, Context, GraphicsPipelineDesc, Image, MemoryLocation, Pipeline, Recorder,
};
use vista::shaders::{diamond_patch_frag, diamond_patch_vert};
use vista::terrain::patch_grid::diamond_indices;
use vista::Result;

/// Bits of a quiet NaN; passed as data so no compiler folds it.
pub const QUIET_NAN_BITS: u32 = 0x7FC0_0000;
/// `hole_vertex` value meaning "no hole".
pub const NO_HOLE: u32 = u32::MAX;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct DiamondPatchPush {
    pub quads_per_side: u32,
    pub hole_vertex: u32,
    pub nan_bits: u32,
    pub pad: u32,
}

pub struct DiamondPatch {
    pipeline: Pipeline,
    indices: Buffer,
    quads: u32,
}

impl DiamondPatch {
    pub const NAME: &'static str = diamond_patch_vert::PASS;

    pub fn new(ctx: &Context, quads_per_side: u32) -> Result<Self> {
        let desc = GraphicsPipelineDesc {
            name: Self::NAME,
            vertex: &diamond_patch_vert::SHADER,
            fragment: &diamond_patch_frag::SHADER,
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
        let pipeline = Pipeline::graphics(ctx, &desc)?;
        let idx = diamond_indices(quads_per_side);
        let indices = Buffer::new(
            ctx,
            &BufferDesc {
                name: "diamond_patch_indices",
                size: (idx.len() * 4) as u64,
                usage: vk::BufferUsageFlags::INDEX_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuOnly,
            },
        )?;
        ctx.upload(&indices, bytemuck::cast_slice(&idx))?;
        Ok(DiamondPatch { pipeline, indices, quads: quads_per_side })
    }

    /// Vertex index of grid point (x, y).
    pub fn vertex(&self, x: u32, y: u32) -> u32 {
        y * (self.quads + 1) + x
    }

    /// `target` must be in COLOR_ATTACHMENT_OPTIMAL; it is cleared first.
    pub fn record(&self, rec: &mut Recorder, target: &Image, hole_vertex: Option<u32>) {
        rec.begin_rendering(&[ColorTarget { image: target, clear: Some([0.0; 4]) }], None);
        rec.bind_pipeline(&self.pipeline);
        let push = DiamondPatchPush {
            quads_per_side: self.quads,
            hole_vertex: hole_vertex.unwrap_or(NO_HOLE),
            nan_bits: QUIET_NAN_BITS,
            pad: 0,
        };
        rec.push_constants(&self.pipeline, &push);
        rec.draw_indexed(&self.indices, self.quads * self.quads * 6, 1);
        rec.end_rendering();
    }
}
