//! `cliff_meshes` (effect `cliff_meshes`): every cell `cliff_mesh_build`
//! listed in ONE indexed indirect draw (instance = cell) into the geometry
//! pass's targets, after the terrain, so the tile passes shade the meshes
//! with the cliff flavours their steep normals classify them into.

use crate::error::Result;
use crate::gpu::{vk, Buffer, Context, GraphicsPipelineDesc, Pipeline, Recorder, Resource, StencilDesc};
use crate::passes::terrain_geometry::{begin_geometry, DepthOptions, RenderTargets};
use crate::render::gbuffer::{GBuffer, CLASSIFICATION_FORMAT, GEOMETRY_NORMALS_FORMAT, PATCH_INFO_FORMAT};
use crate::shaders::{cliff_meshes_frag as fs, cliff_meshes_vert as vs};

pub struct CliffMeshDraw {
    pipeline: Pipeline,
    depth: DepthOptions,
}

impl CliffMeshDraw {
    pub const NAME: &'static str = vs::PASS;

    pub fn new(ctx: &Context, depth: DepthOptions) -> Result<Self> {
        let desc = GraphicsPipelineDesc {
            name: Self::NAME,
            vertex: &vs::SHADER,
            fragment: &fs::SHADER,
            specialization: &[],
            color_formats: &[CLASSIFICATION_FORMAT, GEOMETRY_NORMALS_FORMAT, PATCH_INFO_FORMAT],
            depth_format: Some(depth.format),
            depth_compare: vk::CompareOp::GREATER,
            depth_write: true,
            // Terrain to the engine: the terrain stencil bit.
            stencil: depth.terrain_stencil_bit.map(|_| StencilDesc {
                compare: vk::CompareOp::ALWAYS,
                reference: depth.stencil_mask(),
                compare_mask: 0,
                write_mask: depth.stencil_mask(),
            }),
            cull_mode: vk::CullModeFlags::BACK,
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            blend: false,
        };
        Ok(CliffMeshDraw { pipeline: Pipeline::graphics(ctx, &desc)?, depth })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// Draws over the terrain's geometry pass (its targets loaded).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder,
        targets: &RenderTargets,
        gbuffer: &GBuffer,
        view: &Buffer,
        vertices: &Buffer,
        indices: &Buffer,
        header: &Buffer,
    ) {
        begin_geometry(rec, targets, gbuffer, self.depth, false);
        rec.bind_pipeline(&self.pipeline);
        rec.push_descriptors(
            &self.pipeline,
            &[(vs::VIEW, Resource::Buffer(view)), (vs::VERTICES, Resource::Buffer(vertices))],
        );
        rec.draw_indexed_indirect(indices, header, 0);
        rec.end_rendering();
    }
}
