//! `cliff_meshes` (effect `cliff_meshes`): every cell `cliff_mesh_build`
//! listed in ONE indexed indirect draw (instance = cell) into the geometry
//! pass's targets, after the terrain, so the tile passes shade the meshes
//! with the cliff flavours their steep normals classify them into.

use crate::error::Result;
use crate::gpu::{Buffer, Context, Pipeline, Recorder, Resource};
use crate::passes::terrain_geometry::{begin_geometry, geometry_pipeline, DepthOptions, RenderTargets};
use crate::shaders::{cliff_meshes_frag as fs, cliff_meshes_vert as vs};
use crate::targets::gbuffer::GBuffer;

pub struct CliffMeshDraw {
    pipeline: Pipeline,
    depth: DepthOptions,
}

impl CliffMeshDraw {
    pub const NAME: &'static str = vs::PASS;

    pub fn new(ctx: &Context, depth: DepthOptions) -> Result<Self> {
        Ok(CliffMeshDraw {
            pipeline: geometry_pipeline(ctx, Self::NAME, (&vs::SHADER, &fs::SHADER), &[], depth)?,
            depth,
        })
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
