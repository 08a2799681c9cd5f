//! `terrain_query`: height, normal and material at world points, through the
//! sector data and terrain_sample.glsl (what an engine's own shaders do);
//! a point outside the world or not covered by any resident node has no
//! answer.

use crate::error::{Error, Result};
use crate::gpu::{
    vk, Buffer, BufferDesc, ComputePipelineDesc, Context, MemoryLocation, Pipeline, Recorder, Resource, Sampler,
    SamplerDesc,
};
use crate::passes::sector_data::SectorData;
use crate::shaders::terrain_query as sh;
use crate::terrain::gpu_quadtree::{atlas_name, GpuQuadtree, ATLAS_HEIGHT, ATLAS_LAYOUT, ATLAS_NORMAL, ATLAS_SPLAT};
use crate::world::{WorldDesc, NODE_QUADS};

/// Host twin of `VistaTerrain` (terrain_sample.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VistaTerrain {
    pub sector_size_m: f32,
    pub spacing_m: f32,
    pub sectors_x: u32,
    pub sectors_y: u32,
    pub lod_count: u32,
    pub height_lo: f32,
    pub height_range: f32,
    pub extent_x_m: f32,
    pub extent_y_m: f32,
    /// Where LOD-0 sample (0, 0) lies ([`WorldDesc::grid_origin_m`]).
    pub grid_origin_x_m: f32,
    pub grid_origin_y_m: f32,
    pub pad: u32,
}

impl VistaTerrain {
    pub fn new(world: &WorldDesc, sector_data: &SectorData) -> Self {
        let [lo, hi] = world.height_range_m;
        let sector = world.sector_size_m() as f32;
        VistaTerrain {
            sector_size_m: sector,
            spacing_m: sector / NODE_QUADS as f32,
            sectors_x: sector_data.extent[0],
            sectors_y: sector_data.extent[1],
            lod_count: world.lod_count,
            height_lo: lo,
            height_range: hi - lo,
            extent_x_m: world.extent_m[0] as f32,
            extent_y_m: world.extent_m[1] as f32,
            grid_origin_x_m: world.grid_origin_m[0] as f32,
            grid_origin_y_m: world.grid_origin_m[1] as f32,
            pad: 0,
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TerrainQueryPush {
    pub terrain: VistaTerrain,
    pub count: u32,
    pub pad: [u32; 3],
}

pub struct TerrainQuery {
    pipeline: Pipeline,
    sampler: Sampler,
    points: Buffer,
    results: Buffer,
    materials: Buffer,
    capacity: u32,
}

/// One answer: height (m), unit normal, material id.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QueryAnswer {
    pub height_m: f32,
    pub normal: [f32; 3],
    pub material: u32,
}

impl TerrainQuery {
    pub const NAME: &'static str = sh::PASS;

    pub fn new(ctx: &Context, capacity: u32) -> Result<Self> {
        if capacity == 0 {
            return Err(Error::BadInput("terrain_query capacity is 0".into()));
        }
        let buf = |name, size, location| {
            Buffer::new(
                ctx,
                &BufferDesc {
                    name,
                    size,
                    usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC,
                    location,
                },
            )
        };
        let n = u64::from(capacity);
        Ok(TerrainQuery {
            pipeline: Pipeline::compute(
                ctx,
                &ComputePipelineDesc { name: Self::NAME, shader: &sh::SHADER, specialization: &[] },
            )?,
            sampler: Sampler::new(
                ctx,
                &SamplerDesc {
                    name: "terrain_query_sampler",
                    filter: vk::Filter::NEAREST,
                    address_mode: vk::SamplerAddressMode::CLAMP_TO_EDGE,
                },
            )?,
            points: buf("terrain_query_points", n * 8, MemoryLocation::CpuToGpu)?,
            results: buf("terrain_query_results", n * 16, MemoryLocation::GpuToCpu)?,
            materials: buf("terrain_query_materials", n * 8, MemoryLocation::GpuToCpu)?,
            capacity,
        })
    }

    /// Records a query of `points` (world metres, x/y); read with `answers`.
    pub fn record(
        &mut self,
        rec: &mut Recorder,
        terrain: VistaTerrain,
        tree: &GpuQuadtree,
        sectors: &SectorData,
        points: &[[f32; 2]],
    ) -> Result<()> {
        if points.len() > self.capacity as usize {
            return Err(Error::BadInput(format!("{} query points, capacity {}", points.len(), self.capacity)));
        }
        if let Some(a) = [ATLAS_HEIGHT, ATLAS_NORMAL, ATLAS_SPLAT].into_iter().find(|a| tree.atlas(*a).is_none()) {
            return Err(Error::BadInput(format!(
                "terrain_query reads {}, which this terrain does not keep (the effect using it is off)",
                atlas_name(a)
            )));
        }
        let bytes = bytemuck::cast_slice(points);
        self.points.mapped_mut().expect("mapped")[..bytes.len()].copy_from_slice(bytes);
        rec.bind_pipeline(&self.pipeline);
        rec.push_descriptors(
            &self.pipeline,
            &[
                (sh::SECTOR_DATA, Resource::Buffer(sectors.buffer())),
                (sh::HEIGHT_ATLAS, Resource::Image(tree.required_atlas(ATLAS_HEIGHT), ATLAS_LAYOUT)),
                (sh::NORMAL_ATLAS, Resource::Image(tree.required_atlas(ATLAS_NORMAL), ATLAS_LAYOUT)),
                (sh::SPLAT_ATLAS, Resource::Image(tree.required_atlas(ATLAS_SPLAT), ATLAS_LAYOUT)),
                (sh::ATLAS_SAMPLER, Resource::Sampler(self.sampler.raw())),
                (sh::QUERY_POINTS, Resource::Buffer(&self.points)),
                (sh::QUERY_RESULTS, Resource::Buffer(&self.results)),
                (sh::QUERY_MATERIALS, Resource::Buffer(&self.materials)),
            ],
        );
        let count = points.len() as u32;
        rec.push_constants(&self.pipeline, &TerrainQueryPush { terrain, count, pad: [0; 3] });
        rec.dispatch(count.div_ceil(sh::WORKGROUP_SIZE[0]), 1, 1);
        rec.barrier(
            vk::PipelineStageFlags2::COMPUTE_SHADER,
            vk::PipelineStageFlags2::ALL_COMMANDS | vk::PipelineStageFlags2::HOST,
        );
        Ok(())
    }

    /// The first `n` answers of the last query, once its frame has completed:
    /// `None` where no terrain was found (outside the world, or no resident
    /// node covers the point).
    pub fn answers(&self, n: usize) -> Vec<Option<QueryAnswer>> {
        let r: &[[f32; 4]] = bytemuck::cast_slice(self.results.mapped().expect("mapped"));
        let m: &[[u32; 2]] = bytemuck::cast_slice(self.materials.mapped().expect("mapped"));
        (0..n.min(self.capacity as usize))
            .map(|i| {
                let [material, found] = m[i];
                (found != 0).then(|| QueryAnswer { height_m: r[i][0], normal: [r[i][1], r[i][2], r[i][3]], material })
            })
            .collect()
    }
}
