//! `vista bench accuracy --fly STEP,STEPS`: popping, measured. From each
//! view the camera flies level along its heading, `STEP` metres a step.
//! At every step the frame is drawn twice from the new camera: first with
//! the LOD the previous camera chose (its streamed set, selection and cut,
//! through [`TerrainRenderer::lod_camera`]), then with its own once
//! streaming settles. Both frames see the same camera, so what moves
//! between them moved because the LOD changed, not the camera.
//!
//! Per pixel that shows terrain in both, the jump is the vertical distance
//! between the two drawn surfaces, projected onto the screen: each frame's
//! hit's signed height over the finest surface ([`FinestSurface`]),
//! differenced (the hits lie on one ray, so both are measured against the
//! same continuous surface rather than against each other's x and y), drawn
//! at the second hit. Culling is off in both frames: a frustum or
//! occlusion test made for the previous camera would leave out ground that
//! the new one sees, and that is not a LOD change.

use super::accuracy::Run;
use super::accuracy_error::{quantile, vertical_px, world_point};
use crate::error::Result;
use crate::passes::cull_patches::CullStages;
use crate::reference::FinestSurface;
use crate::render::offscreen::Capture;
use crate::render::{LodRule, TerrainRenderer};
use crate::scene::view::{Camera, View};
use crate::world::{HeightSource, WorldDesc};
use glam::DVec3;
use serde::Serialize;

/// The flight of the popping rows.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct FlySweep {
    /// Metres a step, level along the view's heading.
    pub step_m: f64,
    pub steps: u32,
}

/// One view's popping at one target, for one LOD rule.
#[derive(Debug, Clone, Serialize)]
pub struct PoppingPoint {
    pub view: String,
    /// "patch" or "triangle".
    pub rule: String,
    pub target_error_px: f32,
    pub step_m: f64,
    /// Per step: the largest jump of a pixel (px).
    pub step_max_px: Vec<f64>,
    /// Over every step's pixels that show terrain in both frames.
    pub p99_px: f64,
    pub max_px: f64,
    /// Of those pixels, the share whose jump exceeds the target, and their count.
    pub over_target: f64,
    pub over_target_pixels: u64,
    pub pixels: u64,
    /// Steps whose second frame settled within the timeout.
    pub settled_steps: u32,
}

/// The camera `i` steps along the flight from `c`: level, along its heading.
pub fn flight_camera(c: &Camera, fly: &FlySweep, i: u32) -> Camera {
    let f = c.basis()[0];
    let level = DVec3::new(f.x, f.y, 0.0).normalize_or_zero();
    let p = DVec3::from(c.position_m) + level * fly.step_m * f64::from(i);
    Camera { position_m: p.to_array(), ..*c }
}

/// Per pixel that shows terrain in both `before` (the previous LOD) and
/// `after` (the new one), both drawn from `view`: the jump, pixels.
pub fn jumps_px(before: &Capture, after: &Capture, view: &View, world: &WorldDesc, finest: &FinestSurface) -> Vec<f64> {
    assert_eq!(before.size, after.size, "the two frames of a step have one size");
    let over = |p: DVec3| p.z - f64::from(finest.sample(p.x, p.y));
    (0..after.depth.len())
        .filter_map(|i| {
            let (a, b) = (world_point(before, view, world, i)?, world_point(after, view, world, i)?);
            vertical_px(view, b, b.z, b.z + over(b) - over(a))
        })
        .collect()
}

impl Run<'_> {
    /// The flight from `camera` at `target` with renderer `r` (its rule):
    /// settled at the start, then two frames a step.
    pub(super) fn popping_row(
        &mut self,
        r: &mut TerrainRenderer,
        view: &dyn Fn(Camera) -> View,
        camera: &Camera,
        name: &str,
        fly: &FlySweep,
    ) -> Result<PoppingPoint> {
        let finest = FinestSurface::new(self.world, &**self.source);
        r.stages = CullStages::NONE;
        r.lod_camera = None;
        self.settle(r, &view(*camera))?;
        let (mut all, mut step_max, mut settled_steps) = (Vec::new(), Vec::new(), 0);
        for i in 1..=fly.steps {
            let (from, to) = (flight_camera(camera, fly, i - 1), flight_camera(camera, fly, i));
            let v = view(to);
            r.lod_camera = Some(from);
            self.off.run(self.ctx, r, &v, 2)?;
            let before = self.off.capture(self.ctx)?;
            r.lod_camera = None;
            settled_steps += u32::from(self.settle(r, &v)?);
            self.off.run(self.ctx, r, &v, 2)?;
            let after = self.off.capture(self.ctx)?;
            let jumps = jumps_px(&before, &after, &v, self.world, &finest);
            step_max.push(jumps.iter().copied().fold(0.0, f64::max));
            all.extend(jumps);
        }
        r.stages = CullStages::ALL;
        let target = view(*camera).target_error_px;
        let over = all.iter().filter(|&&j| j > f64::from(target)).count();
        Ok(PoppingPoint {
            view: name.to_string(),
            rule: match r.lod.rule {
                LodRule::Patch => "patch",
                LodRule::Triangle => "triangle",
            }
            .to_string(),
            target_error_px: target,
            step_m: fly.step_m,
            max_px: step_max.iter().copied().fold(0.0, f64::max),
            over_target: over as f64 / all.len().max(1) as f64,
            over_target_pixels: over as u64,
            pixels: all.len() as u64,
            p99_px: quantile(&mut all, 0.99),
            step_max_px: step_max,
            settled_steps,
        })
    }
}
