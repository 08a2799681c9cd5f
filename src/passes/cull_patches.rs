//! `cull_patches`: splits every listed node into 8x8 patches (one thread
//! each, one workgroup per node, dispatched indirectly by `traverse`),
//! culls them (frustum, backface cone, all-hole; each stage switchable),
//! stitches LOD seams (4-bit delta per edge from the LOD map) and writes the
//! visible patch list whose header is the indexed-indirect draw of
//! `terrain_geometry`, with per-stage counters.

use crate::error::Result;
use crate::gpu::{
    vk, Buffer, BufferDesc, ComputePipelineDesc, Context, MemoryLocation, Pipeline, Recorder, Resource, Sampler,
    SamplerDesc,
};
use crate::passes::lod_map::LodMap;
use crate::passes::traverse::Traverse;
use crate::shaders::consts as k;
use crate::shaders::{cull_patches as sh, structs};
use crate::terrain::gpu_quadtree::{
    GpuQuadtree, ATLAS_LAYOUT, ATLAS_PATCH_CONES, ATLAS_PATCH_HOLES, ATLAS_PATCH_MIN_MAX,
};
use crate::terrain::quadtree::node_from_ref;
use crate::world::{PATCHES_PER_NODE, PATCHES_PER_NODE_SIDE, PATCH_QUADS};
use serde::Serialize;

/// Largest stitched LOD delta: a patch edge of 2^4 quads can snap to a grid
/// at most 2^4 times coarser without moving its corners.
pub const MAX_LOD_DELTA: u32 = k::MAX_LOD_DELTA;
const _: () = assert!(MAX_LOD_DELTA == PATCH_QUADS.trailing_zeros());

/// Which culling stages run (all by default; tests and benchmarks switch
/// them off to show what each removes and costs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct CullStages {
    pub frustum: bool,
    pub cone: bool,
    pub hole: bool,
}

impl CullStages {
    pub const ALL: CullStages = CullStages { frustum: true, cone: true, hole: true };
    pub const NONE: CullStages = CullStages { frustum: false, cone: false, hole: false };

    /// Bits of `CullPush::stages`.
    fn bits(self) -> u32 {
        let bit = |on: bool, b: u32| if on { b } else { 0 };
        bit(self.frustum, k::CULL_STAGE_FRUSTUM)
            | bit(self.cone, k::CULL_STAGE_CONE)
            | bit(self.hole, k::CULL_STAGE_HOLE)
    }
}

impl Default for CullStages {
    fn default() -> Self {
        CullStages::ALL
    }
}

/// Host twin of `PatchListHeader` (patch_list.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PatchListHeader {
    pub index_count: u32,
    pub instance_count: u32,
    pub first_index: u32,
    pub vertex_offset: i32,
    pub first_instance: u32,
    pub patches_in: u32,
    pub after_frustum: u32,
    pub after_cone: u32,
    pub after_hole: u32,
    pub pad: [u32; 3],
}

const _: () = assert!(std::mem::size_of::<PatchListHeader>() == structs::PATCH_LIST_HEADER);

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CullPush {
    pub stages: u32,
    pub capacity: u32,
    pub pad: [u32; 2],
}

/// Patch counts after each stage of one frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct CullCounters {
    /// 64 per listed node.
    pub patches_in: u32,
    pub after_frustum: u32,
    pub after_cone: u32,
    pub after_hole: u32,
    /// Instances of the draw.
    pub drawn: u32,
}

/// A visible patch as the GPU wrote it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct PatchRecord {
    pub lod: u8,
    pub node_x: u32,
    pub node_y: u32,
    pub slot: u32,
    /// py * 8 + px.
    pub patch: u32,
    /// LOD delta to the west, east, south and north neighbour.
    pub deltas: [u8; 4],
}

impl PatchRecord {
    fn unpack([n, w]: [u32; 2]) -> Self {
        let node = node_from_ref(n);
        let field = |shift: u32, bits: u32| (w >> shift) & ((1 << bits) - 1);
        let delta = |edge: u32| field(k::PATCH_DELTA_SHIFT + k::PATCH_DELTA_BITS * edge, k::PATCH_DELTA_BITS) as u8;
        PatchRecord {
            lod: node.lod,
            node_x: node.x,
            node_y: node.y,
            slot: field(0, k::SLOT_BITS),
            patch: (w >> k::PATCH_INDEX_SHIFT) & k::PATCH_INDEX_MASK,
            deltas: [k::EDGE_WEST, k::EDGE_EAST, k::EDGE_SOUTH, k::EDGE_NORTH].map(delta),
        }
    }
}

pub struct CullPatches {
    pipeline: Pipeline,
    sampler: Sampler,
    /// Header (indexed-indirect draw args + counters) then the patch list.
    pub list: Buffer,
    capacity: u32,
    index_count: u32,
}

impl CullPatches {
    pub const NAME: &'static str = sh::PASS;

    /// Room for every patch of the traversal's largest final list;
    /// `index_count` is the patch mesh's, written into the draw args.
    pub fn new(ctx: &Context, traverse: &Traverse, index_count: u32) -> Result<Self> {
        assert_eq!(sh::WORKGROUP_SIZE[0] as usize, PATCHES_PER_NODE, "one thread per patch of a node");
        let capacity = traverse.final_capacity() * PATCHES_PER_NODE as u32;
        let list = Buffer::new(
            ctx,
            &BufferDesc {
                name: "patch_list",
                size: (structs::PATCH_LIST_HEADER + capacity as usize * 8) as u64,
                usage: vk::BufferUsageFlags::STORAGE_BUFFER
                    | vk::BufferUsageFlags::INDIRECT_BUFFER
                    | vk::BufferUsageFlags::TRANSFER_DST
                    | vk::BufferUsageFlags::TRANSFER_SRC,
                location: MemoryLocation::GpuOnly,
            },
        )?;
        let sampler = Sampler::new(
            ctx,
            &SamplerDesc {
                name: "cull_patches_sampler",
                filter: vk::Filter::NEAREST,
                address_mode: vk::SamplerAddressMode::CLAMP_TO_EDGE,
            },
        )?;
        let spec = [(sh::SPEC_PATCHES_PER_SIDE, PATCHES_PER_NODE_SIDE), (sh::SPEC_PATCH_QUADS, PATCH_QUADS)];
        let desc = ComputePipelineDesc { name: Self::NAME, shader: &sh::SHADER, specialization: &spec };
        Ok(CullPatches { pipeline: Pipeline::compute(ctx, &desc)?, sampler, list, capacity, index_count })
    }

    /// Writes this frame's view (`view_bytes`, a TerrainView, into `view`)
    /// and resets the draw args and counters behind one barrier, then culls
    /// the patches of every node in `traverse`'s list.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder,
        traverse: &Traverse,
        tree: &GpuQuadtree,
        lod_map: &LodMap,
        view: &Buffer,
        view_bytes: &[u8],
        stages: CullStages,
    ) {
        let header = PatchListHeader { index_count: self.index_count, ..PatchListHeader::default() };
        rec.barrier(vk::PipelineStageFlags2::ALL_COMMANDS, vk::PipelineStageFlags2::ALL_TRANSFER);
        rec.update_buffer(view, 0, view_bytes);
        rec.update_buffer(&self.list, 0, bytemuck::bytes_of(&header));
        rec.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::COMPUTE_SHADER);
        rec.bind_pipeline(&self.pipeline);
        rec.push_descriptors(
            &self.pipeline,
            &[
                (sh::TRAVERSE_OUT, Resource::Buffer(&traverse.output)),
                (sh::VIEW, Resource::Buffer(view)),
                (sh::LOD_MAP, Resource::Image(&lod_map.image, vk::ImageLayout::GENERAL)),
                (sh::PATCH_MIN_MAX, Resource::Image(&tree.atlases[ATLAS_PATCH_MIN_MAX], ATLAS_LAYOUT)),
                (sh::PATCH_CONES, Resource::Image(&tree.atlases[ATLAS_PATCH_CONES], ATLAS_LAYOUT)),
                (sh::PATCH_HOLES, Resource::Image(&tree.atlases[ATLAS_PATCH_HOLES], ATLAS_LAYOUT)),
                (sh::NEAREST, Resource::Sampler(self.sampler.raw())),
                (sh::PATCH_LIST, Resource::Buffer(&self.list)),
            ],
        );
        rec.push_constants(&self.pipeline, &CullPush { stages: stages.bits(), capacity: self.capacity, pad: [0; 2] });
        rec.dispatch_indirect(&traverse.output, 0);
        rec.barrier(
            vk::PipelineStageFlags2::COMPUTE_SHADER,
            vk::PipelineStageFlags2::DRAW_INDIRECT | vk::PipelineStageFlags2::ALL_COMMANDS,
        );
    }

    /// The last frame's counters (tests, CLI after the frames): waits.
    pub fn read_counters(&self, ctx: &Context) -> Result<CullCounters> {
        let h = self.read_header(ctx)?;
        Ok(CullCounters {
            patches_in: h.patches_in,
            after_frustum: h.after_frustum,
            after_cone: h.after_cone,
            after_hole: h.after_hole,
            drawn: h.instance_count.min(self.capacity),
        })
    }

    fn read_header(&self, ctx: &Context) -> Result<PatchListHeader> {
        let bytes = ctx.read_buffer(&self.list)?;
        Ok(bytemuck::pod_read_unaligned(&bytes[..structs::PATCH_LIST_HEADER]))
    }

    /// The last frame's visible patches, sorted (tests): waits.
    pub fn read_patches(&self, ctx: &Context) -> Result<Vec<PatchRecord>> {
        let bytes = ctx.read_buffer(&self.list)?;
        let h: PatchListHeader = bytemuck::pod_read_unaligned(&bytes[..structs::PATCH_LIST_HEADER]);
        let n = h.instance_count.min(self.capacity) as usize;
        let raw = &bytes[structs::PATCH_LIST_HEADER..structs::PATCH_LIST_HEADER + n * 8];
        let mut out: Vec<PatchRecord> =
            raw.chunks_exact(8).map(|c| PatchRecord::unpack(bytemuck::pod_read_unaligned(c))).collect();
        out.sort();
        Ok(out)
    }
}
