//! Case 6: seams under motion. A fly-through across LOD changes and
//! streaming boundaries (few resident slots, so nodes come and go), with
//! the background cleared to magenta and a camera that always looks down
//! onto the terrain: any pixel left with no terrain depth, or magenta, is
//! a crack between patches, between LODs or at a node being replaced.

use super::rig::{fly_through, Rig, MAGENTA};
use super::{CaseReport, Form};
use crate::error::Result;
use crate::gpu::Context;
use crate::render::RendererOptions;

const SLOTS: u32 = 24;

pub fn run(ctx: &Context, form: Form) -> Result<CaseReport> {
    let mut r = CaseReport::new(6, "seams under motion");
    r.measured = "pixels with no terrain (depth 0 or the magenta clear) in a fly-through that looks only at terrain, across LOD changes and node streaming".into();
    r.bound = "0 pixels in every frame".into();
    r.why = "edges snap to the coarser neighbour's grid from the same integer sample indices on both sides (bit-identical shared vertices), and a node is drawn until its children are all resident".into();
    let frames = form.pick(300, 1000);
    let size = form.pick([128, 96], [320, 180]);
    // 24 slots: the path needs more than that over its length, so nodes
    // are evicted and streamed in while the camera moves.
    let mut rig = Rig::new(ctx, size, SLOTS, RendererOptions::default(), Vec::new())?;
    let magenta = MAGENTA.map(|c| (c * 255.0) as u8);
    let (mut worst, mut total, mut bad_frames) = (0usize, 0usize, 0u32);
    let mut lods_seen = 0u32;
    let mut streamed = 0usize;
    for f in 0..frames {
        let view = rig.view(fly_through(&rig, f, frames));
        // The first frame waits for the roots (before them nothing can be
        // drawn at all); after that streaming runs behind the camera.
        let shot = if f == 0 { rig.settled_shot(ctx, &view)? } else { rig.shot(ctx, &view)? };
        let cracks = shot
            .depth
            .iter()
            .zip(shot.rgba.chunks_exact(4))
            .filter(|(d, c)| **d <= 0.0 || c[..3] == magenta[..3])
            .count();
        if cracks > 0 {
            bad_frames += 1;
            if r.details.len() < 5 {
                r.details.push(format!("frame {f}: {cracks} crack pixels, camera {}", view.camera));
            }
        }
        worst = worst.max(cracks);
        total += cracks;
        if let Some(c) = rig.renderer.latest_counters() {
            lods_seen |=
                c.traverse.nodes_per_lod.iter().enumerate().filter(|(_, n)| **n > 0).fold(0, |m, (l, _)| m | 1 << l);
        }
        streamed = rig.renderer.terrain.stats().arrived_total;
    }
    r.details.push(format!(
        "{frames} frames at {}x{}: {total} crack pixels in {bad_frames} frames; LODs drawn (bits) {lods_seen:#06b}; {streamed} nodes streamed into {SLOTS} slots",
        size[0], size[1]
    ));
    r.worst = format!("{worst} pixels");
    r.pass = total == 0;
    Ok(r)
}
