//! One folder, one sharded bake. The shards of a job array write into one
//! folder with no merge step, so two bakes mixed there (another world, an
//! edited source, another shard count) would each succeed and leave a
//! folder no render can trust. Before it writes a node, a shard therefore
//! checks the folder's shard manifests and claims the folder in
//! `manifest/bake-claim.json`: the first shard to start writes it (a hard
//! link, so shards starting at once cannot both win), the others compare.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::cache::NodeCache;
use super::error::{Result, WorldError};
use super::layout::WorldDesc;
use super::manifest::{ShardManifest, MANIFEST_VERSION};

/// The claim's file name in `DIR/manifest`.
pub const CLAIM_FILE: &str = "bake-claim.json";

/// What a folder's bake is: its world, cache keys and shard count.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Claim {
    version: u32,
    shards: u32,
    world: WorldDesc,
    /// World, source, hole set and bake settings hashes, hex (as manifests).
    keys: [String; 4],
}

impl Claim {
    fn of(m: &ShardManifest) -> Self {
        Claim { version: m.version, shards: m.shards, world: m.world, keys: m.keys.clone() }
    }

    /// In the user's terms, beside `other`: the shard count and what the
    /// world is ("this world" where the two agree).
    fn describe(&self, other: &Claim) -> String {
        let w = &self.world;
        let what = if self.world != other.world {
            format!("a {} x {} m world at {} m spacing", w.extent_m[0], w.extent_m[1], w.spacing_m)
        } else if self.keys != other.keys {
            // The same extent: name what differs, with this bake's key of it.
            let kinds = ["world", "height source", "hole set", "bake settings"];
            let differs: Vec<String> = (1..4)
                .filter(|&k| self.keys[k] != other.keys[k])
                .map(|k| format!("{} {}", kinds[k], &self.keys[k][..8]))
                .collect();
            format!("this world with {}", differs.join(", "))
        } else {
            "this world".to_string()
        };
        format!("{} shards of {what}", self.shards)
    }
}

/// Refuses `dir` for shard `shard` of `shards` when its manifests or claim
/// describe another bake (one line naming both); otherwise claims it.
pub fn claim_folder(cache: &NodeCache, dir: &Path, shard: u32, shards: u32) -> Result<()> {
    let ours = Claim {
        version: MANIFEST_VERSION,
        shards,
        world: *cache.world(),
        keys: cache.keys().map(|k| format!("{k:016x}")),
    };
    let refuse = |theirs: String, ours: String| {
        WorldError::ForeignBake(format!(
            "--shard {shard}/{shards}: {} holds a bake of {theirs}; this one is {ours}: bake into another folder, or \
             remove {} to replace that bake",
            dir.display(),
            dir.join("manifest").display()
        ))
    };
    let refuse_claim = |theirs: &Claim| refuse(theirs.describe(&ours), ours.describe(theirs));
    if let Some(other) = manifests(dir).iter().map(Claim::of).find(|c| *c != ours) {
        return Err(refuse_claim(&other));
    }
    let folder = dir.join("manifest");
    std::fs::create_dir_all(&folder).map_err(|e| WorldError::create_dir(&folder, e))?;
    let path = folder.join(CLAIM_FILE);
    let text = serde_json::to_string(&ours).expect("a claim serialises") + "\n";
    if crate::output::write_new(&path, text.as_bytes()).map_err(|e| WorldError::io_write(&path, e.error))? {
        return Ok(());
    }
    let bytes = std::fs::read(&path).map_err(|e| WorldError::io(&path, e))?;
    match serde_json::from_slice::<Claim>(&bytes) {
        Ok(theirs) if theirs == ours => Ok(()),
        Ok(theirs) => Err(refuse_claim(&theirs)),
        Err(e) => Err(refuse(format!("an unreadable claim ({}: {e})", path.display()), ours.describe(&ours))),
    }
}

/// The folder's readable shard manifests (unreadable ones are `verify`'s
/// to report; they describe no bake).
fn manifests(dir: &Path) -> Vec<ShardManifest> {
    let Ok(entries) = std::fs::read_dir(dir.join("manifest")) else { return Vec::new() };
    entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.file_name().is_some_and(|n| n.to_string_lossy().starts_with("shard-")))
        .filter_map(|p| serde_json::from_slice::<ShardManifest>(&std::fs::read(p).ok()?).ok())
        .filter(|m| m.version == MANIFEST_VERSION)
        .collect()
}
