//! What a world costs or where it reaches, said before any work: a placed
//! world beyond the proven range refused, a spacing far finer than its
//! height map and a long error tree noted, each in one line.

use std::path::Path;

use anyhow::{bail, Result};
use vista::world::{GeoTiffInfo, WorldDesc};

use crate::heightmap_files::MapKind;
use crate::world_args::show_m;

/// The whole world, not only its corner, within the range `vista
/// stability` proves exact: otherwise the first camera over it (the
/// default one too) would be refused, naming a camera nobody gave.
pub fn check_far_corner(desc: &WorldDesc, origin_m: [f64; 2], name: &str) -> Result<()> {
    // Unplaced, a world that large is the plan's to refuse (its sectors).
    if origin_m == [0.0, 0.0] {
        return Ok(());
    }
    let far = [origin_m[0] + desc.extent_m[0], origin_m[1] + desc.extent_m[1]];
    let limit = crate::render_cmd::PROVEN_RANGE_M;
    if far.iter().any(|v| v.abs() > limit) {
        bail!(
            "{name} {},{}: the world then reaches {},{} m, beyond +-{limit:e} m, outside what `vista stability` \
             case 1 proves exact",
            show_m(origin_m[0]),
            show_m(origin_m[1]),
            show_m(far[0]),
            show_m(far[1])
        );
    }
    Ok(())
}

/// The error tree reads every LOD-0 sample under the roots it computes
/// before the first frame: a line first when that is long (the plan's
/// per-quad estimate) or needs much memory (a root's tile covers its whole
/// area), so a new world does not sit silent for minutes or swap.
pub fn note_error_tree_time(desc: &WorldDesc, uncached: usize) {
    if uncached == 0 {
        return;
    }
    let plan = vista::world::WorldPlan::new(desc, None);
    let seconds = plan.error_seconds() * uncached as f64 / desc.roots().len().max(1) as f64;
    if seconds >= 30.0 {
        eprintln!(
            "note: the error tree of {uncached} roots needs every LOD-0 sample under them once (cached after): about \
             {seconds:.0} s on {} threads before the first frame; a coarser --spacing shortens it",
            plan.threads
        );
    }
    let m = plan.error_memory();
    let peak = m.peak.min(2 * m.per_root * uncached as u64);
    if peak >= vista::world::LARGE_ERROR_MEMORY {
        eprintln!(
            "note: the error tree needs about {} of memory while it computes ({} a root tile, as large as the root's \
             area at every level, and its file's bytes); fewer --lods make smaller roots",
            vista::world::human_bytes(peak as f64),
            vista::world::human_bytes(m.per_root as f64)
        );
    }
}

/// A spacing far finer than the map's pixels (32 x and more; the scenes'
/// Mont Blanc at 8 m is 12 x) plans nodes of interpolated
/// detail (all but one in N^2 samples between posts): legal, and what the
/// refinement asks for, but a plan of thousands of times the map's posts
/// deserves a line before any work (a GeoTIFF's spacing defaults to its
/// pixel size; a PNG's does not know it).
pub fn note_spacing_beyond_map(path: &Path, kind: MapKind, geotiff: Option<&GeoTiffInfo>, desc: &WorldDesc) {
    let pixel_m = match (kind, geotiff) {
        (_, Some(g)) => g.pixel_m.map(|p| p[0].min(p[1])),
        (MapKind::Png, None) => vista::world::Png16Source::header(path)
            .ok()
            .map(|(w, h)| (desc.extent_m[0] / f64::from(w)).min(desc.extent_m[1] / f64::from(h))),
        _ => None,
    };
    let Some(pixel_m) = pixel_m else { return };
    let finer = pixel_m / desc.spacing_m;
    if finer >= 32.0 {
        eprintln!(
            "note: spacing {} m is {finer:.0} x finer than {}'s {pixel_m:.1} m pixels: {:.0} samples per post, \
             interpolated (Catmull-Rom); --spacing {pixel_m:.1} draws the posts themselves",
            show_m(desc.spacing_m),
            path.display(),
            finer * finer
        );
    }
}
