//! Shard manifests and the verification of a bake folder.
//!
//! Each shard of a bake writes `DIR/manifest/shard-I-of-N.json` when its
//! last node is on disk: the world, the four cache keys every node file
//! carries (hex), its unit range, and every node file it left with its size
//! and trailing crc32. [`verify`] then checks a folder against the whole
//! plan: every node present and valid (fully decoded, as a render reads
//! it), every manifest's files unchanged, and names the shards whose nodes
//! are missing, so a job array knows which tasks to rerun.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::bake_run::BakeStats;
use super::cache::{MissReason, NodeCache};
use super::error::{Result, WorldError};
use super::layout::{NodeId, WorldDesc};
use super::shard::ShardSplit;

/// Bumped whenever the manifest's fields change meaning.
pub const MANIFEST_VERSION: u32 = 1;
/// Examples of bad nodes a verification keeps per shard.
const EXAMPLES: usize = 3;

/// What one shard wrote.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShardManifest {
    pub version: u32,
    pub shard: u32,
    pub shards: u32,
    pub world: WorldDesc,
    /// World, source, hole set and bake settings hashes, hex.
    pub keys: [String; 4],
    /// Level the split cut at, and this shard's units in its order.
    pub split_lod: u8,
    pub units: [usize; 2],
    pub nodes: u64,
    pub baked: u64,
    pub cached: u64,
    pub bytes: u64,
    /// Unix seconds when the shard finished, and its seconds of work
    /// (error tiles and nodes).
    pub finished_unix_s: u64,
    pub seconds: f64,
    /// Every node file: `[lod, x, y, bytes, crc32]`.
    pub files: Vec<(u8, u32, u32, u64, u32)>,
}

/// `DIR/manifest/shard-I-of-N.json`.
pub fn manifest_path(dir: &Path, shard: u32, shards: u32) -> PathBuf {
    dir.join("manifest").join(format!("shard-{shard}-of-{shards}.json"))
}

impl ShardManifest {
    pub fn new(cache: &NodeCache, split: &ShardSplit, shard: u32, stats: &BakeStats) -> Self {
        let finished_unix_s =
            std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs());
        ShardManifest {
            version: MANIFEST_VERSION,
            shard,
            shards: split.count(),
            world: *cache.world(),
            keys: cache.keys().map(|k| format!("{k:016x}")),
            split_lod: split.split_lod(),
            units: split.unit_range(shard),
            nodes: stats.files.len() as u64,
            baked: stats.baked as u64,
            cached: stats.cached as u64,
            bytes: stats.bytes_on_disk,
            finished_unix_s,
            seconds: stats.seconds + stats.errors.seconds,
            files: stats.files.iter().map(|f| (f.id.lod, f.id.x, f.id.y, f.bytes, f.crc32)).collect(),
        }
    }

    /// Writes it atomically to [`manifest_path`].
    pub fn write(&self, dir: &Path) -> Result<PathBuf> {
        let path = manifest_path(dir, self.shard, self.shards);
        let folder = path.parent().expect("a manifest path has a folder");
        std::fs::create_dir_all(folder).map_err(|e| WorldError::create_dir(folder, e))?;
        let text = serde_json::to_string(self).expect("a manifest serialises");
        crate::output::write(&path, (text + "\n").as_bytes()).map_err(|e| WorldError::io_write(&path, e.error))?;
        Ok(path)
    }
}

/// A manifest file in the folder that is not one of this bake's.
#[derive(Clone, Debug, PartialEq)]
pub struct ForeignManifest {
    pub path: PathBuf,
    pub why: String,
}

/// One shard's state in a verified folder.
#[derive(Clone, Debug, PartialEq)]
pub struct ShardVerdict {
    pub shard: u32,
    pub has_manifest: bool,
    pub nodes: u64,
    /// Its nodes missing or invalid, and a few of them.
    pub bad: u64,
    pub examples: Vec<(NodeId, MissReason)>,
    /// Files its manifest lists that have changed since (size or crc32).
    pub changed: u64,
}

impl ShardVerdict {
    pub fn is_complete(&self) -> bool {
        self.has_manifest && self.bad == 0 && self.changed == 0
    }
}

/// What [`verify`] found.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct VerifyReport {
    /// Nodes of the whole world, and of those present and valid.
    pub nodes: u64,
    pub valid: u64,
    pub missing: u64,
    pub corrupt: u64,
    pub stale: u64,
    /// The shard count of this bake's manifests (`None`: no manifest), and
    /// each shard's state under it.
    pub shards: Option<u32>,
    pub verdicts: Vec<ShardVerdict>,
    pub foreign: Vec<ForeignManifest>,
    /// Temporaries a killed writer left beside the node and tile files
    /// (`.NAME.vista-tmp-PID-N`): harmless, and safe to delete once no bake
    /// writes into the folder.
    pub temporaries: Vec<PathBuf>,
    pub seconds: f64,
}

impl VerifyReport {
    /// Every node present and valid and every manifest's files unchanged.
    pub fn is_complete(&self) -> bool {
        self.valid == self.nodes && self.verdicts.iter().all(|v| v.changed == 0)
    }

    /// Shards to run again: missing manifests, missing or invalid nodes, or
    /// changed files.
    pub fn incomplete_shards(&self) -> Vec<u32> {
        self.verdicts.iter().filter(|v| !v.is_complete()).map(|v| v.shard).collect()
    }
}

/// Checks every node of `cache`'s world in its folder (each file read and
/// decoded as a render reads it) and the shard manifests there.
pub fn verify(cache: &NodeCache, dir: &Path) -> Result<VerifyReport> {
    let start = std::time::Instant::now();
    let world = *cache.world();
    let keys = cache.keys().map(|k| format!("{k:016x}"));
    let (mine, foreign) = read_manifests(dir, &world, &keys);
    let mut report = VerifyReport { foreign, ..VerifyReport::default() };
    // The count most manifests of this bake were written for.
    let mut counts: BTreeMap<u32, usize> = BTreeMap::new();
    for m in &mine {
        *counts.entry(m.shards).or_default() += 1;
    }
    report.shards = counts.iter().max_by_key(|(n, c)| (**c, **n)).map(|(n, _)| *n);
    for m in mine.iter().filter(|m| Some(m.shards) != report.shards) {
        let others = report.shards.map_or("none".to_string(), |n| n.to_string());
        let why = format!("written for {} shards; this bake's other manifests are for {others}", m.shards);
        report.foreign.push(ForeignManifest { path: manifest_path(dir, m.shard, m.shards), why });
    }
    let split = match report.shards {
        Some(n) => Some(ShardSplit::new(&world, n).map_err(|e| WorldError::InvalidConfig(e.to_string()))?),
        None => None,
    };
    let shards = split.as_ref().map_or(1, |s| s.count() as usize);
    let mut verdicts: Vec<ShardVerdict> = (0..shards as u32)
        .map(|shard| ShardVerdict {
            shard,
            has_manifest: mine.iter().any(|m| Some(m.shards) == report.shards && m.shard == shard),
            nodes: 0,
            bad: 0,
            examples: Vec::new(),
            changed: 0,
        })
        .collect();
    // Row by row in parallel; a list of the world's nodes is never made.
    let rows: Vec<(u8, u32)> =
        (0..world.lod_count as u8).flat_map(|l| (0..world.grid(l)[1]).map(move |y| (l, y))).collect();
    let found = rows
        .par_iter()
        .map(|&(lod, y)| {
            let mut part = Tally::new(shards);
            for x in 0..world.grid(lod)[0] {
                let id = NodeId::new(lod, x, y);
                let shard = split.as_ref().map_or(0, |s| s.shard_of(id)) as usize;
                part.add(shard, id, cache.read(id).err());
            }
            part
        })
        .reduce(|| Tally::new(shards), Tally::merge);
    report.nodes = found.nodes.iter().sum();
    report.valid = report.nodes - found.bad.iter().sum::<u64>();
    [report.missing, report.corrupt, report.stale] = found.reasons;
    for (v, ((nodes, bad), examples)) in
        verdicts.iter_mut().zip(found.nodes.into_iter().zip(found.bad).zip(found.examples))
    {
        (v.nodes, v.bad, v.examples) = (nodes, bad, examples);
    }
    for m in mine.iter().filter(|m| Some(m.shards) == report.shards) {
        let changed = m
            .files
            .par_iter()
            .filter(|&&(lod, x, y, bytes, crc)| cache.file_summary(NodeId::new(lod, x, y)).ok() != Some((bytes, crc)))
            .count() as u64;
        verdicts[m.shard as usize].changed = changed;
    }
    report.verdicts = if split.is_some() { verdicts } else { Vec::new() };
    report.temporaries = temporaries(dir, &world);
    report.seconds = start.elapsed().as_secs_f64();
    Ok(report)
}

/// Per-shard counts of a part of the world.
struct Tally {
    nodes: Vec<u64>,
    bad: Vec<u64>,
    examples: Vec<Vec<(NodeId, MissReason)>>,
    /// Missing, corrupt, stale.
    reasons: [u64; 3],
}

impl Tally {
    fn new(shards: usize) -> Self {
        Tally { nodes: vec![0; shards], bad: vec![0; shards], examples: vec![Vec::new(); shards], reasons: [0; 3] }
    }

    fn add(&mut self, shard: usize, id: NodeId, miss: Option<MissReason>) {
        self.nodes[shard] += 1;
        let Some(reason) = miss else { return };
        self.bad[shard] += 1;
        let r = match reason {
            MissReason::Missing => 0,
            MissReason::Corrupt => 1,
            MissReason::Stale => 2,
        };
        self.reasons[r] += 1;
        if self.examples[shard].len() < EXAMPLES {
            self.examples[shard].push((id, reason));
        }
    }

    fn merge(mut self, other: Tally) -> Tally {
        for s in 0..self.nodes.len() {
            self.nodes[s] += other.nodes[s];
            self.bad[s] += other.bad[s];
            let room = EXAMPLES - self.examples[s].len();
            self.examples[s].extend(other.examples[s].iter().take(room));
        }
        for r in 0..3 {
            self.reasons[r] += other.reasons[r];
        }
        self
    }
}

/// vista's temporaries in the node folders and the error-tile folders.
fn temporaries(dir: &Path, world: &WorldDesc) -> Vec<PathBuf> {
    let mut folders: Vec<PathBuf> = (0..world.lod_count).map(|l| dir.join(format!("lod{l}"))).collect();
    let mut found = Vec::new();
    let mut trees = vec![dir.join("errors")];
    while let Some(d) = trees.pop() {
        for e in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            if e.file_type().is_ok_and(|t| t.is_dir()) {
                folders.push(e.path());
                trees.push(e.path());
            }
        }
    }
    for f in folders {
        for e in std::fs::read_dir(&f).into_iter().flatten().flatten() {
            if crate::output::is_temporary(&e.file_name().to_string_lossy()) {
                found.push(e.path());
            }
        }
    }
    found.sort();
    found
}

/// The folder's manifests: this bake's (same world and keys) and the rest
/// with the reason they are not.
fn read_manifests(dir: &Path, world: &WorldDesc, keys: &[String; 4]) -> (Vec<ShardManifest>, Vec<ForeignManifest>) {
    let (mut mine, mut foreign) = (Vec::new(), Vec::new());
    let Ok(entries) = std::fs::read_dir(dir.join("manifest")) else { return (mine, foreign) };
    let mut paths: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .filter(|p| p.file_name().is_none_or(|n| n != super::bake_claim::CLAIM_FILE))
        .collect();
    paths.sort();
    for path in paths {
        let parsed = std::fs::read(&path)
            .map_err(|e| e.to_string())
            .and_then(|b| serde_json::from_slice::<ShardManifest>(&b).map_err(|e| format!("not a manifest: {e}")));
        let why = match parsed {
            Err(why) => why,
            Ok(m) if m.version != MANIFEST_VERSION => format!("manifest version {}, not {MANIFEST_VERSION}", m.version),
            Ok(m) if m.world != *world || m.keys != *keys => {
                "for another world, source, hole set or bake settings".to_string()
            }
            Ok(m) if m.shard >= m.shards || path != manifest_path(dir, m.shard, m.shards) => {
                format!("says shard {} of {}, which its name does not", m.shard, m.shards)
            }
            Ok(m) => {
                mine.push(m);
                continue;
            }
        };
        foreign.push(ForeignManifest { path, why });
    }
    (mine, foreign)
}
