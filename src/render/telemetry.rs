//! Telemetry that never stalls: at the end of every frame the GPU copies its
//! counters (traversal, culling per stage and phase, draws) into one slot of
//! a host-visible ring; the renderer reads a slot once the context reports
//! its frame complete (`Context::frame_completed`, which the submitter calls
//! after waiting the frame's fence before reusing its command buffer), so
//! counters come back frames-in-flight + 1 frames late at most, as data,
//! and nothing in the frame path waits for the GPU.

use crate::error::Result;
use crate::gpu::{vk, Buffer, BufferDesc, Context, MemoryLocation, Recorder};
use crate::passes::classify_tiles::{ARGS_BYTES, HEAD_BYTES};
pub use crate::passes::counters::{FrameCounters, TraverseCounters, TRIANGLES_PER_PATCH};
use crate::passes::cull_patches::{CullCounters, PatchListHeader};
use crate::passes::traverse::TraverseHeader;
use crate::scene::effect::Effect;
use crate::shaders::structs;

/// Which lists a renderer has: phase 1's hole list, phase 2's lists.
#[derive(Debug, Clone)]
pub struct CounterLayout {
    pub holes: bool,
    pub occlusion: bool,
    pub lod_count: u32,
    pub list_capacity: u32,
    pub triangles_per_patch: u64,
    /// Built with the per-triangle rule: its two lists' headers follow the core.
    pub triangle_lists: bool,
    /// The built effects' counters and their bytes, in registry order.
    pub effects: Vec<(Effect, u64)>,
}

const TRAVERSE_BYTES: u64 = std::mem::size_of::<TraverseHeader>() as u64;
const HEADER_BYTES: u64 = structs::PATCH_LIST_HEADER as u64;
const SELECT_BYTES: u64 = structs::SELECT_HEADER as u64;
/// Readback bytes of the core: the traversal header, then 4 list headers
/// (phase 1 solid, holes; phase 2 solid, holes), absent ones left zero,
/// the tile lists' head (draw arguments and plane counters) and the
/// selection counters; each effect's counters follow.
const CORE_BYTES: u64 = TRAVERSE_BYTES + 4 * HEADER_BYTES + HEAD_BYTES + SELECT_BYTES;
/// Where the tile lists' draw arguments start in a slot.
const TILES_AT: u64 = TRAVERSE_BYTES + 4 * HEADER_BYTES;
/// Where the selection counters start.
const SELECT_AT: u64 = TILES_AT + HEAD_BYTES;
/// Bytes of one per-triangle list's header.
const TRIANGLE_HEADER_BYTES: u64 = structs::TRIANGLE_LIST_HEADER as u64;

impl CounterLayout {
    /// Bytes of one slot.
    fn slot_bytes(&self) -> u64 {
        self.effects_at() + self.effects.iter().map(|(_, n)| n).sum::<u64>()
    }

    /// Where the effects' counters start: past the core and the
    /// per-triangle lists' headers where built.
    fn effects_at(&self) -> u64 {
        CORE_BYTES + if self.triangle_lists { 2 * TRIANGLE_HEADER_BYTES } else { 0 }
    }

    /// Where each effect's counters start in a slot, and their bytes.
    fn effect_ranges(&self) -> impl Iterator<Item = (Effect, u64, u64)> + '_ {
        self.effects.iter().scan(self.effects_at(), |at, &(e, n)| {
            *at += n;
            Some((e, *at - n, n))
        })
    }

    /// Parses a slot's bytes (also used on a waiting readback in tests).
    pub fn parse(&self, frame: u64, bytes: &[u8]) -> FrameCounters {
        let t: TraverseHeader = bytemuck::pod_read_unaligned(&bytes[..TRAVERSE_BYTES as usize]);
        let header = |i: u64| -> PatchListHeader {
            let at = (TRAVERSE_BYTES + i * HEADER_BYTES) as usize;
            bytemuck::pod_read_unaligned(&bytes[at..at + HEADER_BYTES as usize])
        };
        let holes = |i| self.holes.then(|| header(i));
        let late = self.occlusion.then(|| [Some(header(2)), holes(3)]);
        let cull = CullCounters::from_headers([Some(header(0)), holes(1)], late, self.list_capacity);
        let instances = [0, 1, 2, 3].map(|i| header(i).instance_count.min(self.list_capacity));
        let args = &bytes[TILES_AT as usize..(TILES_AT + ARGS_BYTES) as usize];
        let tiles = bytemuck::pod_collect_to_vec::<u8, [u32; 4]>(args).iter().map(|a| a[1]).collect();
        let planes: [u32; 4] = bytemuck::pod_read_unaligned(&bytes[(TILES_AT + ARGS_BYTES) as usize..][..16]);
        let select = bytemuck::pod_read_unaligned(&bytes[SELECT_AT as usize..(SELECT_AT + SELECT_BYTES) as usize]);
        let triangle = |i: u64| {
            let at = (CORE_BYTES + i * TRIANGLE_HEADER_BYTES) as usize;
            bytemuck::pod_read_unaligned(&bytes[at..at + TRIANGLE_HEADER_BYTES as usize])
        };
        let triangle_lists = self.triangle_lists.then(|| [triangle(0), triangle(1)]);
        let effects =
            self.effect_ranges().map(|(e, at, n)| (e, bytes[at as usize..(at + n) as usize].to_vec())).collect();
        FrameCounters {
            select,
            tiles,
            plane_tiles: [planes[0], planes[1], planes[2]],
            instances,
            frame,
            traverse: TraverseCounters {
                nodes: t.node_count,
                overflow: t.overflow,
                missing_roots: t.missing_roots,
                nodes_per_lod: t.lod_counts[..self.lod_count as usize].to_vec(),
            },
            triangles: u64::from(cull.drawn) * self.triangles_per_patch,
            cull,
            effects,
            triangle_lists,
        }
    }
}

/// The first `n` bytes of `buffer` read back (waits), or `n` zeros.
pub(crate) fn head_bytes(ctx: &Context, buffer: Option<&Buffer>, n: usize) -> Result<Vec<u8>> {
    match buffer {
        Some(b) => Ok(ctx.read_buffer(b)?[..n].to_vec()),
        None => Ok(vec![0; n]),
    }
}

/// The buffers a frame's counters are copied from.
pub struct CounterSources<'a> {
    pub traverse: &'a Buffer,
    /// Phase 1's (solid, holes) then phase 2's.
    pub lists: [Option<&'a Buffer>; 4],
    /// The tile lists (their draw arguments).
    pub tiles: Option<&'a Buffer>,
    /// `select_patches`' levels buffer (its counters come first).
    pub select: &'a Buffer,
    /// Each effect's counters, in the layout's order.
    pub effects: Vec<&'a Buffer>,
    /// The per-triangle rule's lists (phase 1's, phase 2's), where built.
    pub triangle_lists: [Option<&'a Buffer>; 2],
}

struct Slot {
    buffer: Buffer,
    /// Renderer frame and context frame (`Context::frame_recording`).
    frame: u64,
    ctx_frame: u64,
    pending: bool,
}

pub struct Telemetry {
    slots: Vec<Slot>,
    next: usize,
    layout: CounterLayout,
    latest: Option<FrameCounters>,
}

impl Telemetry {
    /// A ring of `frames_in_flight + 1` slots.
    pub fn new(ctx: &Context, frames_in_flight: usize, layout: CounterLayout) -> Result<Self> {
        let mut slots = Vec::new();
        for i in 0..frames_in_flight.max(1) + 1 {
            let buffer = Buffer::new(
                ctx,
                &BufferDesc {
                    name: &format!("gpu_counters[{i}]"),
                    size: layout.slot_bytes(),
                    usage: vk::BufferUsageFlags::TRANSFER_DST,
                    location: MemoryLocation::GpuToCpu,
                },
            )?;
            slots.push(Slot { buffer, frame: 0, ctx_frame: 0, pending: false });
        }
        Ok(Telemetry { slots, next: 0, layout, latest: None })
    }

    pub fn layout(&self) -> &CounterLayout {
        &self.layout
    }

    /// Reads every slot whose frame completed (never waits).
    pub fn harvest(&mut self, ctx: &Context) {
        let done = ctx.frames_completed();
        for slot in &mut self.slots {
            if !slot.pending || slot.ctx_frame > done {
                continue;
            }
            slot.pending = false;
            if self.latest.as_ref().is_some_and(|l| l.frame > slot.frame) {
                continue;
            }
            let bytes = slot.buffer.mapped().expect("GpuToCpu buffers are mapped");
            self.latest = Some(self.layout.parse(slot.frame, bytes));
        }
    }

    /// The newest frame's counters that came back.
    pub fn latest(&self) -> Option<&FrameCounters> {
        self.latest.as_ref()
    }

    /// Records the copies of frame `frame` (context frame `ctx_frame`) at
    /// the end of its last command buffer.
    pub fn record(&mut self, rec: &mut Recorder, frame: u64, ctx_frame: u64, src: &CounterSources) {
        let i = self.next;
        self.next = (self.next + 1) % self.slots.len();
        let slot = &mut self.slots[i];
        if slot.pending {
            log::debug!("counters of frame {} were not back in time and are dropped", slot.frame);
        }
        slot.frame = frame;
        slot.ctx_frame = ctx_frame;
        slot.pending = true;
        rec.barrier(vk::PipelineStageFlags2::ALL_COMMANDS, vk::PipelineStageFlags2::ALL_TRANSFER);
        rec.fill_buffer(&slot.buffer, 0);
        rec.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::ALL_TRANSFER);
        rec.copy_buffer_region(src.traverse, 0, &slot.buffer, 0, TRAVERSE_BYTES);
        for (i, list) in src.lists.iter().enumerate() {
            if let Some(list) = list {
                rec.copy_buffer_region(list, 0, &slot.buffer, TRAVERSE_BYTES + i as u64 * HEADER_BYTES, HEADER_BYTES);
            }
        }
        if let Some(tiles) = src.tiles {
            rec.copy_buffer_region(tiles, 0, &slot.buffer, TILES_AT, HEAD_BYTES);
        }
        rec.copy_buffer_region(src.select, 0, &slot.buffer, SELECT_AT, SELECT_BYTES);
        for (i, list) in src.triangle_lists.iter().enumerate() {
            if let Some(list) = list.filter(|_| self.layout.triangle_lists) {
                let at = CORE_BYTES + i as u64 * TRIANGLE_HEADER_BYTES;
                rec.copy_buffer_region(list, 0, &slot.buffer, at, TRIANGLE_HEADER_BYTES);
            }
        }
        for (buffer, (_, at, n)) in src.effects.iter().zip(self.layout.effect_ranges()) {
            rec.copy_buffer_region(buffer, 0, &slot.buffer, at, n);
        }
        rec.transfer_to_host_barrier();
    }

    /// Device memory of the ring.
    pub fn memory(&self) -> (String, u64) {
        ("gpu_counters".to_string(), self.slots.iter().map(|s| s.buffer.memory_bytes()).sum())
    }
}
