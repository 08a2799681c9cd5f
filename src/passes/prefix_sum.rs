//! `prefix_sum`: exclusive scan of u32s in one workgroup through shared
//! memory (the building block of the one-dispatch traversal).

use crate::error::{Error, Result};
use crate::gpu::{Binding, Buffer, ComputePipelineDesc, Context, Pipeline, Recorder, Resource};
use crate::shaders::prefix_sum as sh;

/// Items each thread scans before the shared-memory pass
/// (`ITEMS_PER_THREAD` in prefix_sum.comp, set here by specialization).
pub const ITEMS_PER_THREAD: u32 = 4;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PrefixSumPush {
    pub count: u32,
}

pub struct PrefixSum {
    pipeline: Pipeline,
}

impl PrefixSum {
    pub const NAME: &'static str = sh::PASS;

    pub fn new(ctx: &Context) -> Result<Self> {
        let spec = [(sh::SPEC_ITEMS_PER_THREAD, ITEMS_PER_THREAD)];
        Ok(PrefixSum {
            pipeline: Pipeline::compute(
                ctx,
                &ComputePipelineDesc { name: Self::NAME, shader: &sh::SHADER, specialization: &spec },
            )?,
        })
    }

    /// Largest input one dispatch scans.
    /// The compute pipeline (tests bind it to probe the recorder's checks).
    pub fn pipeline(&self) -> &Pipeline {
        &self.pipeline
    }

    pub fn capacity() -> u32 {
        sh::WORKGROUP_SIZE[0] * ITEMS_PER_THREAD
    }

    pub fn record(&self, rec: &mut Recorder, input: &Buffer, output: &Buffer, count: u32) -> Result<()> {
        if count > Self::capacity() || u64::from(count) * 4 > input.size.min(output.size) {
            return Err(Error::BadInput(format!(
                "prefix_sum of {count} values: capacity {}, buffers {} / {} bytes",
                Self::capacity(),
                input.size,
                output.size
            )));
        }
        let bindings: [(Binding, Resource); 2] =
            [(sh::INPUT_VALUES, Resource::Buffer(input)), (sh::OUTPUT_SUMS, Resource::Buffer(output))];
        rec.bind_pipeline(&self.pipeline);
        rec.push_descriptors(&self.pipeline, &bindings);
        rec.push_constants(&self.pipeline, &PrefixSumPush { count });
        rec.dispatch(1, 1, 1);
        Ok(())
    }
}
