//! `vista bench effects`: what each effect costs. One renderer per variant
//! (the minimal scene, the full scene, the full scene with each effect that
//! is on turned off in turn), all alive at once and measured round-robin in
//! one run, so slow drift of the machine spreads over every variant. Per
//! variant: the GPU frame time (sum of per-pass medians after warm-up) and
//! the GPU memory the renderer owns.

use crate::effects::{Effect, Effects};
use crate::error::Result;
use crate::frame::profiler::summarize;
use crate::frame::FrameTimings;
use crate::gpu::Context;
use crate::render::offscreen::Offscreen;
use crate::render::report::frame_report;
use crate::render::{RendererOptions, TerrainRenderer};
use crate::scene::view::View;
use crate::terrain::TerrainOptions;
use crate::world::{HeightSource, Hole, WorldDesc};
use serde::Serialize;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

pub struct EffectsBenchConfig {
    pub view: View,
    pub warmup_frames: u32,
    /// Measured frames per block; `rounds` blocks per variant.
    pub frames: u32,
    pub rounds: u32,
    pub settle_timeout: Duration,
    /// Baked nodes are shared by every variant through this cache.
    pub cache_dir: PathBuf,
    /// The world's error tree, shared by every renderer of the bench (`None`:
    /// made under `cache_dir`).
    pub errors: Option<std::sync::Arc<crate::world::ErrorTree>>,
    /// The scene's decals (effect `decals`).
    pub decals: crate::effects::virtual_texture::decals::DecalSet,
    /// The scene's assets (effect `assets`).
    pub assets: Vec<crate::effects::assets::Asset>,
}

#[derive(Debug, Clone, Serialize)]
pub struct PassMedian {
    /// The pass label (marked in phase 2 of occlusion culling).
    pub name: String,
    pub median_ms: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct EffectsBenchRow {
    /// "minimal", "full" or "full - EFFECT".
    pub variant: String,
    /// The effect turned off, for the "full - EFFECT" rows.
    pub without: Option<Effect>,
    /// Effects on in this variant.
    pub effects_on: Vec<Effect>,
    pub pipelines: usize,
    pub frame_ms: f64,
    pub passes: Vec<PassMedian>,
    pub gpu_memory_bytes: u64,
    /// Triangles submitted in the last frame (both terrain draws): resident
    /// sets can differ between variants when the slot budget is tight.
    pub triangles: u64,
    /// Frames measured (medians are over these).
    pub samples: usize,
    /// Full frame time minus this one: what the missing effect costs.
    pub cost_ms: f64,
    pub cost_bytes: i64,
}

/// The variants: minimal, full, and full without each effect it built.
fn variants(full: &Effects, built: &[Effect]) -> Vec<(String, Option<Effect>, Effects)> {
    let mut v = vec![("minimal".to_string(), None, Effects::minimal()), ("full".to_string(), None, full.clone())];
    for e in built {
        v.push((format!("full - {}", e.name()), Some(*e), full.clone().with(*e, false)));
    }
    v
}

/// Runs the benchmark; `full` is the full scene's effects (those not
/// implemented are off in every variant and cost nothing).
pub fn bench_effects(
    ctx: &Context,
    world: &WorldDesc,
    source: Arc<dyn HeightSource>,
    holes: &[Hole],
    full: &Effects,
    cfg: &EffectsBenchConfig,
) -> Result<Vec<EffectsBenchRow>> {
    let terrain = TerrainOptions {
        cache_dir: Some(cfg.cache_dir.clone()),
        errors: cfg.errors.clone(),
        ..TerrainOptions::default()
    };
    let make = |fx: &Effects| {
        let options = RendererOptions {
            terrain: terrain.clone(),
            effects: fx.clone(),
            decals: cfg.decals.clone(),
            assets: cfg.assets.clone(),
            ..RendererOptions::default()
        };
        TerrainRenderer::new(ctx, world, source.clone(), holes.to_vec(), &options)
    };
    let probe = make(full)?;
    let built: Vec<Effect> = probe.effects().iter().filter(|d| d.on).map(|d| d.effect).collect();
    drop(probe);
    let mut off = Offscreen::new(ctx, cfg.view.size, 2, [0.55, 0.68, 0.85, 1.0])?;
    let mut runs = Vec::new();
    for (name, without, fx) in variants(full, &built) {
        let mut r = make(&fx)?;
        let settle = off.settle(ctx, &mut r, &cfg.view, cfg.settle_timeout)?;
        if !settle.settled {
            log::warn!("{name}: streaming did not settle in {:.0} s", cfg.settle_timeout.as_secs_f64());
        }
        runs.push((name, without, r, Vec::<FrameTimings>::new()));
    }
    for _ in 0..cfg.rounds {
        for (_, _, r, timings) in runs.iter_mut() {
            timings.extend(super::measure(ctx, r, &mut off, &cfg.view, cfg.warmup_frames, cfg.frames)?);
        }
    }
    let mut rows = Vec::new();
    for (variant, without, r, timings) in &runs {
        let report = frame_report(ctx, r, None)?;
        let passes: Vec<PassMedian> = summarize(timings)
            .iter()
            .map(|s| PassMedian { name: crate::frame::pass_label(s.name, s.late), median_ms: s.median_ms })
            .collect();
        rows.push(EffectsBenchRow {
            variant: variant.clone(),
            without: *without,
            effects_on: r.effects().iter().filter(|d| d.on).map(|d| d.effect).collect(),
            pipelines: report.pipelines.len(),
            frame_ms: passes.iter().map(|p| p.median_ms).sum(),
            passes,
            gpu_memory_bytes: report.total_memory(),
            triangles: report.passes.iter().filter_map(|p| p.work.triangles).sum(),
            samples: timings.len(),
            cost_ms: 0.0,
            cost_bytes: 0,
        });
    }
    let (full_ms, full_bytes) = (rows[1].frame_ms, rows[1].gpu_memory_bytes as i64);
    for row in &mut rows {
        row.cost_ms = full_ms - row.frame_ms;
        row.cost_bytes = full_bytes - row.gpu_memory_bytes as i64;
    }
    Ok(rows)
}
