//! `lighting_resolve`: the lit output of the tools and tests, from the
//! G-buffer: sun plus sky ambient (variant LIGHTING, the `lighting` effect)
//! or unlit albedo, into the caller's colour target (display-encoded: the
//! lit image exposed and through the scene's tonemapper, `render/tonemap.rs`;
//! unlit albedo clipped) and the renderer's HDR image, one full-screen
//! triangle stencil-tested against the terrain bit so the background keeps
//! the clear colour. With the `shadows` effect (variant SHADOWS) the sun
//! term is scaled by the pixel's share of the sun from `sun_shadows`; with
//! `atmosphere` (variant ATMOSPHERE) the terrain is seen through the height
//! fog of render/atmosphere.rs and the background is its sky (no stencil
//! test then: every pixel is written). It
//! leaves the depth target in its frame layout. An engine lights the
//! G-buffer itself and can leave this pass out of its frame.

use crate::error::Result;
use crate::gpu::{
    depth_layout, vk, Buffer, ColorTarget, Context, DepthTarget, GraphicsPipelineDesc, Pipeline, Recorder, Resource,
    Sampler,
};
use crate::passes::cull_patches::nearest_sampler;
use crate::passes::sector_data::SectorData;
use crate::passes::sun_shadows::SunShadows;
use crate::passes::terrain_geometry::{RenderTargets, COLOR_FORMAT, DEPTH_FORMAT, TERRAIN_ONLY};
use crate::passes::terrain_query::VistaTerrain;
use crate::render::gbuffer::{GBuffer, HDR_FORMAT};
use crate::shaders::{lighting_resolve_frag as fs, lighting_resolve_vert as vs};
use crate::terrain::gpu_quadtree::{GpuQuadtree, ATLAS_HEIGHT, ATLAS_LAYOUT};

/// Host twin of `LightingPush` (lighting_resolve.frag, variants SHADOWS
/// and ATMOSPHERE).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LightingPush {
    pub terrain: VistaTerrain,
    /// x: penumbra height per metre of occluder distance; y: the shadow
    /// texture's side; zw: unused.
    pub shadow: [f32; 4],
    /// [`AtmosphereParams::gpu`](crate::render::atmosphere::AtmosphereParams::gpu).
    pub fog: [[f32; 4]; 3],
}

/// What the SHADOWS and ATMOSPHERE variants read beyond the G-buffer.
pub struct ResolveInputs<'a> {
    pub terrain: VistaTerrain,
    pub sector_data: &'a SectorData,
    pub tree: &'a GpuQuadtree,
    /// The shadow pass and the sun's elevation (degrees), with shadows.
    pub shadows: Option<(&'a SunShadows, f64)>,
    /// The fog's push vectors, with the atmosphere.
    pub fog: Option<[[f32; 4]; 3]>,
}

pub struct LightingResolve {
    pipeline: Pipeline,
    nearest: Sampler,
    shadows: bool,
    atmosphere: bool,
}

impl LightingResolve {
    pub const NAME: &'static str = vs::PASS;

    /// `shadows` and `atmosphere` need `lighting`.
    pub fn new(ctx: &Context, lighting: bool, shadows: bool, atmosphere: bool) -> Result<Self> {
        assert!(lighting || !(shadows || atmosphere), "shadows and atmosphere need the lit image");
        let mut variant = 0;
        for (on, bit) in
            [(lighting, fs::VARIANT_LIGHTING), (shadows, fs::VARIANT_SHADOWS), (atmosphere, fs::VARIANT_ATMOSPHERE)]
        {
            if on {
                variant |= bit;
            }
        }
        let desc = GraphicsPipelineDesc {
            name: Self::NAME,
            vertex: &vs::SHADER,
            fragment: fs::variant(variant),
            specialization: &[],
            color_formats: &[COLOR_FORMAT, HDR_FORMAT],
            depth_format: Some(DEPTH_FORMAT),
            depth_compare: vk::CompareOp::ALWAYS,
            depth_write: false,
            // The atmosphere's sky covers the background too.
            stencil: if atmosphere { None } else { Some(TERRAIN_ONLY) },
            cull_mode: vk::CullModeFlags::NONE,
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
        };
        Ok(LightingResolve {
            pipeline: Pipeline::graphics(ctx, &desc)?,
            nearest: nearest_sampler(ctx, "lighting_resolve_nearest")?,
            shadows,
            atmosphere,
        })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// Expects the depth target in DEPTH_STENCIL_READ_ONLY_OPTIMAL (after
    /// `gbuffer_tiles`); leaves it writable again. `inputs` must carry what
    /// the variant built reads.
    pub fn record(
        &self,
        rec: &mut Recorder,
        targets: &RenderTargets,
        gbuffer: &GBuffer,
        view: &Buffer,
        inputs: &ResolveInputs,
    ) {
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        rec.transition(&gbuffer.albedo, read);
        rec.transition(&gbuffer.normal, read);
        rec.discard_to(&gbuffer.hdr, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
        rec.begin_rendering(
            &[
                ColorTarget { image: targets.color, clear: Some(targets.clear) },
                ColorTarget { image: &gbuffer.hdr, clear: Some(targets.clear) },
            ],
            Some(DepthTarget { image: targets.depth, clear: None, read_only: true }),
        );
        rec.bind_pipeline(&self.pipeline);
        let mut bindings = vec![
            (fs::VIEW, Resource::Buffer(view)),
            (fs::GB_ALBEDO, Resource::Image(&gbuffer.albedo, read)),
            (fs::GB_NORMAL, Resource::Image(&gbuffer.normal, read)),
            (fs::NEAREST, Resource::Sampler(self.nearest.raw())),
        ];
        let mut push = LightingPush { terrain: inputs.terrain, shadow: [0.0; 4], fog: [[0.0; 4]; 3] };
        if self.shadows || self.atmosphere {
            let depth_read = vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL;
            bindings.push((fs::DEPTH_TARGET, Resource::Image(targets.depth, depth_read)));
        }
        if self.shadows {
            let (shadows, elevation_deg) = inputs.shadows.expect("built with shadows");
            bindings.extend([
                (fs::SECTOR_DATA, Resource::Buffer(&inputs.sector_data.buffer)),
                (fs::HEIGHT_ATLAS, Resource::Image(inputs.tree.required_atlas(ATLAS_HEIGHT), ATLAS_LAYOUT)),
                (fs::SHADOW_ATLAS, Resource::Image(&shadows.atlas, vk::ImageLayout::GENERAL)),
            ]);
            let p = &shadows.params;
            push.shadow = [p.penumbra(elevation_deg), p.resolution as f32, 0.0, 0.0];
        }
        if self.atmosphere {
            push.fog = inputs.fog.expect("built with the atmosphere");
        }
        rec.push_descriptors(&self.pipeline, &bindings);
        if self.shadows || self.atmosphere {
            rec.push_constants(&self.pipeline, &push);
        }
        rec.draw(3, 1);
        rec.end_rendering();
        rec.transition(targets.depth, depth_layout(DEPTH_FORMAT, false));
    }
}
