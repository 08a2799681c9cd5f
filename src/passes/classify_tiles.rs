//! `classify_tiles`: ORs the classification bits over each 8x8 screen tile
//! and appends every tile with terrain to the list of its variant (its
//! combined flavour bits); the list's append counter is the instance count
//! of that variant's indirect draw in `gbuffer_tiles`. One invocation per
//! tile (the shader says why not one per pixel). The lists are sized for the first target size seen and remade
//! (the old buffer deferred-destroyed) when it changes.

use crate::error::Result;
use crate::gpu::{
    vk, Buffer, BufferDesc, ComputePipelineDesc, Context, MemoryLocation, Pipeline, Recorder, Resource, Sampler,
};
use crate::passes::cull_patches::nearest_sampler;
use crate::shaders::consts::{FLAVOUR_VARIANTS, TILE_SIZE};
use crate::shaders::{classify_tiles as sh, structs};
use crate::targets::gbuffer::GBuffer;

/// Host twin of `TilePush` (tile_lists.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TilePush {
    pub tiles_x: u32,
    pub tiles_y: u32,
    pub capacity: u32,
    /// Non-zero: every tile with terrain goes to this variant's list (the
    /// one-shader comparison of tests and benchmarks).
    pub force_variant: u32,
    pub width: u32,
    pub height: u32,
    pub pad1: [u32; 2],
}

const _: () = assert!(std::mem::size_of::<TilePush>() == structs::TILE_PUSH);
const _: () = assert!(std::mem::size_of::<vk::DrawIndirectCommand>() == structs::TILE_DRAW_ARGS);

/// Bytes of the draw arguments at the head of the lists.
pub const ARGS_BYTES: u64 = FLAVOUR_VARIANTS as u64 * structs::TILE_DRAW_ARGS as u64;
/// The head of the lists: the draw arguments, then the 4 plane counters
/// (control-map tiles whose background samples 1, 2, 3 planes; one unused).
pub const HEAD_BYTES: u64 = ARGS_BYTES + 16;

impl TilePush {
    pub fn for_size(size: [u32; 2]) -> TilePush {
        let [tx, ty] = size.map(|s| s.div_ceil(TILE_SIZE));
        TilePush { tiles_x: tx, tiles_y: ty, capacity: tx * ty, width: size[0], height: size[1], ..Default::default() }
    }
}

/// The per-variant tile lists and their draw arguments.
pub struct TileLists {
    pub buffer: Buffer,
    pub push: TilePush,
}

impl TileLists {
    /// Byte offset of `variant`'s draw arguments.
    pub fn args_offset(variant: u32) -> u64 {
        u64::from(variant) * structs::TILE_DRAW_ARGS as u64
    }

    /// Tile counts per variant and their entries (x, y), read back (waits;
    /// tests and reports).
    pub fn read(&self, ctx: &Context) -> Result<Vec<Vec<[u32; 2]>>> {
        let bytes = ctx.read_buffer(&self.buffer)?;
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&bytes);
        let cap = self.push.capacity as usize;
        let head = HEAD_BYTES as usize / 4;
        Ok((0..FLAVOUR_VARIANTS as usize)
            .map(|v| {
                let n = (words[v * 4 + 1] as usize).min(cap);
                let list = &words[head + v * cap..head + v * cap + n];
                list.iter().map(|e| [e & 0xFFFF, e >> 16]).collect()
            })
            .collect())
    }
}

pub struct ClassifyTiles {
    pipeline: Pipeline,
    nearest: Sampler,
    pub lists: Option<TileLists>,
}

impl ClassifyTiles {
    pub const NAME: &'static str = sh::PASS;

    pub fn new(ctx: &Context) -> Result<Self> {
        let desc = ComputePipelineDesc { name: Self::NAME, shader: &sh::SHADER, specialization: &[] };
        Ok(ClassifyTiles {
            pipeline: Pipeline::compute(ctx, &desc)?,
            nearest: nearest_sampler(ctx, "classify_tiles_nearest")?,
            lists: None,
        })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// Makes the lists for target `size` unless they exist (before recording).
    pub fn prepare(&mut self, ctx: &Context, size: [u32; 2]) -> Result<()> {
        let push = TilePush::for_size(size);
        if self.lists.as_ref().is_some_and(|l| l.push.width == size[0] && l.push.height == size[1]) {
            return Ok(());
        }
        let bytes = HEAD_BYTES + u64::from(FLAVOUR_VARIANTS) * u64::from(push.capacity) * 4;
        let buffer = Buffer::new(
            ctx,
            &BufferDesc {
                name: "tile_lists",
                size: bytes,
                usage: vk::BufferUsageFlags::STORAGE_BUFFER
                    | vk::BufferUsageFlags::INDIRECT_BUFFER
                    | vk::BufferUsageFlags::TRANSFER_DST
                    | vk::BufferUsageFlags::TRANSFER_SRC,
                location: MemoryLocation::GpuOnly,
            },
        )?;
        self.lists = Some(TileLists { buffer, push });
        Ok(())
    }

    /// Resets the draw arguments and classifies `gbuffer`'s classification
    /// target (left in SHADER_READ_ONLY_OPTIMAL).
    /// `force_variant`: see [`TilePush::force_variant`].
    pub fn record(&self, rec: &mut Recorder, gbuffer: &GBuffer, force_variant: u32) {
        let lists = self.lists.as_ref().expect("classify_tiles::prepare runs before record");
        assert_eq!(gbuffer.size(), [lists.push.width, lists.push.height], "prepare was called for another size");
        // Each variant's arguments, then the zeroed plane counters.
        let args: Vec<[u32; 4]> = (0..FLAVOUR_VARIANTS).map(|_| [6, 0, 0, 0]).chain([[0; 4]]).collect();
        rec.update_buffer(&lists.buffer, 0, bytemuck::cast_slice(&args));
        rec.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::COMPUTE_SHADER);
        rec.transition(&gbuffer.classification, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
        rec.bind_pipeline(&self.pipeline);
        rec.push_descriptors(
            &self.pipeline,
            &[
                (
                    sh::CLASSIFICATION,
                    Resource::Image(&gbuffer.classification, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL),
                ),
                (sh::LISTS, Resource::Buffer(&lists.buffer)),
                (sh::NEAREST, Resource::Sampler(self.nearest.raw())),
            ],
        );
        rec.push_constants(&self.pipeline, &TilePush { force_variant, ..lists.push });
        let [gx, gy, _] = sh::WORKGROUP_SIZE;
        rec.dispatch(lists.push.tiles_x.div_ceil(gx), lists.push.tiles_y.div_ceil(gy), 1);
        rec.barrier(vk::PipelineStageFlags2::COMPUTE_SHADER, vk::PipelineStageFlags2::ALL_COMMANDS);
    }
}
