//! Scene edits in a running `vista view`: when the scene file changes on
//! disk (checked once a second), or a flight's `scene FILE` line names
//! another file of the same world, its stamps are read again and the
//! renderer takes the edited source (`TerrainRenderer::replace_source`):
//! the resident nodes the changed stamps touch reload while the old ones
//! stay drawn. Only stamps are taken live; any other difference (the world,
//! its source, holes, effects, materials) is named and needs a restart.

use crate::world_args::{LoadedWorld, WorldArgs};
use anyhow::Result;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime};
use vista::render::TerrainRenderer;

/// How often the scene file's modification time is looked at.
const CHECK_EVERY: Duration = Duration::from_secs(1);

/// The scene file being watched.
pub struct SceneWatch {
    path: PathBuf,
    modified: Option<SystemTime>,
    checked: Instant,
}

impl SceneWatch {
    pub fn new(path: PathBuf) -> Self {
        let modified = modified(&path);
        SceneWatch { path, modified, checked: Instant::now() }
    }

    /// The file, when it changed since it was last seen.
    pub fn changed(&mut self, now: Instant) -> Option<PathBuf> {
        if now.duration_since(self.checked) < CHECK_EVERY {
            return None;
        }
        self.checked = now;
        let m = modified(&self.path);
        (m != self.modified).then(|| {
            self.modified = m;
            self.path.clone()
        })
    }
}

fn modified(path: &Path) -> Option<SystemTime> {
    std::fs::metadata(path).and_then(|m| m.modified()).ok()
}

/// The union of the boxes of the stamps that differ between two lists (by
/// position in the order: an edit, an addition, a removal or a reordering
/// changes the ground over both).
fn changed_region(old: &[(u64, [f64; 4])], new: &[(u64, [f64; 4])]) -> Option<[f64; 4]> {
    let mut region: Option<[f64; 4]> = None;
    for i in 0..old.len().max(new.len()) {
        let (a, b) = (old.get(i), new.get(i));
        if a.map(|s| s.0) == b.map(|s| s.0) {
            continue;
        }
        for bounds in [a, b].into_iter().flatten().map(|s| s.1) {
            region = Some(match region {
                None => bounds,
                Some(r) => [r[0].min(bounds[0]), r[1].min(bounds[1]), r[2].max(bounds[2]), r[3].max(bounds[3])],
            });
        }
    }
    region
}

/// Reads `file` as the scene of `args`' world and hands its stamps to the
/// renderer; `world` becomes the new world. Returns the line to print.
pub fn apply(args: &WorldArgs, file: &Path, world: &mut LoadedWorld, renderer: &mut TerrainRenderer) -> Result<String> {
    let name = file.display();
    let edited = WorldArgs { scene: Some(file.to_path_buf()), ..args.clone() }.load()?;
    if edited.desc != world.desc || edited.source.base_id_hash() != world.source.base_id_hash() {
        return Ok(format!("scene {name}: its world or terrain source differs: restart vista view to see it"));
    }
    let others = edited.holes != world.holes || edited.effects != world.effects;
    let note = if others { "; its other changes (holes, effects, materials) need a restart" } else { "" };
    let Some(region) = changed_region(&world.stamps, &edited.stamps) else {
        return Ok(format!("scene {name}: no stamp changed{note}"));
    };
    let reloaded = renderer.replace_source(std::sync::Arc::clone(&edited.source), Some(edited.bake.clone()), region)?;
    let n = edited.stamps.len();
    *world = edited;
    Ok(format!(
        "scene {name}: stamps changed over {:.0},{:.0} .. {:.0},{:.0} m ({n} now); {reloaded} resident nodes reload{note}",
        region[0], region[1], region[2], region[3]
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_changed_region_covers_edited_added_and_removed_stamps() {
        let a = (1, [0.0, 0.0, 10.0, 10.0]);
        let b = (2, [100.0, 100.0, 110.0, 110.0]);
        let b2 = (3, [120.0, 100.0, 130.0, 115.0]);
        assert_eq!(changed_region(&[a, b], &[a, b]), None);
        assert_eq!(changed_region(&[a, b], &[a, b2]), Some([100.0, 100.0, 130.0, 115.0]));
        assert_eq!(changed_region(&[a], &[a, b]), Some(b.1));
        assert_eq!(changed_region(&[a, b], &[b]), Some([0.0, 0.0, 110.0, 110.0]), "a removal shifts the order");
    }
}
