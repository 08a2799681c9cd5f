//! `vista bench accuracy`: what accuracy costs in time. On fixed views, a
//! sweep of the target screen-space error with the culling stages on and
//! off (the picture must not change; the time does), and at one target the
//! shading settings (tiled vs one shader doing every flavour, stochastic vs
//! blended cliffs, near/far thresholds halved and doubled). Each point has
//! per-pass GPU medians, what was drawn and resident, and its error against
//! the CPU ray-caster of `reference::raycast`.
//!
//! The frames are lit with a uniform ("clay") albedo so the colour error
//! measures geometry and normals: the reference knows the surface, not the
//! texture set. For the same reason the geometry sweep draws without splat
//! and cliffs (their detail normals); the shading rows draw the scene's
//! effects and also give the FLIP of the textured image against the most
//! accurate shading (one shader, every flavour, blended cliffs). The world's hole regions are left out: the
//! reference does not model looking through holes.

use super::accuracy_error::{accuracy_error, AccuracyError};
use super::accuracy_floor::{grid_floors, Floors};
use super::accuracy_popping::{FlySweep, PoppingPoint};
use super::accuracy_shadows::{shadow_rows, ShadowPoint, ShadowSweep};
use super::accuracy_vt::{vt_rows, VtPoint, VtSweep};
use crate::effects::{Effect, Effects};
use crate::error::Result;
use crate::frame::profiler::summarize;
use crate::frame::FrameTimings;
use crate::gpu::Context;
use crate::passes::cull_patches::CullStages;
use crate::reference::{flip_map, RayCaster, RaycastConfig, ReferenceImage};
use crate::render::offscreen::{Capture, Offscreen};
use crate::render::stats::{collect, RenderStats};
use crate::render::{LodOptions, LodRule, RendererOptions, TerrainRenderer};
use crate::scene::shading::Shading;
use crate::scene::view::{Camera, View, DEFAULT_NEAR_M};
use crate::terrain::TerrainOptions;
use crate::world::{HeightSource, WorldDesc};
use serde::Serialize;
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Linear albedo of the clay image (mid grey keeps sunlit slopes below 1).
pub const CLAY_ALBEDO: f32 = 0.4;
/// Background of the frames and the reference.
pub const SKY: [f32; 4] = [0.55, 0.68, 0.85, 1.0];

pub struct AccuracyBenchConfig {
    pub size: [u32; 2],
    pub fov_y_deg: f64,
    /// Target errors of the geometry sweep, pixels.
    pub targets_px: Vec<f32>,
    /// The target of the shading rows.
    pub shading_target_px: f32,
    /// Shading rows (when the effects have splat or cliffs).
    pub shading: bool,
    pub warmup_frames: u32,
    pub frames: u32,
    pub settle_timeout: Duration,
    pub cache_dir: PathBuf,
    /// The world's error tree, shared by every renderer of the bench (`None`:
    /// made under `cache_dir`).
    pub errors: Option<std::sync::Arc<crate::world::ErrorTree>>,
    /// Resident node slots of every renderer (the budget that caps detail).
    pub slots: u32,
    pub raycast: RaycastConfig,
    /// Keep, per view, the reference and the frame at the shading target.
    pub keep_images: bool,
    /// Shadow rows (when the scene has the `shadows` effect), at the
    /// shading target.
    pub shadows: Option<ShadowSweep>,
    /// Virtual-texture rows (when the scene has `virtual_texture` and
    /// splat), at the shading target.
    pub virtual_texture: Option<VtSweep>,
    /// The LOD rules of the geometry sweep: the per-patch one's rows with
    /// culling on and off, the per-triangle one's a row each (family "per
    /// triangle"); the shading, shadow and virtual-texture rows draw per
    /// patch.
    pub rules: Vec<LodRule>,
    /// Popping along a flight from each view, in place of every other row
    /// ([`super::accuracy_popping`]).
    pub fly: Option<FlySweep>,
}

#[derive(Debug, Clone, Serialize)]
pub struct PassMs {
    pub name: String,
    pub late: bool,
    pub median_ms: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct AccuracyPoint {
    pub view: String,
    /// "culling on", "culling off" or "shading".
    pub family: String,
    pub setting: String,
    pub target_error_px: f32,
    /// The error bound the frame achieved (px): the largest projected
    /// selection error of any drawn patch (p99 within it, the largest error
    /// within twice it); above the target when the slot budget could not
    /// meet it.
    pub bound_px: f32,
    /// Whether the target's promise held: `None` where the bound exceeds the
    /// target (nothing was promised), else the LOD part's p99 within the
    /// target and its maximum within twice the target.
    pub promise_held: Option<bool>,
    pub passes: Vec<PassMs>,
    /// Sum of the pass medians.
    pub gpu_ms: f64,
    pub samples: usize,
    pub triangles_drawn: u64,
    /// Triangles drawn per screen pixel.
    pub triangles_per_pixel: f64,
    /// The fewest triangles per screen pixel any LOD choice on vista's grids
    /// could draw at this target, per triangle and per patch
    /// ([`super::accuracy_floor`]): lower bounds.
    pub floor: Floors,
    pub patches_drawn: u32,
    pub nodes_drawn_per_lod: Vec<u32>,
    pub resident_per_lod: Vec<u32>,
    /// Final nodes the camera wanted finer than was resident.
    pub wanted_finer: u32,
    pub settled: bool,
    pub error: AccuracyError,
    /// Culling off: pixels whose colour or depth differ from culling on.
    pub differs_from_culled_px: Option<u64>,
    /// Shading rows: FLIP of the textured image against the most accurate
    /// shading's.
    pub texture_flip_vs_accurate: Option<f64>,
}

#[derive(Debug, Clone, Serialize)]
pub struct ReferenceInfo {
    pub view: String,
    pub camera: Camera,
    pub seconds: f64,
    pub samples_per_ray: f64,
    pub terrain_fraction: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct AccuracyBench {
    pub references: Vec<ReferenceInfo>,
    pub bounds_seconds: f64,
    pub points: Vec<AccuracyPoint>,
    /// Why shading rows are absent, when they are.
    pub shading_skipped: Option<String>,
    pub shadow_points: Vec<ShadowPoint>,
    /// Why shadow rows are absent, when they are.
    pub shadows_skipped: Option<String>,
    pub vt_points: Vec<VtPoint>,
    /// Why virtual-texture rows are absent, when they are.
    pub vt_skipped: Option<String>,
    /// Popping rows (`fly`).
    pub popping: Vec<PoppingPoint>,
    #[serde(skip)]
    pub images: Vec<ViewImages>,
}

/// The reference and the culled frame at the shading target (RGBA8).
#[derive(Debug, Clone)]
pub struct ViewImages {
    pub view: String,
    pub size: [u32; 2],
    pub reference: Vec<u8>,
    pub frame: Vec<u8>,
}

/// A frame configuration of the shading family.
struct ShadingSetting {
    name: &'static str,
    shading: Shading,
    stochastic: bool,
    threshold_scale: f32,
}

const SHADING_SETTINGS: [ShadingSetting; 6] = [
    ShadingSetting {
        name: "tiled, stochastic cliffs",
        shading: Shading::Tiled,
        stochastic: true,
        threshold_scale: 1.0,
    },
    ShadingSetting { name: "tiled, blended cliffs", shading: Shading::Tiled, stochastic: false, threshold_scale: 1.0 },
    ShadingSetting {
        name: "tiled, near/far thresholds x0.5",
        shading: Shading::Tiled,
        stochastic: true,
        threshold_scale: 0.5,
    },
    ShadingSetting {
        name: "tiled, near/far thresholds x2",
        shading: Shading::Tiled,
        stochastic: true,
        threshold_scale: 2.0,
    },
    ShadingSetting {
        name: "every flavour, stochastic cliffs",
        shading: Shading::OneShaderEveryFlavour,
        stochastic: true,
        threshold_scale: 1.0,
    },
    // Last: the accurate one the textured images are compared with.
    ShadingSetting {
        name: "every flavour, blended cliffs",
        shading: Shading::OneShaderEveryFlavour,
        stochastic: false,
        threshold_scale: 1.0,
    },
];

/// Everything a bench run shares.
pub(super) struct Run<'a> {
    pub ctx: &'a Context,
    pub world: &'a WorldDesc,
    pub source: &'a Arc<dyn HeightSource>,
    pub cfg: &'a AccuracyBenchConfig,
    pub off: Offscreen,
    /// Each view's floors by target (the rows of one view and target share
    /// them: they depend on the reference, not the frame).
    floors: HashMap<(String, u32), Floors>,
}

pub fn bench_accuracy(
    ctx: &Context,
    world: &WorldDesc,
    source: Arc<dyn HeightSource>,
    effects: &Effects,
    views: &[(String, Camera)],
    cfg: &AccuracyBenchConfig,
) -> Result<AccuracyBench> {
    if let Some(fly) = cfg.fly {
        return popping_bench(ctx, world, source, effects, views, cfg, fly);
    }
    let start = Instant::now();
    // The reference sees the scene's atmosphere when the frames do.
    let fog = (effects.is_on(Effect::Atmosphere) && effects.is_on(Effect::Lighting)).then_some(effects.atmosphere);
    let raycast = RaycastConfig { shadow_rays: false, atmosphere: fog, ..cfg.raycast };
    let mut caster = RayCaster::new(&*source, world, raycast);
    let bounds_seconds = start.elapsed().as_secs_f64();
    // The geometry and shading rows compare with an unshadowed reference;
    // the shadow rows have their own.
    let mut fx = effects.clone().with(Effect::Shadows, false);
    fx.lighting.clay_albedo = Some(CLAY_ALBEDO);
    let [shadows_skipped, vt_skipped, shading_skipped] = skipped(effects, &fx, cfg);
    let terrain = terrain_options(cfg);
    let options =
        |shading| RendererOptions { terrain: terrain.clone(), effects: fx.clone(), shading, ..Default::default() };
    // The geometry sweep draws without the detail normals of splat and
    // cliffs: the reference cannot know them (the shading rows have them).
    let geometry = RendererOptions {
        effects: fx.clone().with(Effect::Splat, false).with(Effect::Cliffs, false),
        ..options(Shading::Tiled)
    };
    let off = Offscreen::new(ctx, cfg.size, 2, SKY)?;
    let mut run = Run { ctx, world, source: &source, cfg, off, floors: HashMap::new() };
    let mut out = AccuracyBench {
        references: Vec::new(),
        bounds_seconds,
        points: Vec::new(),
        shading_skipped,
        shadow_points: Vec::new(),
        shadows_skipped,
        vt_points: Vec::new(),
        vt_skipped,
        popping: Vec::new(),
        images: Vec::new(),
    };
    for (name, camera) in views {
        let view = |target| View {
            camera: *camera,
            fov_y_deg: cfg.fov_y_deg,
            size: cfg.size,
            target_error_px: target,
            near_m: DEFAULT_NEAR_M,
        };
        let (reference, info) = reference_image(&caster, &view(1.0), &fx, name, camera);
        out.references.push(info);
        run.geometry_rows(&geometry, &view, &reference, name, &mut out)?;
        if out.shading_skipped.is_none() {
            out.points.extend(run.shading_rows(&options, &view(cfg.shading_target_px), &reference, name)?);
        }
        if let (None, Some(sweep)) = (&out.shadows_skipped, &cfg.shadows) {
            caster.cfg.shadow_rays = true;
            let shadowed = caster.image(&view(1.0), &fx.lighting, CLAY_ALBEDO, SKY);
            caster.cfg.shadow_rays = false;
            let geometry_fx = geometry.effects.clone();
            let with = |fx: Effects| RendererOptions { effects: fx, ..geometry.clone() };
            let v = view(cfg.shading_target_px);
            out.shadow_points.extend(shadow_rows(&mut run, &with, &geometry_fx, sweep, &v, &shadowed, name)?);
        }
        if let (None, Some(sweep)) = (&out.vt_skipped, &cfg.virtual_texture) {
            let with = |fx: Effects| RendererOptions { effects: fx, ..options(Shading::Tiled) };
            let v = view(cfg.shading_target_px);
            out.vt_points.extend(vt_rows(&mut run, &with, &fx, sweep, &v, name)?);
        }
    }
    Ok(out)
}

/// `fly`'s rows only: each view's flight for each rule and target, drawn
/// as the geometry rows are (clay, no splat or cliffs, no shadows).
fn popping_bench(
    ctx: &Context,
    world: &WorldDesc,
    source: Arc<dyn HeightSource>,
    effects: &Effects,
    views: &[(String, Camera)],
    cfg: &AccuracyBenchConfig,
    fly: FlySweep,
) -> Result<AccuracyBench> {
    let mut fx = effects.clone().with(Effect::Shadows, false).with(Effect::Splat, false).with(Effect::Cliffs, false);
    fx.lighting.clay_albedo = Some(CLAY_ALBEDO);
    let skipped = || Some("not asked for (--fly measures popping only)".to_string());
    let mut out = AccuracyBench {
        references: Vec::new(),
        bounds_seconds: 0.0,
        points: Vec::new(),
        shading_skipped: skipped(),
        shadow_points: Vec::new(),
        shadows_skipped: skipped(),
        vt_points: Vec::new(),
        vt_skipped: skipped(),
        popping: Vec::new(),
        images: Vec::new(),
    };
    let off = Offscreen::new(ctx, cfg.size, 2, SKY)?;
    let mut run = Run { ctx, world, source: &source, cfg, off, floors: HashMap::new() };
    for &rule in &cfg.rules {
        let lod = LodOptions { rule, ..LodOptions::default() };
        let options = RendererOptions { terrain: terrain_options(cfg), effects: fx.clone(), lod, ..Default::default() };
        let mut r = TerrainRenderer::new(ctx, world, source.clone(), Vec::new(), &options)?;
        for (name, camera) in views {
            for &target in &cfg.targets_px {
                let view = |camera| View {
                    camera,
                    fov_y_deg: cfg.fov_y_deg,
                    size: cfg.size,
                    target_error_px: target,
                    near_m: DEFAULT_NEAR_M,
                };
                out.popping.push(run.popping_row(&mut r, &view, camera, name, &fly)?);
            }
        }
    }
    Ok(out)
}

/// The terrain of every frame: the bench's cache, slots and errors.
fn terrain_options(cfg: &AccuracyBenchConfig) -> TerrainOptions {
    TerrainOptions {
        cache_dir: Some(cfg.cache_dir.clone()),
        slots: cfg.slots,
        errors: cfg.errors.clone(),
        ..TerrainOptions::default()
    }
}

/// The reference image of a view, and how long it took and how it went.
fn reference_image(
    caster: &RayCaster,
    view: &View,
    fx: &Effects,
    name: &str,
    camera: &Camera,
) -> (ReferenceImage, ReferenceInfo) {
    let t = Instant::now();
    let reference = caster.image(view, &fx.lighting, CLAY_ALBEDO, SKY);
    let rays = f64::from(view.size[0]) * f64::from(view.size[1]);
    let info = ReferenceInfo {
        view: name.to_string(),
        camera: *camera,
        seconds: t.elapsed().as_secs_f64(),
        samples_per_ray: reference.samples as f64 / rays,
        terrain_fraction: reference.depth_m.iter().filter(|&&d| d > 0.0).count() as f64 / rays,
    };
    (reference, info)
}

/// Why the shadow, virtual-texture and shading rows are left out (None:
/// measured).
fn skipped(effects: &Effects, fx: &Effects, cfg: &AccuracyBenchConfig) -> [Option<String>; 3] {
    let shadows = (!effects.is_on(Effect::Shadows))
        .then(|| "the scene does not ask for effect shadows".to_string())
        .or_else(|| (!effects.is_on(Effect::Lighting)).then(|| "the scene's lighting is off".to_string()))
        .or_else(|| cfg.shadows.is_none().then(|| "not asked for".to_string()));
    let vt = (!effects.is_on(Effect::VirtualTexture))
        .then(|| "the scene does not ask for effect virtual_texture".to_string())
        .or_else(|| (!effects.is_on(Effect::Splat)).then(|| "the scene's splat is off".to_string()))
        .or_else(|| cfg.virtual_texture.is_none().then(|| "not asked for".to_string()));
    let shading = (!(fx.is_on(Effect::Splat) || fx.is_on(Effect::Cliffs)))
        .then(|| "the scene has neither splat nor cliffs: every shading setting draws the same".to_string())
        .or_else(|| (!cfg.shading).then(|| "not asked for".to_string()));
    [shadows, vt, shading]
}

impl Run<'_> {
    /// One target's rows with every culling stage and with none, and (when
    /// `keep`) the view's images (culled frame and reference).
    fn culling_rows(
        &mut self,
        r: &mut TerrainRenderer,
        v: &View,
        reference: &ReferenceImage,
        name: &str,
        keep: bool,
    ) -> Result<([AccuracyPoint; 2], Option<ViewImages>)> {
        let settled = self.settle(r, v)?;
        r.stages = CullStages::ALL;
        let (on, on_img) = self.point(r, v, reference, name, "culling on", "all stages", settled)?;
        r.stages = CullStages::NONE;
        let (mut off_pt, off_img) = self.point(r, v, reference, name, "culling off", "no stage", settled)?;
        r.stages = CullStages::ALL;
        off_pt.differs_from_culled_px = Some(differing_pixels(&on_img, &off_img));
        let images = keep.then(|| ViewImages {
            view: name.to_string(),
            size: self.cfg.size,
            reference: reference.rgba.clone(),
            frame: on_img.rgba.clone(),
        });
        Ok(([on, off_pt], images))
    }

    /// The geometry sweep of one view: each rule's renderer at each target.
    fn geometry_rows(
        &mut self,
        geometry: &RendererOptions,
        view: &dyn Fn(f32) -> View,
        reference: &ReferenceImage,
        name: &str,
        out: &mut AccuracyBench,
    ) -> Result<()> {
        for &rule in &self.cfg.rules {
            let options = RendererOptions { lod: LodOptions { rule, ..LodOptions::default() }, ..geometry.clone() };
            let mut r = TerrainRenderer::new(self.ctx, self.world, self.source.clone(), Vec::new(), &options)?;
            for &target in &self.cfg.targets_px {
                let keep = self.cfg.keep_images && target == self.cfg.shading_target_px && rule == LodRule::Patch;
                let (mut points, images) = self.culling_rows(&mut r, &view(target), reference, name, keep)?;
                if rule == LodRule::Triangle {
                    for p in &mut points {
                        p.family = format!("{} per triangle", p.family);
                    }
                }
                out.points.extend(points);
                out.images.extend(images);
            }
        }
        Ok(())
    }

    pub(super) fn settle(&mut self, r: &mut TerrainRenderer, view: &View) -> Result<bool> {
        let s = self.off.settle(self.ctx, r, view, self.cfg.settle_timeout)?;
        if !s.settled {
            log::warn!("streaming did not settle in {:.0} s", self.cfg.settle_timeout.as_secs_f64());
        }
        Ok(s.settled)
    }

    fn floors(&mut self, reference: &ReferenceImage, view: &View, view_name: &str) -> Floors {
        let key = (view_name.to_string(), view.target_error_px.to_bits());
        let (world, source) = (self.world, self.source);
        *self.floors.entry(key).or_insert_with(|| grid_floors(reference, view, world, &**source))
    }

    /// Measures one configuration and compares its last frame.
    #[allow(clippy::too_many_arguments)]
    fn point(
        &mut self,
        r: &mut TerrainRenderer,
        view: &View,
        reference: &ReferenceImage,
        view_name: &str,
        family: &str,
        setting: &str,
        settled: bool,
    ) -> Result<(AccuracyPoint, Capture)> {
        let timings: Vec<FrameTimings> =
            super::measure(self.ctx, r, &mut self.off, view, self.cfg.warmup_frames, self.cfg.frames)?;
        let capture = self.off.capture(self.ctx)?;
        let stats: RenderStats = collect(self.ctx, r, view)?;
        let passes: Vec<PassMs> = summarize(&timings)
            .into_iter()
            .map(|p| PassMs { name: p.name.to_string(), late: p.late, median_ms: p.median_ms })
            .collect();
        let mut resident = vec![0u32; self.world.lod_count as usize];
        for id in r.terrain.resident_nodes() {
            resident[id.lod as usize] += 1;
        }
        let error = accuracy_error(&capture, reference, view, &**self.source, self.world);
        let target = view.target_error_px;
        let promise_held = (stats.bound_px <= target).then(|| {
            let t = f64::from(target);
            error.lod_px_p99 <= t && error.lod_px_max <= 2.0 * t
        });
        let pixels = f64::from(view.size[0]) * f64::from(view.size[1]);
        let point = AccuracyPoint {
            view: view_name.to_string(),
            family: family.to_string(),
            setting: setting.to_string(),
            target_error_px: target,
            bound_px: stats.bound_px,
            promise_held,
            triangles_per_pixel: stats.triangles_drawn as f64 / pixels,
            floor: self.floors(reference, view, view_name),
            gpu_ms: passes.iter().map(|p| p.median_ms).sum(),
            passes,
            samples: timings.len(),
            triangles_drawn: stats.triangles_drawn,
            patches_drawn: stats.patches.drawn,
            nodes_drawn_per_lod: stats.nodes_per_lod,
            resident_per_lod: resident,
            wanted_finer: stats.wanted_finer_per_lod.iter().sum(),
            settled,
            error,
            differs_from_culled_px: None,
            texture_flip_vs_accurate: None,
        };
        Ok((point, capture))
    }

    /// The textured (not clay) picture of the renderer's current settings.
    fn textured(&mut self, r: &mut TerrainRenderer, view: &View) -> Result<Vec<u8>> {
        let clay = r.effects.lighting.clay_albedo.take();
        self.off.run(self.ctx, r, view, 2)?;
        r.effects.lighting.clay_albedo = clay;
        Ok(self.off.capture(self.ctx)?.rgba)
    }

    /// The shading family at one target, with the scene's effects: a tiled
    /// renderer and one doing every flavour in one shader.
    fn shading_rows(
        &mut self,
        options: &dyn Fn(Shading) -> RendererOptions,
        view: &View,
        reference: &ReferenceImage,
        view_name: &str,
    ) -> Result<Vec<AccuracyPoint>> {
        let new =
            |shading| TerrainRenderer::new(self.ctx, self.world, self.source.clone(), Vec::new(), &options(shading));
        let (mut tiled, mut every) = (new(Shading::Tiled)?, new(Shading::OneShaderEveryFlavour)?);
        let base = tiled.shade;
        let mut rows = Vec::new();
        let mut textured = Vec::new();
        for s in &SHADING_SETTINGS {
            let r = if s.shading == Shading::Tiled { &mut tiled } else { &mut every };
            r.shade = base;
            r.shade.stochastic = s.stochastic;
            let k = s.threshold_scale;
            r.shade.far_start_m *= k;
            r.shade.far_end_m *= k;
            r.shade.cliff_split_start_m *= k;
            r.shade.cliff_split_end_m *= k;
            let settled = self.settle(r, view)?;
            let (row, _) = self.point(r, view, reference, view_name, "shading", s.name, settled)?;
            rows.push(row);
            textured.push(self.textured(r, view)?);
        }
        let accurate = textured.last().expect("settings are never empty");
        for (row, img) in rows.iter_mut().zip(&textured) {
            let f = flip_map(accurate, img, view.size);
            row.texture_flip_vs_accurate = Some(f.iter().map(|&e| f64::from(e)).sum::<f64>() / f.len().max(1) as f64);
        }
        Ok(rows)
    }
}

/// Pixels whose colour or depth differ between two frames.
fn differing_pixels(a: &Capture, b: &Capture) -> u64 {
    let colour = a.rgba.chunks_exact(4).zip(b.rgba.chunks_exact(4));
    colour
        .zip(a.depth.iter().zip(&b.depth))
        .filter(|((ca, cb), (da, db))| ca != cb || da.to_bits() != db.to_bits())
        .count() as u64
}
