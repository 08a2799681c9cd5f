//! `cliff_mesh_build` (effect `cliff_meshes`): one thread per world-grid
//! cell within the radius lists the steep ones and writes their patch of
//! the height field pushed out along its normal (effects/cliff_meshes);
//! the header counts them for `cliff_meshes`' indirect draw.

use crate::error::Result;
use crate::gpu::{vk, Buffer, ComputePipelineDesc, Context, Pipeline, Recorder, Resource, Sampler};
use crate::passes::cull_patches::nearest_sampler;
use crate::passes::terrain_query::VistaTerrain;
use crate::shaders::cliff_mesh_build as sh;
use crate::terrain::gpu_quadtree::{GpuQuadtree, ATLAS_HEIGHT, ATLAS_LAYOUT};

/// Host twin of `CliffBuildPush`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CliffBuildPush {
    pub terrain: VistaTerrain,
    pub cell0: [i32; 2],
    pub side: u32,
    pub capacity: u32,
    pub cell_m: f32,
    /// Cells whose centre lies this close to `centre` are built.
    pub reach_m: f32,
    pub cos_start: f32,
    pub cos_full: f32,
    pub amplitude_m: f32,
    pub step_m: f32,
    pub seed: u32,
    pub pad: u32,
    pub centre: [f32; 2],
}

pub struct CliffMeshBuild {
    pipeline: Pipeline,
    nearest: Sampler,
}

impl CliffMeshBuild {
    pub const NAME: &'static str = sh::PASS;

    pub fn new(ctx: &Context) -> Result<Self> {
        let desc = ComputePipelineDesc { name: Self::NAME, shader: &sh::SHADER, specialization: &[] };
        Ok(CliffMeshBuild {
            pipeline: Pipeline::compute(ctx, &desc)?,
            nearest: nearest_sampler(ctx, "cliff_mesh_nearest")?,
        })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// Builds into `vertices`, counting in `header` and marking the cells
    /// in `sink` (both reset by the caller).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder,
        push: &CliffBuildPush,
        sector_data: &Buffer,
        tree: &GpuQuadtree,
        header: &Buffer,
        vertices: &Buffer,
        sink: &Buffer,
    ) {
        rec.bind_pipeline(&self.pipeline);
        rec.push_descriptors(
            &self.pipeline,
            &[
                (sh::SECTOR_DATA, Resource::Buffer(sector_data)),
                (sh::HEIGHT_ATLAS, Resource::Image(tree.required_atlas(ATLAS_HEIGHT), ATLAS_LAYOUT)),
                (sh::NEAREST, Resource::Sampler(self.nearest.raw())),
                (sh::HEADER, Resource::Buffer(header)),
                (sh::VERTICES, Resource::Buffer(vertices)),
                (sh::SINK, Resource::Buffer(sink)),
            ],
        );
        rec.push_constants(&self.pipeline, push);
        rec.dispatch((push.side * push.side).div_ceil(sh::WORKGROUP_SIZE[0]), 1, 1);
        rec.barrier(vk::PipelineStageFlags2::COMPUTE_SHADER, vk::PipelineStageFlags2::ALL_COMMANDS);
    }
}
