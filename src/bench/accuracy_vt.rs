//! The virtual-texture rows of `vista bench accuracy`: what caching the
//! splat blend in pages costs and saves. Per view, direct splat shading
//! (the effect off) is the reference; then one row per cache size x pages
//! per frame with it on: the frames until every page the view asks for is
//! resident, the pages that took, the FLIP of the textured image against
//! direct splat shading over terrain pixels, and the GPU ms of the
//! virtual texture's passes and of the tile shading beside direct splat's.

use super::accuracy::Run;
use crate::effects::{Effect, Effects};
use crate::error::Result;
use crate::frame::profiler::summarize;
use crate::frame::FrameTimings;
use crate::reference::{flip_map, flip_stats};
use crate::render::{RendererOptions, TerrainRenderer};
use crate::scene::view::View;
use serde::Serialize;

/// The grid the virtual-texture rows sweep.
#[derive(Debug, Clone)]
pub struct VtSweep {
    pub cache_mb: Vec<u32>,
    pub pages_per_frame: Vec<u32>,
}

impl Default for VtSweep {
    fn default() -> Self {
        VtSweep { cache_mb: vec![16, 64], pages_per_frame: vec![4, 16] }
    }
}

#[derive(Debug, Clone, Serialize)]
pub struct VtPoint {
    pub view: String,
    /// None: direct splat shading (the reference of the others).
    pub cache_mb: Option<u32>,
    pub pages_per_frame: Option<u32>,
    /// Frames from the renderer's first until it settled (streaming and
    /// pages), and the pages rendered meanwhile.
    pub frames_to_settle: u64,
    pub pages_rendered: u64,
    pub pages_resident: u32,
    pub cache_tiles: u32,
    pub hit_rate: f64,
    /// FLIP of the textured image against direct splat shading's, over the
    /// pixels where either has terrain.
    pub flip_mean: f64,
    pub flip_p99: f64,
    /// Median GPU ms of vt_update + vt_pages + vt_feedback once settled.
    pub vt_ms: f64,
    /// Median GPU ms of every gbuffer_tiles draw.
    pub shade_ms: f64,
    /// The whole frame (sum of pass medians).
    pub frame_ms: f64,
    pub memory_bytes: u64,
    pub settled: bool,
}

fn median_sum(timings: &[FrameTimings], keep: impl Fn(&str) -> bool) -> f64 {
    summarize(timings).into_iter().filter(|p| keep(p.name)).map(|p| p.median_ms).sum()
}

/// The rows of one view; `fx` has splat on.
pub(super) fn vt_rows(
    run: &mut Run,
    options: &dyn Fn(Effects) -> RendererOptions,
    fx: &Effects,
    sweep: &VtSweep,
    view: &View,
    name: &str,
) -> Result<Vec<VtPoint>> {
    let mut settings = vec![None];
    for &cache in &sweep.cache_mb {
        settings.extend(sweep.pages_per_frame.iter().map(|&pages| Some((cache, pages))));
    }
    let mut rows: Vec<VtPoint> = Vec::new();
    let mut direct = Vec::new();
    for setting in settings {
        let mut fx = fx.clone().with(Effect::VirtualTexture, setting.is_some());
        if let Some((cache_mb, pages_per_frame)) = setting {
            fx.virtual_texture.cache_mb = cache_mb;
            fx.virtual_texture.pages_per_frame = pages_per_frame;
        }
        let mut r = TerrainRenderer::new(run.ctx, run.world, run.source.clone(), Vec::new(), &options(fx))?;
        let settled = run.settle(&mut r, view)?;
        let frames_to_settle = r.frames_recorded();
        let (ctx, cfg) = (run.ctx, run.cfg);
        let timings = super::measure(ctx, &mut r, &mut run.off, view, cfg.warmup_frames, cfg.frames)?;
        let clay = r.effects.lighting.clay_albedo.take();
        run.off.run(ctx, &mut r, view, 2)?;
        r.effects.lighting.clay_albedo = clay;
        let capture = run.off.capture(ctx)?;
        let (flip_mean, flip_p99) = if setting.is_none() {
            direct = capture.rgba.clone();
            (0.0, 0.0)
        } else {
            let map = flip_map(&direct, &capture.rgba, view.size);
            let s = flip_stats(map.iter().zip(&capture.depth).filter(|(_, &d)| d > 0.0).map(|(e, _)| *e));
            (f64::from(s.mean), f64::from(s.p99))
        };
        let vt = r.effect::<crate::effects::virtual_texture::VirtualTexture>();
        let c = vt.map(|v| v.counters()).unwrap_or_default();
        rows.push(VtPoint {
            view: name.to_string(),
            cache_mb: setting.map(|s| s.0),
            pages_per_frame: setting.map(|s| s.1),
            frames_to_settle,
            pages_rendered: c.rendered_total,
            pages_resident: c.resident,
            cache_tiles: vt.map_or(0, |v| v.layout().tile_count()),
            hit_rate: c.hit_rate(),
            flip_mean,
            flip_p99,
            vt_ms: median_sum(&timings, |n| n.starts_with("vt_")),
            shade_ms: median_sum(&timings, |n| n.starts_with("gbuffer_tiles")),
            frame_ms: median_sum(&timings, |_| true),
            memory_bytes: vt.map_or(0, |v| v.memory().iter().map(|m| m.1).sum()),
            settled,
        });
    }
    Ok(rows)
}
