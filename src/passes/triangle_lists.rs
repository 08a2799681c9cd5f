//! The per-triangle rule's index lists (one per frame parity and phase):
//! each starts at [`FIRST_TRIANGLES`] and grows to what the frames emit,
//! as the telemetry reports it frames late, up to what one storage buffer
//! binding holds. A list too small for a frame drops the triangles past
//! its end (the header counts them as `overflow`) until the grown list
//! is in use, a few frames later; a fixed capacity kept the worst view's
//! memory for every view (four lists of 4 Mi triangles: 192 MiB) and still
//! dropped triangles with culling off.

use crate::error::Result;
use crate::frame::per_frame::{copy_name, PerFrame};
use crate::gpu::{vk, Buffer, BufferDesc, Context, MemoryLocation};
use crate::shaders::structs;

/// Triangles a list holds when made (12 MiB): a 1280x720 frame at 1 px
/// emits 0.1 to 0.2 a pixel with culling on.
pub const FIRST_TRIANGLES: u32 = 1 << 20;
/// Bytes of a triangle's three indices.
const TRIANGLE_BYTES: u64 = 12;

/// One copy: its buffer and the triangles it holds.
struct ListCopy {
    buffer: Buffer,
    capacity: u32,
}

/// A growable index list, one copy per frame parity.
pub struct TriangleList {
    name: &'static str,
    copies: PerFrame<ListCopy>,
    /// Triangles every copy grows to when next selected.
    wanted: u32,
    /// The most one storage buffer binding holds.
    max: u32,
}

impl TriangleList {
    /// Both copies at `first` triangles (at most what `ctx`'s device binds).
    pub fn new(ctx: &Context, name: &'static str, first: u32) -> Result<Self> {
        let max = max_triangles(ctx.info().limits.max_storage_buffer_range);
        let first = first.min(max).max(1);
        let copies = PerFrame::new(|i| copy(ctx, name, i, first))?;
        Ok(TriangleList { name, copies, wanted: first, max })
    }

    /// Frame `frame` uses its parity's copy from now on, grown first where
    /// a frame emitted more than it holds (the old buffer is retired: the
    /// frames in flight that use it keep it until they complete).
    pub fn select(&mut self, ctx: &Context, frame: u64) -> Result<()> {
        self.copies.select(frame);
        if self.copies.current().capacity < self.wanted {
            let i = (frame % crate::frame::per_frame::COPIES as u64) as usize;
            *self.copies.current_mut() = copy(ctx, self.name, i, self.wanted)?;
            log::info!("{}: grown to {} triangles", self.name, self.wanted);
        }
        Ok(())
    }

    /// A frame emitted `triangles` (drawn or past the list): the copies
    /// grow to hold a quarter more, rounded up to a power of two, at most
    /// what a binding holds. Never shrinks.
    pub fn emitted(&mut self, triangles: u32) {
        if triangles > self.wanted {
            self.wanted = grown_to(triangles, self.max);
        }
    }

    /// The copy of the frame being (or last) recorded.
    pub fn current(&self) -> &Buffer {
        &self.copies.current().buffer
    }

    /// Triangles the current copy holds.
    pub fn capacity(&self) -> u32 {
        self.copies.current().capacity
    }

    /// Both copies' buffers (memory reports).
    pub fn buffers(&self) -> impl Iterator<Item = &Buffer> {
        self.copies.all().iter().map(|c| &c.buffer)
    }
}

/// What a list grows to for a frame that emitted `triangles`.
fn grown_to(triangles: u32, max: u32) -> u32 {
    let room = u64::from(triangles) + u64::from(triangles / 4);
    room.next_power_of_two().min(u64::from(max)) as u32
}

/// Triangles a list bound as one storage buffer of `range` bytes holds.
fn max_triangles(range: u32) -> u32 {
    let room = u64::from(range).saturating_sub(structs::TRIANGLE_LIST_HEADER as u64) / TRIANGLE_BYTES;
    room.min(u64::from(u32::MAX) / 3) as u32
}

fn copy(ctx: &Context, name: &str, i: usize, capacity: u32) -> Result<ListCopy> {
    let buffer = Buffer::new(
        ctx,
        &BufferDesc {
            name: &copy_name(name, i),
            size: structs::TRIANGLE_LIST_HEADER as u64 + u64::from(capacity) * TRIANGLE_BYTES,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::INDEX_BUFFER
                | vk::BufferUsageFlags::INDIRECT_BUFFER
                | vk::BufferUsageFlags::TRANSFER_DST
                | vk::BufferUsageFlags::TRANSFER_SRC,
            location: MemoryLocation::GpuOnly,
        },
    )?;
    Ok(ListCopy { buffer, capacity })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_binding_of_128_mib_holds_11_m_triangles() {
        let header = structs::TRIANGLE_LIST_HEADER as u64;
        assert_eq!(u64::from(max_triangles(1 << 27)), ((1 << 27) - header) / 12);
        assert_eq!(max_triangles(u32::MAX), ((u64::from(u32::MAX) - header) / 12) as u32);
        assert_eq!(max_triangles(8), 0);
    }

    #[test]
    fn a_list_grows_to_a_quarter_more_rounded_up_to_a_power_of_two() {
        assert_eq!(grown_to(4_194_304, u32::MAX), 8 << 20);
        assert_eq!(grown_to(3_000_000, u32::MAX), 4 << 20);
        assert_eq!(grown_to(3_500_000, u32::MAX), 8 << 20);
        assert_eq!(grown_to(9_000_000, 11_184_810), 11_184_810);
    }
}
