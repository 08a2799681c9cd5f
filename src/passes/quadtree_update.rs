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

    /// Uploads the frame's payloads and applies its changes to this frame's
    /// node texture copy, after the last frame's (which the other copy
    /// got then); the results are visible to every later command. Returns
    /// the number of writes. `visibility`: this frame's copy of occlusion's
    /// bits, exactly when built with occlusion.
    pub fn record(&self, rec: &mut Recorder, tree: &mut GpuQuadtree, visibility: Option<&Buffer>) -> Result<u32> {
        assert_eq!(visibility.is_some(), self.occlusion, "visibility bits exactly with occlusion");
        let count = tree.prepare_frame(rec)?;
        let tree = &*tree;
        let mut written = 0;
        for (updates, n) in tree.previous_updates().into_iter().chain([(tree.current_updates(), count)]) {
            if n > 0 {
                self.dispatch(rec, tree, updates, n, visibility);
                written += n;
            }
        }
        rec.barrier(vk::PipelineStageFlags2::ALL_COMMANDS, vk::PipelineStageFlags2::ALL_COMMANDS);
        Ok(written)
    }

    fn dispatch(
        &self,
        rec: &mut Recorder,
        tree: &GpuQuadtree,
        updates: &Buffer,
        count: u32,
        visibility: Option<&Buffer>,
    ) {
        let node_texture = tree.node_texture();
        let mips = node_texture.mip_levels;
        let mut bindings: Vec<(Binding, Resource)> = vec![
            (sh::UPDATES, Resource::Buffer(updates)),
            (sh::NODE_DESCS, Resource::Buffer(&tree.node_descs)),
            (sh::NODE_ERRORS, Resource::Buffer(&tree.node_errors)),
        ];
        for (lod, b) in NODE_LODS.iter().enumerate() {
            // LODs past the world's count are never written: bind mip 0.
            let mip = if (lod as u32) < mips { lod as u32 } else { 0 };
            bindings.push((*b, Resource::ImageMip(node_texture, mip, vk::ImageLayout::GENERAL)));
        }
        if let Some(v) = visibility {
            bindings.push((sh::VISIBILITY, Resource::Buffer(v)));
        }
        // After the payloads' copies and the last list's writes.
        rec.barrier(vk::PipelineStageFlags2::ALL_COMMANDS, vk::PipelineStageFlags2::COMPUTE_SHADER);
        rec.bind_pipeline(&self.pipeline);
        rec.push_descriptors(&self.pipeline, &bindings);
        rec.push_constants(&self.pipeline, &QuadtreeUpdatePush { count });
        rec.dispatch(count.div_ceil(sh::WORKGROUP_SIZE[0]), 1, 1);
    }
}
