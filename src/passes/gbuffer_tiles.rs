//! `gbuffer_tiles`: one indirect draw per shader variant over the tiles
//! `classify_tiles` listed for it, depth-tested to terrain pixels,
//! writing vista's G-buffer (albedo, normal + roughness, material id +
//! flavour bits) or, with output `gbuffer`, the engine's own images in
//! its layout (variant ENGINE_GBUFFER, the layout in specialization
//! constants). A variant is a specialization constant (its flavour bits);
//! pipelines exist only for the variants the scene can produce (every
//! non-empty subset of its allowed flavours), and the fragment shader's
//! MATERIALS switch, with the material resources, only where splat or
//! cliffs are on. Each variant's draw is timed on its own
//! (`gbuffer_tiles[far_atlas+splat]`); a variant with no tiles this frame
//! draws zero instances.

use crate::error::Result;
use crate::gpu::{
    depth_layout, vk, Buffer, ColorTarget, Context, DepthTarget, GraphicsPipelineDesc, Image, Pipeline, Recorder,
    Resource, Sampler, SamplerDesc, ShaderInfo,
};
use crate::passes::classify_tiles::{TileLists, TilePush};
use crate::passes::cull_patches::nearest_sampler;
use crate::passes::terrain_geometry::{RenderTargets, TERRAIN_ONLY};
use crate::passes::terrain_query::VistaTerrain;
use crate::scene::shading::variant_name;
use crate::shaders::consts::FLAVOUR_VARIANTS;
use crate::shaders::{gbuffer_tiles_frag as fs, gbuffer_tiles_vert as vs, structs};
use crate::targets::gbuffer::{GBuffer, ALBEDO_FORMAT, MATERIAL_FORMAT, NORMAL_FORMAT};
use crate::targets::GbufferLayout;
use crate::terrain::gpu_quadtree::{
    GpuQuadtree, ATLAS_ALBEDO, ATLAS_CONTROL, ATLAS_HEIGHT, ATLAS_LAYOUT, ATLAS_NORMAL, ATLAS_SPLAT,
};
use std::sync::OnceLock;

/// Host twin of `TileDrawPush` (gbuffer_tiles.vert/.frag).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TileDrawPush {
    pub tiles: TilePush,
    pub terrain: VistaTerrain,
}

const _: () = assert!(std::mem::size_of::<TileDrawPush>() == structs::TILE_DRAW_PUSH);

/// Timer and debug label of each variant's draw: the pass name with the
/// variant's flavours (static: timings carry `&'static str` names).
pub fn variant_label(bits: u32) -> &'static str {
    static LABELS: OnceLock<Vec<String>> = OnceLock::new();
    let labels = LABELS.get_or_init(|| {
        (0..FLAVOUR_VARIANTS).map(|v| format!("{}[{}]", GbufferTiles::NAME, variant_name(v))).collect()
    });
    &labels[bits as usize]
}

/// The material resources (effects `splat` or `cliffs`).
pub struct MaterialBindings<'a> {
    /// 256 `TerrainMaterial`s.
    pub table: &'a Buffer,
    /// The control-map flavour's `ControlTable` (control-map mode only).
    pub control: Option<&'a Buffer>,
    pub albedo: &'a Image,
    pub normal: &'a Image,
    pub height: &'a Image,
    /// Effect `virtual_texture`: its state buffer and cache images.
    pub virtual_texture: Option<VtBindings<'a>>,
}

/// What the virtual-texture flavour samples.
#[derive(Clone, Copy)]
pub struct VtBindings<'a> {
    pub state: &'a Buffer,
    pub albedo: &'a Image,
    pub detail: &'a Image,
}

/// The detail textures' sampler: trilinear, tiling (every pass that
/// samples the materials makes one).
pub fn detail_sampler(ctx: &Context, name: &str) -> Result<Sampler> {
    let desc = SamplerDesc { name, filter: vk::Filter::LINEAR, address_mode: vk::SamplerAddressMode::REPEAT };
    Sampler::mipmapped(ctx, &desc)
}

/// Which fragment shader a renderer's tile shading uses: the splat and
/// cliff flavours (MATERIALS) or the control-map flavour (CONTROL_MAP), or
/// neither (far atlas only).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TileMaterials {
    None,
    Splat,
    /// Splat's materials, the near flavour from the virtual texture.
    SplatVirtualTexture,
    ControlMap,
}

pub struct GbufferTiles {
    /// (flavour bits, pipeline), in increasing bits.
    pipelines: Vec<(u32, Pipeline)>,
    materials: TileMaterials,
    /// Output `gbuffer`: the engine's layout (None: vista's own G-buffer).
    layout: Option<GbufferLayout>,
    nearest: Sampler,
    linear: Sampler,
    detail: Sampler,
}

/// The colour formats of a pass writing the G-buffer: vista's own, or the
/// engine's `layout`.
fn gbuffer_formats(layout: Option<&GbufferLayout>) -> Vec<vk::Format> {
    match layout {
        Some(l) => l.formats(),
        None => vec![ALBEDO_FORMAT, NORMAL_FORMAT, MATERIAL_FORMAT],
    }
}

/// The specialization constants of `engine_gbuffer.glsl` for `layout`,
/// by the ids `fragment` reflects for them (none for vista's own).
pub fn engine_gbuffer_spec(fragment: &ShaderInfo, layout: Option<&GbufferLayout>) -> Vec<(u32, u32)> {
    let Some(layout) = layout else { return Vec::new() };
    let spec = layout.spec();
    let id = |name: &str| {
        let found = fragment.spec_constants.iter().find(|(n, _)| *n == name);
        found.unwrap_or_else(|| panic!("{} has no specialization constant {name}", fragment.file)).1
    };
    let names = ["GB_CHANNELS0", "GB_CHANNELS1", "GB_CHANNELS2", "GB_CHANNELS3"];
    let mut out: Vec<(u32, u32)> = names.iter().zip(spec.channels).map(|(n, v)| (id(n), v)).collect();
    out.push((id("GB_FLAGS"), spec.flags));
    out
}

/// The colour attachments of a pass writing the G-buffer (the engine's
/// images with output `gbuffer`), each cleared to `clear` or kept.
fn gbuffer_attachments<'a>(
    targets: &RenderTargets<'a>,
    gbuffer: &'a GBuffer,
    clear: Option<[f32; 4]>,
) -> Vec<ColorTarget<'a>> {
    match gbuffer.own() {
        Some(o) => [&o.albedo, &o.normal, &o.material].into_iter().map(|image| ColorTarget { image, clear }).collect(),
        None => targets.gbuffer.iter().map(|image| ColorTarget { image, clear }).collect(),
    }
}

impl GbufferTiles {
    pub const NAME: &'static str = vs::PASS;

    /// Pipelines for `variants`; `materials`: the shader with the splat and
    /// cliff paths, or the control-map one (bound to material resources at
    /// record time); `every_flavour`: evaluate each variant's every flavour
    /// at every pixel. `depth_format`: the renderer's depth target's;
    /// `layout`: the engine's G-buffer (output `gbuffer`), else vista's.
    pub fn new(
        ctx: &Context,
        variants: &[u32],
        materials: TileMaterials,
        every_flavour: bool,
        depth_format: vk::Format,
        layout: Option<&GbufferLayout>,
    ) -> Result<Self> {
        let engine = if layout.is_some() { fs::VARIANT_ENGINE_GBUFFER } else { 0 };
        let fragment = fs::variant(
            engine
                | match materials {
                    TileMaterials::None => 0,
                    TileMaterials::Splat => fs::VARIANT_MATERIALS,
                    TileMaterials::SplatVirtualTexture => fs::VARIANT_MATERIALS | fs::VARIANT_VIRTUAL_TEXTURE,
                    TileMaterials::ControlMap => fs::VARIANT_CONTROL_MAP,
                },
        );
        let formats = gbuffer_formats(layout);
        let engine_spec = engine_gbuffer_spec(fragment, layout);
        let pipelines = variants
            .iter()
            .map(|&bits| {
                let mut spec = vec![(vs::SPEC_VARIANT_BITS, bits), (fs::SPEC_EVERY_FLAVOUR, u32::from(every_flavour))];
                spec.extend(&engine_spec);
                let desc = GraphicsPipelineDesc {
                    name: variant_label(bits),
                    vertex: &vs::SHADER,
                    fragment,
                    specialization: &spec,
                    color_formats: &formats,
                    depth_format: Some(depth_format),
                    depth_compare: TERRAIN_ONLY,
                    depth_write: false,
                    stencil: None,
                    cull_mode: vk::CullModeFlags::NONE,
                    topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                    blend: false,
                };
                Ok((bits, Pipeline::graphics(ctx, &desc)?))
            })
            .collect::<Result<Vec<_>>>()?;
        let sampler = |name, filter, address_mode| Sampler::new(ctx, &SamplerDesc { name, filter, address_mode });
        Ok(GbufferTiles {
            pipelines,
            materials,
            layout: layout.cloned(),
            nearest: nearest_sampler(ctx, "gbuffer_tiles_nearest")?,
            linear: sampler("gbuffer_tiles_linear", vk::Filter::LINEAR, vk::SamplerAddressMode::CLAMP_TO_EDGE)?,
            detail: detail_sampler(ctx, "gbuffer_tiles_detail")?,
        })
    }

    /// The variants built, in increasing flavour bits.
    pub fn variants(&self) -> Vec<u32> {
        self.pipelines.iter().map(|(b, _)| *b).collect()
    }

    pub fn pipeline_labels(&self) -> Vec<String> {
        self.pipelines.iter().map(|(_, p)| p.label.clone()).collect()
    }

    /// Moves the inputs into the layouts the draws read them in and vista's
    /// own G-buffer into attachment layout (before the first variant; the
    /// engine's images are there already).
    pub fn begin(rec: &mut Recorder, targets: &RenderTargets, gbuffer: &GBuffer) {
        rec.transition(&gbuffer.geometry_normals, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
        rec.transition(targets.depth, depth_layout(targets.depth.format, true));
        for img in gbuffer.own().map(|o| [&o.albedo, &o.normal, &o.material]).into_iter().flatten() {
            rec.discard_to(img, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
        }
    }

    /// The pipeline of a pass drawing over the G-buffer after the tile
    /// shading (what [`GbufferTiles::begin_overlay`] opens): its targets
    /// (vista's, or the engine's `layout`, which `fragment`, the pass's
    /// ENGINE_GBUFFER variant then, writes), reversed-Z depth tested and
    /// written, no stencil.
    pub fn overlay_pipeline(
        ctx: &Context,
        name: &str,
        (vertex, fragment): (&'static ShaderInfo, &'static ShaderInfo),
        depth_format: vk::Format,
        cull_mode: vk::CullModeFlags,
        layout: Option<&GbufferLayout>,
    ) -> Result<Pipeline> {
        let formats = gbuffer_formats(layout);
        let spec = engine_gbuffer_spec(fragment, layout);
        let desc = GraphicsPipelineDesc {
            name,
            vertex,
            fragment,
            specialization: &spec,
            color_formats: &formats,
            depth_format: Some(depth_format),
            depth_compare: vk::CompareOp::GREATER,
            depth_write: true,
            stencil: None,
            cull_mode,
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            blend: false,
        };
        Pipeline::graphics(ctx, &desc)
    }

    /// Opens a draw over the G-buffer the variants wrote (kept), writing
    /// depth: geometry drawn after the tile shading (`asset_draw`,
    /// `grass_draw`). The depth target leaves its read-only layout;
    /// [`GbufferTiles::end_overlay`] puts it back for `lighting_resolve`.
    pub fn begin_overlay(rec: &mut Recorder, targets: &RenderTargets, gbuffer: &GBuffer) {
        let depth = targets.depth;
        rec.transition(depth, depth_layout(depth.format, false));
        rec.begin_rendering(
            &gbuffer_attachments(targets, gbuffer, None),
            Some(DepthTarget { image: depth, clear: None, clear_stencil: false, read_only: false }),
        );
    }

    pub fn end_overlay(rec: &mut Recorder, targets: &RenderTargets) {
        rec.end_rendering();
        rec.transition(targets.depth, depth_layout(targets.depth.format, true));
    }

    /// Draws variant `bits`' tiles (`first`: clears the G-buffer first).
    #[allow(clippy::too_many_arguments)]
    pub fn record_variant(
        &self,
        rec: &mut Recorder,
        bits: u32,
        first: bool,
        targets: &RenderTargets,
        gbuffer: &GBuffer,
        view: &Buffer,
        lists: &TileLists,
        sector_data: &Buffer,
        terrain: VistaTerrain,
        tree: &GpuQuadtree,
        materials: Option<&MaterialBindings>,
    ) {
        let (_, pipeline) = self.pipelines.iter().find(|(b, _)| *b == bits).expect("variant was built");
        // vista's own G-buffer is cleared to 0 (no terrain); the engine's
        // as the frame's targets say.
        let clear = match self.layout {
            None => first.then_some([0.0; 4]),
            Some(_) => targets.clear.filter(|_| first),
        };
        rec.begin_rendering(
            &gbuffer_attachments(targets, gbuffer, clear),
            Some(DepthTarget { image: targets.depth, clear: None, clear_stencil: false, read_only: true }),
        );
        rec.bind_pipeline(pipeline);
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        let mut bindings = vec![
            (fs::VIEW, Resource::Buffer(view)),
            (vs::LISTS, Resource::Buffer(&lists.buffer)),
            (fs::DEPTH_TARGET, Resource::Image(targets.depth, depth_layout(targets.depth.format, true))),
            (fs::CLASSIFICATION, Resource::Image(&gbuffer.classification, read)),
            (fs::NORMALS, Resource::Image(&gbuffer.geometry_normals, read)),
            (fs::SECTOR_DATA, Resource::Buffer(sector_data)),
            (fs::ALBEDO_ATLAS, Resource::Image(tree.required_atlas(ATLAS_ALBEDO), ATLAS_LAYOUT)),
            (fs::NORMAL_ATLAS, Resource::Image(tree.required_atlas(ATLAS_NORMAL), ATLAS_LAYOUT)),
            (fs::HEIGHT_ATLAS, Resource::Image(tree.required_atlas(ATLAS_HEIGHT), ATLAS_LAYOUT)),
            (fs::NEAREST, Resource::Sampler(self.nearest.raw())),
            (fs::LINEAR_CLAMP, Resource::Sampler(self.linear.raw())),
        ];
        if self.materials != TileMaterials::None {
            let m = materials.expect("the material shaders need the material resources");
            bindings.extend([
                (fs::DETAIL_ALBEDO, Resource::Image(m.albedo, read)),
                (fs::DETAIL_NORMAL, Resource::Image(m.normal, read)),
                (fs::DETAIL_HEIGHT, Resource::Image(m.height, read)),
                (fs::DETAIL_SAMPLER, Resource::Sampler(self.detail.raw())),
            ]);
        }
        match self.materials {
            TileMaterials::Splat | TileMaterials::SplatVirtualTexture => bindings.extend([
                (fs::SPLAT_ATLAS, Resource::Image(tree.required_atlas(ATLAS_SPLAT), ATLAS_LAYOUT)),
                (fs::MATERIALS, Resource::Buffer(materials.expect("checked").table)),
            ]),
            TileMaterials::ControlMap => bindings.extend([
                (fs::CONTROL_ATLAS, Resource::Image(tree.required_atlas(ATLAS_CONTROL), ATLAS_LAYOUT)),
                (fs::CONTROL, Resource::Buffer(materials.and_then(|m| m.control).expect("the control table"))),
            ]),
            TileMaterials::None => {}
        }
        if self.materials == TileMaterials::SplatVirtualTexture {
            let vt = materials.and_then(|m| m.virtual_texture).expect("the virtual texture's resources");
            let general = vk::ImageLayout::GENERAL;
            bindings.extend([
                (fs::VT_STATE, Resource::Buffer(vt.state)),
                (fs::VT_ALBEDO, Resource::Image(vt.albedo, general)),
                (fs::VT_DETAIL, Resource::Image(vt.detail, general)),
            ]);
        }
        rec.push_descriptors(pipeline, &bindings);
        rec.push_constants(pipeline, &TileDrawPush { tiles: lists.push, terrain });
        rec.draw_indirect(&lists.buffer, TileLists::args_offset(bits));
        rec.end_rendering();
    }
}
