//! `terrain_holes`: the patches that have some holes (the hole list of
//! `cull_patches`) in one instanced indexed-indirect draw over the image
//! `terrain_geometry` drew. Only this vertex shader tests holes: a hole
//! vertex becomes NaN (made at run time from bits passed in) and the
//! rasterizer drops its triangles. Built only with the `holes` effect; a
//! frame with no such patch in view runs it with zero instances.

use crate::error::Result;
use crate::gpu::{Context, Pipeline, Recorder, Resource};
use crate::passes::cull_patches::PatchLists;
use crate::passes::terrain_geometry::{
    begin_geometry, terrain_pipeline, DepthOptions, RenderTargets, TerrainDrawPush, TerrainGeometry,
};
use crate::shaders::terrain_holes_vert as vs;
use crate::targets::gbuffer::GBuffer;
use crate::terrain::gpu_quadtree::{GpuQuadtree, ATLAS_ALBEDO, ATLAS_LAYOUT};

pub struct TerrainHoles {
    pipeline: Pipeline,
}

impl TerrainHoles {
    pub const NAME: &'static str = vs::PASS;

    /// `sink`: as `terrain_geometry`'s (both draw the same terrain).
    pub fn new(ctx: &Context, depth: DepthOptions, sink: bool) -> Result<Self> {
        Ok(TerrainHoles { pipeline: terrain_pipeline(ctx, Self::NAME, &vs::SHADER, depth, sink)? })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// Draws a hole list (phase 1's, or phase 2's when `late`) over the
    /// targets (kept, not cleared).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder,
        targets: &RenderTargets,
        gbuffer: &GBuffer,
        view: &crate::gpu::Buffer,
        lists: &PatchLists,
        geometry: &TerrainGeometry,
        tree: &GpuQuadtree,
        sink: Option<&crate::gpu::Buffer>,
        late: bool,
    ) {
        let list = lists.hole_list.as_ref().expect("terrain_holes is built only with the hole list");
        begin_geometry(rec, targets, gbuffer, geometry.depth(), false);
        let albedo = (vs::ALBEDO_ATLAS, Resource::Image(tree.required_atlas(ATLAS_ALBEDO), ATLAS_LAYOUT));
        geometry.bind(rec, &self.pipeline, view, list, tree, sink, &[albedo]);
        rec.push_constants(&self.pipeline, &TerrainDrawPush::new(late));
        rec.draw_indexed_indirect(geometry.indices(), list, 0);
        rec.end_rendering();
    }
}
