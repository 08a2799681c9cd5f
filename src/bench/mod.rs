//! Benchmarks behind `vista bench`, one file per kind: GPU times from the
//! frame executor's timestamps, medians over frames after warm-up, variants
//! timed in the same run so their ratios are measured under the same
//! conditions.

pub mod accuracy;
pub mod accuracy_error;
pub mod accuracy_floor;
pub mod accuracy_popping;
pub mod accuracy_rule;
pub mod accuracy_shadows;
pub mod accuracy_vt;
pub mod cpu;
pub mod cull;
pub mod effects;
pub mod shade;
pub mod shade_views;
pub mod traverse;

pub use accuracy::{bench_accuracy, AccuracyBench, AccuracyBenchConfig, AccuracyPoint};
pub use accuracy_error::{accuracy_error, AccuracyError};
pub use cpu::{bench_cpu, CpuBenchConfig, CpuBenchRow, CpuWorld};
pub use cull::{bench_cull, cull_views, CullBenchConfig, CullBenchRow};
pub use effects::{bench_effects, EffectsBenchConfig, EffectsBenchRow};
pub use shade::{bench_shade, ShadeBench, ShadeBenchConfig, ShadeRow};
pub use shade_views::{shade_views, ShadeView};
pub use traverse::{bench_traverse, TraverseBenchConfig, TraverseBenchRow};

use crate::error::Result;
use crate::frame::FrameTimings;
use crate::gpu::Context;
use crate::render::offscreen::Offscreen;
use crate::render::TerrainRenderer;
use crate::scene::view::View;

/// Warm-up then `frames` measured frames of one renderer; the timings of
/// the measured frames only (they come back late: collected after a wait).
pub(crate) fn measure(
    ctx: &Context,
    r: &mut TerrainRenderer,
    off: &mut Offscreen,
    view: &View,
    warmup: u32,
    frames: u32,
) -> Result<Vec<FrameTimings>> {
    off.run(ctx, r, view, warmup)?;
    let first = r.frames_recorded() + 1;
    let mut out: Vec<FrameTimings> = off.run(ctx, r, view, frames)?;
    off.capture(ctx)?;
    out.extend(r.poll_timings(ctx).cloned());
    out.retain(|t| t.frame >= first);
    out.dedup_by_key(|t| t.frame);
    Ok(out)
}
