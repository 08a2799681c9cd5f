//! `cull_patches`: splits every listed node into 8x8 patches (one thread
//! each, one workgroup per node, dispatched indirectly by `traverse`),
//! culls them (frustum; backface cone and holes where those effects are
//! built, as shader variants; each built stage switchable per frame),
//! stitches LOD seams (4-bit delta per edge from the LOD map) and writes the
//! visible patch list whose header is the indexed-indirect draw of
//! `terrain_geometry`, with per-stage counters. With holes built, patches
//! that have some holes go to a second list drawn by `terrain_holes`.

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
    /// Instances of both draws.
    pub drawn: u32,
    /// Of those, patches with some holes (drawn by `terrain_holes`).
    pub drawn_with_holes: u32,
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

/// Which optional stages the pipeline is built with (effects `cone_cull`
/// and `holes`); a stage not built has no code, binding or atlas.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CullBuild {
    pub cone: bool,
    pub holes: bool,
}

pub struct CullPatches {
    pipeline: Pipeline,
    sampler: Sampler,
    /// Header (indexed-indirect draw args + counters) then the patch list.
    pub list: Buffer,
    /// Patches with some holes (header: the draw args of `terrain_holes`);
    /// only when holes are built.
    pub hole_list: Option<Buffer>,
    pub build: CullBuild,
    capacity: u32,
    index_count: u32,
}

impl CullPatches {
    pub const NAME: &'static str = sh::PASS;

    /// Room for every patch of the traversal's largest final list;
    /// `index_count` is the patch mesh's, written into the draw args.
    pub fn new(ctx: &Context, traverse: &Traverse, index_count: u32, build: CullBuild) -> Result<Self> {
        assert_eq!(sh::WORKGROUP_SIZE[0] as usize, PATCHES_PER_NODE, "one thread per patch of a node");
        let capacity = traverse.final_capacity() * PATCHES_PER_NODE as u32;
        let list_buffer = |name| {
            Buffer::new(
                ctx,
                &BufferDesc {
                    name,
                    size: (structs::PATCH_LIST_HEADER + capacity as usize * 8) as u64,
                    usage: vk::BufferUsageFlags::STORAGE_BUFFER
                        | vk::BufferUsageFlags::INDIRECT_BUFFER
                        | vk::BufferUsageFlags::TRANSFER_DST
                        | vk::BufferUsageFlags::TRANSFER_SRC,
                    location: MemoryLocation::GpuOnly,
                },
            )
        };
        let list = list_buffer("patch_list")?;
        let hole_list = if build.holes { Some(list_buffer("hole_patch_list")?) } else { None };
        let sampler = Sampler::new(
            ctx,
            &SamplerDesc {
                name: "cull_patches_sampler",
                filter: vk::Filter::NEAREST,
                address_mode: vk::SamplerAddressMode::CLAMP_TO_EDGE,
            },
        )?;
        let spec = [(sh::SPEC_PATCHES_PER_SIDE, PATCHES_PER_NODE_SIDE), (sh::SPEC_PATCH_QUADS, PATCH_QUADS)];
        let bit = |on: bool, b: u32| if on { b } else { 0 };
        let shader = sh::variant(bit(build.cone, sh::VARIANT_CONE_CULL) | bit(build.holes, sh::VARIANT_HOLE_CULL));
        let desc = ComputePipelineDesc { name: Self::NAME, shader, specialization: &spec };
        let pipeline = Pipeline::compute(ctx, &desc)?;
        Ok(CullPatches { pipeline, sampler, list, hole_list, build, capacity, index_count })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
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
        if let Some(holes) = &self.hole_list {
            rec.update_buffer(holes, 0, bytemuck::bytes_of(&header));
        }
        rec.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::COMPUTE_SHADER);
        rec.bind_pipeline(&self.pipeline);
        let mut bindings = vec![
            (sh::TRAVERSE_OUT, Resource::Buffer(&traverse.output)),
            (sh::VIEW, Resource::Buffer(view)),
            (sh::LOD_MAP, Resource::Image(&lod_map.image, vk::ImageLayout::GENERAL)),
            (sh::PATCH_MIN_MAX, Resource::Image(tree.required_atlas(ATLAS_PATCH_MIN_MAX), ATLAS_LAYOUT)),
            (sh::NEAREST, Resource::Sampler(self.sampler.raw())),
            (sh::PATCH_LIST, Resource::Buffer(&self.list)),
        ];
        if self.build.cone {
            bindings.push((sh::PATCH_CONES, Resource::Image(tree.required_atlas(ATLAS_PATCH_CONES), ATLAS_LAYOUT)));
        }
        if let Some(holes) = &self.hole_list {
            bindings.push((sh::PATCH_HOLES, Resource::Image(tree.required_atlas(ATLAS_PATCH_HOLES), ATLAS_LAYOUT)));
            bindings.push((sh::HOLE_LIST, Resource::Buffer(holes)));
        }
        rec.push_descriptors(&self.pipeline, &bindings);
        rec.push_constants(&self.pipeline, &CullPush { stages: stages.bits(), capacity: self.capacity, pad: [0; 2] });
        rec.dispatch_indirect(&traverse.output, 0);
        rec.barrier(
            vk::PipelineStageFlags2::COMPUTE_SHADER,
            vk::PipelineStageFlags2::DRAW_INDIRECT | vk::PipelineStageFlags2::ALL_COMMANDS,
        );
    }

    /// The last frame's counters (tests, CLI after the frames): waits.
    pub fn read_counters(&self, ctx: &Context) -> Result<CullCounters> {
        let h = read_header(ctx, &self.list)?;
        let holes = match &self.hole_list {
            Some(b) => read_header(ctx, b)?.instance_count.min(self.capacity),
            None => 0,
        };
        let solid = h.instance_count.min(self.capacity);
        Ok(CullCounters {
            patches_in: h.patches_in,
            after_frustum: h.after_frustum,
            after_cone: h.after_cone,
            after_hole: h.after_hole,
            drawn: solid + holes,
            drawn_with_holes: holes,
        })
    }

    /// The last frame's visible patches of both lists, sorted (tests): waits.
    pub fn read_patches(&self, ctx: &Context) -> Result<Vec<PatchRecord>> {
        let mut out = Vec::new();
        for list in std::iter::once(&self.list).chain(&self.hole_list) {
            let bytes = ctx.read_buffer(list)?;
            let h: PatchListHeader = bytemuck::pod_read_unaligned(&bytes[..structs::PATCH_LIST_HEADER]);
            let n = h.instance_count.min(self.capacity) as usize;
            let raw = &bytes[structs::PATCH_LIST_HEADER..structs::PATCH_LIST_HEADER + n * 8];
            out.extend(raw.chunks_exact(8).map(|c| PatchRecord::unpack(bytemuck::pod_read_unaligned(c))));
        }
        out.sort();
        Ok(out)
    }
}

fn read_header(ctx: &Context, list: &Buffer) -> Result<PatchListHeader> {
    let bytes = ctx.read_buffer(list)?;
    Ok(bytemuck::pod_read_unaligned(&bytes[..structs::PATCH_LIST_HEADER]))
}
