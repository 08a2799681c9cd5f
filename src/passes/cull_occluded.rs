//! `cull_occluded`: phase 2 of two-phase occlusion culling. Runs the same
//! nodes and stages as `cull_patches`, tests every survivor against the
//! depth pyramid of `hiz_build` and lists those phase 1 did not draw that
//! it leaves visible, for a second `terrain_geometry` / `terrain_holes`
//! draw; rewrites every listed node's visibility bits for the next frame's
//! phase 1. Owns the visibility bits (one per patch and slot, zero at
//! start; `quadtree_update` clears a slot's when its node changes).

use crate::error::Result;
use crate::frame::per_frame::{copy_name, PerFrame};
use crate::gpu::{vk, Buffer, BufferDesc, ComputePipelineDesc, Context, MemoryLocation, Pipeline, Recorder, Resource};
use crate::gpu::{Binding, Image, Sampler};
use crate::passes::cull_patches::{
    list_capacity, nearest_sampler, spec_constants, CullBuild, CullFrame, CullInputs, CullPush, PatchLists,
};
use crate::passes::hiz_build::HizBuild;
use crate::passes::lod_map::LodMap;
use crate::passes::select_patches::SelectPatches;
use crate::passes::traverse::Traverse;
use crate::shaders::{consts as k, cull_occluded as sh};
use crate::terrain::gpu_quadtree::GpuQuadtree;
use crate::terrain::quadtree::FIRST_SLOT;
use crate::world::PATCHES_PER_NODE;

/// This shader's bindings in the order of `CullInputs::bindings`.
const CULL_BINDINGS: [Binding; 12] = [
    sh::TRAVERSE_OUT,
    sh::VIEW,
    sh::LOD_MAP,
    sh::PATCH_MIN_MAX,
    sh::NEAREST,
    sh::PATCH_LIST,
    sh::PATCH_CONES,
    sh::PATCH_HOLES,
    sh::HOLE_LIST,
    sh::NODE_TEXTURE,
    sh::PATCH_ERRORS,
    sh::SELECT_LEVELS,
];

pub struct CullOccluded {
    pipeline: Pipeline,
    sampler: Sampler,
    /// Phase 2's lists (patches drawn in the second draw).
    pub lists: PatchLists,
    /// One bit per patch and slot, rewritten for every listed node; one per
    /// frame parity (`frame::per_frame`): a frame's phase 1 reads the bits
    /// its copy got two frames before, which async compute can read while
    /// the frame between still writes the other copy.
    visibility: PerFrame<Buffer>,
    build: CullBuild,
}

impl CullOccluded {
    pub const NAME: &'static str = sh::PASS;

    /// Lists as large as phase 1's; bits for `slots` node slots.
    pub fn new(ctx: &Context, traverse: &Traverse, index_count: u32, build: CullBuild, slots: u32) -> Result<Self> {
        assert_eq!(sh::WORKGROUP_SIZE[0] as usize, PATCHES_PER_NODE, "one thread per patch of a node");
        assert_eq!(PATCHES_PER_NODE as u32, 32 * k::VISIBILITY_WORDS_PER_SLOT, "one visibility bit per patch");
        let capacity = list_capacity(traverse);
        let names = ["late_patch_list", "late_hole_patch_list"];
        let lists = PatchLists::new(ctx, names, capacity, build.holes, index_count)?;
        let visibility = PerFrame::new(|i| {
            Buffer::new(
                ctx,
                &BufferDesc {
                    name: &copy_name("patch_visibility", i),
                    size: u64::from((slots + FIRST_SLOT) * k::VISIBILITY_WORDS_PER_SLOT * 4),
                    usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                    location: MemoryLocation::GpuOnly,
                },
            )
        })?;
        ctx.submit_and_wait(|rec| {
            visibility.all().iter().for_each(|v| rec.fill_buffer(v, 0));
            Ok(())
        })?;
        let bit = |on: bool, b: u32| if on { b } else { 0 };
        let shader = sh::variant(bit(build.cone, sh::VARIANT_CONE_CULL) | bit(build.holes, sh::VARIANT_HOLE_CULL));
        let desc = ComputePipelineDesc { name: Self::NAME, shader, specialization: &spec_constants() };
        Ok(CullOccluded {
            pipeline: Pipeline::compute(ctx, &desc)?,
            sampler: nearest_sampler(ctx, "cull_occluded_nearest")?,
            lists,
            visibility,
            build,
        })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// The visibility bits of the frame being (or last) recorded.
    pub fn visibility(&self) -> &Buffer {
        self.visibility.current()
    }

    /// Both copies (memory reports).
    pub fn all_visibility(&self) -> &[Buffer] {
        self.visibility.all()
    }

    /// Frame `frame` reads and rewrites its parity's bits.
    pub fn select_frame(&mut self, frame: u64) {
        self.visibility.select(frame);
    }

    /// Culls against `hiz`'s pyramid (built this frame from `depth`'s size);
    /// `view` holds this frame's view, written by phase 1.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder,
        traverse: &Traverse,
        tree: &GpuQuadtree,
        lod_map: &LodMap,
        select: &SelectPatches,
        view: &Buffer,
        cull: CullFrame,
        hiz: &HizBuild,
        depth: &Image,
    ) {
        let pyramid = hiz.pyramid().expect("hiz_build ran before cull_occluded");
        rec.barrier(vk::PipelineStageFlags2::ALL_COMMANDS, vk::PipelineStageFlags2::ALL_TRANSFER);
        let extra = [
            (sh::VISIBILITY, Resource::Buffer(self.visibility())),
            (sh::HIZ, Resource::Image(pyramid, vk::ImageLayout::GENERAL)),
        ];
        let [depth_w, depth_h] = depth.extent;
        let push = CullPush { stages: cull.bits(), capacity: self.lists.capacity, depth_w, depth_h };
        let inputs = CullInputs { traverse, tree, lod_map, view, select };
        inputs.dispatch(rec, &self.pipeline, CULL_BINDINGS, self.build, &self.sampler, &self.lists, &extra, &push);
    }
}
