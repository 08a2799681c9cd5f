//! Case 7: determinism. A 30-frame script (the fly-through, each frame
//! rendered once streaming has settled, so what is resident depends on the
//! script, not on how fast the loader threads were) renders bit-identical
//! images twice in one process; `vista stability` also runs it in a second
//! process and with LP_NUM_THREADS=1 and compares the hashes. The traversal
//! appends nodes with atomics, so draw lists can come in a different order;
//! the pictures may not differ, because every pixel belongs to one triangle
//! (shared edges follow the rasteriser's top-left rule) and the depth test
//! does not depend on the order of disjoint triangles. The script runs with
//! a small refinement budget (`REFINE_BUDGET`), so more LOD-0 patches ask
//! to be refined than it holds: which ones are refused must come from
//! their errors, not from which workgroup reached the counter first. A
//! second script renders with every effect a renderer builds (the virtual
//! texture and its decal, grass, assets, cliff meshes, shadows,
//! atmosphere, ...) over the flight's first cameras, the sun turning 7
//! degrees a frame and the decal turned at its fourth frame. The virtual
//! texture's pages are rendered frames after they are asked for, from
//! whatever nodes are resident then; a page is dropped when a finer node
//! arrives over it or one it may have been made from leaves, so a settled
//! frame's pages are those of its resident set, whatever the loaders' pace.

use super::rig::{every_effect, fly_through, Rig};
use super::{CaseReport, Form};
use crate::error::Result;
use crate::gpu::Context;
use crate::render::{RendererOptions, View};
use std::hash::Hasher;

pub const FRAMES: u32 = 30;
/// LOD-0 patches refined a frame at most in the script: below what its
/// lowest frames ask for.
pub const REFINE_BUDGET: u32 = 24;
/// The script's target error (px).
const TARGET_PX: f32 = 0.1;

/// Frames of the second script: every effect.
pub const EVERY_EFFECT_FRAMES: u32 = 6;

/// One hash per frame of both scripts (colour, depth and the selection's
/// counters), and the frames whose refinement the budget capped.
pub fn script_hashes(ctx: &Context) -> Result<(Vec<u64>, u32)> {
    let lod = crate::render::LodOptions { refine_budget: REFINE_BUDGET, ..Default::default() };
    let capped_script = RendererOptions { lod, ..RendererOptions::default() };
    let (mut out, capped) = script(ctx, capped_script, FRAMES, TARGET_PX, false)?;
    out.extend(script(ctx, every_effect(), EVERY_EFFECT_FRAMES, 1.0, true)?.0);
    Ok((out, capped))
}

/// `frames` settled frames of the fly-through at `target_px`; `edits`: the
/// sun turns and the decal is turned at frame 3.
fn script(
    ctx: &Context,
    options: RendererOptions,
    frames: u32,
    target_px: f32,
    edits: bool,
) -> Result<(Vec<u64>, u32)> {
    let mut rig = Rig::new(ctx, [96, 64], 400, options, Vec::new())?;
    let (mut out, mut capped) = (Vec::new(), 0);
    for f in 0..frames {
        if edits {
            rig.renderer.effects.lighting.sun_azimuth_deg = 200.0 + 7.0 * f64::from(f);
            if f == 3 {
                rig.renderer.set_decals(ctx, vec![super::rig::script_decal(30.0)])?;
            }
        }
        let view = View { target_error_px: target_px, ..rig.view(fly_through(&rig, f, FRAMES)) };
        let shot = rig.settled_shot(ctx, &view)?;
        let select = crate::render::stats::collect(ctx, &rig.renderer, &view)?.select;
        capped += u32::from(select.refine_capped > 0);
        // SipHash with fixed keys: the same in every process.
        let mut h = std::hash::DefaultHasher::new();
        h.write(&shot.rgba);
        h.write(bytemuck::cast_slice(&shot.depth));
        h.write(bytemuck::bytes_of(&select));
        out.push(h.finish());
    }
    Ok((out, capped))
}

/// Another process's run of the script: (what it was, its hashes).
pub type Runs = Vec<(String, Result<Vec<u64>>)>;

/// `others`: the script's hashes from other processes (the command line
/// spawns itself; the test suite runs only the in-process half).
pub fn run(ctx: &Context, _form: Form, others: Runs) -> Result<CaseReport> {
    let mut r = CaseReport::new(7, "determinism");
    r.measured = format!(
        "frames of two scripts ({FRAMES} frames capped, {EVERY_EFFECT_FRAMES} with every effect, a moving sun and a \
         decal edit) that differ between runs: twice in one process, a second process, LP_NUM_THREADS=1"
    );
    r.bound = "0 frames".into();
    r.why = "the same inputs must give the same picture, or regression tests (golden images) cannot tell a change from noise".into();
    let (first, capped) = script_hashes(ctx)?;
    r.details.push(format!(
        "{capped} of {FRAMES} frames ask to refine more LOD-0 patches than the budget of {REFINE_BUDGET}"
    ));
    let mut runs = vec![("the same process, again".to_string(), script_hashes(ctx).map(|(h, _)| h))];
    runs.extend(others);
    let mut worst = 0usize;
    let mut failed = false;
    for (what, hashes) in runs {
        match hashes {
            Ok(h) => {
                let which: Vec<usize> =
                    h.iter().zip(&first).enumerate().filter(|(_, (a, b))| a != b).map(|x| x.0).collect();
                let differ = h.len().abs_diff(first.len()) + which.len();
                let list = if which.is_empty() { String::new() } else { format!(" (frames {which:?})") };
                r.details.push(format!("{what}: {differ} of {} frames differ{list}", first.len()));
                worst = worst.max(differ);
            }
            Err(e) => {
                failed = true;
                r.details.push(format!("{what}: did not run: {e}"));
            }
        }
    }
    r.worst = format!("{worst} frames");
    r.pass = worst == 0 && !failed;
    Ok(r)
}
