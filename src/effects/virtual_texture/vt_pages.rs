//! `vt_pages` (effect `virtual_texture`): renders the frame's pages into
//! the physical cache, one workgroup layer per page, each texel of its
//! padded tile the splat material blend at the texel's world point, then
//! (variant `DECALS`, effect `decals`) the decals touching the page.

use crate::effects::virtual_texture::decal_gpu::DecalResources;
use crate::effects::virtual_texture::layout::PADDED_TILE;
use crate::effects::virtual_texture::state::PageJob;
use crate::error::Result;
use crate::gpu::{vk, Buffer, ComputePipelineDesc, Context, Image, Pipeline, Recorder, Resource, Sampler};
use crate::passes::cull_patches::nearest_sampler;
use crate::passes::gbuffer_tiles::MaterialBindings;
use crate::passes::terrain_query::VistaTerrain;
use crate::shaders::consts::VT_MAX_JOBS;
use crate::shaders::{structs, vt_pages as sh};
use crate::terrain::gpu_quadtree::{GpuQuadtree, ATLAS_HEIGHT, ATLAS_LAYOUT, ATLAS_NORMAL, ATLAS_SPLAT};

const _: () = assert!(std::mem::size_of::<PageJob>() == structs::PAGE_JOB);
const _: () = assert!(std::mem::size_of::<VistaTerrain>() == structs::VT_PAGES_PUSH);

/// The cache images and the buffers a page rendering reads.
pub struct PageTargets<'a> {
    pub state: &'a Buffer,
    pub jobs: &'a Buffer,
    pub albedo: &'a Image,
    pub detail: &'a Image,
}

pub struct VtPages {
    pipeline: Pipeline,
    decals: bool,
    nearest: Sampler,
    detail: Sampler,
}

impl VtPages {
    pub const NAME: &'static str = sh::PASS;

    /// `position_code`: write each texel's position code instead of the
    /// material (tests). `decals`: the variant that blends decals.
    pub fn new(ctx: &Context, position_code: bool, decals: bool) -> Result<Self> {
        let spec = [(sh::SPEC_POSITION_CODE, u32::from(position_code))];
        let shader = sh::variant(if decals { sh::VARIANT_DECALS } else { 0 });
        let desc = ComputePipelineDesc { name: Self::NAME, shader, specialization: &spec };
        Ok(VtPages {
            pipeline: Pipeline::compute(ctx, &desc)?,
            decals,
            nearest: nearest_sampler(ctx, "vt_pages_nearest")?,
            detail: crate::passes::gbuffer_tiles::detail_sampler(ctx, "vt_pages_detail")?,
        })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// Renders `jobs` (1 to VT_MAX_JOBS pages); `decals` for the `DECALS`
    /// variant (uploaded before).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder,
        jobs: &[PageJob],
        out: &PageTargets,
        terrain: VistaTerrain,
        sector_data: &Buffer,
        tree: &GpuQuadtree,
        m: &MaterialBindings,
        decals: Option<&DecalResources>,
    ) {
        assert!(!jobs.is_empty() && jobs.len() <= VT_MAX_JOBS as usize, "{} jobs", jobs.len());
        rec.update_buffer(out.jobs, 0, bytemuck::cast_slice(jobs));
        rec.barrier(vk::PipelineStageFlags2::ALL_COMMANDS, vk::PipelineStageFlags2::COMPUTE_SHADER);
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        let general = vk::ImageLayout::GENERAL;
        rec.bind_pipeline(&self.pipeline);
        let mut bindings = vec![
            (sh::VT_STATE, Resource::Buffer(out.state)),
            (sh::JOBS, Resource::Buffer(out.jobs)),
            (sh::CACHE_ALBEDO, Resource::Image(out.albedo, general)),
            (sh::CACHE_DETAIL, Resource::Image(out.detail, general)),
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
        ];
        assert_eq!(decals.is_some(), self.decals, "decal resources exactly for the DECALS variant");
        if let Some(d) = decals {
            bindings.extend([
                (sh::DECALS, Resource::Buffer(&d.list)),
                (sh::DECAL_POINTS, Resource::Buffer(&d.points)),
                (sh::JOB_DECALS, Resource::Buffer(&d.job_decals)),
                (sh::DECAL_TEXTURES, Resource::Image(&d.textures, read)),
                (sh::DECAL_CLAMP, Resource::Sampler(d.clamp.raw())),
                (sh::DECAL_REPEAT, Resource::Sampler(d.repeat.raw())),
            ]);
        }
        rec.push_descriptors(&self.pipeline, &bindings);
        rec.push_constants(&self.pipeline, &terrain);
        let [gx, gy, _] = sh::WORKGROUP_SIZE;
        rec.dispatch(PADDED_TILE.div_ceil(gx), PADDED_TILE.div_ceil(gy), jobs.len() as u32);
        rec.barrier(vk::PipelineStageFlags2::COMPUTE_SHADER, vk::PipelineStageFlags2::ALL_COMMANDS);
    }
}
