//! `emit_triangles`: the per-triangle rule after the traversal (one
//! workgroup per drawn node): every node's cut of its bintree, by its
//! vertices' baked numbers (`world::vertex_bounds`), into one index list of
//! vertex codes that `terrain_triangles` draws (emit_triangles.comp says
//! how the cut stays conforming across nodes). Writes the frame's view
//! first, as `select_patches` does on the per-patch path.

use crate::error::Result;
use crate::frame::per_frame::{copy_name, PerFrame};
use crate::gpu::{
    vk, Buffer, BufferDesc, ComputePipelineDesc, Context, MemoryLocation, Pipeline, Recorder, Resource, Sampler,
};
use crate::passes::cull_patches::nearest_sampler;
use crate::passes::lod_map::LodMap;
use crate::passes::traverse::Traverse;
use crate::shaders::{consts as k, emit_triangles as sh, structs};
use crate::terrain::gpu_quadtree::{GpuQuadtree, ATLAS_HEIGHT, ATLAS_LAYOUT, ATLAS_VERTEX_BOUNDS};
use crate::terrain::quadtree::FIRST_SLOT;
use crate::world::NODE_QUADS;

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
    /// Largest projected node error (px) of a node drawn down to its
    /// grid's cells (what those cells may be off by).
    pub grid_bound_bits: u32,
}

const _: () = assert!(std::mem::size_of::<TriangleListHeader>() == structs::TRIANGLE_LIST_HEADER);
const _: () = assert!(NODE_QUADS == 1 << k::EMIT_THREAD_DEPTH);

impl TriangleListHeader {
    /// The error bound the frame achieved (px): the larger of the two.
    pub fn bound_px(&self) -> f32 {
        f32::from_bits(self.bound_bits).max(f32::from_bits(self.grid_bound_bits))
    }

    /// Triangles drawn (emitted within the capacity).
    pub fn drawn(&self) -> u32 {
        self.index_count / 3
    }
}

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct EmitPush {
    pub capacity: u32,
    /// 1: subtrees outside the frustum are dropped.
    pub frustum: u32,
    pub pad: [u32; 2],
}

pub struct EmitTriangles {
    pipeline: Pipeline,
    sampler: Sampler,
    /// Header (the draw's args, then counters), then 3 vertex codes a
    /// triangle; also the draw's index buffer (its indices start at
    /// `first_index`, past the header). One per frame parity
    /// (`frame::per_frame`): the compute phase writes it.
    list: PerFrame<Buffer>,
    /// The packed node of every slot drawn this frame (the vertex shader's
    /// way from a vertex code's slot to its node), one per frame parity.
    slot_nodes: PerFrame<Buffer>,
    capacity: u32,
}

impl EmitTriangles {
    pub const NAME: &'static str = sh::PASS;

    pub fn new(ctx: &Context, slot_capacity: u32) -> Result<Self> {
        let pipeline = Pipeline::compute(
            ctx,
            &ComputePipelineDesc {
                name: Self::NAME,
                shader: &sh::SHADER,
                specialization: &[(sh::SPEC_NODE_SIDE, NODE_QUADS)],
            },
        )?;
        let capacity = k::MAX_EMITTED_TRIANGLES;
        let list = PerFrame::new(|i| {
            Buffer::new(
                ctx,
                &BufferDesc {
                    name: &copy_name("emit_triangles_list", i),
                    size: (structs::TRIANGLE_LIST_HEADER + capacity as usize * 12) as u64,
                    usage: vk::BufferUsageFlags::STORAGE_BUFFER
                        | vk::BufferUsageFlags::INDEX_BUFFER
                        | vk::BufferUsageFlags::INDIRECT_BUFFER
                        | vk::BufferUsageFlags::TRANSFER_DST
                        | vk::BufferUsageFlags::TRANSFER_SRC,
                    location: MemoryLocation::GpuOnly,
                },
            )
        })?;
        let slot_nodes = PerFrame::new(|i| {
            Buffer::new(
                ctx,
                &BufferDesc {
                    name: &copy_name("emit_triangles_slot_nodes", i),
                    size: u64::from(FIRST_SLOT + slot_capacity) * 4,
                    usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                    location: MemoryLocation::GpuOnly,
                },
            )
        })?;
        Ok(EmitTriangles {
            pipeline,
            sampler: nearest_sampler(ctx, "emit_triangles_nearest")?,
            list,
            slot_nodes,
            capacity,
        })
    }

    /// The list of the frame being (or last) recorded.
    pub fn list(&self) -> &Buffer {
        self.list.current()
    }

    pub fn slot_nodes(&self) -> &Buffer {
        self.slot_nodes.current()
    }

    /// Frame `frame` writes its parity's copies.
    pub fn select_frame(&mut self, frame: u64) {
        self.list.select(frame);
        self.slot_nodes.select(frame);
    }

    pub fn capacity(&self) -> u32 {
        self.capacity
    }

    pub fn memory(&self) -> impl Iterator<Item = &Buffer> {
        self.list.all().iter().chain(self.slot_nodes.all())
    }

    /// Writes this frame's view (`view_bytes`, a TerrainView, into `view`)
    /// and resets the list's header behind one barrier, then emits every
    /// drawn node's triangles (`frustum`: dropping the subtrees outside
    /// the frustum); the list is visible to the indirect draw and every
    /// later command.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder,
        traverse: &Traverse,
        tree: &GpuQuadtree,
        lod_map: &LodMap,
        view: &Buffer,
        view_bytes: &[u8],
        frustum: bool,
    ) {
        rec.barrier(vk::PipelineStageFlags2::ALL_COMMANDS, vk::PipelineStageFlags2::ALL_TRANSFER);
        rec.update_buffer(view, 0, view_bytes);
        let header = TriangleListHeader {
            instance_count: 1,
            first_index: (structs::TRIANGLE_LIST_HEADER / 4) as u32,
            ..TriangleListHeader::default()
        };
        rec.update_buffer(self.list(), 0, bytemuck::bytes_of(&header));
        rec.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::COMPUTE_SHADER);
        rec.bind_pipeline(&self.pipeline);
        rec.push_descriptors(
            &self.pipeline,
            &[
                (sh::TRAVERSE_OUT, Resource::Buffer(traverse.output())),
                (sh::VIEW, Resource::Buffer(view)),
                (sh::LOD_MAP, Resource::Image(lod_map.image(), vk::ImageLayout::GENERAL)),
                (sh::HEIGHT_ATLAS, Resource::Image(tree.required_atlas(ATLAS_HEIGHT), ATLAS_LAYOUT)),
                (sh::VERTEX_BOUNDS, Resource::Image(tree.required_atlas(ATLAS_VERTEX_BOUNDS), ATLAS_LAYOUT)),
                (sh::NEAREST, Resource::Sampler(self.sampler.raw())),
                (sh::NODE_DESCS, Resource::Buffer(&tree.node_descs)),
                (sh::NODE_ERRORS, Resource::Buffer(&tree.node_errors)),
                (sh::TRIS, Resource::Buffer(self.list())),
                (sh::SLOT_NODES, Resource::Buffer(self.slot_nodes())),
            ],
        );
        let push = EmitPush { capacity: self.capacity, frustum: u32::from(frustum), pad: [0; 2] };
        rec.push_constants(&self.pipeline, &push);
        rec.dispatch_indirect(traverse.output(), 0);
        rec.barrier(
            vk::PipelineStageFlags2::COMPUTE_SHADER,
            vk::PipelineStageFlags2::DRAW_INDIRECT | vk::PipelineStageFlags2::ALL_COMMANDS,
        );
    }

    /// The last frame's header (tests, CLI): waits.
    pub fn read_header(&self, ctx: &Context) -> Result<TriangleListHeader> {
        let bytes = ctx.read_buffer(self.list())?;
        Ok(bytemuck::pod_read_unaligned(&bytes[..structs::TRIANGLE_LIST_HEADER]))
    }
}
