//! `sector_data`: per sector, the atlas slot of the resident node covering it
//! at each LOD (SLOT_BITS each, 0 = none; every LOD a world can have), rebuilt
//! from the node texture, so any shader can sample the terrain through
//! terrain_sample.glsl.

use crate::error::Result;
use crate::frame::per_frame::{copy_name, PerFrame};
use crate::gpu::{
    vk, Buffer, BufferDesc, ComputePipelineDesc, Context, MemoryLocation, Pipeline, Recorder, Resource, Sampler,
    SamplerDesc,
};
use crate::shaders::sector_data as sh;
use crate::terrain::gpu_quadtree::GpuQuadtree;
use crate::terrain::quadtree::texture_extent;
use crate::world::WorldDesc;

/// u32 words per sector: room for the slot of each of `MAX_NODE_LODS` LODs.
pub const SECTOR_DATA_WORDS: u32 = crate::shaders::consts::SECTOR_DATA_WORDS;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SectorDataPush {
    pub sectors_x: u32,
    pub sectors_y: u32,
    pub lod_count: u32,
    pub pad: u32,
}

pub struct SectorData {
    pipeline: Pipeline,
    sampler: Sampler,
    /// `SECTOR_DATA_WORDS` u32 per sector, row-major over the padded extent;
    /// one per frame parity (`frame::per_frame`).
    buffer: PerFrame<Buffer>,
    pub extent: [u32; 2],
    lod_count: u32,
}

impl SectorData {
    pub const NAME: &'static str = sh::PASS;

    pub fn new(ctx: &Context, world: &WorldDesc) -> Result<Self> {
        let extent = texture_extent(world);
        let buffer = PerFrame::new(|i| {
            Buffer::new(
                ctx,
                &BufferDesc {
                    name: &copy_name("sector_data", i),
                    size: u64::from(extent[0] * extent[1]) * u64::from(SECTOR_DATA_WORDS) * 4,
                    usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC,
                    location: MemoryLocation::GpuOnly,
                },
            )
        })?;
        let sampler = Sampler::new(
            ctx,
            &SamplerDesc {
                name: "sector_data_sampler",
                filter: vk::Filter::NEAREST,
                address_mode: vk::SamplerAddressMode::CLAMP_TO_EDGE,
            },
        )?;
        let desc = ComputePipelineDesc { name: Self::NAME, shader: &sh::SHADER, specialization: &[] };
        Ok(SectorData { pipeline: Pipeline::compute(ctx, &desc)?, sampler, buffer, extent, lod_count: world.lod_count })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// The sector data of the frame being (or last) recorded.
    pub fn buffer(&self) -> &Buffer {
        self.buffer.current()
    }

    /// Both copies (memory reports).
    pub fn buffers(&self) -> &[Buffer] {
        self.buffer.all()
    }

    /// Frame `frame` writes its parity's sector data.
    pub fn select_frame(&mut self, frame: u64) {
        self.buffer.select(frame);
    }

    /// Workgroups of one dispatch.
    pub fn groups(&self) -> u64 {
        let [wx, wy, _] = sh::WORKGROUP_SIZE;
        u64::from(self.extent[0].div_ceil(wx)) * u64::from(self.extent[1].div_ceil(wy))
    }

    pub fn record(&self, rec: &mut Recorder, tree: &GpuQuadtree) {
        rec.bind_pipeline(&self.pipeline);
        rec.push_descriptors(
            &self.pipeline,
            &[
                (sh::NODE_TEXTURE, Resource::Image(tree.node_texture(), vk::ImageLayout::GENERAL)),
                (sh::NODE_SAMPLER, Resource::Sampler(self.sampler.raw())),
                (sh::SECTOR_DATA, Resource::Buffer(self.buffer())),
            ],
        );
        let push =
            SectorDataPush { sectors_x: self.extent[0], sectors_y: self.extent[1], lod_count: self.lod_count, pad: 0 };
        rec.push_constants(&self.pipeline, &push);
        let [wx, wy, _] = sh::WORKGROUP_SIZE;
        rec.dispatch(self.extent[0].div_ceil(wx), self.extent[1].div_ceil(wy), 1);
        rec.barrier(vk::PipelineStageFlags2::COMPUTE_SHADER, vk::PipelineStageFlags2::ALL_COMMANDS);
    }
}
