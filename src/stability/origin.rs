//! Case 1: far from the origin. The same terrain placed at 0, 1e4, 1e5,
//! 1e6 and 1e7 m (UTM-like: Mont Blanc sits near 340 000 E, 5 080 000 N)
//! and seen from the same camera, given in the placed coordinates, renders
//! the same picture; a 1 mm camera step at 1e6 m moves every projected
//! vertex the same way each time; and a negative control, the same vertices
//! in absolute f32 world space, shows what this guards against.

use super::rig::{differing_pixels, Rig};
use super::{CaseReport, Form};
use crate::error::Result;
use crate::gpu::Context;
use crate::render::{Lighting, RendererOptions, View};
use crate::scene::shading::ShadeRules;
use crate::terrain::quadtree::texture_extent;

const OFFSETS: [f64; 5] = [0.0, 1e4, 1e5, 1e6, 1e7];
/// The camera steps 1 mm east this many times at 1e6 m.
const STEPS: usize = 64;
const STEP_M: f64 = 1e-3;

pub fn run(ctx: &Context, form: Form) -> Result<CaseReport> {
    let mut r = CaseReport::new(1, "far from the origin");
    r.measured = "pixels differing from the picture at origin 0 (placed at 1e4..1e7 m); 1 mm camera steps at 1e6 m that do not move a projected vertex the right way".into();
    r.bound = "0 pixels; 0 steps".into();
    r.why = "the view is made world-relative in f64 (exact to 2 nm at 1e7 m) and vertices camera-relative from integer sample indices, so placement never reaches f32; the cameras are dyadic, so o + c - o == c exactly".into();
    let size = form.pick([128, 96], [320, 180]);
    let mut rig = Rig::new(ctx, size, 400, RendererOptions::default(), Vec::new())?;
    // Dyadic metres: origin + camera is exact in f64 for every offset.
    let local = rig.camera(1000.25, 600.5, 40.125, 20.0, -12.0);
    let mut worst = 0usize;
    let mut reference = None;
    for o in OFFSETS {
        rig.renderer.origin_m = [o, o * 0.5];
        let mut camera = local;
        camera.position_m[0] += o;
        camera.position_m[1] += o * 0.5;
        let shot = rig.settled_shot(ctx, &rig.view(camera))?;
        match &reference {
            None => reference = Some(shot),
            Some(base) => {
                let d = differing_pixels(base, &shot);
                r.details.push(format!("origin ({o:e}, {:e}) m: {d} pixels differ from origin 0", o * 0.5));
                worst = worst.max(d);
            }
        }
    }
    // Decimal cameras are not exact in f64: the world-relative position is
    // off by up to half an ulp of 1e7 m; say what that is.
    let decimal = [1000.37, 600.91];
    let err = OFFSETS.iter().map(|o| ((o + decimal[0]) - o - decimal[0]).abs()).fold(0.0, f64::max);
    r.details
        .push(format!("decimal camera (1000.37 m) placed at up to 1e7 m: world-relative position off by {err:.1e} m"));

    let view = rig.view(local);
    let step = steps(&rig, &view, 1e6, false);
    let control = steps(&rig, &view, 1e6, true);
    r.details.push(format!(
        "1 mm steps at 1e6 m, {} vertices x {STEPS} steps: {} wrong; largest error against f64 {:.2e} px",
        step.vertices, step.wrong, step.error_px
    ));
    r.details.push(format!(
        "negative control, absolute f32 world space: {} of {} vertex steps wrong (frozen or jumping), error up to {:.2} px",
        control.wrong,
        control.vertices * STEPS,
        control.error_px
    ));
    r.worst = format!("{worst} pixels; {} steps", step.wrong);
    // The control must fail, or the check could not see the failure.
    r.pass = worst == 0 && step.wrong == 0 && control.wrong > 0;
    if control.wrong == 0 {
        r.details.push("the negative control did not fail: the check cannot see what it guards against".into());
    }
    Ok(r)
}

struct Steps {
    vertices: usize,
    wrong: usize,
    error_px: f64,
}

/// Projects LOD-0 vertices around the camera with the vertex shader's f32
/// arithmetic (terrain_vertex.glsl: integer sample offsets times the
/// spacing, minus the camera's fraction, through `view_proj`), from the
/// `TerrainViewGpu` the renderer uploads, while the camera steps 1 mm east.
/// Looking north, each step must move every vertex left on screen.
/// `absolute`: the naive renderer, positions in f32 world space at the
/// offset, camera subtracted in f32.
fn steps(rig: &Rig, view: &View, offset: f64, absolute: bool) -> Steps {
    let world = &rig.world;
    let s = world.spacing_m;
    let extent = texture_extent(world);
    let (light, shade) = (Lighting::default(), ShadeRules::default());
    let view = View { camera: crate::render::Camera { yaw_deg: 0.0, pitch_deg: -10.0, ..view.camera }, ..view.clone() };
    let c = view.camera.position_m;
    let anchor = [(c[0] / s).floor() as i64, (c[1] / s).floor() as i64];
    let mut vertices = Vec::new();
    for j in 4..40 {
        for i in -12..=12 {
            let g = [anchor[0] + i, anchor[1] + j];
            let p = [g[0] as f64 * s, g[1] as f64 * s];
            vertices.push((g, f64::from(rig.source.sample(p[0], p[1]))));
        }
    }
    let (mut wrong, mut error_px) = (0, 0.0f64);
    let mut last: Vec<Option<f32>> = vec![None; vertices.len()];
    for k in 0..STEPS {
        let mut v = view.clone();
        v.camera.position_m[0] += k as f64 * STEP_M;
        let gpu = v.gpu(world, extent, &light, &shade);
        let m = gpu.view_proj;
        let abs_cam = [offset + v.camera.position_m[0], offset + v.camera.position_m[1]];
        for (n, &(g, h)) in vertices.iter().enumerate() {
            let rel: [f32; 3] = if absolute {
                let p = [(offset + g[0] as f64 * s) as f32, (offset + g[1] as f64 * s) as f32];
                [p[0] - abs_cam[0] as f32, p[1] - abs_cam[1] as f32, h as f32 - gpu.camera_z]
            } else {
                let d = [
                    (g[0] - i64::from(gpu.camera_sample[0])) as f32 * gpu.spacing_m,
                    (g[1] - i64::from(gpu.camera_sample[1])) as f32 * gpu.spacing_m,
                ];
                [d[0] - gpu.camera_frac[0], d[1] - gpu.camera_frac[1], h as f32 - gpu.camera_z]
            };
            // view_proj is column-major: clip = sum over columns.
            let clip = |row: usize| m[0][row] * rel[0] + m[1][row] * rel[1] + m[2][row] * rel[2] + m[3][row];
            let (x, w) = (clip(0), clip(3));
            if w <= 0.0 {
                continue;
            }
            let px = (x / w + 1.0) * 0.5 * v.size[0] as f32;
            let exact = v.project([g[0] as f64 * s, g[1] as f64 * s, h]).map(|(q, _)| q[0]);
            if let Some(q) = exact {
                error_px = error_px.max((f64::from(px) - q).abs());
            }
            if let Some(prev) = last[n] {
                // The camera moved east: the vertex must move left.
                wrong += usize::from(px >= prev);
            }
            last[n] = Some(px);
        }
    }
    Steps { vertices: vertices.len(), wrong, error_px }
}
