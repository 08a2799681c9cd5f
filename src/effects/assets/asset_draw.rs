//! `asset_draw` (effect `assets`): the example assets (effects/assets)
//! into the G-buffer after `gbuffer_tiles`, depth-tested and
//! depth-writing, one indexed instanced draw per mesh kind; the vertex
//! shader sets each on the terrain and blends its vertices near the ground
//! into the terrain's normal and colour (terrain_blend.glsl): with variant
//! `MATERIALS` (effect splat in splat mode) the splat blend's colour, the
//! near ground's, else the baked albedo.

use crate::effects::assets::AssetResources;
use crate::error::Result;
use crate::gpu::{vk, Buffer, Context, Pipeline, Recorder, Resource, Sampler};
use crate::passes::cull_patches::nearest_sampler;
use crate::passes::gbuffer_tiles::GbufferTiles;
use crate::passes::gbuffer_tiles::MaterialBindings;
use crate::passes::terrain_geometry::RenderTargets;
use crate::passes::terrain_query::VistaTerrain;
use crate::shaders::{asset_draw_frag as fs, asset_draw_vert as vs, structs};
use crate::targets::gbuffer::GBuffer;
use crate::targets::GbufferLayout;
use crate::terrain::gpu_quadtree::{GpuQuadtree, ATLAS_ALBEDO, ATLAS_HEIGHT, ATLAS_LAYOUT, ATLAS_NORMAL, ATLAS_SPLAT};

/// Host twin of `AssetDrawPush`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct AssetDrawPush {
    pub terrain: VistaTerrain,
    pub instance_base: u32,
    pub blend_height_m: f32,
    pub pad: [u32; 2],
}

const _: () = assert!(std::mem::size_of::<AssetDrawPush>() == structs::ASSET_DRAW_PUSH);

pub struct AssetDraw {
    pipeline: Pipeline,
    materials: bool,
    detail: Sampler,
    nearest: Sampler,
    linear: Sampler,
}

impl AssetDraw {
    pub const NAME: &'static str = vs::PASS;

    /// `materials`: the variant that colours by the splat blend; `layout`:
    /// the engine's G-buffer (output `gbuffer`), else vista's.
    pub fn new(
        ctx: &Context,
        depth_format: vk::Format,
        materials: bool,
        layout: Option<&GbufferLayout>,
    ) -> Result<Self> {
        Ok(AssetDraw {
            pipeline: GbufferTiles::overlay_pipeline(
                ctx,
                Self::NAME,
                (
                    vs::variant(if materials { vs::VARIANT_MATERIALS } else { 0 }),
                    fs::variant(if layout.is_some() { fs::VARIANT_ENGINE_GBUFFER } else { 0 }),
                ),
                depth_format,
                vk::CullModeFlags::BACK,
                layout,
            )?,
            materials,
            detail: crate::passes::gbuffer_tiles::detail_sampler(ctx, "asset_draw_detail")?,
            nearest: nearest_sampler(ctx, "asset_draw_nearest")?,
            linear: crate::passes::cull_patches::linear_clamp_sampler(ctx, "asset_draw_linear")?,
        })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// Built with the MATERIALS variant.
    pub fn materials(&self) -> bool {
        self.materials
    }

    /// Draws every kind with instances; the depth target read-only on
    /// entry and exit (as gbuffer_tiles leaves it, lighting_resolve wants it).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder,
        targets: &RenderTargets,
        gbuffer: &GBuffer,
        view: &Buffer,
        assets: &AssetResources,
        terrain: VistaTerrain,
        sector_data: &Buffer,
        tree: &GpuQuadtree,
        m: Option<&MaterialBindings>,
    ) {
        assert_eq!(m.is_some(), self.materials, "material resources exactly for the MATERIALS variant");
        GbufferTiles::begin_overlay(rec, targets, gbuffer);
        rec.bind_pipeline(&self.pipeline);
        let mut bindings = vec![
            (vs::VIEW, Resource::Buffer(view)),
            (vs::VERTICES, Resource::Buffer(&assets.vertices)),
            (vs::INSTANCES, Resource::Buffer(&assets.instances)),
            (vs::SECTOR_DATA, Resource::Buffer(sector_data)),
            (vs::HEIGHT_ATLAS, Resource::Image(tree.required_atlas(ATLAS_HEIGHT), ATLAS_LAYOUT)),
            (vs::NORMAL_ATLAS, Resource::Image(tree.required_atlas(ATLAS_NORMAL), ATLAS_LAYOUT)),
            (vs::ALBEDO_ATLAS, Resource::Image(tree.required_atlas(ATLAS_ALBEDO), ATLAS_LAYOUT)),
            (vs::NEAREST, Resource::Sampler(self.nearest.raw())),
            (vs::LINEAR_CLAMP, Resource::Sampler(self.linear.raw())),
        ];
        if let Some(m) = m {
            let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
            bindings.extend([
                (vs::SPLAT_ATLAS, Resource::Image(tree.required_atlas(ATLAS_SPLAT), ATLAS_LAYOUT)),
                (vs::MATERIALS, Resource::Buffer(m.table)),
                (vs::DETAIL_ALBEDO, Resource::Image(m.albedo, read)),
                (vs::DETAIL_NORMAL, Resource::Image(m.normal, read)),
                (vs::DETAIL_HEIGHT, Resource::Image(m.height, read)),
                (vs::DETAIL_SAMPLER, Resource::Sampler(self.detail.raw())),
            ]);
        }
        rec.push_descriptors(&self.pipeline, &bindings);
        for &(kind, first, count) in &assets.draws {
            if count == 0 {
                continue;
            }
            let (_, indices, index_count) =
                assets.indices.iter().find(|(k, _, _)| *k == kind).expect("a mesh per kind");
            let push = AssetDrawPush {
                terrain,
                instance_base: first,
                blend_height_m: assets.params.blend_height_m,
                pad: [0; 2],
            };
            rec.push_constants(&self.pipeline, &push);
            rec.draw_indexed(indices, *index_count, count);
        }
        GbufferTiles::end_overlay(rec, targets);
    }
}
