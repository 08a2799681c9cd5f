//! `vt_update` (effect `virtual_texture`): applies the frame's state writes
//! (sub-texture words, indirection texels) in order, in one workgroup
//! (the shader says why).

use crate::effects::virtual_texture::state::StateWrite;
use crate::error::Result;
use crate::gpu::{vk, Buffer, ComputePipelineDesc, Context, Pipeline, Recorder, Resource};
use crate::shaders::consts::VT_MAX_WRITES;
use crate::shaders::{structs, vt_update as sh};

const _: () = assert!(std::mem::size_of::<StateWrite>() == structs::STATE_WRITE);

pub struct VtUpdate {
    pipeline: Pipeline,
}

impl VtUpdate {
    pub const NAME: &'static str = sh::PASS;

    pub fn new(ctx: &Context) -> Result<Self> {
        let desc = ComputePipelineDesc { name: Self::NAME, shader: &sh::SHADER, specialization: &[] };
        Ok(VtUpdate { pipeline: Pipeline::compute(ctx, &desc)? })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// Uploads `writes` (at most VT_MAX_WRITES) into `staging` and applies
    /// them to `state`.
    pub fn record(&self, rec: &mut Recorder, state: &Buffer, staging: &Buffer, writes: &[StateWrite]) {
        assert!(writes.len() <= VT_MAX_WRITES as usize, "{} writes", writes.len());
        let bytes: &[u8] = bytemuck::cast_slice(writes);
        for (i, chunk) in bytes.chunks(65536).enumerate() {
            rec.update_buffer(staging, i as u64 * 65536, chunk);
        }
        rec.barrier(vk::PipelineStageFlags2::ALL_COMMANDS, vk::PipelineStageFlags2::COMPUTE_SHADER);
        rec.bind_pipeline(&self.pipeline);
        rec.push_descriptors(
            &self.pipeline,
            &[(sh::STATE, Resource::Buffer(state)), (sh::WRITES, Resource::Buffer(staging))],
        );
        rec.push_constants(&self.pipeline, &[writes.len() as u32, 0, 0, 0]);
        rec.dispatch(1, 1, 1);
        rec.barrier(vk::PipelineStageFlags2::COMPUTE_SHADER, vk::PipelineStageFlags2::ALL_COMMANDS);
    }
}
