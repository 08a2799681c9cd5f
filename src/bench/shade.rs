//! `vista bench shade`: what tile shading saves. Per view (`shade_views`), four renderers alive at once and measured round-robin in
//! one run: tiled, the two one-pipeline references (branching; every
//! flavour everywhere) and tiled with fully blended cliffs. Shading time is
//! `classify_tiles` plus the `gbuffer_tiles` draws for tiled shading, the
//! one draw for a one-pipeline shader (it needs no classification; its
//! `classify_tiles`, which only fills one list, is reported apart).

use crate::effects::Effects;
use crate::error::Result;
use crate::frame::profiler::summarize;
use crate::frame::FrameTimings;
use crate::gpu::Context;
use crate::passes::classify_tiles::ClassifyTiles;
use crate::passes::gbuffer_tiles::variant_label;
use crate::passes::lighting_resolve::LightingResolve;
use crate::reference::image_metric::{flip_map, flip_stats, FlipStats};
use crate::render::offscreen::Offscreen;
use crate::render::{RendererOptions, TerrainRenderer};
use crate::scene::shading::{variant_name, Shading};
use crate::scene::view::View;
use crate::shaders::consts::{FLAVOUR_FAR_CLIFF, FLAVOUR_NEAR_CLIFF};
use crate::terrain::TerrainOptions;
use crate::world::{HeightSource, Hole, WorldDesc};
use serde::Serialize;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use super::shade_views::ShadeView;

pub struct ShadeBenchConfig {
    pub fov_y_deg: f64,
    pub size: [u32; 2],
    pub target_error_px: f32,
    pub warmup_frames: u32,
    /// Measured frames per block; `rounds` blocks per renderer.
    pub frames: u32,
    pub rounds: u32,
    pub settle_timeout: Duration,
    /// Baked nodes are shared by every renderer through this cache.
    pub cache_dir: PathBuf,
    /// The world's error tree, shared by every renderer of the bench (`None`:
    /// made under `cache_dir`).
    pub errors: Option<std::sync::Arc<crate::world::ErrorTree>>,
}

#[derive(Debug, Clone, Serialize)]
pub struct VariantTime {
    pub variant: String,
    pub tiles: u32,
    pub median_ms: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct ShadeRow {
    pub view: String,
    pub shading: Shading,
    pub stochastic_cliffs: bool,
    pub classify_ms: f64,
    /// The `gbuffer_tiles` draws, summed.
    pub draws_ms: f64,
    /// What shading costs: classification plus draws (tiled), draws only
    /// (one pipeline).
    pub shading_ms: f64,
    /// classify_ms / shading_ms (tiled rows).
    pub classify_fraction: Option<f64>,
    /// shading_ms over the two one-pipeline references of the same view.
    pub vs_every_flavour: f64,
    pub vs_branching: f64,
    pub variants: Vec<VariantTime>,
    pub lighting_resolve_ms: f64,
    pub samples: usize,
}

/// The error stochastic cliffs make against fully blended ones (tiled
/// shading, same view, same frame count).
#[derive(Debug, Clone, Serialize)]
pub struct StochasticError {
    pub view: String,
    pub whole_image: FlipStats,
    /// Over the pixels classified as near or far cliff.
    pub cliff_pixels: FlipStats,
}

#[derive(Debug, Clone, Serialize)]
pub struct ShadeBench {
    pub views: Vec<ShadeView>,
    pub rows: Vec<ShadeRow>,
    pub stochastic_error: Vec<StochasticError>,
}

/// The renderers of one view, in row order.
const RUNS: [(Shading, bool); 4] = [
    (Shading::Tiled, true),
    (Shading::OneShader, true),
    (Shading::OneShaderEveryFlavour, true),
    (Shading::Tiled, false),
];

/// `effects`: the scene's, with splat and cliffs on (the caller's choice).
pub fn bench_shade(
    ctx: &Context,
    world: &WorldDesc,
    source: Arc<dyn HeightSource>,
    holes: &[Hole],
    effects: &Effects,
    views: &[ShadeView],
    cfg: &ShadeBenchConfig,
) -> Result<ShadeBench> {
    let terrain = TerrainOptions {
        cache_dir: Some(cfg.cache_dir.clone()),
        errors: cfg.errors.clone(),
        ..TerrainOptions::default()
    };
    let mut off = Offscreen::new(ctx, cfg.size, 2, [0.55, 0.68, 0.85, 1.0])?;
    let mut out = ShadeBench { views: views.to_vec(), rows: Vec::new(), stochastic_error: Vec::new() };
    for sv in views {
        let view = View {
            camera: sv.camera,
            fov_y_deg: cfg.fov_y_deg,
            size: cfg.size,
            target_error_px: cfg.target_error_px,
            near_m: crate::render::DEFAULT_NEAR_M,
        };
        let mut runs = Vec::new();
        for (shading, stochastic) in RUNS {
            let mut fx = effects.clone();
            fx.shade.stochastic = stochastic;
            let options =
                RendererOptions { terrain: terrain.clone(), effects: fx, shading, ..RendererOptions::default() };
            let mut r = TerrainRenderer::new(ctx, world, source.clone(), holes.to_vec(), &options)?;
            let settle = off.settle(ctx, &mut r, &view, cfg.settle_timeout)?;
            if !settle.settled {
                log::warn!("{}: streaming did not settle in {:.0} s", sv.name, cfg.settle_timeout.as_secs_f64());
            }
            runs.push((r, Vec::<FrameTimings>::new()));
        }
        for _ in 0..cfg.rounds {
            for (r, timings) in runs.iter_mut() {
                timings.extend(super::measure(ctx, r, &mut off, &view, cfg.warmup_frames, cfg.frames)?);
            }
        }
        let mut rows = Vec::new();
        for ((shading, stochastic), (r, timings)) in RUNS.iter().zip(&runs) {
            rows.push(row(ctx, &sv.name, *shading, *stochastic, r, timings)?);
        }
        let (every, branching) = (rows[2].shading_ms, rows[1].shading_ms);
        for row in &mut rows {
            row.vs_every_flavour = row.shading_ms / every;
            row.vs_branching = row.shading_ms / branching;
        }
        out.rows.extend(rows);
        out.stochastic_error.push(stochastic_error(ctx, &sv.name, &mut off, &view, &mut runs)?);
    }
    Ok(out)
}

fn row(
    ctx: &Context,
    view: &str,
    shading: Shading,
    stochastic: bool,
    r: &TerrainRenderer,
    timings: &[FrameTimings],
) -> Result<ShadeRow> {
    let s = summarize(timings);
    let ms = |name: &str| s.iter().filter(|p| p.name == name).map(|p| p.median_ms).sum::<f64>();
    let tiles = r.read_counters(ctx)?.tiles;
    let variants: Vec<VariantTime> = r
        .gbuffer_tiles
        .variants()
        .into_iter()
        .map(|bits| VariantTime {
            variant: variant_name(bits),
            tiles: tiles.get(bits as usize).copied().unwrap_or(0),
            median_ms: ms(variant_label(bits)),
        })
        .collect();
    let classify_ms = ms(ClassifyTiles::NAME);
    let draws_ms: f64 = variants.iter().map(|v| v.median_ms).sum();
    let tiled = shading == Shading::Tiled;
    let shading_ms = if tiled { classify_ms + draws_ms } else { draws_ms };
    Ok(ShadeRow {
        view: view.to_string(),
        shading,
        stochastic_cliffs: stochastic,
        classify_ms,
        draws_ms,
        shading_ms,
        classify_fraction: tiled.then(|| classify_ms / shading_ms),
        vs_every_flavour: f64::NAN,
        vs_branching: f64::NAN,
        variants,
        lighting_resolve_ms: ms(LightingResolve::NAME),
        samples: timings.len(),
    })
}

/// FLIP of the stochastic tiled image against the blended one.
fn stochastic_error(
    ctx: &Context,
    view_name: &str,
    off: &mut Offscreen,
    view: &View,
    runs: &mut [(TerrainRenderer, Vec<FrameTimings>)],
) -> Result<StochasticError> {
    let mut image = |r: &mut TerrainRenderer| -> Result<Vec<u8>> {
        off.run(ctx, r, view, 1)?;
        Ok(off.capture(ctx)?.rgba)
    };
    let stochastic = image(&mut runs[0].0)?;
    let blended = image(&mut runs[3].0)?;
    let classes = runs[3].0.gbuffer.as_ref().expect("a frame was rendered").capture(ctx)?.classification;
    let errors = flip_map(&blended, &stochastic, view.size);
    let cliff = (FLAVOUR_NEAR_CLIFF | FLAVOUR_FAR_CLIFF) as u8;
    Ok(StochasticError {
        view: view_name.to_string(),
        whole_image: flip_stats(errors.iter().copied()),
        cliff_pixels: flip_stats(errors.iter().zip(&classes).filter(|(_, &c)| c & cliff != 0).map(|(e, _)| *e)),
    })
}
