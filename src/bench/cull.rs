//! `vista bench cull`: what patch culling removes and what it costs, per
//! view (ground level, low flight, high flight, facing a ridge). Each view
//! renders in blocks with every culling stage on, with the cone stage off
//! and with culling off, in one run; per-pass GPU medians after warm-up.
//! With occlusion built, a fourth block switches it off: the pyramid and
//! phase 2 cost against the geometry time they save, and the patches drawn
//! in each phase.

use crate::error::Result;
use crate::frame::profiler::summarize;
use crate::gpu::Context;
use crate::passes::cull_occluded::CullOccluded;
use crate::passes::cull_patches::{CullCounters, CullPatches, CullStages};
use crate::passes::hiz_build::HizBuild;
use crate::passes::terrain_geometry::TerrainGeometry;
use crate::passes::terrain_holes::TerrainHoles;
use crate::passes::traverse::Traverse;
use crate::render::offscreen::Offscreen;
use crate::render::TerrainRenderer;
use crate::scene::view::{Camera, View, DEFAULT_NEAR_M};
use crate::world::{HeightSource, WorldDesc};
use serde::Serialize;
use std::time::Duration;

pub struct CullBenchConfig {
    pub size: [u32; 2],
    pub target_error_px: f32,
    /// Warm-up frames per block (their timings are dropped).
    pub warmup_frames: u32,
    /// Measured frames per block; the median is reported.
    pub frames: u32,
    pub settle_timeout: Duration,
}

/// Medians of one stage configuration.
#[derive(Debug, Clone, Serialize)]
pub struct CullTiming {
    pub traverse_ms: f64,
    pub cull_ms: f64,
    /// Both draws (terrain_geometry, terrain_holes), both phases.
    pub geometry_ms: f64,
    /// hiz_build + cull_occluded (0 without occlusion).
    pub occlusion_ms: f64,
    pub counters: CullCounters,
}

#[derive(Debug, Clone, Serialize)]
pub struct CullBenchRow {
    pub view: String,
    pub camera: [f64; 5],
    pub all: CullTiming,
    pub no_cone: CullTiming,
    pub none: CullTiming,
    /// Every stage but occlusion (where occlusion is built).
    pub no_occlusion: Option<CullTiming>,
    /// Geometry time occlusion saves (no occlusion - all) and what its
    /// passes cost (hiz_build + cull_occluded).
    pub occlusion_saves_ms: Option<f64>,
    pub occlusion_cost_ms: Option<f64>,
    pub nodes: u32,
    pub triangles_drawn: u64,
    /// Triangles of the whole world at LOD 0 (2 per quad).
    pub full_res_triangles: f64,
    pub triangles_vs_full_res: f64,
    /// Patches drawn / patches of the selected nodes.
    pub drawn_vs_selected: f64,
    /// (traverse + cull_patches) / terrain_geometry, every stage on.
    pub traverse_cull_vs_geometry: f64,
    /// cull_patches time the cone stage costs (all - no cone).
    pub cone_cost_ms: f64,
    /// terrain_geometry time the cone stage saves (no cone - all).
    pub cone_saves_ms: f64,
    /// terrain_geometry with culling off / on.
    pub geometry_off_vs_on: f64,
}

/// The four benchmark views of a world: ground level (2 m up, looking
/// level), low flight (60 m up, 10 degrees down), high flight (a twentieth
/// of the world's size up, 30 degrees down), facing a ridge (30 m up, a
/// tenth of the world away from its highest sampled point, looking at it).
pub fn cull_views(world: &WorldDesc, source: &dyn HeightSource) -> Vec<(String, Camera)> {
    let [ex, ey] = world.extent_m;
    let ground = |x: f64, y: f64| f64::from(source.sample(x, y));
    let (cx, cy) = (ex * 0.5, ey * 0.3);
    let mut peak = (f64::MIN, cx, cy);
    for j in 0..64 {
        for i in 0..64 {
            let (x, y) = ((f64::from(i) + 0.5) * ex / 64.0, (f64::from(j) + 0.5) * ey / 64.0);
            if ground(x, y) > peak.0 {
                peak = (ground(x, y), x, y);
            }
        }
    }
    // Stand south-west of the peak (or north-east when that leaves the world).
    let d = 0.1 * ex.min(ey);
    let (sx, sy) =
        if peak.1 - d > 0.0 && peak.2 - d > 0.0 { (peak.1 - d, peak.2 - d) } else { (peak.1 + d, peak.2 + d) };
    let yaw = (peak.1 - sx).atan2(peak.2 - sy).to_degrees();
    let cam = |x: f64, y: f64, up: f64, yaw_deg: f64, pitch_deg: f64| Camera {
        position_m: [x, y, ground(x, y) + up],
        yaw_deg,
        pitch_deg,
    };
    vec![
        ("ground".into(), cam(cx, cy, 2.0, 0.0, 0.0)),
        ("low flight".into(), cam(cx, cy, 60.0, 0.0, -10.0)),
        ("high flight".into(), cam(cx, cy, 0.05 * ex.max(ey), 0.0, -30.0)),
        ("facing ridge".into(), cam(sx, sy, 30.0, yaw, 5.0)),
    ]
}

fn block(
    ctx: &Context,
    renderer: &mut TerrainRenderer,
    off: &mut Offscreen,
    view: &View,
    stages: CullStages,
    cfg: &CullBenchConfig,
) -> Result<CullTiming> {
    renderer.stages = stages;
    let frames = off.run(ctx, renderer, view, cfg.warmup_frames + cfg.frames + 1)?;
    off.capture(ctx)?;
    // Timings come back a frame late: the first ones may be the previous block's.
    let measured: Vec<_> = frames.into_iter().skip(cfg.warmup_frames as usize + 1).collect();
    let s = summarize(&measured);
    let ms = |name: &str| s.iter().find(|p| p.name == name).map_or(f64::NAN, |p| p.median_ms);
    // Passes that may be absent (not built or off): 0; drawing passes in both phases.
    let sum = |name: &str| s.iter().filter(|p| p.name == name).map(|p| p.median_ms).sum::<f64>();
    Ok(CullTiming {
        traverse_ms: ms(Traverse::NAME),
        cull_ms: ms(CullPatches::NAME),
        geometry_ms: sum(TerrainGeometry::NAME) + sum(TerrainHoles::NAME),
        occlusion_ms: sum(HizBuild::NAME) + sum(CullOccluded::NAME),
        counters: renderer.read_counters(ctx)?.cull,
    })
}

pub fn bench_cull(
    ctx: &Context,
    renderer: &mut TerrainRenderer,
    views: &[(String, Camera)],
    cfg: &CullBenchConfig,
) -> Result<Vec<CullBenchRow>> {
    let world = *renderer.world();
    let mut off = Offscreen::new(ctx, cfg.size, 2, [0.0, 0.0, 0.0, 1.0])?;
    let mut rows = Vec::new();
    let full = world.extent_m[0] / world.spacing_m * (world.extent_m[1] / world.spacing_m) * 2.0;
    for (name, camera) in views {
        let view = View {
            camera: *camera,
            fov_y_deg: 60.0,
            size: cfg.size,
            target_error_px: cfg.target_error_px,
            near_m: DEFAULT_NEAR_M,
        };
        renderer.stages = CullStages::ALL;
        let settle = off.settle(ctx, renderer, &view, cfg.settle_timeout)?;
        if !settle.settled {
            log::warn!("{name}: streaming did not settle in {:.0} s", cfg.settle_timeout.as_secs_f64());
        }
        let all = block(ctx, renderer, &mut off, &view, CullStages::ALL, cfg)?;
        let no_cone = block(ctx, renderer, &mut off, &view, CullStages { cone: false, ..CullStages::ALL }, cfg)?;
        let none = block(ctx, renderer, &mut off, &view, CullStages::NONE, cfg)?;
        let no_occlusion = if renderer.occlusion.is_some() {
            Some(block(ctx, renderer, &mut off, &view, CullStages { occlusion: false, ..CullStages::ALL }, cfg)?)
        } else {
            None
        };
        let stats = crate::render::stats::collect(ctx, renderer, &view)?;
        let tri = u64::from(all.counters.drawn) * crate::render::stats::TRIANGLES_PER_PATCH;
        let p = camera.position_m;
        rows.push(CullBenchRow {
            view: name.clone(),
            camera: [p[0], p[1], p[2], camera.yaw_deg, camera.pitch_deg],
            nodes: stats.node_count,
            triangles_drawn: tri,
            full_res_triangles: full,
            triangles_vs_full_res: tri as f64 / full,
            drawn_vs_selected: f64::from(all.counters.drawn) / f64::from(all.counters.patches_in.max(1)),
            traverse_cull_vs_geometry: (all.traverse_ms + all.cull_ms) / all.geometry_ms,
            cone_cost_ms: all.cull_ms - no_cone.cull_ms,
            cone_saves_ms: no_cone.geometry_ms - all.geometry_ms,
            geometry_off_vs_on: none.geometry_ms / all.geometry_ms,
            occlusion_saves_ms: no_occlusion.as_ref().map(|n| n.geometry_ms - all.geometry_ms),
            occlusion_cost_ms: no_occlusion.as_ref().map(|_| all.occlusion_ms),
            no_occlusion,
            all,
            no_cone,
            none,
        });
    }
    Ok(rows)
}
