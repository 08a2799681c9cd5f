//! The frame executor: wraps every pass in a debug-utils label and a pair of
//! timestamps, and hands timings back as data once the GPU has finished the
//! frame (one frame late or more; never by waiting).

pub mod profiler;

use crate::error::Result;
use crate::gpu::{Context, Recorder, TimestampPool};
use serde::Serialize;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum QueueKind {
    Graphics,
    /// Async compute when the device has a compute-only family; otherwise
    /// recorded on the graphics queue and still reported as compute work.
    Compute,
}

#[derive(Debug, Clone, Serialize)]
pub struct PassTiming {
    pub name: &'static str,
    pub queue: QueueKind,
    /// Start relative to the frame's first pass.
    pub start_ms: f64,
    pub gpu_ms: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct FrameTimings {
    /// Counts frames begun on this executor, from 1.
    pub frame: u64,
    /// Absolute GPU time of the first pass, in nanoseconds.
    pub start_ns: f64,
    pub passes: Vec<PassTiming>,
}

struct Slot {
    pool: Option<TimestampPool>,
    passes: Vec<(&'static str, QueueKind)>,
    frame: u64,
    pending: bool,
}

pub struct FrameExecutor {
    slots: Vec<Slot>,
    next: usize,
    frame: u64,
    max_passes: u32,
    period_ns: f64,
    latest: Option<FrameTimings>,
}

impl FrameExecutor {
    /// `frames_in_flight` must be at least the caller's; `max_passes` bounds
    /// the passes of one frame.
    pub fn new(ctx: &Context, frames_in_flight: usize, max_passes: u32) -> Result<Self> {
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
            slots.push(Slot { pool, passes: Vec::new(), frame: 0, pending: false });
        }
        Ok(FrameExecutor {
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
                .map(|(i, (name, queue))| PassTiming {
                    name,
                    queue: *queue,
                    start_ms: (ns(ticks[2 * i]) - t0) / 1e6,
                    gpu_ms: (ns(ticks[2 * i + 1]) - ns(ticks[2 * i])) / 1e6,
                })
                .collect();
            self.latest = Some(FrameTimings { frame: slot.frame, start_ns: t0, passes });
        }
    }

    /// Starts recording a frame into `rec`; collects any finished timings first.
    pub fn begin<'e, 'r>(&'e mut self, rec: &'e mut Recorder<'r>) -> Frame<'e, 'r> {
        self.harvest();
        self.frame += 1;
        let slot_index = self.next;
        self.next = (self.next + 1) % self.slots.len();
        let slot = &mut self.slots[slot_index];
        if slot.pending {
            log::debug!("timings of frame {} were not back in time and are dropped", slot.frame);
        }
        slot.passes.clear();
        slot.frame = self.frame;
        slot.pending = false;
        if let Some(pool) = &slot.pool {
            rec.reset_queries(pool, 0, pool.capacity);
        }
        Frame { exec: self, rec, slot: slot_index }
    }
}

/// One frame being recorded; `pass` wraps each pass.
pub struct Frame<'e, 'r> {
    exec: &'e mut FrameExecutor,
    rec: &'e mut Recorder<'r>,
    slot: usize,
}

impl<'r> Frame<'_, 'r> {
    /// This frame's number (counts from 1; `FrameTimings::frame`).
    pub fn number(&self) -> u64 {
        self.exec.slots[self.slot].frame
    }

    /// Records one pass between a timestamp pair inside a debug label. The
    /// name is the pass's file, shader and timer label.
    pub fn pass<T>(&mut self, name: &'static str, queue: QueueKind, f: impl FnOnce(&mut Recorder<'r>) -> T) -> T {
        let slot = &mut self.exec.slots[self.slot];
        let i = slot.passes.len() as u32;
        assert!(i < self.exec.max_passes, "more than {} passes in one frame", self.exec.max_passes);
        slot.passes.push((name, queue));
        self.rec.begin_label(name);
        if let Some(pool) = &slot.pool {
            self.rec.write_timestamp(pool, 2 * i);
        }
        let out = f(self.rec);
        let slot = &self.exec.slots[self.slot];
        if let Some(pool) = &slot.pool {
            self.rec.write_timestamp(pool, 2 * i + 1);
        }
        self.rec.end_label();
        out
    }
}

impl Drop for Frame<'_, '_> {
    fn drop(&mut self) {
        self.exec.slots[self.slot].pending = true;
    }
}
