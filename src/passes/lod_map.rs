//! `lod_map`: the R8 texture with one texel per sector holding the LOD of the
//! listed node covering it (0xFF: none), refilled from the traversal's final
//! node list every frame; the patch stitching reads LOD deltas from it.

use crate::error::Result;
use crate::frame::per_frame::{copy_name, PerFrame};
use crate::gpu::{vk, ComputePipelineDesc, Context, Image, ImageDesc, Pipeline, Recorder, Resource};
use crate::passes::traverse::Traverse;
use crate::shaders::lod_map as sh;
use crate::terrain::quadtree::texture_extent;
use crate::world::WorldDesc;

/// LOD map value of a sector no listed node covers (outside the world, or
/// its root not resident yet).
pub const NO_LOD: u8 = crate::shaders::consts::NO_LOD as u8;

pub struct LodMap {
    pipeline: Pipeline,
    /// R8_UINT, the node texture's padded mip-0 extent, GENERAL layout; one
    /// per frame parity (`frame::per_frame`).
    image: PerFrame<Image>,
}

impl LodMap {
    pub const NAME: &'static str = sh::PASS;

    pub fn new(ctx: &Context, world: &WorldDesc) -> Result<Self> {
        let image = PerFrame::new(|i| {
            Image::new(
                ctx,
                &ImageDesc {
                    name: &copy_name("lod_map", i),
                    format: vk::Format::R8_UINT,
                    extent: texture_extent(world),
                    mip_levels: 1,
                    array_layers: 1,
                    usage: vk::ImageUsageFlags::STORAGE
                        | vk::ImageUsageFlags::SAMPLED
                        | vk::ImageUsageFlags::TRANSFER_DST
                        | vk::ImageUsageFlags::TRANSFER_SRC,
                },
            )
        })?;
        ctx.submit_and_wait(|rec| {
            image.all().iter().for_each(|i| rec.discard_to(i, vk::ImageLayout::GENERAL));
            Ok(())
        })?;
        let desc = ComputePipelineDesc { name: Self::NAME, shader: &sh::SHADER, specialization: &[] };
        Ok(LodMap { pipeline: Pipeline::compute(ctx, &desc)?, image })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// The LOD map of the frame being (or last) recorded.
    pub fn image(&self) -> &Image {
        self.image.current()
    }

    /// Both copies (memory reports).
    pub fn images(&self) -> &[Image] {
        self.image.all()
    }

    /// Frame `frame` writes its parity's LOD map.
    pub fn select_frame(&mut self, frame: u64) {
        self.image.select(frame);
    }

    /// Clears, then fills from `traverse`'s output (indirect: one workgroup per node).
    pub fn record(&self, rec: &mut Recorder, traverse: &Traverse) {
        rec.clear_color_u32(self.image(), u32::from(NO_LOD));
        rec.barrier(vk::PipelineStageFlags2::ALL_COMMANDS, vk::PipelineStageFlags2::COMPUTE_SHADER);
        rec.bind_pipeline(&self.pipeline);
        rec.push_descriptors(
            &self.pipeline,
            &[
                (sh::TRAVERSE_OUT, Resource::Buffer(traverse.output())),
                (sh::LOD_MAP, Resource::Image(self.image(), vk::ImageLayout::GENERAL)),
            ],
        );
        rec.dispatch_indirect(traverse.output(), 0);
        rec.barrier(vk::PipelineStageFlags2::COMPUTE_SHADER, vk::PipelineStageFlags2::ALL_COMMANDS);
    }
}
