//! A scene's stamps, decals and assets that miss the world entirely are
//! refused, in one line in the user's coordinates: each would silently do
//! nothing (a stamp changes no height, a decal and an asset are never
//! drawn), which is almost always a typo or a wrong origin. Holes that miss
//! get a note instead (`world_spec::note_holes_outside`), as before: a hole
//! list is often shared between worlds.

use anyhow::Result;
use vista::effects::assets::Asset;
use vista::effects::virtual_texture::decals::{Decal, DecalShape};
use vista::world::WorldDesc;

use crate::scene::SceneStampSpec;
use crate::InputError;

/// Refuses the first placement (world-relative) whose bounds miss `desc`.
pub fn check_inside(
    scene: &std::path::Path,
    stamps: &[SceneStampSpec],
    decals: &[Decal],
    assets: &[Asset],
    desc: &WorldDesc,
    origin_m: [f64; 2],
) -> Result<()> {
    let [ox, oy] = origin_m;
    let misses = |[x0, y0, x1, y1]: [f64; 4]| x1 < 0.0 || y1 < 0.0 || x0 > desc.extent_m[0] || y0 > desc.extent_m[1];
    let refuse = |what: String, effect: &str| -> Result<()> {
        let message = format!(
            "scene file {}: {what} lies outside the world ({ox}..{} x {oy}..{} m): {effect}",
            scene.display(),
            ox + desc.extent_m[0],
            oy + desc.extent_m[1]
        );
        Err(InputError(message).into())
    };
    for (i, st) in stamps.iter().enumerate() {
        let p = &st.placement;
        // The rotated square lies within its half diagonal of the centre.
        let r = p.size_m * std::f64::consts::FRAC_1_SQRT_2;
        let [cx, cy] = p.center_m;
        if misses([cx - r, cy - r, cx + r, cy + r]) {
            let what = format!("stamp {} ({} at {},{})", i + 1, st.source.display(), cx + ox, cy + oy);
            return refuse(what, "it would change no height");
        }
    }
    for (i, d) in decals.iter().enumerate() {
        let (b, at) = match &d.shape {
            DecalShape::Quad { center_m, size_m, .. } => {
                let r = size_m.length() * 0.5;
                ([center_m.x - r, center_m.y - r, center_m.x + r, center_m.y + r], *center_m)
            }
            DecalShape::Road { points_m, width_m, .. } => {
                let lo = points_m.iter().fold(points_m[0], |a, p| a.min(*p)) - *width_m;
                let hi = points_m.iter().fold(points_m[0], |a, p| a.max(*p)) + *width_m;
                ([lo.x, lo.y, hi.x, hi.y], points_m[0])
            }
        };
        if misses(b) {
            return refuse(format!("decal {} (at {},{})", i + 1, at.x + ox, at.y + oy), "it would never be drawn");
        }
    }
    for (i, a) in assets.iter().enumerate() {
        let [x, y] = a.at_m;
        if misses([x, y, x, y]) {
            let what = format!("asset {} ({} at {},{})", i + 1, a.kind.name(), x + ox, y + oy);
            return refuse(what, "it would never be drawn");
        }
    }
    Ok(())
}

/// A control map much coarser than the splat texels it feeds (one per two
/// samples) paints whole slopes with one word: legal, often meant, but
/// worth a line (grass up a cliff is what a user sees otherwise).
pub fn note_coarse_control_map(path: &std::path::Path, desc: &WorldDesc) {
    // Of another shape, or unreadable: the renderer refuses it, in one line.
    let Ok(([w, h], [tx, ty])) = vista::world::control_map_texels(path, desc.extent_m) else { return };
    let texel = tx.max(ty);
    let splat = 2.0 * desc.spacing_m;
    if texel > 16.0 * splat {
        eprintln!(
            "note: control map {} is {w} x {h} over {} x {} m: a word per {texel:.0} m, {:.0} splat texels a side \
             (materials change in {texel:.0} m steps)",
            path.display(),
            desc.extent_m[0],
            desc.extent_m[1],
            texel / splat
        );
    }
}
