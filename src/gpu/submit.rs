//! Submission for tools and tests (an engine submits its own command
//! buffers): a ring of per-frame command buffers with fences (one per
//! frame, or a compute and a graphics one joined by a timeline semaphore),
//! one-shot submit-and-wait, and buffer/image upload and readback.

use super::commands::Recorder;
use super::context::{Context, Shared};
use super::queue_mode::{QueueMode, COMPUTE_LAG};
use super::resources::{inc, Buffer, BufferDesc, Garbage, Image, MemoryLocation};
use crate::error::{vk_err, Error, Result};
use ash::vk;
use std::sync::atomic::Ordering;
use std::sync::Arc;

/// A command pool with one primary command buffer and its fence (signalled
/// when the slot's last submission completed).
struct Slot {
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    /// Frame number (`Context::frame_submitted`) last submitted from here.
    frame: u64,
}

fn create_slot(ctx: &Context, name: &str) -> Result<Slot> {
    create_slot_on(ctx, name, ctx.shared.graphics.family)
}

fn create_slot_on(ctx: &Context, name: &str, family: u32) -> Result<Slot> {
    let s = &ctx.shared;
    let info =
        vk::CommandPoolCreateInfo::default().queue_family_index(family).flags(vk::CommandPoolCreateFlags::TRANSIENT);
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
    if s.faults.wait_loses_device() {
        return Err(Error::DeviceLost);
    }
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
    end_and_submit_with(s, slot, s.graphics.raw, &[], &[])
}

/// Ends `slot`'s buffer and submits it to `queue` with the given timeline
/// waits and signals; the slot's fence signals on completion.
fn end_and_submit_with(
    s: &Shared,
    slot: &Slot,
    queue: vk::Queue,
    waits: &[vk::SemaphoreSubmitInfo],
    signals: &[vk::SemaphoreSubmitInfo],
) -> Result<()> {
    let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(slot.cmd)];
    let submit = vk::SubmitInfo2::default()
        .command_buffer_infos(&cmds)
        .wait_semaphore_infos(waits)
        .signal_semaphore_infos(signals);
    if s.faults.submit_loses_device() {
        // Nothing submitted and the fence not reset: it stays signalled, so
        // nobody waits on it forever and teardown destroys the slot as is.
        return Err(Error::DeviceLost);
    }
    // SAFETY: the buffer is in the recording state; the fence is signalled
    // and unused.
    unsafe {
        s.device.end_command_buffer(slot.cmd).map_err(vk_err("vkEndCommandBuffer"))?;
        s.device.reset_fences(&[slot.fence]).map_err(vk_err("vkResetFences"))?;
    }
    if let Some(engine) = &s.submitter {
        s.submissions_engine.fetch_add(1, Ordering::AcqRel);
        return engine(queue, &submit, slot.fence).map_err(vk_err("the engine's submit (RawHandles::submit)"));
    }
    let _q = s.queue_lock.lock().unwrap_or_else(|e| e.into_inner());
    s.submissions_direct.fetch_add(1, Ordering::AcqRel);
    // SAFETY: the buffer was ended above; the queue is externally
    // synchronized by `queue_lock` (one lock for both queues); the
    // semaphores are live (timeline, or binary ones their owner signals and
    // waits for once per use).
    unsafe { s.device.queue_submit2(queue, &[submit], slot.fence).map_err(vk_err("vkQueueSubmit2")) }
}

fn create_timeline(ctx: &Context, name: &str) -> Result<vk::Semaphore> {
    let mut ty = vk::SemaphoreTypeCreateInfo::default().semaphore_type(vk::SemaphoreType::TIMELINE).initial_value(0);
    let info = vk::SemaphoreCreateInfo::default().push_next(&mut ty);
    // SAFETY: valid device; timeline semaphores are a required feature.
    let sem = unsafe { ctx.shared.device.create_semaphore(&info, None) }.map_err(vk_err("vkCreateSemaphore"))?;
    inc(&ctx.shared.live.sync_objects);
    ctx.set_name(sem, name);
    Ok(sem)
}

fn destroy_slot(s: &Shared, slot: &Slot) {
    s.retire(Garbage::Fence(slot.fence));
    s.retire(Garbage::CommandPool(slot.pool));
}

/// Per-frame command buffers for tools and tests, `depth` frames in flight.
/// In a split mode each frame has a compute and a graphics command buffer,
/// and two timeline semaphores count the frames each queue finished: frame
/// k's compute submission waits for frame k - `COMPUTE_LAG`'s graphics
/// (the last to read the per-frame copies it rewrites, `frame::per_frame`)
/// and signals compute value k; its graphics submission waits for compute
/// value k and signals graphics value k. With async compute, frame k's
/// compute thus runs beside frame k - 1's graphics.
pub struct FrameRing {
    slots: Vec<Slot>,
    /// Compute command buffers of a split mode, one per slot.
    compute: Vec<Slot>,
    /// (compute done, graphics done) of a split mode.
    timeline: Option<[vk::Semaphore; 2]>,
    mode: QueueMode,
    /// Frames recorded through this ring (timeline values derive from it).
    frames: u64,
    next: usize,
    /// Binary semaphores of the frame being recorded ([`FrameRing::record_synced`]).
    sync: Option<BinarySync>,
    shared: Arc<Shared>,
}

/// A frame's binary semaphores: waited for at `wait_stage` (a swapchain
/// image's acquisition), signalled at the end (its presentation).
#[derive(Debug, Clone, Copy)]
pub struct BinarySync {
    pub wait: vk::Semaphore,
    pub wait_stage: vk::PipelineStageFlags2,
    pub signal: vk::Semaphore,
}

/// The command buffers of one frame: one, or compute and graphics.
pub enum FrameCommands<'r, 'c> {
    One(&'r mut Recorder<'c>),
    Split { compute: &'r mut Recorder<'c>, graphics: &'r mut Recorder<'c> },
}

impl FrameRing {
    pub fn new(ctx: &Context, depth: usize) -> Result<Self> {
        Self::with_mode(ctx, depth, QueueMode::Single)
    }

    /// A ring submitting in `mode` (checked against the device).
    pub fn with_mode(ctx: &Context, depth: usize, mode: QueueMode) -> Result<Self> {
        assert!(depth >= 1);
        mode.check(ctx.info())?;
        let mut ring = FrameRing {
            slots: Vec::new(),
            compute: Vec::new(),
            timeline: None,
            mode,
            frames: 0,
            next: 0,
            sync: None,
            shared: ctx.shared.clone(),
        };
        // On error, Drop frees whatever was created.
        for i in 0..depth {
            ring.slots.push(create_slot(ctx, &format!("frame_ring[{i}]"))?);
            if mode.is_split() {
                let family = if mode == QueueMode::AsyncCompute {
                    ctx.shared.compute.family
                } else {
                    ctx.shared.graphics.family
                };
                ring.compute.push(create_slot_on(ctx, &format!("frame_ring_compute[{i}]"), family)?);
            }
        }
        if mode.is_split() {
            let compute = create_timeline(ctx, "frame_ring_compute_done")?;
            match create_timeline(ctx, "frame_ring_graphics_done") {
                Ok(graphics) => ring.timeline = Some([compute, graphics]),
                Err(e) => {
                    ctx.shared.retire(Garbage::Semaphore(compute));
                    return Err(e);
                }
            }
        }
        Ok(ring)
    }

    pub fn mode(&self) -> QueueMode {
        self.mode
    }

    /// Waits for the slot's previous frame, then records the next frame into
    /// one command buffer (a ring in `Single` mode).
    pub fn record<'c>(&mut self, ctx: &'c Context, f: impl FnOnce(&mut Recorder<'c>) -> Result<()>) -> Result<u64> {
        assert_eq!(self.mode, QueueMode::Single, "a split ring records with record_frame");
        self.record_frame(ctx, |cmds| match cmds {
            FrameCommands::One(rec) => f(rec),
            FrameCommands::Split { .. } => unreachable!(),
        })
    }

    /// Waits until the slot the next frame records into is free: its last
    /// frame completed, so a semaphore that frame waited on may be signalled
    /// again (acquire the swapchain image after this).
    pub fn wait_next(&self, ctx: &Context) -> Result<()> {
        let slot = &self.slots[self.next];
        wait_fence(&ctx.shared, slot.fence)?;
        ctx.frame_completed(slot.frame);
        Ok(())
    }

    /// Like [`FrameRing::record`], for a frame that waits for and signals
    /// the binary semaphores of `sync` (`Single` mode).
    pub fn record_synced<'c>(
        &mut self,
        ctx: &'c Context,
        sync: BinarySync,
        f: impl FnOnce(&mut Recorder<'c>) -> Result<()>,
    ) -> Result<u64> {
        self.sync = Some(sync);
        let frame = self.record(ctx, f);
        self.sync = None;
        frame
    }

    /// Waits for the slot's previous frame, then records the next frame into
    /// the command buffers of the ring's mode and submits them.
    pub fn record_frame<'c>(
        &mut self,
        ctx: &'c Context,
        f: impl FnOnce(FrameCommands<'_, 'c>) -> Result<()>,
    ) -> Result<u64> {
        let s = &ctx.shared;
        let i = self.next;
        wait_fence(s, self.slots[i].fence)?;
        if let Some(c) = self.compute.get(i) {
            wait_fence(s, c.fence)?;
        }
        ctx.frame_completed(self.slots[i].frame);
        // Resources dropped while recording wait for this frame too.
        ctx.frame_recording();
        match self.record_and_submit(ctx, i, f) {
            Ok(()) => {}
            Err((e, compute_submitted)) => {
                if compute_submitted {
                    // Its compute half runs: the frame counts, so what it
                    // uses waits for its fence.
                    let frame = ctx.frame_submitted();
                    self.compute[i].frame = frame;
                } else {
                    // Nothing of it reached the queue: what was dropped while
                    // it was recorded waits for the frames before it only.
                    s.abandon_recording();
                }
                self.next = (self.next + 1) % self.slots.len();
                return Err(e);
            }
        }
        let frame = ctx.frame_submitted();
        self.slots[i].frame = frame;
        if let Some(c) = self.compute.get_mut(i) {
            c.frame = frame;
        }
        self.next = (self.next + 1) % self.slots.len();
        Ok(frame)
    }

    /// Records slot `i`'s commands and submits them; on failure, says
    /// whether the compute half was already submitted.
    fn record_and_submit<'c>(
        &mut self,
        ctx: &'c Context,
        i: usize,
        f: impl FnOnce(FrameCommands<'_, 'c>) -> Result<()>,
    ) -> std::result::Result<(), (Error, bool)> {
        let s = &ctx.shared;
        let early = |e: Error| (e, false);
        begin(s, &self.slots[i]).map_err(early)?;
        // SAFETY: the slot's buffer was just begun and is used by nobody else.
        let mut graphics = unsafe { Recorder::from_raw(ctx, self.slots[i].cmd) };
        match self.compute.get(i) {
            None => f(FrameCommands::One(&mut graphics)).map_err(early)?,
            Some(c) => {
                begin(s, c).map_err(early)?;
                // SAFETY: as above, for the slot's compute buffer.
                let mut compute = unsafe { Recorder::from_raw(ctx, c.cmd) };
                f(FrameCommands::Split { compute: &mut compute, graphics: &mut graphics }).map_err(early)?;
            }
        }
        let k = self.frames + 1;
        if let (Some(c), Some([compute_done, graphics_done])) = (self.compute.get(i), self.timeline) {
            let info = |semaphore, value| {
                vk::SemaphoreSubmitInfo::default()
                    .semaphore(semaphore)
                    .value(value)
                    .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            };
            let queue = if self.mode == QueueMode::AsyncCompute { s.compute.raw } else { s.graphics.raw };
            // Frame k - COMPUTE_LAG's graphics read the copies compute k rewrites.
            let lagged = k.saturating_sub(COMPUTE_LAG);
            let waits: Vec<_> = (lagged > 0).then(|| info(graphics_done, lagged)).into_iter().collect();
            end_and_submit_with(s, c, queue, &waits, &[info(compute_done, k)]).map_err(early)?;
            // The compute timeline has moved: the next frame must signal past
            // it. (After a failure here the ring cannot go on: graphics k
            // never comes.)
            self.frames = k;
            end_and_submit_with(s, &self.slots[i], s.graphics.raw, &[info(compute_done, k)], &[info(graphics_done, k)])
                .map_err(|e| (e, true))?;
        } else if let Some(b) = self.sync {
            let wait = [vk::SemaphoreSubmitInfo::default().semaphore(b.wait).stage_mask(b.wait_stage)];
            let signal = [vk::SemaphoreSubmitInfo::default()
                .semaphore(b.signal)
                .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
            end_and_submit_with(s, &self.slots[i], s.graphics.raw, &wait, &signal).map_err(early)?;
        } else {
            end_and_submit(s, &self.slots[i]).map_err(early)?;
        }
        self.frames = k;
        Ok(())
    }

    /// Waits for every frame of the ring.
    pub fn wait_all(&self, ctx: &Context) -> Result<()> {
        for slot in self.slots.iter().chain(&self.compute) {
            wait_fence(&ctx.shared, slot.fence)?;
            ctx.frame_completed(slot.frame);
        }
        Ok(())
    }
}

impl Drop for FrameRing {
    fn drop(&mut self) {
        // Pending frames must finish before their buffers' pools go.
        for slot in self.slots.iter().chain(&self.compute) {
            let _ = wait_fence(&self.shared, slot.fence);
            destroy_slot(&self.shared, slot);
        }
        for t in self.timeline.into_iter().flatten() {
            self.shared.retire(Garbage::Semaphore(t));
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
    /// is a programmer error. For a block-compressed image `bytes_per_texel`
    /// is the bytes of one 4x4 block, and the blocks come back row by row.
    pub fn read_image(&self, img: &Image, mip: u32, layer: u32, bytes_per_texel: u64) -> Result<Vec<u8>> {
        let layout = img.layout();
        assert_ne!(layout, vk::ImageLayout::UNDEFINED, "read of {}, which holds nothing yet", img.name);
        let mut w = (img.extent[0] >> mip).max(1) as u64;
        let mut h = (img.extent[1] >> mip).max(1) as u64;
        if let Some(block) = block_bytes(img.format) {
            assert_eq!(bytes_per_texel, block, "{}: pass the bytes of one 4x4 block", img.name);
            (w, h) = (w.div_ceil(4), h.div_ceil(4));
        }
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

    /// Reads the stencil of a depth-stencil image, a byte per texel; the
    /// image returns to its tracked layout afterwards.
    pub fn read_stencil(&self, img: &Image) -> Result<Vec<u8>> {
        let layout = img.layout();
        assert_ne!(layout, vk::ImageLayout::UNDEFINED, "read of {}, which holds nothing yet", img.name);
        let staging = Buffer::new(
            self,
            &BufferDesc {
                name: "stencil_readback_staging",
                size: u64::from(img.extent[0]) * u64::from(img.extent[1]),
                usage: vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuToCpu,
            },
        )?;
        self.submit_and_wait(|rec| {
            rec.transition(img, vk::ImageLayout::TRANSFER_SRC_OPTIMAL);
            rec.copy_stencil_to_buffer(img, &staging);
            rec.transition(img, layout);
            Ok(())
        })?;
        Ok(staging.mapped().expect("GpuToCpu buffers are mapped").to_vec())
    }
}

/// Bytes of one 4x4 block of a block-compressed format vista uses.
fn block_bytes(format: vk::Format) -> Option<u64> {
    match format {
        vk::Format::BC1_RGBA_UNORM_BLOCK | vk::Format::BC1_RGB_UNORM_BLOCK => Some(8),
        vk::Format::BC3_UNORM_BLOCK => Some(16),
        _ => None,
    }
}

/// A command pool of the graphics family for code that allocates and
/// submits its own command buffers (a UI library's texture uploads).
pub struct CommandPool {
    raw: vk::CommandPool,
    shared: Arc<Shared>,
}

impl CommandPool {
    pub fn new(ctx: &Context, name: &str) -> Result<CommandPool> {
        let s = &ctx.shared;
        let info = vk::CommandPoolCreateInfo::default().queue_family_index(s.graphics.family);
        // SAFETY: valid device and create info; the pool is counted and
        // owned by the returned value.
        let raw = unsafe { s.device.create_command_pool(&info, None) }.map_err(vk_err("vkCreateCommandPool"))?;
        inc(&s.live.command_pools);
        ctx.set_name(raw, name);
        Ok(CommandPool { raw, shared: s.clone() })
    }

    pub fn raw(&self) -> vk::CommandPool {
        self.raw
    }
}

impl Drop for CommandPool {
    fn drop(&mut self) {
        self.shared.retire(Garbage::CommandPool(self.raw));
    }
}
