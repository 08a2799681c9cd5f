//! Case 10: soak. A streaming fly-through back and forth over the small
//! world with few resident slots (nodes are evicted and streamed in all the
//! time), every effect a renderer builds on (`rig::every_effect`), the sun
//! turning a degree a frame and the decal turned every 100 frames, for 10 000 frames (the full form; 2 400 in the quick form), with
//! validation messages, live Vulkan objects, the allocator's bytes and the
//! process's resident memory sampled every `every` frames. Not part of the
//! test suite: `vista stability --cases 10 --full`.
//!
//! Growth is measured from the end of warm-up: the first sample after one
//! whole round trip (`2 x LEG` frames), when every node of the flight has
//! been streamed in, evicted and streamed again, and every pipeline and
//! allocator pool the flight uses exists. Before that the process grows by
//! design (loader threads' malloc arenas, the driver's shader compiles, the
//! first uploads): a sample taken at frame 100, before the stream had moved
//! at all, made a machine that compiled more then look like a leak.

use super::rig::{fly_through, Rig};
use super::{CaseReport, Form};
use crate::error::Result;
use crate::gpu::Context;
use serde::Serialize;

/// Process memory may move by allocator noise after warm-up, not grow.
const RSS_SLACK_MIB: f64 = 16.0;
/// The fly-through's one-way length in frames.
const LEG: u32 = 400;
/// Resident node slots: few, so nodes stream in and out all the time.
const SLOTS: u32 = 24;

#[derive(Debug, Clone, Serialize)]
pub struct SoakSample {
    pub frame: u32,
    pub validation_messages: usize,
    pub live_objects: i64,
    pub allocated_bytes: u64,
    pub reserved_bytes: u64,
    pub rss_mib: f64,
    pub nodes_streamed: usize,
}

fn rss_mib() -> f64 {
    let statm = std::fs::read_to_string("/proc/self/statm").unwrap_or_default();
    let pages: f64 = statm.split_whitespace().nth(1).and_then(|v| v.parse().ok()).unwrap_or(0.0);
    pages * 4096.0 / (1 << 20) as f64
}

pub fn run(ctx: &Context, form: Form, every: u32, mut on_sample: impl FnMut(&SoakSample)) -> Result<CaseReport> {
    let frames = form.pick(3 * 2 * LEG, 10_000);
    let mut r = CaseReport::new(10, "soak");
    r.measured = format!(
        "growth after warm-up (the first sample after one round trip, {} frames) over {frames} streaming frames: live \
         objects, allocator bytes, resident memory; validation messages",
        2 * LEG
    );
    r.bound = format!("0 objects, 0 bytes, < {RSS_SLACK_MIB} MiB; 0 messages");
    r.why = "a renderer that runs for hours must hold steady: every per-frame or per-node resource is reused or freed once its frame's fence has passed".into();
    let mut rig = Rig::new(ctx, [96, 64], SLOTS, super::rig::every_effect(), Vec::new())?;
    let log = ctx.validation_log();
    let mut samples: Vec<SoakSample> = Vec::new();
    for f in 0..frames {
        // Back and forth along the fly-through.
        let leg = f % (2 * LEG);
        let at = if leg < LEG { leg } else { 2 * LEG - 1 - leg };
        // A decal edit every 100 frames: the virtual texture re-renders
        // the pages under it, and nothing may pile up from it.
        if f % 100 == 99 {
            rig.renderer.set_decals(ctx, vec![super::rig::script_decal(f64::from(f / 100 % 8) * 45.0)])?;
        }
        // The sun turns a degree a frame: the shadows are made again as it
        // moves, and nothing may pile up from that either.
        rig.renderer.effects.lighting.sun_azimuth_deg = 200.0 + f64::from(f % 360);
        let view = rig.view(fly_through(&rig, at, LEG));
        rig.off.frame(ctx, &mut rig.renderer, &view)?;
        if (f + 1) % every == 0 || f + 1 == frames {
            rig.off.capture(ctx)?;
            let (allocated_bytes, reserved_bytes) = ctx.allocator_bytes();
            let s = SoakSample {
                frame: f + 1,
                validation_messages: log.messages().len(),
                live_objects: ctx.live_objects().total(),
                allocated_bytes,
                reserved_bytes,
                rss_mib: rss_mib(),
                nodes_streamed: rig.renderer.terrain.stats().arrived_total,
            };
            on_sample(&s);
            samples.push(s);
        }
    }
    let warm = samples.iter().position(|s| s.frame >= 2 * LEG).unwrap_or(0);
    let first = samples[warm].clone();
    let after = &samples[warm..];
    let last = samples.last().expect("at least one sample");
    let objects = after.iter().map(|s| s.live_objects - first.live_objects).max().unwrap_or(0);
    let bytes = after.iter().map(|s| s.allocated_bytes.saturating_sub(first.allocated_bytes)).max().unwrap_or(0);
    let rss = after.iter().map(|s| s.rss_mib - first.rss_mib).fold(0.0, f64::max);
    for (i, s) in samples.iter().enumerate() {
        let warming = if i < warm { " (warm-up)" } else { "" };
        r.details.push(format!(
            "frame {:>6}{warming}: {} messages, {} live objects, {:.1} MiB allocated ({:.1} reserved), {:.1} MiB resident, {} nodes streamed",
            s.frame,
            s.validation_messages,
            s.live_objects,
            s.allocated_bytes as f64 / (1 << 20) as f64,
            s.reserved_bytes as f64 / (1 << 20) as f64,
            s.rss_mib,
            s.nodes_streamed
        ));
    }
    // What the budgets allow the renderer to hold on the CPU: its resident
    // nodes' payloads; the rest of the process (driver, validation layer,
    // code) is fixed once warm.
    let budget = crate::world::MemoryReport::for_format(SLOTS as usize, crate::world::PayloadFormat::default());
    r.details.push(format!(
        "warm-up: {} samples; after it resident memory is bounded by the {SLOTS} node slots' payloads ({:.1} MiB CPU) on \
         top of the warm process ({:.1} MiB at frame {})",
        warm,
        budget.cpu_total() as f64 / (1 << 20) as f64,
        first.rss_mib,
        first.frame
    ));
    r.worst = format!("{objects} objects, {bytes} bytes, {rss:.1} MiB; {} messages", last.validation_messages);
    r.pass = objects == 0 && bytes == 0 && rss < RSS_SLACK_MIB && last.validation_messages == 0;
    Ok(r)
}
