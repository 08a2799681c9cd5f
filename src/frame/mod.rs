//! The frame executor: wraps every pass in a debug-utils label and a pair of
//! timestamps, and hands timings back as data once the GPU has finished the
//! frame (one frame late or more; never by waiting).

pub mod per_frame;
pub mod profiler;

use crate::error::Result;
use crate::gpu::{Context, FrameCommands, QueueMode, Recorder, StatisticsPool, TimestampPool};
use serde::Serialize;

/// A queue kind: where a pass belongs when compute is split off
/// ([`FramePass::queue`](crate::scene::graph::FramePass::queue)), or where
/// it actually ran ([`PassTiming::queue`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum QueueKind {
    Graphics,
    /// The queue of a compute-only family (async compute).
    Compute,
}

#[derive(Debug, Clone, Serialize)]
pub struct PassTiming {
    pub name: &'static str,
    /// Phase 2 of occlusion culling (a second run of a drawing pass).
    pub late: bool,
    /// The queue it ran on.
    pub queue: QueueKind,
    /// Start relative to the frame's first pass.
    pub start_ms: f64,
    pub gpu_ms: f64,
    /// The pass's pipeline statistics, where the executor counts them
    /// (asked for, the device enabled them, a graphics queue).
    pub counters: Option<PassCounters>,
}

/// One pass's pipeline statistics (Vulkan's counters of the same names;
/// on lavapipe a fragment invocation is counted per pixel shaded).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct PassCounters {
    /// Primitives the input assembler read (triangles of a triangle list).
    pub input_primitives: u64,
    pub vertex_invocations: u64,
    /// Primitives that came out of clipping (culled ones not counted).
    pub clipped_primitives: u64,
    pub fragment_invocations: u64,
    pub compute_invocations: u64,
}

impl PassCounters {
    fn from_raw(c: [u64; 5]) -> Self {
        let [input_primitives, vertex_invocations, clipped_primitives, fragment_invocations, compute_invocations] = c;
        PassCounters {
            input_primitives,
            vertex_invocations,
            clipped_primitives,
            fragment_invocations,
            compute_invocations,
        }
    }
}

#[derive(Debug, Clone, Serialize)]
pub struct FrameTimings {
    /// Counts frames begun on this executor, from 1.
    pub frame: u64,
    /// Absolute GPU time of the first pass, in nanoseconds.
    pub start_ns: f64,
    /// How the frame was submitted.
    pub mode: QueueMode,
    /// Passes with timestamps; a pass on a queue without timestamp support
    /// is missing.
    pub passes: Vec<PassTiming>,
    /// CPU milliseconds the renderer spent recording the frame: streaming,
    /// the quadtree's and effects' plans, command recording (not the
    /// submission, never a wait for the GPU; the read of earlier frames'
    /// timestamps is `query_ms`). 0 when not set.
    pub cpu_ms: f64,
    /// CPU milliseconds the executor's read of finished frames' timestamps
    /// took while recording this frame (a driver may wait there: lavapipe
    /// drains the device).
    pub query_ms: f64,
}

/// Timer label of a pass: its name, marked in phase 2.
pub fn pass_label(name: &str, late: bool) -> String {
    if late {
        format!("{name} (phase 2)")
    } else {
        name.to_string()
    }
}

struct Slot {
    pool: Option<TimestampPool>,
    /// Per-pass statistics, one query a pass (its timestamp pair's index).
    stats: Option<StatisticsPool>,
    /// Whether each pass in `passes` began a statistics query.
    counted: Vec<bool>,
    /// (name, late, queue) of each pass with a timestamp pair, in query order.
    passes: Vec<(&'static str, bool, QueueKind)>,
    mode: QueueMode,
    frame: u64,
    pending: bool,
    cpu_ms: [f64; 2],
}

pub struct FrameExecutor {
    /// The compute family's queue can write timestamps.
    compute_timestamps: bool,
    slots: Vec<Slot>,
    next: usize,
    frame: u64,
    max_passes: u32,
    period_ns: f64,
    latest: Option<FrameTimings>,
}

impl FrameExecutor {
    /// `frames_in_flight` must be at least the caller's; `max_passes` bounds
    /// the passes of one frame; `counters`: count each graphics-queue
    /// pass's pipeline statistics where the device enabled them.
    pub fn new(ctx: &Context, frames_in_flight: usize, max_passes: u32, counters: bool) -> Result<Self> {
        let limits = &ctx.info().limits;
        if !limits.timestamps_supported {
            log::info!("{}: no timestamp support on the graphics queue; running without pass timings", ctx.info().name);
        }
        let mut slots = Vec::new();
        for i in 0..frames_in_flight.max(1) + 1 {
            let pool = if limits.timestamps_supported {
                Some(TimestampPool::new(ctx, &format!("pass_timestamps[{i}]"), max_passes * 2)?)
            } else {
                None
            };
            let stats = match counters && limits.pipeline_statistics && pool.is_some() {
                true => Some(StatisticsPool::new(ctx, &format!("pass_statistics[{i}]"), max_passes)?),
                false => None,
            };
            slots.push(Slot {
                pool,
                stats,
                counted: Vec::new(),
                passes: Vec::new(),
                mode: QueueMode::Single,
                frame: 0,
                pending: false,
                cpu_ms: [0.0; 2],
            });
        }
        let compute_timestamps =
            ctx.info().queue_families.iter().any(|f| {
                f.index == ctx.info().compute_family && f.timestamp_valid_bits > 0 && limits.timestamps_supported
            });
        Ok(FrameExecutor {
            compute_timestamps,
            slots,
            next: 0,
            frame: 0,
            max_passes,
            period_ns: limits.timestamp_period_ns as f64,
            latest: None,
        })
    }

    /// The newest frame whose timings are back, if any.
    pub fn latest(&self) -> Option<&FrameTimings> {
        self.latest.as_ref()
    }

    /// Collects the timings of frames that finished (never waits).
    pub fn poll(&mut self) {
        self.harvest();
    }

    fn harvest(&mut self) {
        for slot in &mut self.slots {
            let Some(pool) = slot.pool.as_ref().filter(|_| slot.pending) else {
                continue;
            };
            let Some(ticks) = pool.try_read(slot.passes.len() as u32 * 2) else {
                continue;
            };
            let counts = slot.stats.as_ref().map(|s| s.try_read(slot.passes.len() as u32));
            if counts.as_ref().is_some_and(|c| c.iter().zip(&slot.counted).any(|(c, asked)| *asked && c.is_none())) {
                continue;
            }
            slot.pending = false;
            if self.latest.as_ref().is_some_and(|l| l.frame > slot.frame) || ticks.is_empty() {
                continue;
            }
            let ns = |t: u64| t as f64 * self.period_ns;
            let t0 = ns(ticks[0]);
            let passes = slot
                .passes
                .iter()
                .enumerate()
                .map(|(i, (name, late, queue))| PassTiming {
                    name,
                    late: *late,
                    queue: *queue,
                    start_ms: (ns(ticks[2 * i]) - t0) / 1e6,
                    gpu_ms: (ns(ticks[2 * i + 1]) - ns(ticks[2 * i])) / 1e6,
                    counters: counts
                        .as_ref()
                        .and_then(|c| c[i].filter(|_| slot.counted[i]))
                        .map(PassCounters::from_raw),
                })
                .collect();
            let (frame, mode, [cpu_ms, query_ms]) = (slot.frame, slot.mode, slot.cpu_ms);
            self.latest = Some(FrameTimings { frame, start_ns: t0, mode, passes, cpu_ms, query_ms });
        }
    }

    /// Frame `frame`'s CPU recording time and its timestamp read's,
    /// reported with its timings.
    pub fn set_cpu_ms(&mut self, frame: u64, cpu_ms: f64, query_ms: f64) {
        if let Some(slot) = self.slots.iter_mut().find(|s| s.frame == frame) {
            slot.cpu_ms = [cpu_ms, query_ms];
        }
    }

    /// The number the next `begin` gives its frame.
    pub fn next_frame(&self) -> u64 {
        self.frame + 1
    }

    /// Starts recording a frame into `cmds` (`mode` says how they are
    /// submitted); collects any finished timings first.
    pub fn begin<'e, 'r>(&'e mut self, mut cmds: FrameCommands<'e, 'r>, mode: QueueMode) -> Frame<'e, 'r> {
        assert_eq!(mode.is_split(), matches!(cmds, FrameCommands::Split { .. }), "{mode:?} with the wrong buffers");
        self.harvest();
        self.frame += 1;
        let slot_index = self.next;
        self.next = (self.next + 1) % self.slots.len();
        let slot = &mut self.slots[slot_index];
        if slot.pending {
            log::debug!("timings of frame {} were not back in time and are dropped", slot.frame);
        }
        slot.passes.clear();
        slot.counted.clear();
        slot.cpu_ms = [0.0; 2];
        slot.frame = self.frame;
        slot.mode = mode;
        slot.pending = false;
        if let Some(pool) = &slot.pool {
            // In the buffer submitted first: the other one runs after it.
            let first = match &mut cmds {
                FrameCommands::One(r) => &mut **r,
                FrameCommands::Split { compute, .. } => &mut **compute,
            };
            first.reset_queries(pool, 0, pool.capacity);
            if let Some(stats) = &slot.stats {
                first.reset_statistics(stats);
            }
        }
        Frame { exec: self, cmds, mode, slot: slot_index }
    }
}

/// One frame being recorded; `pass` wraps each pass.
pub struct Frame<'e, 'r> {
    exec: &'e mut FrameExecutor,
    cmds: FrameCommands<'e, 'r>,
    mode: QueueMode,
    slot: usize,
}

impl<'r> Frame<'_, 'r> {
    /// This frame's number (counts from 1; `FrameTimings::frame`).
    pub fn number(&self) -> u64 {
        self.exec.slots[self.slot].frame
    }

    /// Records one pass between a timestamp pair inside a debug label, into
    /// the command buffer of `queue` (the one buffer when not split). The
    /// name is the pass's file, shader and timer label; `late` marks phase 2.
    pub fn pass<T>(
        &mut self,
        name: &'static str,
        late: bool,
        queue: QueueKind,
        f: impl FnOnce(&mut Recorder<'r>) -> T,
    ) -> T {
        let (rec, ran_on) = match (&mut self.cmds, queue) {
            (FrameCommands::One(r), _) => (&mut **r, QueueKind::Graphics),
            (FrameCommands::Split { compute, .. }, QueueKind::Compute) => {
                let on = if self.mode == QueueMode::AsyncCompute { QueueKind::Compute } else { QueueKind::Graphics };
                (&mut **compute, on)
            }
            (FrameCommands::Split { graphics, .. }, QueueKind::Graphics) => (&mut **graphics, QueueKind::Graphics),
        };
        let timed = ran_on == QueueKind::Graphics || self.exec.compute_timestamps;
        let slot = &mut self.exec.slots[self.slot];
        let i = slot.passes.len() as u32;
        assert!(i < self.exec.max_passes, "more than {} passes in one frame", self.exec.max_passes);
        let pool = slot.pool.as_ref().filter(|_| timed);
        // Graphics counters are legal on a graphics queue only.
        let stats = slot.stats.as_ref().filter(|_| pool.is_some() && ran_on == QueueKind::Graphics);
        if pool.is_some() {
            slot.passes.push((name, late, ran_on));
            slot.counted.push(stats.is_some());
        }
        rec.begin_label(&pass_label(name, late));
        if let Some(pool) = pool {
            rec.write_timestamp(pool, 2 * i);
        }
        if let Some(stats) = stats {
            rec.begin_statistics(stats, i);
        }
        let out = f(rec);
        let unpublished = rec.host_unpublished();
        assert!(
            unpublished.is_empty(),
            "pass {name} wrote {unpublished:?}, which the host reads, with no barrier to the host"
        );
        if let Some(stats) = stats {
            rec.end_statistics(stats, i);
        }
        if let Some(pool) = pool {
            rec.write_timestamp(pool, 2 * i + 1);
        }
        rec.end_label();
        out
    }
}

impl<'r> Frame<'_, 'r> {
    /// Records work that is no pass (e.g. the telemetry copies) into the
    /// command buffer of `queue`, without timestamps.
    pub fn untimed<T>(&mut self, queue: QueueKind, f: impl FnOnce(&mut Recorder<'r>) -> T) -> T {
        match (&mut self.cmds, queue) {
            (FrameCommands::One(r), _) => f(r),
            (FrameCommands::Split { compute, .. }, QueueKind::Compute) => f(compute),
            (FrameCommands::Split { graphics, .. }, QueueKind::Graphics) => f(graphics),
        }
    }
}

impl Drop for Frame<'_, '_> {
    fn drop(&mut self) {
        self.exec.slots[self.slot].pending = true;
    }
}
