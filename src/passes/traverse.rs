//! `traverse`: the terrain quadtree walked in ONE dispatch of one workgroup,
//! the per-level lists in shared memory (Far Cry 5). `traverse_level` is the
//! reference variant with one dispatch per LOD and lists in global memory.
//! Both write the final node list, per-LOD counts, an overflow counter and
//! the indirect dispatch arguments for patch culling.

use crate::error::{Error, Result};
use crate::frame::per_frame::{copy_name, PerFrame};
use crate::gpu::{
    vk, Binding, Buffer, BufferDesc, ComputePipelineDesc, Context, MemoryLocation, Pipeline, Recorder, Resource,
    Sampler, SamplerDesc,
};
use crate::shaders::{consts as k, structs, traverse as single, traverse_level as multi};
use crate::terrain::gpu_quadtree::GpuQuadtree;
use crate::terrain::quadtree::node_from_ref;
use crate::terrain::selection::{GpuInputs, TraverseParams, TraverseResult, MAX_CAMERAS};
use crate::world::{NodeId, WorldDesc};

/// Entries of each shared-memory list: every entry is a distinct resident
/// node, so the slot budget bounds it.
pub const SHARED_LIST_CAPACITY: u32 = k::SHARED_LIST_CAPACITY;
/// Shared memory of traverse.comp: two lists plus two counters.
pub const SHARED_BYTES: u32 = 2 * SHARED_LIST_CAPACITY * 4 + 8;
/// `current_lod` of the finalize dispatch.
const LEVEL_FINALIZE: u32 = k::LEVEL_FINALIZE;
/// Levels of the `TraverseLevels` / `lod_counts` arrays.
const MAX_LEVELS: usize = k::MAX_LEVELS as usize;

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TraversePush {
    pub cameras: [[f32; 4]; MAX_CAMERAS],
    pub forwards: [[f32; 4]; MAX_CAMERAS],
    pub camera_count: u32,
    pub target_error_px: f32,
    pub sector_size_m: f32,
    pub lod_count: u32,
    pub root_grid_x: u32,
    pub root_grid_y: u32,
    pub height_lo: f32,
    pub height_scale: f32,
    pub list_capacity: u32,
    pub final_capacity: u32,
    pub current_lod: u32,
    pub box_pad: f32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TraverseHeader {
    pub dispatch: [u32; 3],
    pub node_count: u32,
    /// Nodes kept unrefined (roots included, never dropped) because a level
    /// list was full.
    pub overflow: u32,
    pub missing_roots: u32,
    pub pad: [u32; 2],
    pub lod_counts: [u32; MAX_LEVELS],
}

/// One level's indirect dispatch and list length (traverse_level.comp).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LevelArgs {
    pub x: u32,
    pub y: u32,
    pub z: u32,
    pub count: u32,
}

const LEVEL_ARGS_BYTES: u64 = std::mem::size_of::<LevelArgs>() as u64;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TraverseMode {
    /// One dispatch, lists in shared memory.
    SingleDispatch,
    /// One dispatch per LOD plus a finalize dispatch, lists in global memory.
    MultiDispatch,
}

pub struct Traverse {
    single: Pipeline,
    /// The per-level mode (benchmarks, tests): built on request only.
    multi: Option<Pipeline>,
    sampler: Sampler,
    /// Header + final node list; also the indirect args of patch culling.
    /// One per frame parity (`frame::per_frame`).
    output: PerFrame<Buffer>,
    levels: Option<Buffer>,
    world: WorldDesc,
    list_capacity: u32,
    final_capacity: u32,
    /// [`GpuInputs::box_pad`]: 0 but for the per-triangle rule.
    box_pad: f32,
}

impl Traverse {
    pub const NAME: &'static str = single::PASS;
    pub const LEVEL_NAME: &'static str = multi::PASS;

    /// Entries of the final node list (nodes past it are counted, not listed).
    pub fn final_capacity(&self) -> u32 {
        self.final_capacity
    }

    /// Checks the fixed bounds against the device and the slot budget.
    pub fn new(ctx: &Context, world: &WorldDesc, slots: u32) -> Result<Self> {
        Self::build(ctx, world, slots, false)
    }

    /// Also builds the per-level mode (`TraverseMode::MultiDispatch`).
    pub fn with_per_level(ctx: &Context, world: &WorldDesc, slots: u32) -> Result<Self> {
        Self::build(ctx, world, slots, true)
    }

    pub fn pipeline_label(&self) -> &str {
        &self.single.label
    }

    fn level_args(&self) -> &Buffer {
        self.levels.as_ref().expect("per-level mode needs Traverse::with_per_level")
    }

    /// Device memory: (name, bytes) of each buffer.
    pub fn memory(&self) -> Vec<(String, u64)> {
        self.output.all().iter().chain(&self.levels).map(|b| (b.name.clone(), b.memory_bytes())).collect()
    }

    /// The node list of the frame being (or last) recorded.
    pub fn output(&self) -> &Buffer {
        self.output.current()
    }

    /// Frame `frame` writes its parity's node list.
    pub fn select_frame(&mut self, frame: u64) {
        self.output.select(frame);
    }

    fn build(ctx: &Context, world: &WorldDesc, slots: u32, per_level: bool) -> Result<Self> {
        let limit = ctx.info().limits.max_compute_shared_memory_bytes;
        if SHARED_BYTES > limit {
            return Err(Error::Unsupported(format!(
                "traverse needs {SHARED_BYTES} bytes of shared memory, device has {limit}"
            )));
        }
        if slots >= SHARED_LIST_CAPACITY || world.lod_count as usize > MAX_LEVELS {
            return Err(Error::BadInput(format!(
                "traverse: {slots} slots / {} LODs exceed the fixed bounds ({} slots, {MAX_LEVELS} LODs)",
                world.lod_count,
                SHARED_LIST_CAPACITY - 1
            )));
        }
        let compute = |name, shader| Pipeline::compute(ctx, &ComputePipelineDesc { name, shader, specialization: &[] });
        let final_capacity = slots + 1;
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_DST
            | vk::BufferUsageFlags::TRANSFER_SRC;
        let header = std::mem::size_of::<TraverseHeader>() as u64;
        Ok(Traverse {
            single: compute(Self::NAME, &single::SHADER)?,
            multi: if per_level { Some(compute(Self::LEVEL_NAME, &multi::SHADER)?) } else { None },
            sampler: Sampler::new(
                ctx,
                &SamplerDesc {
                    name: "node_texture_sampler",
                    filter: vk::Filter::NEAREST,
                    address_mode: vk::SamplerAddressMode::CLAMP_TO_EDGE,
                },
            )?,
            output: PerFrame::new(|i| {
                Buffer::new(
                    ctx,
                    &BufferDesc {
                        name: &copy_name("traverse_output", i),
                        size: header + u64::from(final_capacity) * 8,
                        usage: storage | vk::BufferUsageFlags::INDIRECT_BUFFER,
                        location: MemoryLocation::GpuOnly,
                    },
                )
            })?,
            levels: if per_level {
                Some(Buffer::new(
                    ctx,
                    &BufferDesc {
                        name: "traverse_levels",
                        size: MAX_LEVELS as u64 * LEVEL_ARGS_BYTES
                            + u64::from(world.lod_count * SHARED_LIST_CAPACITY) * 4,
                        usage: storage | vk::BufferUsageFlags::INDIRECT_BUFFER,
                        location: MemoryLocation::GpuOnly,
                    },
                )?)
            } else {
                None
            },
            world: *world,
            list_capacity: SHARED_LIST_CAPACITY,
            final_capacity,
            box_pad: 0.0,
        })
    }

    /// Shrinks the level lists (tests provoke overflow with it).
    /// Pads every node's box by `pad` node sides (the per-triangle rule:
    /// its vertices' boxes reach a cell past their node).
    pub fn set_box_pad(&mut self, pad: f32) {
        assert!((0.0..1.0).contains(&pad));
        self.box_pad = pad;
    }

    pub fn set_list_capacity(&mut self, capacity: u32) {
        assert!((1..=SHARED_LIST_CAPACITY).contains(&capacity));
        self.list_capacity = capacity;
    }

    fn push(&self, params: &TraverseParams, current_lod: u32) -> TraversePush {
        let g = GpuInputs { box_pad: self.box_pad, ..GpuInputs::new(&self.world, params) };
        let root = self.world.grid(self.world.root_lod());
        TraversePush {
            cameras: g.cameras,
            forwards: g.forwards,
            camera_count: g.camera_count,
            target_error_px: g.target_error_px,
            sector_size_m: g.sector_size_m,
            lod_count: self.world.lod_count,
            root_grid_x: root[0],
            root_grid_y: root[1],
            height_lo: g.height_lo,
            height_scale: g.height_scale,
            list_capacity: self.list_capacity,
            final_capacity: self.final_capacity,
            current_lod,
            box_pad: g.box_pad,
        }
    }

    /// Records the traversal; the output is visible to every later command.
    pub fn record(&self, rec: &mut Recorder, tree: &GpuQuadtree, params: &TraverseParams, mode: TraverseMode) {
        let header = std::mem::size_of::<TraverseHeader>();
        rec.update_buffer(self.output(), 0, &vec![0u8; header]);
        let p = match mode {
            TraverseMode::SingleDispatch => &self.single,
            TraverseMode::MultiDispatch => self.multi.as_ref().expect("per-level mode needs Traverse::with_per_level"),
        };
        let mut bindings: Vec<(Binding, Resource)> = vec![
            (single::NODE_TEXTURE, Resource::Image(tree.node_texture(), vk::ImageLayout::GENERAL)),
            (single::NODE_SAMPLER, Resource::Sampler(self.sampler.raw())),
            (single::NODE_DESCS, Resource::Buffer(&tree.node_descs)),
            (single::NODE_ERRORS, Resource::Buffer(&tree.node_errors)),
            (single::TRAVERSE_OUT, Resource::Buffer(self.output())),
        ];
        if mode == TraverseMode::MultiDispatch {
            let init = [LevelArgs { x: 0, y: 1, z: 1, count: 0 }; MAX_LEVELS];
            rec.update_buffer(self.level_args(), 0, bytemuck::cast_slice(&init));
            bindings.push((multi::TRAVERSE_LEVELS, Resource::Buffer(self.level_args())));
        }
        rec.barrier(vk::PipelineStageFlags2::ALL_COMMANDS, vk::PipelineStageFlags2::COMPUTE_SHADER);
        rec.bind_pipeline(p);
        rec.push_descriptors(p, &bindings);
        match mode {
            TraverseMode::SingleDispatch => {
                rec.push_constants(p, &self.push(params, 0));
                rec.dispatch(1, 1, 1);
            }
            TraverseMode::MultiDispatch => {
                let root = self.world.root_lod() as u32;
                let [gx, gy] = self.world.grid(root as u8);
                for lod in (0..=root).rev() {
                    rec.push_constants(p, &self.push(params, lod));
                    if lod == root {
                        rec.dispatch((gx * gy).div_ceil(multi::WORKGROUP_SIZE[0]), 1, 1);
                    } else {
                        rec.dispatch_indirect(self.level_args(), u64::from(lod) * LEVEL_ARGS_BYTES);
                    }
                    rec.barrier(
                        vk::PipelineStageFlags2::COMPUTE_SHADER,
                        vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::DRAW_INDIRECT,
                    );
                }
                rec.push_constants(p, &self.push(params, LEVEL_FINALIZE));
                rec.dispatch(1, 1, 1);
            }
        }
        rec.barrier(vk::PipelineStageFlags2::ALL_COMMANDS, vk::PipelineStageFlags2::ALL_COMMANDS);
    }

    /// Reads the output back (tests, debug CLI): waits for the GPU.
    pub fn read_result(&self, ctx: &Context) -> Result<(TraverseHeader, TraverseResult)> {
        let bytes = ctx.read_buffer(self.output())?;
        let hsize = std::mem::size_of::<TraverseHeader>();
        let header: TraverseHeader = bytemuck::pod_read_unaligned(&bytes[..hsize]);
        let n = (header.node_count.min(self.final_capacity)) as usize;
        let raw: &[[u32; 2]] = bytemuck::cast_slice(&bytes[hsize..hsize + n * 8]);
        let mut nodes: Vec<(NodeId, u32)> = raw.iter().map(|[p, slot]| (node_from_ref(*p), *slot)).collect();
        nodes.sort();
        let result = TraverseResult {
            nodes,
            lod_counts: header.lod_counts,
            overflow: header.overflow,
            missing_roots: header.missing_roots,
        };
        Ok((header, result))
    }
}

/// Twin size checks live in tests/shaders.rs; this keeps the header in step.
const _: () = assert!(std::mem::size_of::<TraverseHeader>() == structs::TRAVERSE_HEADER);
