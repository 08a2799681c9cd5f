//! `emit_triangles`: the per-triangle rule after the traversal (one
//! workgroup per drawn node): every node's cut of its bintree, by its
//! vertices' baked numbers (`world::vertex_bounds`), into one index list of
//! vertex codes that `terrain_triangles` draws (emit_triangles.comp says
//! how the cut stays conforming across nodes). The LOD-0 cell halves its
//! cut reaches go to the fine list, which `emit_fine` walks below the
//! samples into the same index list. Writes the frame's view first, as
//! `select_patches` does on the per-patch path. With effect
//! `occlusion` it runs twice a frame ([`EmitPhase`]): phase 1 emits the
//! subtrees visible when last tested, phase 2 (after `hiz_build`) the
//! others the depth pyramid leaves visible, into its own list.

use crate::error::Result;
use crate::frame::per_frame::{copy_name, PerFrame};
use crate::gpu::{
    vk, Buffer, BufferDesc, ComputePipelineDesc, Context, Image, MemoryLocation, Pipeline, Recorder, Resource, Sampler,
};
use crate::passes::cull_patches::nearest_sampler;
use crate::passes::lod_map::LodMap;
use crate::passes::traverse::Traverse;
use crate::passes::triangle_lists::{TriangleList, FIRST_TRIANGLES};
use crate::shaders::{consts as k, emit_triangles as sh, structs};
use crate::terrain::gpu_quadtree::{
    GpuQuadtree, ATLAS_HEIGHT, ATLAS_LAYOUT, ATLAS_PATCH_HOLES, ATLAS_PATCH_MIN_MAX, ATLAS_VERTEX_BOUNDS,
};
use crate::terrain::quadtree::FIRST_SLOT;
use crate::world::{NODE_QUADS, PATCH_QUADS};

/// Host twin of `TriangleListHeader` (triangle_list.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable, serde::Serialize)]
pub struct TriangleListHeader {
    pub index_count: u32,
    pub instance_count: u32,
    pub first_index: u32,
    pub vertex_offset: i32,
    pub first_instance: u32,
    /// Triangles emitted (drawn, or past the capacity).
    pub triangles: u32,
    pub overflow: u32,
    /// Vertices the rule splits that a coarser node across the border lacks
    /// (drawn unsplit: the bound there is over the target).
    pub clamped: u32,
    /// Splits made for a finer neighbour's corners.
    pub forced: u32,
    /// Subtrees whose box lies outside the frustum.
    pub culled: u32,
    /// Largest projected error (px) of a drawn triangle's unsplit vertex.
    pub bound_bits: u32,
    /// Largest projected node error (px) of a node coarser than LOD 0
    /// drawn down to its grid's cells (what those cells may be off by; a
    /// LOD-0 node's finest triangles lie on the finest surface).
    pub grid_bound_bits: u32,
    /// LOD-0 cell halves drawn whole because the fine list was full (their
    /// node's error counts in `grid_bound_bits`).
    pub unrefined: u32,
    /// Subtrees inside a patch whose samples are all holes (not emitted).
    pub holes: u32,
    /// Triangles the cut left whole that face away from the camera (not
    /// emitted; effect `cone_cull`, each triangle on the node's grid).
    pub facing_away: u32,
    /// Triangles the cut left whole outside the frustum where their
    /// subtree's box is not (not emitted; each triangle on the node's grid).
    pub outside: u32,
}

/// Host twin of `FineCellsHeader` (fine_cells.glsl): `emit_fine`'s
/// dispatch, then the cell halves appended.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FineCellsHeader {
    pub groups: [u32; 3],
    pub count: u32,
}

const _: () = assert!(std::mem::size_of::<TriangleListHeader>() == structs::TRIANGLE_LIST_HEADER);
const _: () = assert!(std::mem::size_of::<FineCellsHeader>() == structs::FINE_CELLS_HEADER);
// A fine cell: slot | its index among the node's 2 << (2 x EMIT_THREAD_DEPTH) cell halves.
const _: () = assert!(k::SLOT_BITS + 2 * k::EMIT_THREAD_DEPTH < 32);
const _: () = assert!(NODE_QUADS == 1 << k::EMIT_THREAD_DEPTH);
// Each invocation decides its way to 4 of the 2 << EMIT_THREAD_DEPTH subtrees.
const _: () = assert!(sh::WORKGROUP_SIZE[0] == k::EMIT_GROUP_SIZE);
const _: () = assert!(4 * k::EMIT_GROUP_SIZE == 2 << k::EMIT_THREAD_DEPTH);
// emit_triangles_fine.glsl writes out the four bisections of two levels.
const _: () = assert!(k::REFINE_LEVELS == 2);
// A vertex code: x and y in lattice units (0..=NODE_QUADS << REFINE_LEVELS),
// their low and high bits, then the slot (constants.glsl's TRIANGLE_*).
const _: () = assert!((NODE_QUADS << k::REFINE_LEVELS) >> k::TRIANGLE_LOW_BITS < 1 << k::TRIANGLE_HIGH_BITS);
const _: () = assert!(k::TRIANGLE_SLOT_SHIFT == 2 * (k::TRIANGLE_LOW_BITS + k::TRIANGLE_HIGH_BITS));
const _: () = assert!(k::TRIANGLE_SLOT_SHIFT + k::SLOT_BITS <= 32);
// The mixed byte replaces exactly the low bits of x and y.
const _: () = assert!(2 * k::TRIANGLE_LOW_BITS == 8);

/// A vertex code's slot and point (x, y in lattice units): the host twin of
/// triangle_list.glsl's decoding (tests read the list back with it).
pub fn vertex_code_point(code: u32) -> (u32, [u32; 2]) {
    let (l, h) = (k::TRIANGLE_LOW_BITS, k::TRIANGLE_HIGH_BITS);
    let upper = code >> (2 * l);
    let bottom = (code & ((1 << (2 * l)) - 1)) ^ (upper.wrapping_mul(k::TRIANGLE_MIX_MUL) >> 24);
    let x = (bottom & ((1 << l) - 1)) | ((upper & ((1 << h) - 1)) << l);
    let y = (bottom >> l) | (((upper >> h) & ((1 << h) - 1)) << l);
    (code >> k::TRIANGLE_SLOT_SHIFT, [x, y])
}

impl TriangleListHeader {
    /// The error bound the frame achieved (px): the larger of the two.
    pub fn bound_px(&self) -> f32 {
        f32::from_bits(self.bound_bits).max(f32::from_bits(self.grid_bound_bits))
    }

    /// Triangles drawn (emitted within the capacity).
    pub fn drawn(&self) -> u32 {
        self.index_count / 3
    }

    /// Phase 1's and phase 2's counts added, their bounds the larger.
    fn merged(mut self, late: &TriangleListHeader) -> Self {
        self.index_count += late.index_count;
        self.triangles += late.triangles;
        self.overflow += late.overflow;
        self.clamped += late.clamped;
        self.forced += late.forced;
        self.culled += late.culled;
        self.unrefined += late.unrefined;
        self.holes += late.holes;
        self.facing_away += late.facing_away;
        self.outside += late.outside;
        self.bound_bits = self.bound_bits.max(late.bound_bits);
        self.grid_bound_bits = self.grid_bound_bits.max(late.grid_bound_bits);
        self
    }
}

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct EmitPush {
    pub capacity: u32,
    /// `EMIT_CULL_*` bits: subtrees outside the frustum, or inside a patch
    /// of holes only, and triangles facing away or (on their own) outside
    /// the frustum, are dropped.
    pub cull: u32,
    /// Phase 2: the depth target's size (the pyramid's level 0 comes from it).
    pub depth_size: [u32; 2],
    /// Cell halves the fine list holds.
    pub fine_capacity: u32,
}

/// What one recording of the pass emits.
#[derive(Clone, Copy)]
pub enum EmitPhase<'a> {
    /// Every triangle of the cut (occlusion not built, or off this frame).
    All,
    /// Occlusion's phase 1: the triangles above the invocations' depth and
    /// the subtrees visible when last tested.
    Early,
    /// Phase 2: the other subtrees `hiz`'s pyramid (made from a depth
    /// target of this size) leaves visible, into the second list.
    Late(&'a Image, [u32; 2]),
}

/// Occlusion's side of the pass (effect `occlusion`).
struct EmitOcclusion {
    early: Pipeline,
    late: Pipeline,
    /// Phase 2's list (its header and indices, as `list`), one per parity.
    list: TriangleList,
    /// One bit per invocation's subtree and slot, rewritten by phase 2;
    /// one per parity: a frame's phase 1 reads what its copy got two frames
    /// before (`cull_occluded` keeps its bits the same way). Unlike the
    /// patches' bits they are not cleared when a slot takes another node:
    /// a stale bit only moves a subtree from phase 2's test to phase 1's
    /// draw, and phase 2 rewrites it that frame.
    visibility: PerFrame<Buffer>,
    /// Which depth-7 triangles phase 1's cut reached (a bit each, as the
    /// visibility bits), for phase 2; one per parity.
    reached: PerFrame<Buffer>,
    /// Phase 2's fine list (as `fine`).
    fine: Buffer,
}

/// What every recording of the pass reads.
pub struct EmitInputs<'a> {
    pub traverse: &'a Traverse,
    pub tree: &'a GpuQuadtree,
    pub lod_map: &'a LodMap,
    /// The view the cut is made for, and its bytes (written into it by
    /// phase 1, or without occlusion).
    pub view: &'a Buffer,
    pub view_bytes: &'a [u8],
    /// Subtrees outside the frustum are dropped.
    pub frustum: bool,
    /// Subtrees inside a patch of holes only are dropped.
    pub holes: bool,
    /// Triangles facing away from the camera are dropped (where the pass is
    /// built with effect `cone_cull`).
    pub facing: bool,
}

pub struct EmitTriangles {
    pipeline: Pipeline,
    sampler: Sampler,
    /// Header (the draw's args, then counters), then 3 vertex codes a
    /// triangle; also the draw's index buffer (its indices start at
    /// `first_index`, past the header). One per frame parity
    /// (`frame::per_frame`): the compute phase writes it. It grows to
    /// what the frames emit (`emitted`).
    list: TriangleList,
    /// The packed node of every slot drawn this frame (the vertex shader's
    /// way from a vertex code's slot to its node), one per frame parity.
    slot_nodes: PerFrame<Buffer>,
    /// The LOD-0 cell halves the cut reaches, for `emit_fine` (its
    /// dispatch's header, then a word each). Written and read within the
    /// frame's LOD phase on one queue, so one copy, not one per parity.
    fine: Buffer,
    /// Cell halves the fine lists are used up to (`limit_fine_cells`).
    fine_capacity: u32,
    occlusion: Option<EmitOcclusion>,
    /// Built with effect `cone_cull`: triangles facing away may be dropped.
    facing: bool,
}

/// What the pass is built with (effects `occlusion` and `cone_cull`).
#[derive(Clone, Copy, Debug)]
pub struct EmitBuild {
    /// Phase 2's list and the visibility bits.
    pub occlusion: bool,
    /// The facing test of every triangle the cut leaves whole.
    pub facing: bool,
}

/// Whether the hole stage runs: asked for, and the world has holes (effect
/// `holes` keeps the per-patch hole flags only then).
fn holes_stage(inputs: &EmitInputs) -> bool {
    inputs.holes && inputs.tree.atlas(ATLAS_PATCH_HOLES).is_some()
}

/// The per-patch hole flags; without holes in the world (no such atlas)
/// another unsigned atlas fills the binding, never read: the push
/// constants leave the hole stage off (`holes_stage`).
fn patch_holes(tree: &GpuQuadtree) -> &Image {
    tree.atlas(ATLAS_PATCH_HOLES).unwrap_or_else(|| tree.required_atlas(ATLAS_VERTEX_BOUNDS))
}

fn fine_buffer(ctx: &Context, name: &str) -> Result<Buffer> {
    Buffer::new(
        ctx,
        &BufferDesc {
            name,
            size: (structs::FINE_CELLS_HEADER + k::MAX_FINE_CELLS as usize * 4) as u64,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::INDIRECT_BUFFER
                | vk::BufferUsageFlags::TRANSFER_DST
                | vk::BufferUsageFlags::TRANSFER_SRC,
            location: MemoryLocation::GpuOnly,
        },
    )
}

/// The debug names of phase 1's and phase 2's index lists.
const LIST: &str = "emit_triangles_list";
const LATE_LIST: &str = "emit_triangles_late_list";

fn pipeline(ctx: &Context, variant: u32) -> Result<Pipeline> {
    let specialization = [(sh::SPEC_NODE_SIDE, NODE_QUADS), (sh::SPEC_PATCH_QUADS, PATCH_QUADS)];
    Pipeline::compute(
        ctx,
        &ComputePipelineDesc {
            name: EmitTriangles::NAME,
            shader: sh::variant(variant),
            specialization: &specialization,
        },
    )
}

impl EmitOcclusion {
    fn new(ctx: &Context, slot_capacity: u32, first: u32) -> Result<Self> {
        let bits = |name: &str| {
            PerFrame::new(|i| {
                Buffer::new(
                    ctx,
                    &BufferDesc {
                        name: &copy_name(name, i),
                        size: u64::from((FIRST_SLOT + slot_capacity) * k::VISIBILITY_WORDS_PER_SLOT * 4),
                        usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                        location: MemoryLocation::GpuOnly,
                    },
                )
            })
        };
        let visibility = bits("triangle_visibility")?;
        ctx.submit_and_wait(|rec| {
            visibility.all().iter().for_each(|v| rec.fill_buffer(v, 0));
            Ok(())
        })?;
        Ok(EmitOcclusion {
            early: pipeline(ctx, sh::VARIANT_OCCLUSION)?,
            late: pipeline(ctx, sh::VARIANT_OCCLUSION | sh::VARIANT_LATE)?,
            list: TriangleList::new(ctx, LATE_LIST, first)?,
            visibility,
            reached: bits("triangle_reached")?,
            fine: fine_buffer(ctx, "emit_triangles_late_fine")?,
        })
    }
}

impl EmitTriangles {
    pub const NAME: &'static str = sh::PASS;

    pub fn new(ctx: &Context, slot_capacity: u32, build: EmitBuild) -> Result<Self> {
        let pipeline = pipeline(ctx, 0)?;
        let first = FIRST_TRIANGLES;
        let list = TriangleList::new(ctx, LIST, first)?;
        let slot_nodes = PerFrame::new(|i| {
            Buffer::new(
                ctx,
                &BufferDesc {
                    name: &copy_name("emit_triangles_slot_nodes", i),
                    size: u64::from(FIRST_SLOT + slot_capacity) * 4,
                    // TRANSFER_SRC: read back by tests, to place the list's triangles.
                    usage: vk::BufferUsageFlags::STORAGE_BUFFER
                        | vk::BufferUsageFlags::TRANSFER_DST
                        | vk::BufferUsageFlags::TRANSFER_SRC,
                    location: MemoryLocation::GpuOnly,
                },
            )
        })?;
        Ok(EmitTriangles {
            pipeline,
            sampler: nearest_sampler(ctx, "emit_triangles_nearest")?,
            list,
            slot_nodes,
            fine: fine_buffer(ctx, "emit_triangles_fine")?,
            fine_capacity: k::MAX_FINE_CELLS,
            occlusion: build.occlusion.then(|| EmitOcclusion::new(ctx, slot_capacity, first)).transpose()?,
            facing: build.facing,
        })
    }

    /// Built with occlusion's two phases.
    pub fn occludes(&self) -> bool {
        self.occlusion.is_some()
    }

    /// The list of the frame being (or last) recorded.
    pub fn list(&self) -> &Buffer {
        self.list.current()
    }

    /// Triangles the lists of the frame being (or last) recorded hold:
    /// phase 1's and phase 2's (`late`).
    pub fn capacity(&self, late: bool) -> u32 {
        match (late, &self.occlusion) {
            (true, Some(o)) => o.list.capacity(),
            _ => self.list.capacity(),
        }
    }

    /// A frame (phase 1, phase 2) emitted these triangles, drawn or past
    /// its list (the telemetry's, frames late): the lists grow to hold
    /// them when next selected.
    pub fn emitted(&mut self, early: u32, late: u32) {
        self.list.emitted(early);
        if let Some(o) = &mut self.occlusion {
            o.list.emitted(late);
        }
    }

    /// Phase 2's list of the frame being (or last) recorded.
    pub fn late_list(&self) -> Option<&Buffer> {
        self.occlusion.as_ref().map(|o| o.list.current())
    }

    /// The fine list of phase 2 (`late`) or of phase 1 / the only phase.
    pub fn fine_cells(&self, late: bool) -> &Buffer {
        match (late, &self.occlusion) {
            (true, Some(o)) => &o.fine,
            (true, None) => panic!("phase 2's fine list: built without occlusion"),
            (false, _) => &self.fine,
        }
    }

    pub fn slot_nodes(&self) -> &Buffer {
        self.slot_nodes.current()
    }

    /// Frame `frame` writes its parity's copies (its lists grown first
    /// where a frame emitted more than they hold).
    pub fn select_frame(&mut self, ctx: &Context, frame: u64) -> Result<()> {
        self.list.select(ctx, frame)?;
        self.slot_nodes.select(frame);
        if let Some(o) = &mut self.occlusion {
            o.list.select(ctx, frame)?;
            o.visibility.select(frame);
            o.reached.select(frame);
        }
        Ok(())
    }

    /// What `emit_triangles` and `emit_fine` push.
    pub fn push(&self, inputs: &EmitInputs, depth_size: [u32; 2], late: bool) -> EmitPush {
        EmitPush {
            capacity: self.capacity(late),
            cull: u32::from(inputs.frustum) * k::EMIT_CULL_FRUSTUM
                + u32::from(holes_stage(inputs)) * k::EMIT_CULL_HOLES
                + u32::from(inputs.facing && self.facing) * k::EMIT_CULL_FACING,
            depth_size,
            fine_capacity: self.fine_capacity,
        }
    }

    /// Makes the triangle lists anew at `triangles` each (tests reach
    /// their growth with it); they grow from there as before.
    pub fn restart_lists(&mut self, ctx: &Context, triangles: u32) -> Result<()> {
        self.list = TriangleList::new(ctx, LIST, triangles)?;
        if let Some(o) = &mut self.occlusion {
            o.list = TriangleList::new(ctx, LATE_LIST, triangles)?;
        }
        Ok(())
    }

    /// Makes the fine lists hold only `cells` cell halves (at most
    /// `MAX_FINE_CELLS`): the cells past it are drawn whole, counted in
    /// the header's `unrefined` (tests reach that path with it).
    pub fn limit_fine_cells(&mut self, cells: u32) {
        assert!(cells <= k::MAX_FINE_CELLS, "{cells} cell halves: the fine lists hold {}", k::MAX_FINE_CELLS);
        self.fine_capacity = cells;
    }

    pub fn memory(&self) -> impl Iterator<Item = &Buffer> {
        self.list.buffers().chain(self.slot_nodes.all()).chain([&self.fine])
    }

    /// Occlusion's buffers (phase 2's lists, the visibility bits).
    pub fn occlusion_memory(&self) -> impl Iterator<Item = &Buffer> {
        self.occlusion
            .iter()
            .flat_map(|o| o.list.buffers().chain(o.visibility.all()).chain(o.reached.all()).chain([&o.fine]))
    }

    /// Emits every drawn node's triangles of `phase` into its list, after
    /// resetting that list's header (and, in phase 1 or without occlusion,
    /// writing this frame's view first; without occlusion this frame, phase
    /// 2's list is emptied too), behind barriers: the list is visible to
    /// the indirect draw and every later command.
    pub fn record(&self, rec: &mut Recorder, inputs: &EmitInputs, phase: EmitPhase) {
        let occlusion = || self.occlusion.as_ref().expect("built with occlusion");
        let late = matches!(phase, EmitPhase::Late(..));
        let (pipeline, list) = match phase {
            EmitPhase::All => (&self.pipeline, self.list()),
            EmitPhase::Early => (&occlusion().early, self.list()),
            EmitPhase::Late(..) => (&occlusion().late, occlusion().list.current()),
        };
        let fine = FineCellsHeader { groups: [0, 1, 1], count: 0 };
        let header = TriangleListHeader {
            instance_count: 1,
            first_index: (structs::TRIANGLE_LIST_HEADER / 4) as u32,
            ..TriangleListHeader::default()
        };
        rec.barrier(vk::PipelineStageFlags2::ALL_COMMANDS, vk::PipelineStageFlags2::ALL_TRANSFER);
        if !matches!(phase, EmitPhase::Late(..)) {
            rec.update_buffer(inputs.view, 0, inputs.view_bytes);
        }
        rec.update_buffer(list, 0, bytemuck::bytes_of(&header));
        rec.update_buffer(self.fine_cells(late), 0, bytemuck::bytes_of(&fine));
        if let (EmitPhase::All, Some(o)) = (phase, &self.occlusion) {
            rec.update_buffer(o.list.current(), 0, bytemuck::bytes_of(&header));
        }
        rec.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::COMPUTE_SHADER);
        rec.bind_pipeline(pipeline);
        let mut bindings = self.bindings(inputs, list, late);
        bindings.push((sh::TRAVERSE_OUT, Resource::Buffer(inputs.traverse.output())));
        let mut depth_size = [0; 2];
        if let Some(o) = self.occlusion.as_ref().filter(|_| !matches!(phase, EmitPhase::All)) {
            bindings.push((sh::VISIBILITY, Resource::Buffer(o.visibility.current())));
            bindings.push((sh::REACHED, Resource::Buffer(o.reached.current())));
        }
        if let EmitPhase::Late(hiz, size) = phase {
            bindings.push((sh::HIZ, Resource::Image(hiz, vk::ImageLayout::GENERAL)));
            let min_max = inputs.tree.required_atlas(ATLAS_PATCH_MIN_MAX);
            bindings.push((sh::PATCH_MIN_MAX, Resource::Image(min_max, ATLAS_LAYOUT)));
            depth_size = size;
        }
        rec.push_descriptors(pipeline, &bindings);
        rec.push_constants(pipeline, &self.push(inputs, depth_size, late));
        rec.dispatch_indirect(inputs.traverse.output(), 0);
        rec.barrier(
            vk::PipelineStageFlags2::COMPUTE_SHADER,
            vk::PipelineStageFlags2::DRAW_INDIRECT | vk::PipelineStageFlags2::ALL_COMMANDS,
        );
    }

    /// What `emit_triangles` and `emit_fine` both bind (the same numbers,
    /// emit_triangles_core.glsl): phase `late`'s list and fine list.
    pub fn bindings<'b>(
        &'b self,
        i: &EmitInputs<'b>,
        list: &'b Buffer,
        late: bool,
    ) -> Vec<(crate::gpu::Binding, Resource<'b>)> {
        let tree = i.tree;
        vec![
            (sh::VIEW, Resource::Buffer(i.view)),
            (sh::LOD_MAP, Resource::Image(i.lod_map.image(), vk::ImageLayout::GENERAL)),
            (sh::HEIGHT_ATLAS, Resource::Image(tree.required_atlas(ATLAS_HEIGHT), ATLAS_LAYOUT)),
            (sh::VERTEX_BOUNDS, Resource::Image(tree.required_atlas(ATLAS_VERTEX_BOUNDS), ATLAS_LAYOUT)),
            (sh::PATCH_HOLES, Resource::Image(patch_holes(tree), ATLAS_LAYOUT)),
            (sh::NEAREST, Resource::Sampler(self.sampler.raw())),
            (sh::NODE_DESCS, Resource::Buffer(&tree.node_descs)),
            (sh::NODE_ERRORS, Resource::Buffer(&tree.node_errors)),
            (sh::TRIS, Resource::Buffer(list)),
            (sh::SLOT_NODES, Resource::Buffer(self.slot_nodes())),
            (sh::FINE, Resource::Buffer(self.fine_cells(late))),
        ]
    }

    /// The last frame's header, both phases' merged (tests, CLI): waits.
    pub fn read_header(&self, ctx: &Context) -> Result<TriangleListHeader> {
        let read = |list: &Buffer| -> Result<TriangleListHeader> {
            let bytes = ctx.read_buffer(list)?;
            Ok(bytemuck::pod_read_unaligned(&bytes[..structs::TRIANGLE_LIST_HEADER]))
        };
        let early = read(self.list())?;
        match self.late_list() {
            Some(late) => Ok(early.merged(&read(late)?)),
            None => Ok(early),
        }
    }
}
