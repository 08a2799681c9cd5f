//! `debug_view`: one full-screen triangle over the display image that shows,
//! at terrain pixels, what the geometry pass recorded in the patch info
//! (the LOD each patch was drawn from, its refinement, the occlusion phase,
//! the patch grid's edges) or the shading classification. Recorded after
//! `lighting_resolve` only when a view is asked for
//! (`TerrainRenderer::debug_view`); [`DebugView::colour_of`] is the CPU
//! twin of the shader.

use crate::error::Result;
use crate::gpu::{vk, ColorTarget, Context, GraphicsPipelineDesc, Pipeline, Recorder, Resource, Sampler};
use crate::passes::cull_patches::nearest_sampler;
use crate::passes::terrain_geometry::RenderTargets;
use crate::shaders::consts as k;
use crate::shaders::{debug_view_frag as fs, debug_view_vert as vs};
use crate::targets::gbuffer::{classification_palette, GBuffer, FLAVOUR_COUNT};
use serde::Serialize;

/// What a debug view shows at terrain pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum DebugView {
    /// The LOD each patch was drawn from (6 colours, repeating), lighter
    /// per level refined below LOD 0.
    Lod,
    /// The shading flavours each pixel needs (as `classification.png`).
    Classification,
    /// Black outlines of every patch drawn, over the lit image.
    PatchEdges,
    /// Green where occlusion culling's phase 1 drew (visible last frame),
    /// magenta where phase 2 did.
    OcclusionPhase,
}

/// The LOD colours: LOD n takes `LOD_COLOURS[n % 6]`.
pub const LOD_COLOURS: [[u8; 3]; 6] =
    [[230, 60, 50], [240, 170, 40], [120, 200, 60], [40, 180, 200], [70, 90, 230], [190, 70, 210]];
const EDGE_COLOUR: [u8; 3] = [0, 0, 0];
const PHASE_COLOURS: [[u8; 3]; 2] = [[60, 200, 90], [230, 50, 220]];

/// Host twin of `DebugViewPush` (debug_view.frag).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct DebugViewPush {
    pub colours: [[f32; 4]; 6],
    pub mode: u32,
    pub pad: [u32; 3],
}

impl DebugView {
    pub const ALL: [DebugView; 4] =
        [DebugView::Lod, DebugView::Classification, DebugView::PatchEdges, DebugView::OcclusionPhase];

    pub fn name(self) -> &'static str {
        match self {
            DebugView::Lod => "LOD per patch",
            DebugView::Classification => "classification",
            DebugView::PatchEdges => "patch edges",
            DebugView::OcclusionPhase => "occlusion phase",
        }
    }

    fn mode(self) -> u32 {
        match self {
            DebugView::Lod => k::DEBUG_VIEW_LOD,
            DebugView::Classification => k::DEBUG_VIEW_CLASSIFICATION,
            DebugView::PatchEdges => k::DEBUG_VIEW_EDGES,
            DebugView::OcclusionPhase => k::DEBUG_VIEW_PHASE,
        }
    }

    /// The shader's colour table for this view (0..1).
    fn colours(self) -> [[f32; 3]; 6] {
        let mut c = [[0u8; 3]; 6];
        match self {
            DebugView::Lod => c = LOD_COLOURS,
            DebugView::Classification => c[..FLAVOUR_COUNT].copy_from_slice(&classification_palette()),
            DebugView::PatchEdges => c[0] = EDGE_COLOUR,
            DebugView::OcclusionPhase => c[..2].copy_from_slice(&PHASE_COLOURS),
        }
        c.map(|rgb| rgb.map(|v| f32::from(v) / 255.0))
    }

    /// The colour the shader writes at a pixel with this patch info and
    /// classification (`None`: the picture stays), rounded as UNORM.
    pub fn colour_of(self, patch_info: u8, classification: u8) -> Option<[u8; 3]> {
        let (info, class) = (u32::from(patch_info), u32::from(classification));
        if class == 0 {
            return None;
        }
        let colours = self.colours();
        let c = match self {
            DebugView::Lod => {
                let refine = (info >> k::PATCH_INFO_REFINE_SHIFT) & 3;
                let base = colours[((info & k::PATCH_INFO_LOD_MASK) % 6) as usize];
                base.map(|v| v + (1.0 - v) * 0.25 * refine as f32)
            }
            DebugView::Classification => {
                let on: Vec<[f32; 3]> =
                    (0..FLAVOUR_COUNT).filter(|b| class & (1 << b) != 0).map(|b| colours[b]).collect();
                let n = on.len().max(1) as f32;
                [0, 1, 2].map(|i| on.iter().map(|c| c[i]).sum::<f32>() / n)
            }
            DebugView::PatchEdges if info >> k::PATCH_INFO_EDGE_SHIFT == 0 => return None,
            DebugView::PatchEdges => colours[0],
            DebugView::OcclusionPhase => colours[((info >> k::PATCH_INFO_PHASE_SHIFT) & 1) as usize],
        };
        Some(c.map(|v| (v * 255.0).round() as u8))
    }
}

pub struct DebugViewPass {
    pipeline: Pipeline,
    nearest: Sampler,
}

impl DebugViewPass {
    pub const NAME: &'static str = vs::PASS;

    /// `format`: the colour target's (outputs `lit` and `hdr`).
    pub fn new(ctx: &Context, format: vk::Format) -> Result<Self> {
        let desc = GraphicsPipelineDesc {
            name: Self::NAME,
            vertex: &vs::SHADER,
            fragment: &fs::SHADER,
            specialization: &[],
            color_formats: &[format],
            depth_format: None,
            depth_compare: vk::CompareOp::ALWAYS,
            depth_write: false,
            stencil: None,
            cull_mode: vk::CullModeFlags::NONE,
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            // Alpha 0 where the picture stays.
            blend: true,
        };
        Ok(DebugViewPass {
            pipeline: Pipeline::graphics(ctx, &desc)?,
            nearest: nearest_sampler(ctx, "debug_view_nearest")?,
        })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// Draws `view` over the colour target (kept, in its frame layout).
    pub fn record(&self, rec: &mut Recorder, targets: &RenderTargets, gbuffer: &GBuffer, view: DebugView) {
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        rec.transition(&gbuffer.patch_info, read);
        rec.transition(&gbuffer.classification, read);
        rec.begin_rendering(&[ColorTarget { image: targets.required_color(), clear: None }], None);
        rec.bind_pipeline(&self.pipeline);
        rec.push_descriptors(
            &self.pipeline,
            &[
                (fs::PATCH_INFO, Resource::Image(&gbuffer.patch_info, read)),
                (fs::CLASSIFICATION, Resource::Image(&gbuffer.classification, read)),
                (fs::NEAREST, Resource::Sampler(self.nearest.raw())),
            ],
        );
        let colours = view.colours().map(|[r, g, b]| [r, g, b, 1.0]);
        rec.push_constants(&self.pipeline, &DebugViewPush { colours, mode: view.mode(), pad: [0; 3] });
        rec.draw(3, 1);
        rec.end_rendering();
    }
}
