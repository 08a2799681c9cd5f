//! What a frame's view and targets must be, checked before anything is
//! recorded, and the per-view resources sized for them.

use super::TerrainRenderer;
use crate::error::{Error, Result};
use crate::gpu::{vk, Context};
use crate::passes::debug_view::DebugViewPass;
use crate::passes::hiz_build::HizBuild;
use crate::passes::terrain_geometry::RenderTargets;
use crate::scene::view::View;
use crate::targets::gbuffer::GBuffer;
use crate::targets::Output;

impl TerrainRenderer {
    /// What a user can get wrong in a frame's view and targets; returns the
    /// view relative to the world's origin.
    pub(super) fn check_frame(&self, view: &View, targets: &RenderTargets) -> Result<View> {
        view.validate()?;
        if !self.origin_m.iter().all(|v| v.is_finite()) {
            return Err(Error::BadInput(format!("world origin {:?} is not finite", self.origin_m)));
        }
        let view = view.relative_to(self.origin_m);
        let depth_format = self.geometry.depth().format;
        let mut expected = vec![("depth", targets.depth, depth_format)];
        match (&self.output, targets.color) {
            (Output::Gbuffer(layout), None) => {
                if targets.gbuffer.len() != layout.attachments.len() {
                    return Err(Error::BadInput(format!(
                        "output gbuffer: {} G-buffer image(s) given, the layout has {}",
                        targets.gbuffer.len(),
                        layout.attachments.len()
                    )));
                }
                expected
                    .extend(targets.gbuffer.iter().zip(&layout.attachments).map(|(i, a)| ("G-buffer", *i, a.format)));
                if self.debug_view.is_some() {
                    return Err(Error::BadInput(
                        "output gbuffer has no colour target to draw a debug view over".into(),
                    ));
                }
            }
            (Output::Gbuffer(_), Some(c)) => {
                return Err(Error::BadInput(format!(
                    "output gbuffer writes the engine's G-buffer images, not a colour target ({} given)",
                    c.name
                )))
            }
            (output, Some(color)) if targets.gbuffer.is_empty() => {
                expected.push(("colour", color, output.color_format().expect("lit and hdr have one")));
            }
            (output, _) => {
                return Err(Error::BadInput(format!(
                    "output {} writes one colour target and no G-buffer images",
                    output.name()
                )))
            }
        }
        for (what, image, format) in expected {
            if image.extent != view.size || image.format != format {
                return Err(Error::BadInput(format!(
                    "{what} target {} is {:?} {}x{}, the view needs {format:?} {}x{}",
                    image.name, image.format, image.extent[0], image.extent[1], view.size[0], view.size[1]
                )));
            }
        }
        if !targets.depth.usage.contains(vk::ImageUsageFlags::SAMPLED) {
            return Err(Error::BadInput(format!(
                "depth target {} lacks SAMPLED usage, which the G-buffer tile shading needs to read it",
                targets.depth.name
            )));
        }
        Ok(view)
    }

    /// Sizes the per-view resources before anything is recorded.
    pub(super) fn prepare_frame(&mut self, ctx: &Context, view: &View, targets: &RenderTargets) -> Result<()> {
        let triangle_hiz = self.triangles.as_mut().and_then(|t| t.hiz.as_mut());
        if let Some(hiz) = self.occlusion.as_mut().map(|o| &mut o.hiz).or(triangle_hiz) {
            HizBuild::check_target(targets.depth)?;
            hiz.prepare(ctx, targets.depth.extent)?;
        }
        if self.gbuffer.as_ref().is_none_or(|g| g.size() != view.size) {
            self.gbuffer = Some(GBuffer::new(ctx, view.size, &self.output)?);
        }
        self.classify.prepare(ctx, view.size)?;
        if self.debug_view.is_some() && self.debug_pass.is_none() {
            let format = self.output.color_format().expect("check_frame refuses debug views without a colour target");
            self.debug_pass = Some(DebugViewPass::new(ctx, format)?);
        }
        Ok(())
    }
}
