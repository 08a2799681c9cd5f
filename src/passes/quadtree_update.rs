//! `quadtree_update`: applies a frame's coalesced node-texture and
//! node-description writes from the upload ring (Far Cry 5: one compute
//! dispatch per frame adds and removes nodes).

use crate::error::Result;
use crate::gpu::{vk, Binding, Buffer, ComputePipelineDesc, Context, Pipeline, Recorder, Resource};
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
    occlusion: bool,
}

impl QuadtreeUpdatePass {
    pub const NAME: &'static str = sh::PASS;

    /// `occlusion`: variant OCCLUSION, which clears a changed slot's
    /// visibility bits.
    pub fn new(ctx: &Context, occlusion: bool) -> Result<Self> {
        let shader = sh::variant(if occlusion { sh::VARIANT_OCCLUSION } else { 0 });
        let desc = ComputePipelineDesc { name: Self::NAME, shader, specialization: &[] };
        Ok(QuadtreeUpdatePass { pipeline: Pipeline::compute(ctx, &desc)?, occlusion })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// Uploads the frame's payloads and applies its changes; the results are
    /// visible to every later command. Returns the number of writes.
    /// `visibility`: occlusion's bits, exactly when built with occlusion.
    pub fn record(&self, rec: &mut Recorder, tree: &mut GpuQuadtree, visibility: Option<&Buffer>) -> Result<u32> {
        assert_eq!(visibility.is_some(), self.occlusion, "visibility bits exactly with occlusion");
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
            if let Some(v) = visibility {
                bindings.push((sh::VISIBILITY, Resource::Buffer(v)));
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
