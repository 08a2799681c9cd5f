//! `cull_patches`: splits every listed node into 16x16 patches (one thread
//! each, one workgroup per node, dispatched indirectly by `traverse`), draws
//! for each what `select_patches` chose (an ancestor's patch, its own, or
//! its sub-patches below LOD 0), culls them (frustum; backface cone and
//! holes where those effects are built, as shader variants; each built
//! stage switchable per frame), stitches LOD seams (4-bit delta per edge
//! from the neighbours' drawn levels) and writes the visible patch list
//! whose header is the indexed-indirect draw of `terrain_geometry`, with
//! per-stage counters and the frame's achieved error bound. With holes built, patches
//! that have some holes go to a second list drawn by `terrain_holes`. With
//! occlusion built (variant OCCLUSION) this is phase 1: only patches
//! visible last frame are listed; `cull_occluded` handles the rest.

use crate::error::Result;
use crate::frame::per_frame::{copy_name, PerFrame};
use crate::gpu::{
    vk, Binding, Buffer, BufferDesc, ComputePipelineDesc, Context, MemoryLocation, Pipeline, Recorder, Resource,
    Sampler, SamplerDesc,
};
use crate::passes::lod_map::LodMap;
use crate::passes::select_patches::SelectPatches;
use crate::passes::traverse::Traverse;
use crate::shaders::consts as k;
use crate::shaders::{cull_patches as sh, structs};
use crate::terrain::gpu_quadtree::{
    GpuQuadtree, ATLAS_LAYOUT, ATLAS_PATCH_CONES, ATLAS_PATCH_ERRORS, ATLAS_PATCH_HOLES, ATLAS_PATCH_MIN_MAX,
};
use crate::terrain::quadtree::node_from_ref;
use crate::world::{PATCHES_PER_NODE, PATCHES_PER_NODE_SIDE, PATCH_QUADS};
use serde::Serialize;

/// Largest stitched LOD delta: a patch edge of 2^4 quads can snap to a grid
/// at most 2^4 times coarser without moving its corners.
pub const MAX_LOD_DELTA: u32 = k::MAX_LOD_DELTA;
// Stitching snaps to a coarser grid that must divide the node's side
// (terrain_vertex.glsl), and the delta must fit its bits in the record.
const _: () = assert!(1 << MAX_LOD_DELTA <= PATCH_QUADS * PATCHES_PER_NODE_SIDE);
const _: () = assert!(MAX_LOD_DELTA < 1 << k::PATCH_DELTA_BITS);

/// Which culling stages run (all by default; tests and benchmarks switch
/// them off to show what each removes and costs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct CullStages {
    pub frustum: bool,
    pub cone: bool,
    pub hole: bool,
    /// Two-phase occlusion (where built); off, phase 1 draws every survivor
    /// and the occlusion passes are skipped.
    pub occlusion: bool,
}

impl CullStages {
    pub const ALL: CullStages = CullStages { frustum: true, cone: true, hole: true, occlusion: true };
    pub const NONE: CullStages = CullStages { frustum: false, cone: false, hole: false, occlusion: false };

    /// Bits of `CullPush::stages`.
    fn bits(self) -> u32 {
        let bit = |on: bool, b: u32| if on { b } else { 0 };
        bit(self.frustum, k::CULL_STAGE_FRUSTUM)
            | bit(self.cone, k::CULL_STAGE_CONE)
            | bit(self.hole, k::CULL_STAGE_HOLE)
            | bit(self.occlusion, k::CULL_STAGE_OCCLUSION)
    }
}

/// What one frame's culling does: the stages, and whether holes are drawn
/// (off: every patch is solid, `FrameSwitches::holes`).
#[derive(Debug, Clone, Copy)]
pub struct CullFrame {
    pub stages: CullStages,
    pub holes: bool,
}

impl CullFrame {
    pub(crate) fn bits(self) -> u32 {
        self.stages.bits() | if self.holes { 0 } else { k::CULL_HOLES_OFF }
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
    /// Phase 2 only: patches the depth pyramid left visible.
    pub after_occlusion: u32,
    /// Largest projected error (px) of a listed patch, as f32 bits.
    pub bound_bits: u32,
    /// Edges whose neighbour was more than `MAX_LOD_DELTA` coarser (clamped).
    pub seam_overflow: u32,
}

/// Bytes of one patch record (uvec4).
pub const RECORD_BYTES: usize = 16;

const _: () = assert!(std::mem::size_of::<PatchListHeader>() == structs::PATCH_LIST_HEADER);

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CullPush {
    pub stages: u32,
    pub capacity: u32,
    /// Phase 2: the depth target's size.
    pub depth_w: u32,
    pub depth_h: u32,
}

/// Patch counts after each stage of one frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct CullCounters {
    /// 256 per listed node.
    pub patches_in: u32,
    pub after_frustum: u32,
    pub after_cone: u32,
    pub after_hole: u32,
    /// Instances of every draw (both lists, both phases).
    pub drawn: u32,
    /// Of those, patches with some holes (drawn by `terrain_holes`).
    pub drawn_with_holes: u32,
    /// Occlusion (0 without it): patches drawn in phase 1 (visible last
    /// frame), tested against the depth pyramid in phase 2 (the rest of
    /// the survivors) and drawn in phase 2 (those it left visible).
    pub drawn_phase1: u32,
    pub occlusion_tested: u32,
    pub drawn_phase2: u32,
    /// The error bound the frame achieved: the largest projected selection
    /// error (px) of any patch drawn (0 when none was): 99 % of every drawn
    /// patch within it, all of it within twice it.
    pub bound_px: f32,
    /// Patch edges clamped to `MAX_LOD_DELTA` (0 unless a seam may open).
    pub seam_overflow: u32,
}

impl CullCounters {
    /// Counters from the list headers: phase 1's (solid, holes) and, with
    /// occlusion, phase 2's; instance counts past `capacity` were not listed.
    pub fn from_headers(
        early: [Option<PatchListHeader>; 2],
        late: Option<[Option<PatchListHeader>; 2]>,
        capacity: u32,
    ) -> CullCounters {
        let drawn = |h: &Option<PatchListHeader>| h.map_or(0, |h| h.instance_count.min(capacity));
        let e = early[0].unwrap_or_default();
        let mut c = CullCounters {
            patches_in: e.patches_in,
            after_frustum: e.after_frustum,
            after_cone: e.after_cone,
            after_hole: e.after_hole,
            drawn: drawn(&early[0]) + drawn(&early[1]),
            drawn_with_holes: drawn(&early[1]),
            ..CullCounters::default()
        };
        let lists = early.iter().chain(late.iter().flatten()).flatten();
        for h in lists {
            c.bound_px = c.bound_px.max(f32::from_bits(h.bound_bits));
            c.seam_overflow += h.seam_overflow;
        }
        if let Some(late) = late {
            c.drawn_phase1 = c.drawn;
            c.drawn_phase2 = drawn(&late[0]) + drawn(&late[1]);
            c.occlusion_tested = late[0].map_or(0, |h| h.after_hole);
            c.drawn += c.drawn_phase2;
            c.drawn_with_holes += drawn(&late[1]);
        }
        c
    }
}

/// A patch list and, with holes, the list of patches with some holes; each
/// a header (indexed-indirect draw args + counters) then the records.
pub struct PatchLists {
    pub list: Buffer,
    pub hole_list: Option<Buffer>,
    pub capacity: u32,
    index_count: u32,
}

impl PatchLists {
    pub(crate) fn new(ctx: &Context, names: [&str; 2], capacity: u32, holes: bool, index_count: u32) -> Result<Self> {
        let list_buffer = |name| {
            Buffer::new(
                ctx,
                &BufferDesc {
                    name,
                    size: (structs::PATCH_LIST_HEADER + capacity as usize * RECORD_BYTES) as u64,
                    usage: vk::BufferUsageFlags::STORAGE_BUFFER
                        | vk::BufferUsageFlags::INDIRECT_BUFFER
                        | vk::BufferUsageFlags::TRANSFER_DST
                        | vk::BufferUsageFlags::TRANSFER_SRC,
                    location: MemoryLocation::GpuOnly,
                },
            )
        };
        let list = list_buffer(names[0])?;
        let hole_list = if holes { Some(list_buffer(names[1])?) } else { None };
        Ok(PatchLists { list, hole_list, capacity, index_count })
    }

    /// Resets both headers (draw args with zero instances, counters zero).
    pub(crate) fn reset(&self, rec: &mut Recorder) {
        let header = PatchListHeader { index_count: self.index_count, ..PatchListHeader::default() };
        rec.update_buffer(&self.list, 0, bytemuck::bytes_of(&header));
        if let Some(holes) = &self.hole_list {
            rec.update_buffer(holes, 0, bytemuck::bytes_of(&header));
        }
    }

    /// Both headers of the last frame (tests, CLI): waits.
    pub fn read_headers(&self, ctx: &Context) -> Result<[Option<PatchListHeader>; 2]> {
        let holes = match &self.hole_list {
            Some(b) => Some(read_header(ctx, b)?),
            None => None,
        };
        Ok([Some(read_header(ctx, &self.list)?), holes])
    }

    /// The last frame's patches of both lists (tests): waits.
    pub fn read_patches(&self, ctx: &Context) -> Result<Vec<PatchRecord>> {
        let mut out = Vec::new();
        for list in std::iter::once(&self.list).chain(&self.hole_list) {
            let bytes = ctx.read_buffer(list)?;
            let h: PatchListHeader = bytemuck::pod_read_unaligned(&bytes[..structs::PATCH_LIST_HEADER]);
            let n = h.instance_count.min(self.capacity) as usize;
            let raw = &bytes[structs::PATCH_LIST_HEADER..structs::PATCH_LIST_HEADER + n * RECORD_BYTES];
            out.extend(raw.chunks_exact(RECORD_BYTES).map(|c| PatchRecord::unpack(bytemuck::pod_read_unaligned(c))));
        }
        Ok(out)
    }

    pub fn memory(&self) -> impl Iterator<Item = &Buffer> {
        std::iter::once(&self.list).chain(&self.hole_list)
    }
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
    /// Levels below LOD 0 (0: the node's own samples).
    pub refine: u8,
    /// Sub-patch (row-major over 2^refine x 2^refine).
    pub sub: u8,
}

impl PatchRecord {
    pub(crate) fn unpack([n, w, r, _]: [u32; 4]) -> Self {
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
            refine: (r & k::PATCH_REFINE_MASK) as u8,
            sub: (r >> k::PATCH_SUB_SHIFT) as u8,
        }
    }
}

/// Which optional stages the pipeline is built with (effects `cone_cull`,
/// `holes` and `occlusion`); a stage not built has no code, binding or atlas.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CullBuild {
    pub cone: bool,
    pub holes: bool,
    /// Phase 1 of two-phase occlusion: list only patches visible last frame.
    pub occlusion: bool,
}

/// The inputs both culling phases bind, in the order of `CULL_INPUTS`.
pub(crate) struct CullInputs<'a> {
    pub traverse: &'a Traverse,
    pub tree: &'a GpuQuadtree,
    pub lod_map: &'a LodMap,
    pub view: &'a Buffer,
    pub select: &'a SelectPatches,
}

impl<'a> CullInputs<'a> {
    /// Resets `lists`, then dispatches `pipeline` (one workgroup per listed
    /// node) with the bindings of patch_cull.glsl plus `extra`; its writes
    /// are visible to indirect draws and every later command.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn dispatch(
        &self,
        rec: &mut Recorder,
        pipeline: &Pipeline,
        b: [Binding; 12],
        build: CullBuild,
        sampler: &Sampler,
        lists: &'a PatchLists,
        extra: &[(Binding, Resource<'a>)],
        push: &CullPush,
    ) {
        lists.reset(rec);
        rec.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::COMPUTE_SHADER);
        rec.bind_pipeline(pipeline);
        let mut bindings = self.bindings(b, build, sampler, lists);
        bindings.extend_from_slice(extra);
        rec.push_descriptors(pipeline, &bindings);
        rec.push_constants(pipeline, push);
        rec.dispatch_indirect(self.traverse.output(), 0);
        rec.barrier(
            vk::PipelineStageFlags2::COMPUTE_SHADER,
            vk::PipelineStageFlags2::DRAW_INDIRECT | vk::PipelineStageFlags2::ALL_COMMANDS,
        );
    }

    /// Bindings of patch_cull.glsl, given each shader's own reflected
    /// bindings [traverse_out, view, lod_map, patch_min_max, nearest,
    /// patch_list, patch_cones, patch_holes, hole_list, node_texture,
    /// patch_errors, select_levels].
    fn bindings(
        &self,
        b: [Binding; 12],
        build: CullBuild,
        sampler: &Sampler,
        lists: &'a PatchLists,
    ) -> Vec<(Binding, Resource<'a>)> {
        let mut out = vec![
            (b[0], Resource::Buffer(self.traverse.output())),
            (b[1], Resource::Buffer(self.view)),
            (b[2], Resource::Image(self.lod_map.image(), vk::ImageLayout::GENERAL)),
            (b[3], Resource::Image(self.tree.required_atlas(ATLAS_PATCH_MIN_MAX), ATLAS_LAYOUT)),
            (b[4], Resource::Sampler(sampler.raw())),
            (b[5], Resource::Buffer(&lists.list)),
            (b[9], Resource::Image(self.tree.node_texture(), vk::ImageLayout::GENERAL)),
            (b[10], Resource::Image(self.tree.required_atlas(ATLAS_PATCH_ERRORS), ATLAS_LAYOUT)),
            (b[11], Resource::Buffer(self.select.levels())),
        ];
        if build.cone {
            out.push((b[6], Resource::Image(self.tree.required_atlas(ATLAS_PATCH_CONES), ATLAS_LAYOUT)));
        }
        if let Some(holes) = &lists.hole_list {
            out.push((b[7], Resource::Image(self.tree.required_atlas(ATLAS_PATCH_HOLES), ATLAS_LAYOUT)));
            out.push((b[8], Resource::Buffer(holes)));
        }
        out
    }
}

pub(crate) fn nearest_sampler(ctx: &Context, name: &str) -> Result<Sampler> {
    Sampler::new(
        ctx,
        &SamplerDesc { name, filter: vk::Filter::NEAREST, address_mode: vk::SamplerAddressMode::CLAMP_TO_EDGE },
    )
}

/// Bilinear, clamped: the terrain's colour under an overlay's vertex
/// (terrain_blend.glsl), a pigment map.
pub(crate) fn linear_clamp_sampler(ctx: &Context, name: &str) -> Result<Sampler> {
    Sampler::new(
        ctx,
        &SamplerDesc { name, filter: vk::Filter::LINEAR, address_mode: vk::SamplerAddressMode::CLAMP_TO_EDGE },
    )
}

pub(crate) fn spec_constants() -> [(u32, u32); 2] {
    [(sh::SPEC_PATCHES_PER_SIDE, PATCHES_PER_NODE_SIDE), (sh::SPEC_PATCH_QUADS, PATCH_QUADS)]
}

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

/// Patch-list entries: every patch of the traversal's largest final list,
/// plus the sub-patches of the refined LOD-0 patches (at most
/// `MAX_REFINED_PATCHES`, each adding up to 4^REFINE_LEVELS - 1 records).
pub(crate) fn list_capacity(traverse: &Traverse) -> u32 {
    let per_refined = (1 << (2 * k::REFINE_LEVELS)) - 1;
    traverse.final_capacity() * PATCHES_PER_NODE as u32 + k::MAX_REFINED_PATCHES * per_refined
}

pub struct CullPatches {
    pipeline: Pipeline,
    sampler: Sampler,
    /// Phase 1's lists (all visible patches without occlusion); one per
    /// frame parity (`frame::per_frame`).
    lists: PerFrame<PatchLists>,
    pub build: CullBuild,
}

impl CullPatches {
    pub const NAME: &'static str = sh::PASS;

    /// Phase 1's lists of the frame being (or last) recorded.
    pub fn lists(&self) -> &PatchLists {
        self.lists.current()
    }

    /// Both copies (memory reports).
    pub fn all_lists(&self) -> &[PatchLists] {
        self.lists.all()
    }

    /// Frame `frame` writes its parity's lists.
    pub fn select_frame(&mut self, frame: u64) {
        self.lists.select(frame);
    }

    /// Room for every patch of the traversal's largest final list;
    /// `index_count` is the patch mesh's, written into the draw args.
    pub fn new(ctx: &Context, traverse: &Traverse, index_count: u32, build: CullBuild) -> Result<Self> {
        assert_eq!(sh::WORKGROUP_SIZE[0] as usize, PATCHES_PER_NODE, "one thread per patch of a node");
        let capacity = list_capacity(traverse);
        let lists = PerFrame::new(|i| {
            let names = [copy_name("patch_list", i), copy_name("hole_patch_list", i)];
            PatchLists::new(ctx, [names[0].as_str(), names[1].as_str()], capacity, build.holes, index_count)
        })?;
        let sampler = nearest_sampler(ctx, "cull_patches_sampler")?;
        let bit = |on: bool, b: u32| if on { b } else { 0 };
        let shader = sh::variant(
            bit(build.cone, sh::VARIANT_CONE_CULL)
                | bit(build.holes, sh::VARIANT_HOLE_CULL)
                | bit(build.occlusion, sh::VARIANT_OCCLUSION),
        );
        let desc = ComputePipelineDesc { name: Self::NAME, shader, specialization: &spec_constants() };
        let pipeline = Pipeline::compute(ctx, &desc)?;
        Ok(CullPatches { pipeline, sampler, lists, build })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// Resets the draw args and counters, then culls the patches of every
    /// node in `traverse`'s list as `select` chose them (the view was
    /// written by `select`). `visibility`: last frame's bits, with occlusion
    /// built.
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
        visibility: Option<&Buffer>,
    ) {
        assert_eq!(visibility.is_some(), self.build.occlusion, "visibility bits exactly with occlusion");
        rec.barrier(vk::PipelineStageFlags2::ALL_COMMANDS, vk::PipelineStageFlags2::ALL_TRANSFER);
        let extra: Vec<_> = visibility.map(|v| (sh::VISIBILITY, Resource::Buffer(v))).into_iter().collect();
        let lists = self.lists();
        let push = CullPush { stages: cull.bits(), capacity: lists.capacity, depth_w: 0, depth_h: 0 };
        let inputs = CullInputs { traverse, tree, lod_map, view, select };
        inputs.dispatch(rec, &self.pipeline, CULL_BINDINGS, self.build, &self.sampler, lists, &extra, &push);
    }
}

fn read_header(ctx: &Context, list: &Buffer) -> Result<PatchListHeader> {
    let bytes = ctx.read_buffer(list)?;
    Ok(bytemuck::pod_read_unaligned(&bytes[..structs::PATCH_LIST_HEADER]))
}
