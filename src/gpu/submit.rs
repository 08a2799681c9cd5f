//! Submission for tools and tests (an engine submits its own command
//! buffers): a ring of per-frame command buffers with fences, one-shot
//! submit-and-wait, and buffer/image upload and readback built on it.

use super::commands::Recorder;
use super::context::{Context, Shared};
use super::resources::{inc, Buffer, BufferDesc, Garbage, Image, MemoryLocation};
use crate::error::{vk_err, Error, Result};
use ash::vk;
use std::sync::Arc;

/// A command pool with one primary command buffer and its fence.
struct Slot {
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    /// Frame number (`Context::frame_submitted`) last submitted from here.
    frame: u64,
}

fn create_slot(ctx: &Context, name: &str) -> Result<Slot> {
    let s = &ctx.shared;
    let info = vk::CommandPoolCreateInfo::default()
        .queue_family_index(s.graphics.family)
        .flags(vk::CommandPoolCreateFlags::TRANSIENT);
    // SAFETY: valid device and create infos; each created object is counted
    // and owned by the returned slot.
    unsafe {
        let pool = s.device.create_command_pool(&info, None).map_err(vk_err("vkCreateCommandPool"))?;
        inc(&s.live.command_pools);
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        let cmd = match s.device.allocate_command_buffers(&alloc) {
            Ok(c) => c[0],
            Err(e) => {
                s.retire(Garbage::CommandPool(pool));
                return Err(Error::vk("vkAllocateCommandBuffers", e));
            }
        };
        let fence =
            match s.device.create_fence(&vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED), None) {
                Ok(f) => f,
                Err(e) => {
                    s.retire(Garbage::CommandPool(pool));
                    return Err(Error::vk("vkCreateFence", e));
                }
            };
        inc(&s.live.sync_objects);
        ctx.set_name(pool, name);
        ctx.set_name(cmd, name);
        ctx.set_name(fence, name);
        Ok(Slot { pool, cmd, fence, frame: 0 })
    }
}

fn wait_fence(s: &Shared, fence: vk::Fence) -> Result<()> {
    // SAFETY: live fence of this device.
    unsafe { s.device.wait_for_fences(&[fence], true, u64::MAX) }.map_err(vk_err("vkWaitForFences"))
}

fn begin(s: &Shared, slot: &Slot) -> Result<()> {
    // SAFETY: the slot's fence has signalled, so its buffer is not pending.
    // The fence is reset only just before submission, so a recording error
    // leaves it signalled and nobody waits on it forever.
    unsafe {
        s.device
            .reset_command_pool(slot.pool, vk::CommandPoolResetFlags::empty())
            .map_err(vk_err("vkResetCommandPool"))?;
        let bi = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        s.device.begin_command_buffer(slot.cmd, &bi).map_err(vk_err("vkBeginCommandBuffer"))
    }
}

fn end_and_submit(s: &Shared, slot: &Slot) -> Result<()> {
    let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(slot.cmd)];
    let submit = vk::SubmitInfo2::default().command_buffer_infos(&cmds);
    let _q = s.queue_lock.lock().unwrap_or_else(|e| e.into_inner());
    // SAFETY: the buffer is in the recording state; the fence is signalled
    // and unused; the queue is externally synchronized by `queue_lock`.
    unsafe {
        s.device.end_command_buffer(slot.cmd).map_err(vk_err("vkEndCommandBuffer"))?;
        s.device.reset_fences(&[slot.fence]).map_err(vk_err("vkResetFences"))?;
        s.device.queue_submit2(s.graphics.raw, &[submit], slot.fence).map_err(vk_err("vkQueueSubmit2"))
    }
}

fn destroy_slot(s: &Shared, slot: &Slot) {
    s.retire(Garbage::Fence(slot.fence));
    s.retire(Garbage::CommandPool(slot.pool));
}

/// Per-frame command buffers for tools and tests, `depth` frames in flight.
pub struct FrameRing {
    slots: Vec<Slot>,
    next: usize,
    shared: Arc<Shared>,
}

impl FrameRing {
    pub fn new(ctx: &Context, depth: usize) -> Result<Self> {
        assert!(depth >= 1);
        let mut slots = Vec::new();
        for i in 0..depth {
            match create_slot(ctx, &format!("frame_ring[{i}]")) {
                Ok(s) => slots.push(s),
                Err(e) => {
                    slots.iter().for_each(|s| destroy_slot(&ctx.shared, s));
                    return Err(e);
                }
            }
        }
        Ok(FrameRing { slots, next: 0, shared: ctx.shared.clone() })
    }

    /// Waits for the slot's previous frame, then records the next frame.
    pub fn record<'c>(&mut self, ctx: &'c Context, f: impl FnOnce(&mut Recorder<'c>) -> Result<()>) -> Result<u64> {
        let s = &ctx.shared;
        let slot = &mut self.slots[self.next];
        wait_fence(s, slot.fence)?;
        ctx.frame_completed(slot.frame);
        begin(s, slot)?;
        // SAFETY: the slot's buffer was just begun and is used by nobody else.
        let mut rec = unsafe { Recorder::from_raw(ctx, slot.cmd) };
        f(&mut rec)?;
        end_and_submit(s, slot)?;
        slot.frame = ctx.frame_submitted();
        let frame = slot.frame;
        self.next = (self.next + 1) % self.slots.len();
        Ok(frame)
    }

    /// Waits for every frame of the ring.
    pub fn wait_all(&self, ctx: &Context) -> Result<()> {
        for slot in &self.slots {
            wait_fence(&ctx.shared, slot.fence)?;
            ctx.frame_completed(slot.frame);
        }
        Ok(())
    }
}

impl Drop for FrameRing {
    fn drop(&mut self) {
        // Pending frames must finish before their buffers' pools go.
        for slot in &self.slots {
            let _ = wait_fence(&self.shared, slot.fence);
            destroy_slot(&self.shared, slot);
        }
    }
}

impl Context {
    /// Records, submits and waits: for uploads, readback and tests.
    pub fn submit_and_wait<'c>(&'c self, f: impl FnOnce(&mut Recorder<'c>) -> Result<()>) -> Result<()> {
        let slot = create_slot(self, "one_shot")?;
        let result = (|| {
            begin(&self.shared, &slot)?;
            // SAFETY: freshly begun buffer owned by this call.
            let mut rec = unsafe { Recorder::from_raw(self, slot.cmd) };
            f(&mut rec)?;
            end_and_submit(&self.shared, &slot)?;
            wait_fence(&self.shared, slot.fence)
        })();
        // On error the buffer may still be pending: wait before freeing.
        let _ = wait_fence(&self.shared, slot.fence);
        destroy_slot(&self.shared, &slot);
        result
    }

    /// Copies `bytes` into `dst` at offset 0 through a staging buffer.
    pub fn upload(&self, dst: &Buffer, bytes: &[u8]) -> Result<()> {
        assert!(
            bytes.len() as u64 <= dst.size,
            "upload of {} bytes into {} ({} bytes)",
            bytes.len(),
            dst.name,
            dst.size
        );
        if bytes.is_empty() {
            return Ok(());
        }
        let mut staging = Buffer::new(
            self,
            &BufferDesc {
                name: "upload_staging",
                size: bytes.len() as u64,
                usage: vk::BufferUsageFlags::TRANSFER_SRC,
                location: MemoryLocation::CpuToGpu,
            },
        )?;
        staging.mapped_mut().expect("CpuToGpu buffers are mapped").copy_from_slice(bytes);
        self.submit_and_wait(|rec| {
            rec.copy_buffer(&staging, dst, bytes.len() as u64);
            Ok(())
        })
    }

    /// Reads a whole buffer back (waits for the GPU).
    pub fn read_buffer(&self, src: &Buffer) -> Result<Vec<u8>> {
        let staging = Buffer::new(
            self,
            &BufferDesc {
                name: "readback_staging",
                size: src.size,
                usage: vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuToCpu,
            },
        )?;
        self.submit_and_wait(|rec| {
            rec.barrier(vk::PipelineStageFlags2::ALL_COMMANDS, vk::PipelineStageFlags2::ALL_COMMANDS);
            rec.copy_buffer(src, &staging, src.size);
            Ok(())
        })?;
        Ok(staging.mapped().expect("GpuToCpu buffers are mapped").to_vec())
    }

    /// Reads one mip of one layer, tightly packed; the image returns to its
    /// tracked layout afterwards. Reading an image nothing was recorded into
    /// is a programmer error.
    pub fn read_image(&self, img: &Image, mip: u32, layer: u32, bytes_per_texel: u64) -> Result<Vec<u8>> {
        let layout = img.layout();
        assert_ne!(layout, vk::ImageLayout::UNDEFINED, "read of {}, which holds nothing yet", img.name);
        let w = (img.extent[0] >> mip).max(1) as u64;
        let h = (img.extent[1] >> mip).max(1) as u64;
        let staging = Buffer::new(
            self,
            &BufferDesc {
                name: "readback_staging",
                size: w * h * bytes_per_texel,
                usage: vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuToCpu,
            },
        )?;
        self.submit_and_wait(|rec| {
            rec.transition(img, vk::ImageLayout::TRANSFER_SRC_OPTIMAL);
            rec.copy_image_to_buffer(img, mip, layer, &staging);
            rec.transition(img, layout);
            Ok(())
        })?;
        Ok(staging.mapped().expect("GpuToCpu buffers are mapped").to_vec())
    }
}
