//! Benchmarks behind `vista bench`, one file per kind: GPU times from the
//! frame executor's timestamps, medians over frames after warm-up, variants
//! timed in the same run so their ratios are measured under the same
//! conditions.

pub mod cull;
pub mod effects;
pub mod traverse;

pub use cull::{bench_cull, cull_views, CullBenchConfig, CullBenchRow};
pub use effects::{bench_effects, EffectsBenchConfig, EffectsBenchRow};
pub use traverse::{bench_traverse, TraverseBenchConfig, TraverseBenchRow};
