//! `select_patches`: per-patch LOD selection after the traversal. For every
//! patch of every listed node: the coarsest ancestor (up to `MAX_COARSEN`
//! levels up) whose patch error still meets the target, within what the
//! seams allow (phase 0), and for LOD-0 patches that LOD 0 itself does not
//! serve, 2x or 4x refinement below the samples (phase 1). `cull_patches`
//! and `cull_occluded` draw what it decided (shaders_glsl/common/
//! lod_select.glsl says how and why). It also writes the frame's view,
//! which it is the first pass to read.

use crate::error::Result;
use crate::frame::per_frame::{copy_name, PerFrame};
use crate::gpu::{
    vk, Buffer, BufferDesc, ComputePipelineDesc, Context, MemoryLocation, Pipeline, Recorder, Resource, Sampler,
};
use crate::passes::cull_patches::{nearest_sampler, spec_constants};
use crate::passes::lod_map::LodMap;
use crate::passes::traverse::Traverse;
use crate::shaders::{consts as k, select_patches as sh, structs};
use crate::terrain::gpu_quadtree::{GpuQuadtree, ATLAS_LAYOUT, ATLAS_PATCH_ERRORS, ATLAS_PATCH_MIN_MAX};
use crate::terrain::quadtree::FIRST_SLOT;
use crate::world::{WorldDesc, PATCHES_PER_NODE};

/// Host twin of `SelectHeader` (lod_select.glsl): the frame's selection counters.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable, serde::Serialize)]
pub struct SelectHeader {
    /// Listed nodes next to a node more than `MAX_LOD_DELTA` LODs coarser
    /// (their patches are lifted to keep the seams closed).
    pub conflicts: u32,
    /// LOD-0 patches that asked to be refined below the samples.
    pub refined: u32,
    /// Of those, refused by the per-frame budget (`LodOptions::refine_budget`,
    /// by priority: see select_patches.comp).
    pub refine_capped: u32,
    /// Listed patches drawn from an ancestor.
    pub coarsened: u32,
}

const _: () = assert!(std::mem::size_of::<SelectHeader>() == structs::SELECT_HEADER);
const _: () = assert!(std::mem::size_of::<SelectHeader>() == 4 * k::SELECT_HEADER_WORDS as usize);

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SelectPush {
    pub phase: u32,
    pub lod_count: u32,
    pub budget: u32,
    pub buckets_at: u32,
    /// 1: the node list and each node's patches taken in reverse order
    /// (tests: order independence).
    pub reversed: u32,
    pub pad: [u32; 3],
}

pub struct SelectPatches {
    pipeline: Pipeline,
    sampler: Sampler,
    /// The counters, then two i32 levels (coarse, drawn) per patch of every
    /// slot, then the refinement's priority buckets and cut-off; one per
    /// frame parity (`frame::per_frame`).
    levels: PerFrame<Buffer>,
    lod_count: u32,
    /// LOD-0 patches refined a frame at most.
    budget: u32,
    /// Index in the levels of the first bucket.
    buckets_at: u32,
    /// Tests only (feature `test-hooks`): the node list and each node's
    /// patches taken in reverse order (the workgroup and invocation order
    /// of another device).
    #[cfg(feature = "test-hooks")]
    pub reversed: bool,
}

impl SelectPatches {
    pub const NAME: &'static str = sh::PASS;

    pub fn new(ctx: &Context, world: &WorldDesc, slots: u32, budget: u32) -> Result<Self> {
        assert_eq!(sh::WORKGROUP_SIZE[0] as usize, PATCHES_PER_NODE, "one thread per patch of a node");
        assert!((1..=k::MAX_REFINED_PATCHES).contains(&budget), "refine budget {budget}");
        let levels_len = u64::from(slots + FIRST_SLOT) * PATCHES_PER_NODE as u64 * 2;
        let entries = levels_len + u64::from(k::REFINE_BUCKETS) + 1;
        let levels = PerFrame::new(|i| {
            Buffer::new(
                ctx,
                &BufferDesc {
                    name: &copy_name("select_levels", i),
                    size: structs::SELECT_HEADER as u64 + entries * 4,
                    usage: vk::BufferUsageFlags::STORAGE_BUFFER
                        | vk::BufferUsageFlags::TRANSFER_DST
                        | vk::BufferUsageFlags::TRANSFER_SRC,
                    location: MemoryLocation::GpuOnly,
                },
            )
        })?;
        let desc = ComputePipelineDesc { name: Self::NAME, shader: &sh::SHADER, specialization: &spec_constants() };
        Ok(SelectPatches {
            pipeline: Pipeline::compute(ctx, &desc)?,
            sampler: nearest_sampler(ctx, "select_patches_sampler")?,
            levels,
            lod_count: world.lod_count,
            budget,
            buckets_at: u32::try_from(levels_len).expect("levels fit u32 indices"),
            #[cfg(feature = "test-hooks")]
            reversed: false,
        })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// Whether the order is reversed (always false without `test-hooks`).
    fn reversed(&self) -> bool {
        #[cfg(feature = "test-hooks")]
        return self.reversed;
        #[cfg(not(feature = "test-hooks"))]
        false
    }

    /// The levels of the frame being (or last) recorded.
    pub fn levels(&self) -> &Buffer {
        self.levels.current()
    }

    /// Both copies (memory reports).
    pub fn all_levels(&self) -> &[Buffer] {
        self.levels.all()
    }

    /// Frame `frame` writes its parity's levels.
    pub fn select_frame(&mut self, frame: u64) {
        self.levels.select(frame);
    }

    /// Writes this frame's view (`view_bytes`, a TerrainView, into `view`)
    /// and resets the counters behind one barrier, then selects every listed
    /// patch's level in four dispatches (select_patches.comp); the levels
    /// are visible to every later command.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder,
        traverse: &Traverse,
        tree: &GpuQuadtree,
        lod_map: &LodMap,
        view: &Buffer,
        view_bytes: &[u8],
    ) {
        rec.barrier(vk::PipelineStageFlags2::ALL_COMMANDS, vk::PipelineStageFlags2::ALL_TRANSFER);
        rec.update_buffer(view, 0, view_bytes);
        rec.update_buffer(self.levels(), 0, bytemuck::bytes_of(&SelectHeader::default()));
        let buckets = structs::SELECT_HEADER as u64 + u64::from(self.buckets_at) * 4;
        rec.update_buffer(self.levels(), buckets, &[0u8; 4 * k::REFINE_BUCKETS as usize]);
        rec.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::COMPUTE_SHADER);
        rec.bind_pipeline(&self.pipeline);
        rec.push_descriptors(
            &self.pipeline,
            &[
                (sh::TRAVERSE_OUT, Resource::Buffer(traverse.output())),
                (sh::VIEW, Resource::Buffer(view)),
                (sh::LOD_MAP, Resource::Image(lod_map.image(), vk::ImageLayout::GENERAL)),
                (sh::PATCH_MIN_MAX, Resource::Image(tree.required_atlas(ATLAS_PATCH_MIN_MAX), ATLAS_LAYOUT)),
                (sh::NEAREST, Resource::Sampler(self.sampler.raw())),
                (sh::NODE_TEXTURE, Resource::Image(tree.node_texture(), vk::ImageLayout::GENERAL)),
                (sh::PATCH_ERRORS, Resource::Image(tree.required_atlas(ATLAS_PATCH_ERRORS), ATLAS_LAYOUT)),
                (sh::SELECT_LEVELS, Resource::Buffer(self.levels())),
            ],
        );
        for phase in 0..4 {
            let push = SelectPush {
                phase,
                lod_count: self.lod_count,
                budget: self.budget,
                buckets_at: self.buckets_at,
                reversed: u32::from(self.reversed()),
                pad: [0; 3],
            };
            rec.push_constants(&self.pipeline, &push);
            // Phase 2 is one workgroup: the cut-off over all buckets.
            if phase == 2 {
                rec.dispatch(1, 1, 1);
            } else {
                rec.dispatch_indirect(traverse.output(), 0);
            }
            rec.barrier(vk::PipelineStageFlags2::COMPUTE_SHADER, vk::PipelineStageFlags2::ALL_COMMANDS);
        }
    }
}
