//! `quadtree_update`: applies a frame's coalesced node-texture and
//! node-description writes from the upload ring (Far Cry 5: one compute
//! dispatch per frame adds and removes nodes).

use crate::error::Result;
use crate::gpu::{vk, Binding, ComputePipelineDesc, Context, Pipeline, Recorder, Resource};
use crate::shaders::quadtree_update as sh;
use crate::terrain::gpu_quadtree::GpuQuadtree;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct QuadtreeUpdatePush {
    pub count: u32,
}

/// The node-texture bindings, LOD 0 first (one storage view per mip).
const NODE_LODS: [Binding; 10] = [
    sh::NODE_LOD0,
    sh::NODE_LOD1,
    sh::NODE_LOD2,
    sh::NODE_LOD3,
    sh::NODE_LOD4,
    sh::NODE_LOD5,
    sh::NODE_LOD6,
    sh::NODE_LOD7,
    sh::NODE_LOD8,
    sh::NODE_LOD9,
];

pub struct QuadtreeUpdatePass {
    pipeline: Pipeline,
}

impl QuadtreeUpdatePass {
    pub const NAME: &'static str = sh::PASS;

    pub fn new(ctx: &Context) -> Result<Self> {
        let desc = ComputePipelineDesc { name: Self::NAME, shader: &sh::SHADER, specialization: &[] };
        Ok(QuadtreeUpdatePass { pipeline: Pipeline::compute(ctx, &desc)? })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// Uploads the frame's payloads and applies its changes; the results are
    /// visible to every later command. Returns the number of writes.
    pub fn record(&self, rec: &mut Recorder, tree: &mut GpuQuadtree) -> Result<u32> {
        let count = tree.prepare_frame(rec)?;
        let updates = tree.current_updates();
        if count > 0 {
            let mips = tree.node_texture.mip_levels;
            let mut bindings: Vec<(Binding, Resource)> = vec![
                (sh::UPDATES, Resource::Buffer(updates)),
                (sh::NODE_DESCS, Resource::Buffer(&tree.node_descs)),
                (sh::NODE_ERRORS, Resource::Buffer(&tree.node_errors)),
            ];
            for (lod, b) in NODE_LODS.iter().enumerate() {
                // LODs past the world's count are never written: bind mip 0.
                let mip = if (lod as u32) < mips { lod as u32 } else { 0 };
                bindings.push((*b, Resource::ImageMip(&tree.node_texture, mip, vk::ImageLayout::GENERAL)));
            }
            rec.barrier(vk::PipelineStageFlags2::ALL_COMMANDS, vk::PipelineStageFlags2::COMPUTE_SHADER);
            rec.bind_pipeline(&self.pipeline);
            rec.push_descriptors(&self.pipeline, &bindings);
            rec.push_constants(&self.pipeline, &QuadtreeUpdatePush { count });
            rec.dispatch(count.div_ceil(sh::WORKGROUP_SIZE[0]), 1, 1);
        }
        rec.barrier(vk::PipelineStageFlags2::ALL_COMMANDS, vk::PipelineStageFlags2::ALL_COMMANDS);
        Ok(count)
    }
}
