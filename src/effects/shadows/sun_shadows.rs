//! `sun_shadows`: makes the sun shadow texture of each node in this frame's
//! job list (effects/shadows decides which): per texel how far above
//! the ground there the sun's shadow reaches, and the occluder's distance,
//! marched towards the sun through the finest resident heights
//! (sun_shadows.comp). The atlas has one layer per
//! node slot, like the payload atlases, and rests in GENERAL (written here,
//! read by `lighting_resolve`). The effect's parameters and the job list's
//! entries live here with the pass; `effects::shadows` schedules it.

use crate::error::Result;
use crate::gpu::{
    vk, Buffer, BufferDesc, Context, Image, ImageDesc, MemoryLocation, Pipeline, Recorder, Resource, Sampler,
};
use crate::passes::cull_patches::nearest_sampler;
use crate::passes::sector_data::SectorData;
use crate::passes::terrain_query::VistaTerrain;
use crate::shaders::{consts, sun_shadows as sh};
use crate::terrain::gpu_quadtree::{GpuQuadtree, ATLAS_HEIGHT, ATLAS_LAYOUT, MAX_UPLOADS_PER_FRAME};
use crate::terrain::quadtree::FIRST_SLOT;
use crate::world::NodeId;
use glam::DVec3;

/// Largest `update_budget`: the job list holds the budget plus a frame's
/// uploads.
pub const MAX_UPDATE_BUDGET: u32 = consts::SUN_SHADOW_MAX_JOBS - MAX_UPLOADS_PER_FRAME as u32;

/// Parameters of the `shadows` effect (scene keys of the same names).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadowParams {
    /// Texels per node side (2..=SUN_SHADOW_MAX_SIDE), corner-aligned: texel
    /// 0 and the last lie on the node's edges.
    pub resolution: u32,
    /// Height samples per texel's march towards the sun.
    pub steps: u32,
    /// Nodes re-marched per frame while the sun moves.
    pub update_budget: u32,
    /// The sun's angular diameter (degrees): the penumbra widens with the
    /// occluder's distance by this spread ([`ShadowParams::penumbra`]); 0: a
    /// hard edge.
    pub softness_deg: f32,
    /// Farthest a march looks (m); it also stops where the ray clears the
    /// world's highest point.
    pub reach_m: f32,
}

impl Default for ShadowParams {
    fn default() -> Self {
        // The real sun is 0.53 degrees across.
        ShadowParams { resolution: 65, steps: 24, update_budget: 16, softness_deg: 0.53, reach_m: 20_000.0 }
    }
}

impl ShadowParams {
    /// Penumbra height per metre of occluder distance with the sun at
    /// `elevation_deg`: the spread of tan(elevation) over the sun's disc.
    pub fn penumbra(&self, elevation_deg: f64) -> f32 {
        let half = f64::from(self.softness_deg) * 0.5;
        let top = (elevation_deg + half).clamp(-89.9, 89.9).to_radians().tan();
        let bottom = (elevation_deg - half).clamp(-89.9, 89.9).to_radians().tan();
        (top - bottom) as f32
    }
}

/// One node's march this frame (`SunShadowJob` in sun_shadows.comp).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SunShadowJob {
    pub slot: u32,
    pub lod: u32,
    pub x: u32,
    pub y: u32,
}

impl SunShadowJob {
    pub fn new(node: NodeId, slot: u32) -> Self {
        SunShadowJob { slot, lod: u32::from(node.lod), x: node.x, y: node.y }
    }
}

/// Host twin of `SunShadowPush` (sun_shadows.comp).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SunShadowPush {
    pub terrain: VistaTerrain,
    /// xy: horizontal unit vector towards the sun; z: tan(elevation); w: reach (m).
    pub sun: [f32; 4],
    /// steps, texture side, jobs, unused.
    pub params: [u32; 4],
    /// Variant CANOPY: `Canopy::map`, then its size (xy) and the nearest
    /// distance a march reads it at (z, [`canopy_skip_m`]).
    pub canopy_map: [f32; 4],
    pub canopy_grid: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<SunShadowPush>() == crate::shaders::structs::SUN_SHADOW_PUSH);

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

/// Heights above the ground that cast the sun's shadow over the terrain
/// (effect `vegetation`'s trees and bushes), over a grid of the world.
#[derive(Clone, Copy)]
pub struct Canopy<'a> {
    /// f16 pairs (the first in the low bits), row-major from the south-west.
    pub heights: &'a Buffer,
    /// xy: cell (0, 0)'s south-west corner (world m), z: cells per metre,
    /// w: the tallest height (m).
    pub map: [f32; 4],
    pub size: [u32; 2],
}

/// The nearest distance a march reads a canopy of `cell_m` cells at (a
/// cell and a half): nearer, the interpolated canopy and the texels
/// between which `lighting_resolve` reads the threshold stand above a
/// crown's own sunlit side, which would shade itself. The ground right
/// under a crown loses only what the crown above it casts within that
/// distance (a high sun's).
pub fn canopy_skip_m(cell_m: f32) -> f32 {
    1.5 * cell_m
}

/// What a march reads: the terrain's heights and a canopy on them.
pub struct MarchOver<'a> {
    pub terrain: VistaTerrain,
    pub sector_data: &'a SectorData,
    pub tree: &'a GpuQuadtree,
    pub canopy: Option<Canopy<'a>>,
}

pub struct SunShadows {
    /// (variant bits, pipeline): without and (effect vegetation) with CANOPY.
    pipelines: Vec<(u32, Pipeline)>,
    nearest: Sampler,
    /// R32G32_SFLOAT (threshold above the ground, occluder distance), `resolution`
    /// square, one layer per slot; GENERAL.
    pub atlas: Image,
    jobs: Buffer,
    pub params: ShadowParams,
}

/// Bytes of one slot's layer of the shadow atlas (R32G32_SFLOAT).
pub fn layer_bytes(resolution: u32) -> u64 {
    u64::from(resolution).pow(2) * 8
}

impl SunShadows {
    pub const NAME: &'static str = sh::PASS;

    /// `canopy`: effect vegetation is on (its trees may cast).
    pub fn new(ctx: &Context, params: ShadowParams, slots: u32, canopy: bool) -> Result<Self> {
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
        let variants = if canopy { vec![0, sh::VARIANT_CANOPY] } else { vec![0] };
        let pipelines = Pipeline::compute_variants(ctx, Self::NAME, &variants, sh::variant)?;
        Ok(SunShadows { pipelines, nearest: nearest_sampler(ctx, "sun_shadows_nearest")?, atlas, jobs, params })
    }

    pub fn pipeline_labels(&self) -> impl Iterator<Item = &str> {
        self.pipelines.iter().map(|(_, p)| p.label.as_str())
    }

    pub fn memory(&self) -> [(String, u64); 2] {
        [(self.atlas.name.clone(), self.atlas.memory_bytes()), (self.jobs.name.clone(), self.jobs.memory_bytes())]
    }

    /// Marches `jobs` (at most SUN_SHADOW_MAX_JOBS) for the sun `sun_dir`
    /// over the terrain's heights and the `canopy` on them.
    pub fn record(&self, rec: &mut Recorder, jobs: &[SunShadowJob], sun_dir: DVec3, on: MarchOver) {
        assert!(!jobs.is_empty() && jobs.len() <= consts::SUN_SHADOW_MAX_JOBS as usize, "{} jobs", jobs.len());
        rec.update_buffer(&self.jobs, 0, bytemuck::cast_slice(jobs));
        rec.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::COMPUTE_SHADER);
        let want = if on.canopy.is_some() { sh::VARIANT_CANOPY } else { 0 };
        let (_, pipeline) =
            self.pipelines.iter().find(|(v, _)| *v == want).expect("sun_shadows built with CANOPY for vegetation");
        rec.bind_pipeline(pipeline);
        let mut bindings = vec![
            (sh::SECTOR_DATA, Resource::Buffer(on.sector_data.buffer())),
            (sh::HEIGHT_ATLAS, Resource::Image(on.tree.required_atlas(ATLAS_HEIGHT), ATLAS_LAYOUT)),
            (sh::NEAREST, Resource::Sampler(self.nearest.raw())),
            (sh::SHADOW_ATLAS, Resource::Image(&self.atlas, vk::ImageLayout::GENERAL)),
            (sh::JOBS, Resource::Buffer(&self.jobs)),
        ];
        if let Some(c) = &on.canopy {
            bindings.push((sh::CANOPY, Resource::Buffer(c.heights)));
        }
        rec.push_descriptors(pipeline, &bindings);
        let [ux, uy, rise] = march_sun(sun_dir);
        let p = &self.params;
        let push = SunShadowPush {
            terrain: on.terrain,
            sun: [ux, uy, rise, p.reach_m],
            params: [p.steps, p.resolution, jobs.len() as u32, 0],
            canopy_map: on.canopy.map_or([0.0; 4], |c| c.map),
            canopy_grid: on
                .canopy
                .map_or([0.0; 4], |c| [c.size[0] as f32, c.size[1] as f32, canopy_skip_m(1.0 / c.map[2]), 0.0]),
        };
        rec.push_constants(pipeline, &push);
        let [wx, wy, _] = sh::WORKGROUP_SIZE;
        rec.dispatch(p.resolution.div_ceil(wx), p.resolution.div_ceil(wy), jobs.len() as u32);
        rec.barrier(vk::PipelineStageFlags2::COMPUTE_SHADER, vk::PipelineStageFlags2::ALL_COMMANDS);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn penumbra_is_the_slope_spread_of_the_disc() {
        let p = ShadowParams { softness_deg: 2.0, ..ShadowParams::default() };
        let want = 31f64.to_radians().tan() - 29f64.to_radians().tan();
        assert!((f64::from(p.penumbra(30.0)) - want).abs() < 1e-6);
        assert_eq!(ShadowParams { softness_deg: 0.0, ..p }.penumbra(30.0), 0.0);
    }
}
