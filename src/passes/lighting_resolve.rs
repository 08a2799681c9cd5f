//! `lighting_resolve`: vista's own lighting of the G-buffer (outputs
//! `lit` and `hdr`; with output `gbuffer` the engine lights and this pass
//! is not built): sun plus sky ambient (variant LIGHTING, the `lighting`
//! effect) or unlit albedo. Output `lit` writes the caller's display target
//! (the lit image exposed and through the scene's tonemapper,
//! `scene/tonemap.rs`; unlit albedo clipped; sRGB-encoded by the shader
//! or, for an sRGB target, by the target) and the renderer's HDR image;
//! output `hdr` (variant HDR_OUTPUT) writes the linear radiance alone into
//! the engine's float target. One full-screen triangle whose shader-set
//! depth fails a NOT_EQUAL test on the pixels vista did not draw (the
//! engine's own under a loaded depth, and the background unless the
//! atmosphere's sky fills it), leaving them as they are: the background
//! keeps the clear colour. With the `shadows` effect (variant SHADOWS) the sun
//! term is scaled by the pixel's share of the sun from `sun_shadows`; with
//! `atmosphere` (variant ATMOSPHERE) the terrain is seen through the height
//! fog of effects/atmosphere and, where the output has a sky, the
//! background is its sky (no depth test then). It leaves the depth target
//! in its frame layout.

use crate::error::Result;
use crate::gpu::{
    depth_layout, vk, Buffer, ColorTarget, Context, DepthTarget, GraphicsPipelineDesc, Image, Pipeline, Recorder,
    Resource, Sampler,
};
use crate::passes::cull_patches::nearest_sampler;
use crate::passes::sector_data::SectorData;
use crate::passes::terrain_geometry::RenderTargets;
use crate::passes::terrain_query::VistaTerrain;
use crate::shaders::{lighting_resolve_frag as fs, lighting_resolve_vert as vs};
use crate::targets::gbuffer::{GBuffer, HDR_FORMAT};
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
    /// [`AtmosphereParams::gpu`](crate::effects::atmosphere::AtmosphereParams::gpu).
    pub fog: [[f32; 4]; 3],
}

/// What effect `shadows` gives the resolve: the per-node shadow atlas,
/// the penumbra's height per metre of occluder distance and the atlas'
/// texels per node side.
pub struct ShadowInput<'a> {
    pub atlas: &'a Image,
    pub penumbra: f32,
    pub resolution: u32,
}

/// What the SHADOWS and ATMOSPHERE variants read beyond the G-buffer.
pub struct ResolveInputs<'a> {
    pub terrain: VistaTerrain,
    pub sector_data: &'a SectorData,
    pub tree: &'a GpuQuadtree,
    /// Effect `shadows`: its atlas and penumbra.
    pub shadows: Option<ShadowInput<'a>>,
    /// The fog's push vectors, with the atmosphere.
    pub fog: Option<[[f32; 4]; 3]>,
}

/// What the pass writes: output `lit` (a display target of `format`, and
/// vista's HDR image) or `hdr` (the engine's float target of `format`;
/// `sky`: the atmosphere's sky fills the background).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ResolveTarget {
    pub hdr: bool,
    pub format: vk::Format,
    pub sky: bool,
}

impl ResolveTarget {
    /// The target of `output` (None: output `gbuffer`, no resolve).
    pub fn of(output: &crate::targets::Output) -> Option<ResolveTarget> {
        use crate::targets::Output;
        match output {
            Output::Lit { format } => Some(ResolveTarget { hdr: false, format: *format, sky: true }),
            Output::Hdr { format, sky } => Some(ResolveTarget { hdr: true, format: *format, sky: *sky }),
            Output::Gbuffer(_) => None,
        }
    }
}

pub struct LightingResolve {
    /// Per combination of lighting (bit 0), shadows (bit 1) and atmosphere
    /// (bit 2) on, of those built: its variant, once asked for (the built
    /// one at once).
    pipelines: [Option<Pipeline>; 8],
    nearest: Sampler,
    /// Built with (the most a frame may ask for).
    built: usize,
    /// What this frame's `record` draws (`prepare`).
    current: usize,
    depth_format: vk::Format,
    target: ResolveTarget,
}

const LIGHTING: usize = 1;
const SHADOWS: usize = 2;
const ATMOSPHERE: usize = 4;

/// The index of a combination in `LightingResolve::pipelines`; shadows and
/// the atmosphere need the lit image.
fn combination(lighting: bool, shadows: bool, atmosphere: bool) -> usize {
    let lit = |on: bool, bit: usize| if lighting && on { bit } else { 0 };
    lit(true, LIGHTING) | lit(shadows, SHADOWS) | lit(atmosphere, ATMOSPHERE)
}

fn pipeline(ctx: &Context, on: usize, depth_format: vk::Format, target: ResolveTarget) -> Result<Pipeline> {
    let sky = on & ATMOSPHERE != 0 && target.sky;
    let mut variant =
        [(LIGHTING, fs::VARIANT_LIGHTING), (SHADOWS, fs::VARIANT_SHADOWS), (ATMOSPHERE, fs::VARIANT_ATMOSPHERE)]
            .into_iter()
            .filter(|&(bit, _)| on & bit != 0)
            .fold(0, |v, (_, variant)| v | variant);
    if target.hdr {
        variant |= fs::VARIANT_HDR_OUTPUT;
    }
    let srgb = matches!(target.format, vk::Format::R8G8B8A8_SRGB | vk::Format::B8G8R8A8_SRGB);
    let fragment = fs::variant(variant);
    let mut spec = vec![(fs::SPEC_SKY, u32::from(sky))];
    if !target.hdr {
        spec.push((fs::SPEC_DISPLAY_SRGB_TARGET, u32::from(srgb)));
    }
    let lit_formats = [target.format, HDR_FORMAT];
    let desc = GraphicsPipelineDesc {
        name: LightingResolve::NAME,
        vertex: &vs::SHADER,
        fragment,
        specialization: &spec,
        color_formats: if target.hdr { &lit_formats[..1] } else { &lit_formats },
        depth_format: Some(depth_format),
        // The shader's depth picks the pixels it writes: 0 over what vista
        // drew, 1 where the sky fills the background, the stored depth
        // (never written) elsewhere.
        depth_compare: vk::CompareOp::NOT_EQUAL,
        depth_write: false,
        stencil: None,
        cull_mode: vk::CullModeFlags::NONE,
        topology: vk::PrimitiveTopology::TRIANGLE_LIST,
        blend: false,
    };
    Pipeline::graphics(ctx, &desc)
}

impl LightingResolve {
    pub const NAME: &'static str = vs::PASS;

    /// `shadows` and `atmosphere` need `lighting`; `depth_format`: the
    /// renderer's depth target's; `target`: what it writes.
    pub fn new(
        ctx: &Context,
        (lighting, shadows, atmosphere): (bool, bool, bool),
        depth_format: vk::Format,
        target: ResolveTarget,
    ) -> Result<Self> {
        assert!(lighting || !(shadows || atmosphere), "shadows and atmosphere need the lit image");
        let built = combination(lighting, shadows, atmosphere);
        let mut pipelines: [Option<Pipeline>; 8] = Default::default();
        pipelines[built] = Some(pipeline(ctx, built, depth_format, target)?);
        Ok(LightingResolve {
            pipelines,
            nearest: nearest_sampler(ctx, "lighting_resolve_nearest")?,
            built,
            current: built,
            depth_format,
            target,
        })
    }

    /// Labels of the variants made.
    pub fn pipeline_labels(&self) -> Vec<String> {
        self.pipelines.iter().flatten().map(|p| p.label.clone()).collect()
    }

    /// What it writes.
    pub fn target(&self) -> ResolveTarget {
        self.target
    }

    /// The next frame draws with `lighting`, `shadows` and `atmosphere`
    /// (each only if built); makes that variant the first time.
    pub fn prepare(&mut self, ctx: &Context, lighting: bool, shadows: bool, atmosphere: bool) -> Result<()> {
        let on = self.built & combination(lighting, shadows, atmosphere);
        if self.pipelines[on].is_none() {
            self.pipelines[on] = Some(pipeline(ctx, on, self.depth_format, self.target)?);
        }
        self.current = on;
        Ok(())
    }

    /// Expects the depth target in its read-only layout (after
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
        let own = gbuffer.own().expect("outputs lit and hdr keep vista's G-buffer");
        for img in [&own.albedo, &own.normal, &own.material] {
            rec.transition(img, read);
        }
        let color = ColorTarget { image: targets.required_color(), clear: targets.clear };
        let depth = Some(DepthTarget { image: targets.depth, clear: None, clear_stencil: false, read_only: true });
        match &own.hdr {
            Some(hdr) => {
                rec.discard_to(hdr, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
                let hdr = ColorTarget { image: hdr, clear: Some(targets.clear.unwrap_or_default()) };
                rec.begin_rendering(&[color, hdr], depth);
            }
            None => rec.begin_rendering(&[color], depth),
        }
        let pipeline = self.pipelines[self.current].as_ref().expect("made by prepare or new");
        let (shadows_on, atmosphere_on) = (self.current & SHADOWS != 0, self.current & ATMOSPHERE != 0);
        rec.bind_pipeline(pipeline);
        let mut bindings = vec![
            (fs::VIEW, Resource::Buffer(view)),
            (fs::GB_ALBEDO, Resource::Image(&own.albedo, read)),
            (fs::GB_NORMAL, Resource::Image(&own.normal, read)),
            (fs::GB_MATERIAL, Resource::Image(&own.material, read)),
            (fs::NEAREST, Resource::Sampler(self.nearest.raw())),
        ];
        let mut push = LightingPush { terrain: inputs.terrain, shadow: [0.0; 4], fog: [[0.0; 4]; 3] };
        let depth_read = depth_layout(targets.depth.format, true);
        bindings.push((fs::DEPTH_TARGET, Resource::Image(targets.depth, depth_read)));
        if shadows_on {
            let shadows = inputs.shadows.as_ref().expect("built with shadows");
            bindings.extend([
                (fs::SECTOR_DATA, Resource::Buffer(inputs.sector_data.buffer())),
                (fs::HEIGHT_ATLAS, Resource::Image(inputs.tree.required_atlas(ATLAS_HEIGHT), ATLAS_LAYOUT)),
                (fs::SHADOW_ATLAS, Resource::Image(shadows.atlas, vk::ImageLayout::GENERAL)),
            ]);
            push.shadow = [shadows.penumbra, shadows.resolution as f32, 0.0, 0.0];
        }
        if atmosphere_on {
            push.fog = inputs.fog.expect("built with the atmosphere");
        }
        rec.push_descriptors(pipeline, &bindings);
        if shadows_on || atmosphere_on {
            rec.push_constants(pipeline, &push);
        }
        rec.draw(3, 1);
        rec.end_rendering();
        rec.transition(targets.depth, depth_layout(targets.depth.format, false));
    }
}
