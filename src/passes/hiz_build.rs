//! `hiz_build`: the depth pyramid of occlusion culling's phase 2, built from
//! the depth phase 1 drew. Level 0 is the target's size rounded down to
//! powers of two (each texel the farthest depth of the up to 3x3 pixels it
//! covers, none dropped at non-power-of-two sizes), every later level an
//! exact 2x2 reduction; one dispatch per level (see the shader for why).
//! The pyramid (R32_SFLOAT, GENERAL) is made for the first target size
//! seen and remade when it changes; the old one is deferred-destroyed.

use crate::error::{Error, Result};
use crate::gpu::{vk, ComputePipelineDesc, Context, Image, ImageDesc, Pipeline, Recorder, Resource, Sampler};
use crate::passes::cull_patches::nearest_sampler;
use crate::shaders::hiz_build as sh;

/// Level 0's size for a `depth` target: each side rounded down to a power of two.
pub fn pyramid_size(depth: [u32; 2]) -> [u32; 2] {
    depth.map(|d| 1 << d.max(1).ilog2())
}

/// Levels down to 1x1.
pub fn pyramid_mips(size0: [u32; 2]) -> u32 {
    size0[0].max(size0[1]).ilog2() + 1
}

/// Size of `level`.
pub fn level_size(size0: [u32; 2], level: u32) -> [u32; 2] {
    size0.map(|s| (s >> level).max(1))
}

/// Host twin of `HizPush` (hiz_build.comp).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct HizPush {
    pub src_size: [u32; 2],
    pub dst_size: [u32; 2],
    pub level: u32,
    pub pad: [u32; 3],
}

pub struct HizBuild {
    pipeline: Pipeline,
    sampler: Sampler,
    pyramid: Option<Image>,
    /// The depth target size the pyramid was made for.
    source: [u32; 2],
}

impl HizBuild {
    pub const NAME: &'static str = sh::PASS;

    pub fn new(ctx: &Context) -> Result<Self> {
        let desc = ComputePipelineDesc { name: Self::NAME, shader: &sh::SHADER, specialization: &[] };
        Ok(HizBuild {
            pipeline: Pipeline::compute(ctx, &desc)?,
            sampler: nearest_sampler(ctx, "hiz_build_nearest")?,
            pyramid: None,
            source: [0, 0],
        })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// The pyramid of the last `record` (None before the first).
    pub fn pyramid(&self) -> Option<&Image> {
        self.pyramid.as_ref()
    }

    /// The depth target size the pyramid reduces.
    pub fn source_size(&self) -> [u32; 2] {
        self.source
    }

    /// A depth target the pass can read: sampled usage is needed.
    pub fn check_target(depth: &Image) -> Result<()> {
        if !depth.usage.contains(vk::ImageUsageFlags::SAMPLED) {
            return Err(Error::BadInput(format!(
                "depth target {} lacks SAMPLED usage, which occlusion culling needs to read it (or switch the \
                 occlusion effect off)",
                depth.name
            )));
        }
        Ok(())
    }

    /// Makes the pyramid for `size` unless it exists (before recording).
    pub fn prepare(&mut self, ctx: &Context, size: [u32; 2]) -> Result<()> {
        if self.pyramid.is_some() && self.source == size {
            return Ok(());
        }
        let size0 = pyramid_size(size);
        self.pyramid = Some(Image::new(
            ctx,
            &ImageDesc {
                name: "hiz_pyramid",
                format: vk::Format::R32_SFLOAT,
                extent: size0,
                mip_levels: pyramid_mips(size0),
                array_layers: 1,
                usage: vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC,
            },
        )?);
        self.source = size;
        Ok(())
    }

    /// Reduces `depth` (in its attachment layout, left so afterwards) into
    /// the pyramid made by `prepare`.
    pub fn record(&self, rec: &mut Recorder, depth: &Image) {
        let pyramid = self.pyramid.as_ref().expect("hiz_build::prepare runs before record");
        assert_eq!(depth.extent, self.source, "prepare was called for another target size");
        rec.transition(depth, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
        if pyramid.layout() != vk::ImageLayout::GENERAL {
            rec.discard_to(pyramid, vk::ImageLayout::GENERAL);
        }
        rec.bind_pipeline(&self.pipeline);
        let size0 = [pyramid.extent[0], pyramid.extent[1]];
        let [gx, gy, _] = sh::WORKGROUP_SIZE;
        for level in 0..pyramid.mip_levels {
            let dst = level_size(size0, level);
            let src = if level == 0 { depth.extent } else { level_size(size0, level - 1) };
            rec.push_descriptors(
                &self.pipeline,
                &[
                    (sh::DEPTH, Resource::Image(depth, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)),
                    (sh::NEAREST, Resource::Sampler(self.sampler.raw())),
                    (sh::PYRAMID, Resource::Image(pyramid, vk::ImageLayout::GENERAL)),
                    (sh::DST, Resource::ImageMip(pyramid, level, vk::ImageLayout::GENERAL)),
                ],
            );
            rec.push_constants(&self.pipeline, &HizPush { src_size: src, dst_size: dst, level, pad: [0; 3] });
            rec.dispatch(dst[0].div_ceil(gx), dst[1].div_ceil(gy), 1);
            rec.barrier(vk::PipelineStageFlags2::COMPUTE_SHADER, vk::PipelineStageFlags2::COMPUTE_SHADER);
        }
        rec.transition(depth, crate::gpu::depth_layout(depth.format, false));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pyramid_sizes_round_down_to_powers_of_two() {
        assert_eq!(pyramid_size([1280, 720]), [1024, 512]);
        assert_eq!(pyramid_size([256, 256]), [256, 256]);
        assert_eq!(pyramid_size([257, 131]), [256, 128]);
        assert_eq!(pyramid_mips([1024, 512]), 11);
        assert_eq!(level_size([1024, 512], 10), [1, 1]);
        assert_eq!(level_size([1024, 512], 9), [2, 1]);
    }
}
