//! `sun_shadows`: makes the sun shadow texture of each node in this frame's
//! job list (render/sun_shadows.rs decides which): per texel the height
//! below which that point is in shadow, marched towards the sun through the
//! finest resident heights (sun_shadows.comp). The atlas has one layer per
//! node slot, like the payload atlases, and rests in GENERAL (written here,
//! read by `lighting_resolve`).

use crate::error::Result;
use crate::gpu::{
    vk, Buffer, BufferDesc, ComputePipelineDesc, Context, Image, ImageDesc, MemoryLocation, Pipeline, Recorder,
    Resource, Sampler,
};
use crate::passes::cull_patches::nearest_sampler;
use crate::passes::sector_data::SectorData;
use crate::passes::terrain_query::VistaTerrain;
use crate::render::sun_shadows::{ShadowParams, SunShadowJob};
use crate::shaders::{consts, sun_shadows as sh};
use crate::terrain::gpu_quadtree::{GpuQuadtree, ATLAS_HEIGHT, ATLAS_LAYOUT};
use crate::terrain::quadtree::FIRST_SLOT;
use glam::DVec3;

/// Host twin of `SunShadowPush` (sun_shadows.comp).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SunShadowPush {
    pub terrain: VistaTerrain,
    /// xy: horizontal unit vector towards the sun; z: tan(elevation); w: reach (m).
    pub sun: [f32; 4],
    /// steps, texture side, jobs, unused.
    pub params: [u32; 4],
}

/// The march's sun: horizontal unit direction and the rise per metre
/// (`SunShadowPush::sun`'s xyz, also what the CPU twin takes).
pub fn march_sun(sun_dir: DVec3) -> [f32; 3] {
    let h = sun_dir.truncate();
    let len = h.length();
    if len < 1e-9 {
        // The sun overhead: no march direction, and nothing casts a shadow.
        return [1.0, 0.0, f32::MAX];
    }
    let u = h / len;
    [u.x as f32, u.y as f32, (sun_dir.z / len) as f32]
}

pub struct SunShadows {
    pipeline: Pipeline,
    nearest: Sampler,
    /// R32G32_SFLOAT (threshold height, occluder distance), `resolution`
    /// square, one layer per slot; GENERAL.
    pub atlas: Image,
    jobs: Buffer,
    pub params: ShadowParams,
}

impl SunShadows {
    pub const NAME: &'static str = sh::PASS;

    pub fn new(ctx: &Context, params: ShadowParams, slots: u32) -> Result<Self> {
        let side = params.resolution;
        assert!((2..=consts::SUN_SHADOW_MAX_SIDE).contains(&side), "shadow resolution {side} (checked by the scene)");
        let atlas = Image::new(
            ctx,
            &ImageDesc {
                name: "sun_shadow_atlas",
                format: vk::Format::R32G32_SFLOAT,
                extent: [side, side],
                mip_levels: 1,
                array_layers: slots + FIRST_SLOT,
                usage: vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC,
            },
        )?;
        ctx.submit_and_wait(|rec| {
            rec.discard_to(&atlas, vk::ImageLayout::GENERAL);
            Ok(())
        })?;
        let jobs = Buffer::new(
            ctx,
            &BufferDesc {
                name: "sun_shadow_jobs",
                size: u64::from(consts::SUN_SHADOW_MAX_JOBS) * std::mem::size_of::<SunShadowJob>() as u64,
                usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuOnly,
            },
        )?;
        let desc = ComputePipelineDesc { name: Self::NAME, shader: &sh::SHADER, specialization: &[] };
        Ok(SunShadows {
            pipeline: Pipeline::compute(ctx, &desc)?,
            nearest: nearest_sampler(ctx, "sun_shadows_nearest")?,
            atlas,
            jobs,
            params,
        })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    pub fn memory(&self) -> [(String, u64); 2] {
        [(self.atlas.name.clone(), self.atlas.memory_bytes()), (self.jobs.name.clone(), self.jobs.memory_bytes())]
    }

    /// Marches `jobs` (at most SUN_SHADOW_MAX_JOBS) for the sun `sun_dir`.
    pub fn record(
        &self,
        rec: &mut Recorder,
        jobs: &[SunShadowJob],
        sun_dir: DVec3,
        terrain: VistaTerrain,
        sector_data: &SectorData,
        tree: &GpuQuadtree,
    ) {
        assert!(!jobs.is_empty() && jobs.len() <= consts::SUN_SHADOW_MAX_JOBS as usize, "{} jobs", jobs.len());
        rec.update_buffer(&self.jobs, 0, bytemuck::cast_slice(jobs));
        rec.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::COMPUTE_SHADER);
        rec.bind_pipeline(&self.pipeline);
        rec.push_descriptors(
            &self.pipeline,
            &[
                (sh::SECTOR_DATA, Resource::Buffer(&sector_data.buffer)),
                (sh::HEIGHT_ATLAS, Resource::Image(tree.required_atlas(ATLAS_HEIGHT), ATLAS_LAYOUT)),
                (sh::NEAREST, Resource::Sampler(self.nearest.raw())),
                (sh::SHADOW_ATLAS, Resource::Image(&self.atlas, vk::ImageLayout::GENERAL)),
                (sh::JOBS, Resource::Buffer(&self.jobs)),
            ],
        );
        let [ux, uy, rise] = march_sun(sun_dir);
        let p = &self.params;
        let push = SunShadowPush {
            terrain,
            sun: [ux, uy, rise, p.reach_m],
            params: [p.steps, p.resolution, jobs.len() as u32, 0],
        };
        rec.push_constants(&self.pipeline, &push);
        let [wx, wy, _] = sh::WORKGROUP_SIZE;
        rec.dispatch(p.resolution.div_ceil(wx), p.resolution.div_ceil(wy), jobs.len() as u32);
        rec.barrier(vk::PipelineStageFlags2::COMPUTE_SHADER, vk::PipelineStageFlags2::ALL_COMMANDS);
    }
}
