//! `vista bench cpu`: the renderer's CPU milliseconds per frame (streaming,
//! the effects' plans, command recording; no GPU wait) on worlds of
//! different sizes seen through the same view and the same slot budget.
//! Per-frame CPU work should follow what is resident or near (slots, the
//! virtual texture's window), not the world's extent, so the rows' ratio is
//! the measure. Every world's renderer is alive at once and measured
//! round-robin, so slow drift of the machine spreads over every row.

use crate::effects::virtual_texture::decals::DecalSet;
use crate::effects::Effects;
use crate::error::Result;
use crate::frame::FrameTimings;
use crate::gpu::Context;
use crate::render::offscreen::Offscreen;
use crate::render::{RendererOptions, TerrainRenderer};
use crate::scene::view::View;
use crate::terrain::TerrainOptions;
use crate::world::{ErrorTree, HeightSource, Hole, WorldDesc};
use serde::Serialize;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

/// One world of the comparison.
pub struct CpuWorld {
    pub label: String,
    pub desc: WorldDesc,
    pub source: Arc<dyn HeightSource>,
    pub holes: Vec<Hole>,
    /// Its error tree (`None`: made under the config's cache folder).
    pub errors: Option<Arc<ErrorTree>>,
}

pub struct CpuBenchConfig {
    /// The same view (world metres) in every world.
    pub view: View,
    /// Resident node slots of every renderer: the bound that "near" means.
    pub slots: u32,
    pub effects: Effects,
    pub decals: DecalSet,
    pub assets: Vec<crate::effects::assets::Asset>,
    pub warmup_frames: u32,
    /// Measured frames per block; `rounds` blocks per world.
    pub frames: u32,
    pub rounds: u32,
    pub settle_timeout: Duration,
    /// Nodes are baked here (one subfolder per world).
    pub cache_dir: PathBuf,
}

#[derive(Debug, Clone, Serialize)]
pub struct CpuBenchRow {
    pub world: String,
    pub extent_m: [f64; 2],
    pub spacing_m: f64,
    pub lod_count: u32,
    /// Root nodes (always resident).
    pub roots: u64,
    /// Resident nodes after settling, of `slots`.
    pub resident: usize,
    pub slots: u32,
    pub settled: bool,
    /// Median CPU milliseconds recording a frame.
    pub cpu_ms: f64,
    /// 90th percentile of the same frames.
    pub cpu_p90_ms: f64,
    /// Median milliseconds reading finished timestamps (the driver's work,
    /// apart: lavapipe drains the device there).
    pub query_ms: f64,
    pub samples: usize,
    /// This row's median over the first row's.
    pub ratio: f64,
}

fn quantile(mut v: Vec<f64>, q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// Settles one renderer per world on the view, then measures them
/// round-robin; one row per world, in the given order.
pub fn bench_cpu(ctx: &Context, worlds: &[CpuWorld], cfg: &CpuBenchConfig) -> Result<Vec<CpuBenchRow>> {
    assert!(!worlds.is_empty() && cfg.frames > 0 && cfg.rounds > 0, "bench_cpu needs worlds and frames");
    let mut off = Offscreen::new(ctx, cfg.view.size, 2, [0.55, 0.68, 0.85, 1.0])?;
    let mut runs = Vec::new();
    for (i, w) in worlds.iter().enumerate() {
        let options = RendererOptions {
            terrain: TerrainOptions {
                slots: cfg.slots,
                cache_dir: Some(cfg.cache_dir.join(format!("world{i}"))),
                errors: w.errors.clone(),
                ..TerrainOptions::default()
            },
            effects: cfg.effects.clone(),
            decals: cfg.decals.clone(),
            assets: cfg.assets.clone(),
            ..RendererOptions::default()
        };
        let mut r = TerrainRenderer::new(ctx, &w.desc, w.source.clone(), w.holes.clone(), &options)?;
        let settle = off.settle(ctx, &mut r, &cfg.view, cfg.settle_timeout)?;
        if !settle.settled {
            log::warn!("{}: streaming did not settle in {:.0} s", w.label, cfg.settle_timeout.as_secs_f64());
        }
        runs.push((r, settle.settled, Vec::<FrameTimings>::new()));
    }
    for _ in 0..cfg.rounds {
        for (r, _, timings) in runs.iter_mut() {
            timings.extend(super::measure(ctx, r, &mut off, &cfg.view, cfg.warmup_frames, cfg.frames)?);
        }
    }
    let mut rows: Vec<CpuBenchRow> = Vec::new();
    for (w, (r, settled, timings)) in worlds.iter().zip(&runs) {
        let cpu: Vec<f64> = timings.iter().map(|t| t.cpu_ms).collect();
        let cpu_ms = quantile(cpu.clone(), 0.5);
        let [gx, gy] = w.desc.grid(w.desc.root_lod());
        rows.push(CpuBenchRow {
            world: w.label.clone(),
            extent_m: w.desc.extent_m,
            spacing_m: w.desc.spacing_m,
            lod_count: w.desc.lod_count,
            roots: u64::from(gx) * u64::from(gy),
            resident: r.terrain.stats().resident,
            slots: r.terrain.slots(),
            settled: *settled,
            cpu_ms,
            cpu_p90_ms: quantile(cpu, 0.9),
            query_ms: quantile(timings.iter().map(|t| t.query_ms).collect(), 0.5),
            samples: timings.len(),
            ratio: cpu_ms / rows.first().map_or(cpu_ms, |f| f.cpu_ms),
        });
    }
    Ok(rows)
}
