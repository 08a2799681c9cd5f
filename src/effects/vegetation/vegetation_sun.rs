//! `vegetation_sun`: the generator's sun march on the GPU (`vista vegetate
//! --sun gpu`, seed 004's "percentage of the sun's trajectory in which it
//! is in shadow"). The CPU's `world::vegetation::lit_share` in f32, one
//! thread a cell: the field's heights go up once, the cells of the tiles to
//! make in chunks, their shares come back. Between f32 and f64 a ray that
//! grazes a ridge may fall the other way: a cell's share may differ by a
//! sample's (`tests/vegetation.rs` bounds how often).

use crate::error::{Error, Result};
use crate::gpu::{vk, Buffer, BufferDesc, ComputePipelineDesc, Context, MemoryLocation, Pipeline, Resource};
use crate::shaders::{structs, vegetation_sun as sh};
use crate::world::vegetation::{HeightField, SunMarch, Window};
use crate::world::WorldError;
use glam::DVec3;

/// Cells a dispatch marches (its groups stay under the 65 535 limit).
const CHUNK: usize = 1 << 20;

/// Host twin of `VegetationSunPush`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VegetationSunPush {
    /// Cells across, cells up, listed cells, sun samples.
    pub grid: [u32; 4],
    /// Cell side (m), reach (m), the highest cell (m), unused.
    pub march: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<VegetationSunPush>() == structs::VEGETATION_SUN_PUSH);

/// The pass and the device it runs on.
pub struct VegetationSun<'c> {
    ctx: &'c Context,
    pipeline: Pipeline,
}

impl<'c> VegetationSun<'c> {
    pub const NAME: &'static str = sh::PASS;

    pub fn new(ctx: &'c Context) -> Result<Self> {
        let desc = ComputePipelineDesc { name: Self::NAME, shader: &sh::SHADER, specialization: &[] };
        Ok(VegetationSun { ctx, pipeline: Pipeline::compute(ctx, &desc)? })
    }

    /// The shares of `cells` (indices into the field), in their order.
    fn shares(&self, field: &HeightField, cells: &[u32], path: &[DVec3], reach_m: f64) -> Result<Vec<f32>> {
        let ctx = self.ctx;
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let heights = Buffer::with_data(ctx, "vegetation_sun_field", bytemuck::cast_slice(&field.z), storage)?;
        let dirs: Vec<[f32; 4]> = path.iter().map(|d| d.as_vec3().extend(0.0).to_array()).collect();
        let sun = Buffer::with_data(ctx, "vegetation_sun_path", bytemuck::cast_slice(&dirs), storage)?;
        let chunk = cells.len().clamp(1, CHUNK) as u64;
        let buffer = |name, usage| {
            Buffer::new(ctx, &BufferDesc { name, size: chunk * 4, usage, location: MemoryLocation::GpuOnly })
        };
        let list = buffer("vegetation_sun_cells", storage | vk::BufferUsageFlags::TRANSFER_DST)?;
        let out = buffer("vegetation_sun_shares", storage | vk::BufferUsageFlags::TRANSFER_SRC)?;
        let mut shares = Vec::with_capacity(cells.len());
        for part in cells.chunks(CHUNK) {
            ctx.upload(&list, bytemuck::cast_slice(part))?;
            let push = VegetationSunPush {
                grid: [field.size[0] as u32, field.size[1] as u32, part.len() as u32, path.len() as u32],
                march: [field.cell_m as f32, reach_m as f32, field.z_max, 0.0],
            };
            ctx.submit_and_wait(|rec| {
                rec.begin_label(Self::NAME);
                rec.bind_pipeline(&self.pipeline);
                let bindings = [
                    (sh::FIELD, Resource::Buffer(&heights)),
                    (sh::PATH, Resource::Buffer(&sun)),
                    (sh::CELLS, Resource::Buffer(&list)),
                    (sh::SHARES, Resource::Buffer(&out)),
                ];
                rec.push_descriptors(&self.pipeline, &bindings);
                rec.push_constants(&self.pipeline, &push);
                rec.dispatch((part.len() as u32).div_ceil(sh::WORKGROUP_SIZE[0]), 1, 1);
                rec.end_label();
                Ok(())
            })?;
            let bytes = ctx.read_buffer(&out)?;
            shares.extend_from_slice(&bytemuck::cast_slice::<u8, f32>(&bytes)[..part.len()]);
        }
        Ok(shares)
    }
}

impl SunMarch for VegetationSun<'_> {
    fn name(&self) -> String {
        format!("gpu {}", self.ctx.info().name)
    }

    fn march(
        &self,
        field: &HeightField,
        windows: &[Window],
        path: &[DVec3],
        reach_m: f64,
    ) -> std::result::Result<Vec<Vec<f32>>, WorldError> {
        if field.z.len() > u32::MAX as usize {
            return Err(WorldError::Vegetation(format!("{} cells are too many for the GPU's sun", field.z.len())));
        }
        let cells: Vec<u32> = windows
            .iter()
            .flat_map(|w| {
                (w.lo[1]..w.lo[1] + w.size[1])
                    .flat_map(move |j| (w.lo[0]..w.lo[0] + w.size[0]).map(move |i| field.index(i, j) as u32))
            })
            .collect();
        let gpu = |e: Error| WorldError::Vegetation(format!("the sun on the GPU: {e}"));
        let shares = self.shares(field, &cells, path, reach_m).map_err(gpu)?;
        let mut rest = &shares[..];
        Ok(windows
            .iter()
            .map(|w| {
                let (mine, after) = rest.split_at(w.size[0] * w.size[1]);
                rest = after;
                mine.to_vec()
            })
            .collect())
    }
}
