//! `grass_pigment` (effect `grass`): the pigment map, a top-down render of
//! the near terrain's albedo (the splat blend at each texel, with variant
//! `DECALS` the decals blended over it) that colours the grass. Recorded
//! only in frames where the camera crossed into another step of the map's
//! centre, the resident terrain or the decals changed.

use crate::effects::grass::grass_place::GrassDecals;
use crate::error::Result;
use crate::gpu::{vk, Buffer, ComputePipelineDesc, Context, Image, Pipeline, Recorder, Resource, Sampler};
use crate::passes::cull_patches::nearest_sampler;
use crate::passes::gbuffer_tiles::MaterialBindings;
use crate::passes::terrain_query::VistaTerrain;
use crate::shaders::consts::GRASS_PIGMENT_TEXELS;
use crate::shaders::{grass_pigment as sh, structs};
use crate::terrain::gpu_quadtree::{GpuQuadtree, ATLAS_HEIGHT, ATLAS_LAYOUT, ATLAS_NORMAL, ATLAS_SPLAT};

/// Host twin of `GrassPigmentPush`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GrassPigmentPush {
    pub terrain: VistaTerrain,
    /// The map's south-west corner (world m).
    pub origin_m: [f32; 2],
    pub texel_m: f32,
    /// DECALS: the decals touching the map (the grass decal list from DECAL_MAX).
    pub decal_count: u32,
}

const _: () = assert!(std::mem::size_of::<GrassPigmentPush>() == structs::GRASS_PIGMENT_PUSH);

pub struct GrassPigment {
    pipeline: Pipeline,
    decals: bool,
    nearest: Sampler,
    detail: Sampler,
}

impl GrassPigment {
    pub const NAME: &'static str = sh::PASS;

    /// `decals`: the variant that blends the decals.
    pub fn new(ctx: &Context, decals: bool) -> Result<Self> {
        let shader = sh::variant(if decals { sh::VARIANT_DECALS } else { 0 });
        let desc = ComputePipelineDesc { name: Self::NAME, shader, specialization: &[] };
        Ok(GrassPigment {
            pipeline: Pipeline::compute(ctx, &desc)?,
            decals,
            nearest: nearest_sampler(ctx, "grass_pigment_nearest")?,
            detail: crate::passes::gbuffer_tiles::detail_sampler(ctx, "grass_pigment_detail")?,
        })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// Renders the map into `pigment` (left in GENERAL layout); `decals`
    /// exactly for the DECALS variant.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder,
        pigment: &Image,
        push: GrassPigmentPush,
        sector_data: &Buffer,
        tree: &GpuQuadtree,
        m: &MaterialBindings,
        decals: Option<GrassDecals>,
    ) {
        assert_eq!(decals.is_some(), self.decals, "decal resources exactly for the DECALS variant");
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        rec.discard_to(pigment, vk::ImageLayout::GENERAL);
        rec.bind_pipeline(&self.pipeline);
        let mut bindings = vec![
            (sh::SECTOR_DATA, Resource::Buffer(sector_data)),
            (sh::HEIGHT_ATLAS, Resource::Image(tree.required_atlas(ATLAS_HEIGHT), ATLAS_LAYOUT)),
            (sh::NORMAL_ATLAS, Resource::Image(tree.required_atlas(ATLAS_NORMAL), ATLAS_LAYOUT)),
            (sh::SPLAT_ATLAS, Resource::Image(tree.required_atlas(ATLAS_SPLAT), ATLAS_LAYOUT)),
            (sh::MATERIALS, Resource::Buffer(m.table)),
            (sh::DETAIL_ALBEDO, Resource::Image(m.albedo, read)),
            (sh::DETAIL_NORMAL, Resource::Image(m.normal, read)),
            (sh::DETAIL_HEIGHT, Resource::Image(m.height, read)),
            (sh::DETAIL_SAMPLER, Resource::Sampler(self.detail.raw())),
            (sh::NEAREST, Resource::Sampler(self.nearest.raw())),
            (sh::PIGMENT, Resource::Image(pigment, vk::ImageLayout::GENERAL)),
        ];
        // grass_place's binding numbers: the two shaders declare them alike.
        const _: () = assert!(sh::DECALS.binding == crate::shaders::grass_place::DECALS.binding);
        const _: () = assert!(sh::GRASS_DECALS.binding == crate::shaders::grass_place::GRASS_DECALS.binding);
        bindings.extend(decals.iter().flat_map(|d| d.bindings()));
        rec.push_descriptors(&self.pipeline, &bindings);
        rec.push_constants(&self.pipeline, &push);
        let [gx, gy, _] = sh::WORKGROUP_SIZE;
        rec.dispatch(GRASS_PIGMENT_TEXELS.div_ceil(gx), GRASS_PIGMENT_TEXELS.div_ceil(gy), 1);
        rec.barrier(vk::PipelineStageFlags2::COMPUTE_SHADER, vk::PipelineStageFlags2::ALL_COMMANDS);
    }
}
