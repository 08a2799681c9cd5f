//! `emit_fine`: the per-triangle rule below a LOD-0 node's samples, after
//! `emit_triangles` of the same phase: one invocation per cell half that
//! pass appended to its fine list (an indirect dispatch it sized), each
//! walking the bisection down to the finest lattice and appending what it
//! leaves whole to the phase's index list (emit_fine.comp). A pass of its
//! own so that only the cells that refine pay for the walk.

use crate::error::Result;
use crate::gpu::{vk, ComputePipelineDesc, Context, Pipeline, Recorder};
use crate::passes::emit_triangles::{EmitInputs, EmitTriangles};
use crate::shaders::{consts as k, emit_fine as sh};
use crate::world::{NODE_QUADS, PATCH_QUADS};

// The fine list's dispatch counts workgroups of this many cells.
const _: () = assert!(sh::WORKGROUP_SIZE[0] == k::FINE_GROUP_SIZE);

pub struct EmitFine {
    pipeline: Pipeline,
}

impl EmitFine {
    pub const NAME: &'static str = sh::PASS;

    pub fn new(ctx: &Context) -> Result<Self> {
        let specialization = [(sh::SPEC_NODE_SIDE, NODE_QUADS), (sh::SPEC_PATCH_QUADS, PATCH_QUADS)];
        let desc = ComputePipelineDesc { name: Self::NAME, shader: &sh::SHADER, specialization: &specialization };
        Ok(EmitFine { pipeline: Pipeline::compute(ctx, &desc)? })
    }

    /// Walks the cell halves `emit`'s phase (`late`: phase 2) appended,
    /// into that phase's list, behind a barrier: the list is visible to the
    /// indirect draw and every later command. `emit` recorded that phase
    /// just before, its barrier ordering the fine list's header (this
    /// dispatch's arguments) before this.
    pub fn record(&self, rec: &mut Recorder, emit: &EmitTriangles, inputs: &EmitInputs, late: bool) {
        let list = if late { emit.late_list().expect("phase 2 built") } else { emit.list() };
        rec.bind_pipeline(&self.pipeline);
        rec.push_descriptors(&self.pipeline, &emit.bindings(inputs, list, late));
        let push = emit.push(inputs, [0; 2], late);
        rec.push_constants(&self.pipeline, &push);
        rec.dispatch_indirect(emit.fine_cells(late), 0);
        rec.barrier(
            vk::PipelineStageFlags2::COMPUTE_SHADER,
            vk::PipelineStageFlags2::DRAW_INDIRECT | vk::PipelineStageFlags2::ALL_COMMANDS,
        );
    }
}
