//! Case 11: tiny and huge fields of view. The pixel on the optical axis
//! looks along the same ray at every field of view, so it must see the
//! same ground at the same depth; what changes with the fov is only the
//! LOD (finer for a narrow view). Measured from 1e-6 to 179.9 degrees, the
//! range `View::validate` (and so `vista render --fov`) takes, against 60
//! degrees.
//!
//! Why the range ends where it does: [`crate::scene::view::MIN_FOV_DEG`].

use super::rig::Rig;
use super::{CaseReport, Form};
use crate::error::Result;
use crate::gpu::Context;
use crate::render::{Camera, RendererOptions};
use crate::scene::view::{MAX_FOV_DEG, MIN_FOV_DEG};

/// Odd, so a pixel centre lies on the optical axis.
const SIZE: [u32; 2] = [65, 49];
/// Relative depth difference allowed on the axis: the LOD error of the
/// hit point at 60 degrees (1 px target: centimetres at tens of metres).
const BOUND: f64 = 0.01;

fn axis_depth(rig: &mut Rig, ctx: &Context, camera: Camera, fov: f64) -> Result<f64> {
    let mut view = rig.view(camera);
    view.fov_y_deg = fov;
    let shot = rig.settled_shot(ctx, &view)?;
    let depth = shot.linear_depth(view.near_m);
    Ok(f64::from(depth[(SIZE[1] / 2 * SIZE[0] + SIZE[0] / 2) as usize]))
}

pub fn run(ctx: &Context, form: Form) -> Result<CaseReport> {
    let mut r = CaseReport::new(11, "tiny and huge fov");
    r.measured = format!(
        "depth on the optical axis at fovs {MIN_FOV_DEG:e}..{MAX_FOV_DEG} degrees against 60 degrees, relative"
    );
    r.bound = format!("{BOUND} (1 %)");
    r.why = "the axis pixel's ray does not depend on the fov; only the LOD does (finer when narrow), which moves \
             the hit by the LOD error, centimetres at tens of metres"
        .into();
    let mut rig = Rig::new(ctx, SIZE, 400, RendererOptions::default(), Vec::new())?;
    let camera = rig.camera(1000.25, 600.5, 40.125, 20.0, -30.0);
    let reference = axis_depth(&mut rig, ctx, camera, 60.0)?;
    let fovs = form.pick(
        vec![MIN_FOV_DEG, 1e-3, 1.0, 120.0, MAX_FOV_DEG],
        vec![MIN_FOV_DEG, 1e-5, 1e-4, 1e-3, 1e-2, 0.1, 1.0, 10.0, 90.0, 120.0, 170.0, 179.0, MAX_FOV_DEG],
    );
    let mut worst = 0.0f64;
    for fov in fovs {
        let d = axis_depth(&mut rig, ctx, camera, fov)?;
        let rel = (d - reference).abs() / reference;
        r.details
            .push(format!("fov {fov:e} degrees: axis depth {d:.3} m ({rel:.1e} from 60 degrees' {reference:.3} m)"));
        worst = worst.max(if rel.is_finite() { rel } else { f64::INFINITY });
    }
    r.worst = format!("{worst:.1e}");
    r.pass = worst <= BOUND;
    Ok(r)
}
