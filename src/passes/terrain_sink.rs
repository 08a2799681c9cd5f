//! The terrain's sink (terrain_sink.glsl): the cells of a square of the
//! world grid where an effect's surface replaces the height field. The
//! terrain's fragments there are pushed behind along their normal (the
//! SINK variant of terrain_geometry, terrain_holes and terrain_triangles),
//! so a mesh lying on the height field at its own triangulation wins the
//! depth test everywhere, while the terrain still covers every pixel it
//! covered: no fight and no hole where the two triangulations part.

use crate::error::Result;
use crate::gpu::{vk, Buffer, BufferDesc, Context, MemoryLocation, Recorder};
use crate::shaders::structs;

/// Host twin of `TerrainSinkHeader`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TerrainSinkHeader {
    pub cell0: [i32; 2],
    pub side: u32,
    pub cell_m: f32,
    pub sink_m: f32,
    pub pad: [u32; 3],
}

/// The sink's buffer: the header, then a bit per cell of a square of up
/// to `max_side` cells a side (row by row). The effect owns it.
pub struct TerrainSink {
    buffer: Buffer,
    max_side: u32,
}

impl TerrainSink {
    pub fn new(ctx: &Context, name: &str, max_side: u32) -> Result<Self> {
        let words = u64::from(max_side * max_side).div_ceil(32);
        let desc = BufferDesc {
            name,
            size: structs::TERRAIN_SINK_HEADER as u64 + 4 * words,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::TRANSFER_DST
                | vk::BufferUsageFlags::TRANSFER_SRC,
            location: MemoryLocation::GpuOnly,
        };
        Ok(TerrainSink { buffer: Buffer::new(ctx, &desc)?, max_side })
    }

    pub fn buffer(&self) -> &Buffer {
        &self.buffer
    }

    /// Starts a square: writes `header` and clears every bit (the writer
    /// sets its cells' bits after the transfer barrier the caller records).
    pub fn reset(&self, rec: &mut Recorder, header: &TerrainSinkHeader) {
        assert!(
            header.side <= self.max_side,
            "a sink of {} cells a side in a buffer of {}",
            header.side,
            self.max_side
        );
        rec.fill_buffer(&self.buffer, 0);
        rec.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::ALL_TRANSFER);
        rec.update_buffer(&self.buffer, 0, bytemuck::bytes_of(header));
    }

    /// The sunk cells of the last square (waits for the GPU; tests).
    pub fn read(&self, ctx: &Context) -> Result<(TerrainSinkHeader, Vec<[i32; 2]>)> {
        let bytes = ctx.read_buffer(&self.buffer)?;
        let at = structs::TERRAIN_SINK_HEADER;
        let h: TerrainSinkHeader = bytemuck::pod_read_unaligned(&bytes[..at]);
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&bytes[at..]);
        let cells = (0..h.side * h.side)
            .filter(|&i| words[(i / 32) as usize] & (1 << (i % 32)) != 0)
            .map(|i| [h.cell0[0] + (i % h.side) as i32, h.cell0[1] + (i / h.side) as i32])
            .collect();
        Ok((h, cells))
    }

    pub fn memory(&self) -> (String, u64) {
        (self.buffer.name.clone(), self.buffer.memory_bytes())
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_header_twin_has_the_shader_size() {
        assert_eq!(std::mem::size_of::<super::TerrainSinkHeader>(), crate::shaders::structs::TERRAIN_SINK_HEADER);
    }
}
