//! `vt_feedback` (effect `virtual_texture`): lists the pages of the virtual
//! texture the frame's terrain pixels sample, one sample per
//! VT_FEEDBACK_STRIDE^2 block jittered over frames, each page once, without
//! a clear pass (the shader says how). The list is copied into the
//! renderer's readback ring right after (effects/virtual_texture).

use crate::error::Result;
use crate::gpu::{depth_layout, vk, Buffer, ComputePipelineDesc, Context, Pipeline, Recorder, Resource, Sampler};
use crate::passes::cull_patches::nearest_sampler;
use crate::passes::terrain_geometry::RenderTargets;
use crate::shaders::consts::VT_FEEDBACK_STRIDE;
use crate::shaders::{structs, vt_feedback as sh};
use crate::targets::gbuffer::GBuffer;

/// Host twin of `VtFeedbackPush`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VtFeedbackPush {
    pub jitter: [u32; 2],
    pub size: [u32; 2],
    pub stamp: u32,
    /// One sample per stride^2 pixels: VT_FEEDBACK_STRIDE, or 1 (`whole`).
    pub stride: u32,
    pub pad: [u32; 2],
}

const _: () = assert!(std::mem::size_of::<VtFeedbackPush>() == structs::VT_FEEDBACK_PUSH);

impl VtFeedbackPush {
    /// Frame `frame`'s sample place in each block: every place once per
    /// VT_FEEDBACK_STRIDE^2 frames, consecutive frames far apart.
    pub fn for_frame(frame: u64, size: [u32; 2]) -> VtFeedbackPush {
        let s = u64::from(VT_FEEDBACK_STRIDE);
        let i = frame % (s * s);
        let (x, row) = (i % s, i / s);
        // Each column visits every row (3 is coprime with the stride).
        let y = (row + 3 * x) % s;
        // Stamp 0 is the status buffer's initial value: never a frame's.
        let stamp = (frame % u64::from(u32::MAX)) as u32 + 1;
        VtFeedbackPush { jitter: [x as u32, y as u32], size, stamp, stride: VT_FEEDBACK_STRIDE, pad: [0; 2] }
    }

    /// Frame `frame` sampling every pixel: what the whole jitter cycle
    /// samples, in one frame (an offline render settling).
    pub fn whole(frame: u64, size: [u32; 2]) -> VtFeedbackPush {
        VtFeedbackPush { jitter: [0; 2], stride: 1, ..Self::for_frame(frame, size) }
    }

    /// Whether it samples every pixel.
    pub fn is_whole(&self) -> bool {
        self.stride == 1
    }
}

/// The buffers the feedback writes.
pub struct FeedbackTargets<'a> {
    pub state: &'a Buffer,
    pub status: &'a Buffer,
    pub requests: &'a Buffer,
}

pub struct VtFeedback {
    pipeline: Pipeline,
    nearest: Sampler,
}

impl VtFeedback {
    pub const NAME: &'static str = sh::PASS;

    pub fn new(ctx: &Context) -> Result<Self> {
        let desc = ComputePipelineDesc { name: Self::NAME, shader: &sh::SHADER, specialization: &[] };
        Ok(VtFeedback {
            pipeline: Pipeline::compute(ctx, &desc)?,
            nearest: nearest_sampler(ctx, "vt_feedback_nearest")?,
        })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// Resets the list's count and samples `gbuffer` (classification and
    /// normals in SHADER_READ_ONLY_OPTIMAL, as classify_tiles leaves them).
    pub fn record(
        &self,
        rec: &mut Recorder,
        view: &Buffer,
        targets: &RenderTargets,
        gbuffer: &GBuffer,
        out: &FeedbackTargets,
        push: VtFeedbackPush,
    ) {
        rec.update_buffer(out.requests, 0, bytemuck::bytes_of(&[0u32; 4]));
        rec.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::COMPUTE_SHADER);
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        rec.transition(&gbuffer.geometry_normals, read);
        rec.transition(targets.depth, depth_layout(targets.depth.format, true));
        rec.bind_pipeline(&self.pipeline);
        rec.push_descriptors(
            &self.pipeline,
            &[
                (sh::VIEW, Resource::Buffer(view)),
                (sh::DEPTH_TARGET, Resource::Image(targets.depth, depth_layout(targets.depth.format, true))),
                (sh::NORMALS, Resource::Image(&gbuffer.geometry_normals, read)),
                (sh::CLASSIFICATION, Resource::Image(&gbuffer.classification, read)),
                (sh::NEAREST, Resource::Sampler(self.nearest.raw())),
                (sh::VT_STATE, Resource::Buffer(out.state)),
                (sh::STATUS, Resource::Buffer(out.status)),
                (sh::REQUESTS, Resource::Buffer(out.requests)),
            ],
        );
        rec.push_constants(&self.pipeline, &push);
        let [gx, gy, _] = sh::WORKGROUP_SIZE;
        let cells = push.size.map(|s| s.div_ceil(push.stride));
        rec.dispatch(cells[0].div_ceil(gx), cells[1].div_ceil(gy), 1);
        rec.barrier(vk::PipelineStageFlags2::COMPUTE_SHADER, vk::PipelineStageFlags2::ALL_COMMANDS);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_jitter_visits_every_place_of_a_block() {
        let s = VT_FEEDBACK_STRIDE as u64;
        let places: std::collections::HashSet<[u32; 2]> =
            (0..s * s).map(|f| VtFeedbackPush::for_frame(f, [8, 8]).jitter).collect();
        assert_eq!(places.len() as u64, s * s);
        assert_ne!(VtFeedbackPush::for_frame(u64::from(u32::MAX) - 1, [8, 8]).stamp, 0);
    }
}
