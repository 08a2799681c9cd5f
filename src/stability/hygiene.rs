//! Case 5: NaN and infinity hygiene. Height maps with NaN, infinities,
//! denormals and huge values are rejected (with a count) or give a valid
//! world; degenerate cameras give an error or a valid image; over a
//! fly-through, every float the renderer writes (depth, the lit HDR
//! target) is finite, holes included: the NaN the hole vertices carry is
//! dropped by the rasteriser and leaks nowhere.

use super::rig::{fly_through, Rig};
use super::{CaseReport, Form};
use crate::error::Result;
use crate::gpu::Context;
use crate::render::{Camera, RendererOptions, View};
use crate::world::{write_height_exr, ExrSource, Hole, WorldDesc};

pub fn run(ctx: &Context, form: Form) -> Result<CaseReport> {
    let mut r = CaseReport::new(5, "NaN and infinity hygiene");
    r.measured = "height maps with NaN, +-inf, denormals, +-3e38 accepted without an error; degenerate cameras that neither fail nor render finite; non-finite depth or lit texels over a fly-through over holes".into();
    r.bound = "0; 0; 0".into();
    r.why = "bad numbers must be refused where they enter (with a count) or never be produced: one NaN texel spreads through filtering, TAA and exposure in an engine".into();
    let bad_inputs = height_maps(&mut r)?;
    let holes = vec![Hole::Circle { center_m: [1000.0, 900.0], radius_m: 60.0 }];
    let size = form.pick([96, 64], [256, 144]);
    let mut rig = Rig::new(ctx, size, 300, RendererOptions::default(), holes)?;
    let bad_cameras = cameras(ctx, &mut rig, &mut r)?;
    let frames = form.pick(100, 300);
    let (mut texels, mut bad_texels) = (0usize, 0usize);
    for f in 0..frames {
        let view = rig.view(fly_through(&rig, f, frames));
        let shot = rig.shot(ctx, &view)?;
        let gb = rig.renderer.gbuffer.as_ref().expect("made by the first frame").capture(ctx)?;
        bad_texels += shot.depth.iter().filter(|d| !d.is_finite()).count();
        bad_texels += gb.hdr.iter().flatten().filter(|v| !v.is_finite()).count();
        texels += shot.depth.len() + gb.hdr.len() * 4;
    }
    r.details.push(format!(
        "{frames} fly-through frames over a hole: {bad_texels} non-finite of {texels} depth and HDR values"
    ));
    r.worst = format!("{bad_inputs}; {bad_cameras}; {bad_texels}");
    r.pass = bad_inputs == 0 && bad_cameras == 0 && bad_texels == 0;
    Ok(r)
}

/// Height maps with bad values go through the EXR path (parse, range fit,
/// world validation): each must fail with the count of bad samples or make
/// a world whose range is finite and ordered. Returns the failures.
fn height_maps(r: &mut CaseReport) -> Result<usize> {
    let dir = std::env::temp_dir().join(format!("vista-hygiene-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| crate::Error::BadInput(format!("{}: {e}", dir.display())))?;
    let nan = f32::from_bits(0x7FC0_0001);
    let cases: [(&str, f32, usize); 6] = [
        ("NaN", nan, 5),
        ("+inf", f32::INFINITY, 3),
        ("-inf", f32::NEG_INFINITY, 1),
        ("denormal", f32::from_bits(1), 7),
        ("+3e38", 3e38, 2),
        ("-3e38 and +3e38", -3e38, 2),
    ];
    let mut failures = 0;
    for (what, value, count) in cases {
        let (w, h) = (16usize, 16usize);
        let mut heights: Vec<f32> = (0..w * h).map(|i| (i % 7) as f32 * 10.0).collect();
        for k in 0..count {
            heights[(k * 37 + 3) % (w * h)] = value;
        }
        if what.starts_with("-3e38") {
            heights[100] = 3e38;
        }
        let path = dir.join("bad.exr");
        write_height_exr(&path, w, h, &heights)?;
        let outcome = match ExrSource::open(&path, [1000.0, 1000.0]) {
            Err(e) => {
                let msg = e.to_string();
                // The mixed case adds one +3e38 to the -3e38 samples.
                let expected = count + usize::from(what.starts_with("-3e38"));
                let counted = msg.contains(&format!(" {expected} "));
                if !counted {
                    failures += 1;
                }
                format!("refused{}: {msg}", if counted { "" } else { " WITHOUT the count" })
            }
            Ok(source) => {
                let range = source.grid().resampled_range();
                let desc = WorldDesc {
                    height_range_m: range,
                    extent_m: [1000.0, 1000.0],
                    spacing_m: 1.0,
                    lod_count: 4,
                    ..WorldDesc::default()
                };
                match desc.validate() {
                    Err(e) => format!("refused: {e}"),
                    Ok(()) if range.iter().all(|v| v.is_finite()) && range[0] < range[1] => {
                        format!("accepted, range {:.3e}..{:.3e} m", range[0], range[1])
                    }
                    Ok(()) => {
                        failures += 1;
                        format!("ACCEPTED with range {range:?}")
                    }
                }
            }
        };
        r.details.push(format!("height map with {count} {what}: {outcome}"));
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(failures)
}

/// Degenerate cameras: each is refused by `View::validate` or renders an
/// image whose depth is finite. Returns how many did neither.
fn cameras(ctx: &Context, rig: &mut Rig, r: &mut CaseReport) -> Result<usize> {
    let base = rig.view(rig.camera(1024.0, 1024.0, 50.0, 0.0, -30.0));
    let at = |pitch: f64| Camera { pitch_deg: pitch, ..base.camera };
    let cases: Vec<(&str, View)> = vec![
        ("straight down", View { camera: at(-90.0), ..base.clone() }),
        ("straight up", View { camera: at(90.0), ..base.clone() }),
        ("fov 1e-4 degrees", View { fov_y_deg: 1e-4, ..base.clone() }),
        ("fov 179.99 degrees", View { fov_y_deg: 179.99, ..base.clone() }),
        ("near plane 0", View { near_m: 0.0, ..base.clone() }),
        ("near plane 1e-30 m", View { near_m: 1e-30, ..base.clone() }),
        ("yaw NaN (no forward)", View { camera: Camera { yaw_deg: f64::NAN, ..base.camera }, ..base.clone() }),
        (
            "camera at +inf",
            View { camera: Camera { position_m: [f64::INFINITY, 0.0, 0.0], ..base.camera }, ..base.clone() },
        ),
        ("fov 180", View { fov_y_deg: 180.0, ..base.clone() }),
        ("target error 0", View { target_error_px: 0.0, ..base.clone() }),
    ];
    let mut bad = 0;
    for (what, view) in cases {
        let outcome = match view.validate() {
            Err(e) => format!("refused: {e}"),
            Ok(()) => {
                let shot = rig.settled_shot(ctx, &view)?;
                let gb = rig.renderer.gbuffer.as_ref().expect("made by the frame").capture(ctx)?;
                let nonfinite = shot.depth.iter().filter(|d| !d.is_finite()).count()
                    + gb.hdr.iter().flatten().filter(|v| !v.is_finite()).count();
                let terrain = shot.depth.iter().filter(|d| **d > 0.0).count();
                bad += usize::from(nonfinite > 0);
                format!("rendered: {terrain} terrain pixels, {nonfinite} non-finite values")
            }
        };
        r.details.push(format!("camera {what}: {outcome}"));
    }
    Ok(bad)
}
