//! The shadow rows of `vista bench accuracy`: what shadow accuracy costs in
//! time. Against a reference whose every lit hit casts an exact shadow ray,
//! one row with the `shadows` effect off, then one per shadow resolution x
//! march steps: the share of pixels whose lit/shadowed state differs from
//! the reference, the lit FLIP, and the GPU time of the shadow pass per
//! node re-marched and for all resident nodes (what a moving sun costs; a
//! static sun costs nothing once settled), beside `lighting_resolve`'s.
//!
//! The frame's state of a pixel comes from its lit radiance: with the clay
//! albedo a, the G-buffer normal n and the sun and sky of the scene, the
//! HDR value is a (sun * max(n.l, 0) * v + sky * (1 + n.z) / 2), so the
//! sun share v follows (summed over RGB). Pixels where either normal faces
//! the sun by less than `MIN_FACING` are left out: there v is ill-posed and
//! the sun term is dark either way.

use super::accuracy::{Run, CLAY_ALBEDO};
use super::accuracy_error::terrain_flip_mean;
use crate::effects::shadows::sun_shadows::{ShadowParams, MAX_UPDATE_BUDGET};
use crate::effects::{Effect, Effects};
use crate::error::Result;
use crate::frame::profiler::summarize;
use crate::reference::octahedral::oct_decode_unorm8;
use crate::reference::ReferenceImage;
use crate::render::{RendererOptions, TerrainRenderer};
use crate::scene::view::{Lighting, View};
use glam::DVec3;
use serde::Serialize;

/// n.l below which a pixel's sun share is not compared.
pub const MIN_FACING: f64 = 0.15;

/// The grid the shadow rows sweep.
#[derive(Debug, Clone)]
pub struct ShadowSweep {
    pub resolutions: Vec<u32>,
    pub steps: Vec<u32>,
}

impl Default for ShadowSweep {
    fn default() -> Self {
        ShadowSweep { resolutions: vec![33, 65, 129], steps: vec![8, 24, 64] }
    }
}

#[derive(Debug, Clone, Serialize)]
pub struct ShadowPoint {
    pub view: String,
    /// None: the effect off.
    pub resolution: Option<u32>,
    pub steps: Option<u32>,
    /// Pixels compared (terrain in both, facing the sun in both).
    pub compared_pixels: u64,
    /// Share of them lit in one image and shadowed in the other, and of
    /// them those the frame has in shadow (the reference lit).
    pub state_mismatch: f64,
    pub mismatch_frame_dark: f64,
    /// Mean FLIP of the lit (clay) image against the shadowed reference,
    /// over the pixels where either has terrain.
    pub flip_mean: f64,
    /// Median GPU ms of `sun_shadows` per node re-marched (sun moving).
    pub ms_per_node: Option<f64>,
    /// That times the resident nodes: one full update after the sun moved.
    pub full_update_ms: Option<f64>,
    pub resident_nodes: u32,
    /// Median GPU ms of `lighting_resolve` with the sun static.
    pub resolve_ms: f64,
    pub settled: bool,
}

/// The rows of one view; `reference` has shadow rays.
pub(super) fn shadow_rows(
    run: &mut Run,
    options: &dyn Fn(Effects) -> RendererOptions,
    fx: &Effects,
    sweep: &ShadowSweep,
    view: &View,
    reference: &ReferenceImage,
    name: &str,
) -> Result<Vec<ShadowPoint>> {
    let mut settings = vec![None];
    for &resolution in &sweep.resolutions {
        settings.extend(sweep.steps.iter().map(|&steps| Some((resolution, steps))));
    }
    let mut rows = Vec::new();
    for setting in settings {
        let mut fx = fx.clone().with(Effect::Shadows, setting.is_some());
        if let Some((resolution, steps)) = setting {
            fx.shadows = ShadowParams { resolution, steps, update_budget: MAX_UPDATE_BUDGET, ..fx.shadows };
        }
        let mut r = TerrainRenderer::new(run.ctx, run.world, run.source.clone(), Vec::new(), &options(fx))?;
        rows.push(row(run, &mut r, view, reference, name, setting)?);
    }
    Ok(rows)
}

fn row(
    run: &mut Run,
    r: &mut TerrainRenderer,
    view: &View,
    reference: &ReferenceImage,
    name: &str,
    setting: Option<(u32, u32)>,
) -> Result<ShadowPoint> {
    let settled = run.settle(r, view)?;
    let (ctx, cfg) = (run.ctx, run.cfg);
    let timings = super::measure(ctx, r, &mut run.off, view, cfg.warmup_frames, cfg.frames)?;
    let capture = run.off.capture(ctx)?;
    let gbuffer = r.gbuffer.as_ref().expect("rendered").capture(ctx)?;
    let median = |timings: &[crate::frame::FrameTimings], pass: &str| {
        summarize(timings).into_iter().find(|p| p.name == pass).map(|p| p.median_ms)
    };
    let resolve_ms = median(&timings, "lighting_resolve").unwrap_or(0.0);
    let resident = r.terrain.tree.shadow.resident_count();
    let (mismatch, frame_dark, compared) =
        state_mismatch(&capture.depth, &gbuffer.hdr, &gbuffer.normal, reference, &r.effects.lighting);
    let flip_mean = terrain_flip_mean(&capture, reference);
    let ms_per_node = if setting.is_some() {
        Some(moving_sun_ms(run, r, view)? / f64::from(resident.clamp(1, MAX_UPDATE_BUDGET)))
    } else {
        None
    };
    Ok(ShadowPoint {
        view: name.to_string(),
        resolution: setting.map(|s| s.0),
        steps: setting.map(|s| s.1),
        compared_pixels: compared,
        state_mismatch: mismatch,
        mismatch_frame_dark: frame_dark,
        flip_mean,
        full_update_ms: ms_per_node.map(|m| m * f64::from(resident)),
        ms_per_node,
        resident_nodes: resident,
        resolve_ms,
        settled,
    })
}

/// Median `sun_shadows` ms over frames whose sun moves a hair each frame:
/// every frame re-marches min(resident, budget) nodes.
fn moving_sun_ms(run: &mut Run, r: &mut TerrainRenderer, view: &View) -> Result<f64> {
    let base = r.effects.lighting.sun_azimuth_deg;
    let mut timings = Vec::new();
    let frames = run.cfg.warmup_frames + run.cfg.frames;
    for i in 0..frames {
        r.effects.lighting.sun_azimuth_deg = base + if i % 2 == 0 { 1e-3 } else { -1e-3 };
        timings.extend(run.off.run(run.ctx, r, view, 1)?);
    }
    run.off.capture(run.ctx)?;
    timings.extend(r.poll_timings(run.ctx).cloned());
    r.effects.lighting.sun_azimuth_deg = base;
    let first = r.frames_recorded() - u64::from(run.cfg.frames) + 1;
    timings.retain(|t| t.frame >= first);
    timings.dedup_by_key(|t| t.frame);
    Ok(summarize(&timings).into_iter().find(|p| p.name == "sun_shadows").map_or(0.0, |p| p.median_ms))
}

/// (share of compared pixels whose sun state differs, share the frame has
/// dark and the reference lit, pixels compared).
fn state_mismatch(
    depth: &[f32],
    hdr: &[[f32; 4]],
    normal: &[[u8; 4]],
    reference: &ReferenceImage,
    light: &Lighting,
) -> (f64, f64, u64) {
    let sun = light.sun_dir();
    let a = f64::from(CLAY_ALBEDO);
    let (sum_sun, sky): (f64, [f64; 3]) =
        (light.sun_color.iter().map(|&c| f64::from(c)).sum(), light.sky_color.map(f64::from));
    let (mut compared, mut differ, mut dark) = (0u64, 0u64, 0u64);
    for i in 0..hdr.len() {
        let n_ref = DVec3::from(reference.normal[i].map(f64::from));
        if reference.depth_m[i] <= 0.0 || depth[i] <= 0.0 || n_ref.dot(sun) < MIN_FACING {
            continue;
        }
        let n = oct_decode_unorm8([normal[i][0], normal[i][1]]);
        let facing = n.dot(sun);
        if facing < MIN_FACING {
            continue;
        }
        let ambient: f64 = sky.iter().map(|s| s * 0.5 * (1.0 + n.z)).sum();
        let radiance: f64 = (0..3).map(|c| f64::from(hdr[i][c])).sum();
        let seen = (radiance / a - ambient) / (sum_sun * facing);
        compared += 1;
        differ += u64::from((seen >= 0.5) == reference.in_shadow[i]);
        dark += u64::from(seen < 0.5 && !reference.in_shadow[i]);
    }
    let n = compared.max(1) as f64;
    (differ as f64 / n, dark as f64 / n, compared)
}
