//! Case 2: depth. Reversed-Z float depth with an infinite far plane stores
//! `near / d`, whose relative precision is the float's at every distance.
//! Two parallel planes 1e-5 of their distance apart are drawn through the
//! renderer's projection (`View::view_proj`, camera-relative, into
//! [`DEPTH_FORMAT`] with GREATER) from 1 m to 100 km: in both drawing
//! orders the nearer must win every pixel, and drawn alone its depth must
//! be larger than the farther one's at every pixel.

use super::{CaseReport, Form};
use crate::error::Result;
use crate::gpu::{vk, ColorTarget, Context, DepthTarget, GraphicsPipelineDesc, Image, ImageDesc, Pipeline};
use crate::passes::terrain_geometry::{DEPTH_FORMAT, DEPTH_LAYOUT};
use crate::render::{Camera, View, DEFAULT_NEAR_M};
use crate::shaders::{depth_probe_frag, depth_probe_vert};

/// Distances along the centre ray, metres.
const DISTANCES: [f64; 6] = [1.0, 10.0, 100.0, 1e3, 1e4, 1e5];
const SEPARATION: f64 = 1e-5;
/// Looking 60 degrees down: with a 60 degree field of view every pixel
/// sees the planes, from the centre distance's 0.87x to 1.73x.
const PITCH_DEG: f64 = -60.0;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct DepthProbePush {
    view_proj: [[f32; 4]; 4],
    planes: [f32; 4],
}

pub fn run(ctx: &Context, form: Form) -> Result<CaseReport> {
    let mut r = CaseReport::new(2, "depth");
    r.measured = "pixels where the farther of two parallel planes 1e-5 of their distance apart wins or ties, 1 m to 100 km, both drawing orders; the smallest gap between their stored depths".into();
    r.bound = "0 pixels; gap >= 1 float step".into();
    r.why = "reversed-Z float stores near/d with 2^-24 relative precision at any distance, so a 1e-5 relative gap is 84 to 168 float steps at any distance; a standard (forward) depth would lose it beyond a few hundred metres".into();
    let size = form.pick([128, 96], [512, 288]);
    let probe = Probe::new(ctx, size)?;
    let (mut wrong, mut min_gap) = (0usize, u32::MAX);
    for d in DISTANCES {
        let view = View {
            camera: Camera { position_m: [0.0; 3], yaw_deg: 0.0, pitch_deg: PITCH_DEG },
            fov_y_deg: 60.0,
            size,
            target_error_px: 1.0,
            near_m: DEFAULT_NEAR_M,
        };
        let height = d * (-PITCH_DEG).to_radians().sin();
        let (near, far) = (-height, -height * (1.0 + SEPARATION));
        let half = 8.0 * height;
        let vp = view.view_proj().as_mat4().to_cols_array_2d();
        let push =
            |z0: f64, z1: f64| DepthProbePush { view_proj: vp, planes: [z0 as f32, z1 as f32, half as f32, 0.0] };
        let (_, near_depth) = probe.draw(ctx, &push(near, near), 1)?;
        let (_, far_depth) = probe.draw(ctx, &push(far, far), 1)?;
        let (near_first, _) = probe.draw(ctx, &push(near, far), 2)?;
        let (far_first, _) = probe.draw(ctx, &push(far, near), 2)?;
        let (mut here, mut gap_here) = (0usize, u32::MAX);
        for i in 0..near_depth.len() {
            let (a, b) = (near_depth[i], far_depth[i]);
            // Red is instance 0, green instance 1: the near plane is red
            // when drawn first, green when drawn second.
            let near_won = near_first[i * 4] == 255 && far_first[i * 4 + 1] == 255;
            let gap = if a > b && b > 0.0 { a.to_bits() - b.to_bits() } else { 0 };
            here += usize::from(!near_won || gap == 0);
            gap_here = gap_here.min(gap);
        }
        r.details.push(format!(
            "{d:>8} m: {here} pixels wrong; smallest depth gap {gap_here} float steps (stored near/d {:.3e})",
            DEFAULT_NEAR_M / d
        ));
        wrong += here;
        min_gap = min_gap.min(gap_here);
    }
    r.worst = format!("{wrong} pixels; gap {min_gap} steps");
    r.pass = wrong == 0 && min_gap >= 1;
    Ok(r)
}

struct Probe {
    pipeline: Pipeline,
    color: Image,
    depth: Image,
}

impl Probe {
    fn new(ctx: &Context, size: [u32; 2]) -> Result<Probe> {
        let pipeline = Pipeline::graphics(
            ctx,
            &GraphicsPipelineDesc {
                name: depth_probe_vert::PASS,
                vertex: &depth_probe_vert::SHADER,
                fragment: &depth_probe_frag::SHADER,
                specialization: &[],
                color_formats: &[vk::Format::R8G8B8A8_UNORM],
                depth_format: Some(DEPTH_FORMAT),
                depth_compare: vk::CompareOp::GREATER,
                depth_write: true,
                stencil: None,
                cull_mode: vk::CullModeFlags::NONE,
                topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                blend: false,
            },
        )?;
        let image = |name, format, usage| {
            Image::new(ctx, &ImageDesc { name, format, extent: size, mip_levels: 1, array_layers: 1, usage })
        };
        let src = vk::ImageUsageFlags::TRANSFER_SRC;
        let color =
            image("depth_probe_color", vk::Format::R8G8B8A8_UNORM, vk::ImageUsageFlags::COLOR_ATTACHMENT | src)?;
        let depth = image("depth_probe_depth", DEPTH_FORMAT, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | src)?;
        Ok(Probe { pipeline, color, depth })
    }

    /// Clears (depth 0 = infinitely far), draws `instances` planes, reads
    /// colour (RGBA8) and depth back.
    fn draw(&self, ctx: &Context, push: &DepthProbePush, instances: u32) -> Result<(Vec<u8>, Vec<f32>)> {
        ctx.submit_and_wait(|rec| {
            rec.discard_to(&self.color, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
            rec.discard_to(&self.depth, DEPTH_LAYOUT);
            rec.begin_rendering(
                &[ColorTarget { image: &self.color, clear: Some([0.0; 4]) }],
                Some(DepthTarget { image: &self.depth, clear: Some(0.0), clear_stencil: true, read_only: false }),
            );
            rec.bind_pipeline(&self.pipeline);
            rec.push_constants(&self.pipeline, push);
            rec.draw(6, instances);
            rec.end_rendering();
            Ok(())
        })?;
        let rgba = ctx.read_image(&self.color, 0, 0, 4)?;
        let depth = ctx.read_image(&self.depth, 0, 0, 4)?;
        Ok((rgba, bytemuck::pod_collect_to_vec(&depth)))
    }
}
