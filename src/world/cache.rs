//! One file per baked node, validated by header and checksum on every read.
//!
//! Layout (little-endian): magic "VNOD", format version u32, world hash u64,
//! source region hash u64, holes hash u64, bake settings hash u64, lod u8, x
//! u32, y u32, payload length u32 (uncompressed), the payload
//! ([`BakedNode::to_bytes`]) as one zstd frame, crc32 of all preceding bytes.
//!
//! The source and hole keys are a node's own ([`NodeCache::node_keys`]):
//! they cover only what its bake reads (the source over the node and the
//! samples around it, the holes touching that), so an edit (a stamp added
//! or moved, a hole cut, a height map retouched) makes exactly the nodes it
//! touches stale, and their ancestors, whose areas hold it too.
//!
//! zstd because it is the general-purpose compressor with the best speed
//! for its ratio at low levels, and decompression (on the streaming path)
//! runs at GB/s; the checksum covers the compressed bytes, so a damaged
//! file is caught before the decompressor sees it.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use super::bake::{bake_node_with, BakeSettings};
use super::error::{Result, WorldError};
use super::errors::ErrorTree;
use super::holes::{holes_hash, Hole};
use super::layout::{NodeId, WorldDesc};
use super::payload::BakedNode;
use super::source::HeightSource;
use super::texels::PayloadFormat;

/// File magic: identifies a vista node file.
const MAGIC: [u8; 4] = *b"VNOD";
/// Bumped whenever the file layout or the bake's output changes.
const FORMAT_VERSION: u32 = 8;
/// Bytes before the payload.
const HEADER_BYTES: usize = 4 + 4 + 8 * 4 + 1 + 4 + 4 + 4;
/// zstd level: 3 (zstd's default) measured within 1 % of level 9's size on
/// default-world nodes (BC blocks are near-random; heights compress) at a
/// fraction of its time.
const ZSTD_LEVEL: i32 = 3;
/// Trailing crc32.
const CRC_BYTES: usize = 4;
/// The user's vista cache (error trees, and node files where a tool bakes
/// into it): `$VISTA_CACHE` (empty: none, everything in memory), else
/// `$XDG_CACHE_HOME/vista`, else `~/.cache/vista`; `None` without any.
pub fn default_cache_dir() -> Option<PathBuf> {
    if let Some(v) = std::env::var_os("VISTA_CACHE") {
        return (!v.is_empty()).then(|| PathBuf::from(v));
    }
    let xdg = std::env::var_os("XDG_CACHE_HOME").filter(|v| !v.is_empty()).map(PathBuf::from);
    xdg.or_else(|| std::env::var_os("HOME").filter(|v| !v.is_empty()).map(|h| Path::new(&h).join(".cache")))
        .map(|d| d.join("vista"))
}

/// Bytes a node file of `format` would take without compression: what the
/// cache's compression ratio is measured against.
pub fn uncompressed_file_bytes(format: PayloadFormat) -> u64 {
    (HEADER_BYTES + BakedNode::serialized_bytes(format, false) + CRC_BYTES) as u64
}

/// zstd's ratio over the node files of the whole default world (1.49:1,
/// `vista bake` with BC payloads); plans use it before anything is baked.
const PLANNED_ZSTD_RATIO: f64 = 1.49;

/// Bytes of one node file, for plans made before anything is baked.
pub fn estimated_file_bytes(format: PayloadFormat) -> u64 {
    (uncompressed_file_bytes(format) as f64 / PLANNED_ZSTD_RATIO) as u64
}

/// Metres around a node that its bake reads besides its own area, in its
/// own sample steps: the atlas border (2 samples) and the half-step grid's
/// central differences beyond it.
const BAKE_MARGIN_STEPS: f64 = 3.0;

/// The area whose source and holes decide node `id`'s file: its bounds and
/// the samples its bake reads around them ([min x, min y, max x, max y]).
pub fn bake_region(world: &WorldDesc, id: NodeId) -> [f64; 4] {
    let b = world.bounds_m(id);
    let m = BAKE_MARGIN_STEPS * world.node_spacing_m(id.lod);
    [b[0] - m, b[1] - m, b[2] + m, b[3] + m]
}

/// Why a node was (re)baked instead of read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CacheOutcome {
    Hit,
    Baked(MissReason),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MissReason {
    /// No file yet.
    Missing,
    /// Wrong magic, version, length or checksum.
    Corrupt,
    /// Valid file for another world, source, hole set or node.
    Stale,
}

fn overlaps(a: [f64; 4], b: [f64; 4]) -> bool {
    a[0] <= b[2] && a[2] >= b[0] && a[1] <= b[3] && a[3] >= b[1]
}

/// Node cache for one world + source + hole set under a directory.
pub struct NodeCache {
    dir: PathBuf,
    world: WorldDesc,
    source: Arc<dyn HeightSource>,
    holes: Vec<Hole>,
    settings: BakeSettings,
    keys: [u64; 4],
    errors: Arc<ErrorTree>,
    /// A write failed while rendering: reported once, then no more writes.
    unwritable: AtomicBool,
}

impl NodeCache {
    /// Creates `dir` if needed; default [`BakeSettings`]. Fails on an
    /// invalid world.
    pub fn new(dir: &Path, world: WorldDesc, source: Arc<dyn HeightSource>, holes: Vec<Hole>) -> Result<Self> {
        Self::with_settings(dir, world, source, holes, BakeSettings::default())
    }

    /// As [`Self::new`], baking with `settings`.
    pub fn with_settings(
        dir: &Path,
        world: WorldDesc,
        source: Arc<dyn HeightSource>,
        holes: Vec<Hole>,
        settings: BakeSettings,
    ) -> Result<Self> {
        world.validate()?;
        settings.materials.validate()?;
        std::fs::create_dir_all(dir).map_err(|e| WorldError::create_dir(dir, e))?;
        let keys = [world.hash(), source.id_hash(), holes_hash(&holes), settings.hash()];
        let errors = Arc::new(ErrorTree::new(&world, Arc::clone(&source), Some(dir))?);
        Ok(NodeCache {
            dir: dir.to_path_buf(),
            world,
            source,
            holes,
            settings,
            keys,
            errors,
            unwritable: AtomicBool::new(false),
        })
    }

    /// Takes its errors from `errors` (shared with other users of the
    /// world, cached where that tree is) instead of `DIR/errors`.
    pub fn with_errors(mut self, errors: Arc<ErrorTree>) -> Self {
        assert!(errors.is_for(&self.world, self.source.as_ref()), "an error tree of another world or source");
        self.errors = errors;
        self
    }

    pub fn world(&self) -> &WorldDesc {
        &self.world
    }

    /// The world's error tree (tiles cached under `DIR/errors`).
    pub fn errors(&self) -> &ErrorTree {
        &self.errors
    }

    /// The world, source, hole set and bake settings hashes of the whole
    /// world: its identity in shard manifests.
    pub fn keys(&self) -> [u64; 4] {
        self.keys
    }

    /// The keys node `id`'s file carries and must match to be read: the
    /// world and the bake settings, the source's [`HeightSource::region_hash`]
    /// over its [`bake_region`] and the holes touching that.
    pub fn node_keys(&self, id: NodeId) -> [u64; 4] {
        let r = bake_region(&self.world, id);
        let near: Vec<Hole> = self.holes.iter().filter(|h| overlaps(h.bounds(), r)).cloned().collect();
        let control = self.settings.control.as_ref().map_or(0, |c| c.region_hash(r));
        [self.keys[0], self.source.region_hash(r), holes_hash(&near), self.keys[3] ^ control]
    }

    /// A node file's size and its trailing crc32 (of every byte before it),
    /// read from its last four bytes: what a shard's manifest records.
    pub fn file_summary(&self, id: NodeId) -> Result<(u64, u32)> {
        use std::io::{Read, Seek, SeekFrom};
        let path = self.path(id);
        let mut file = std::fs::File::open(&path).map_err(|e| WorldError::io(&path, e))?;
        let mut crc = [0u8; CRC_BYTES];
        let len = file
            .seek(SeekFrom::End(-(CRC_BYTES as i64)))
            .and_then(|at| file.read_exact(&mut crc).map(|()| at + CRC_BYTES as u64))
            .map_err(|e| WorldError::io(&path, e))?;
        Ok((len, u32::from_le_bytes(crc)))
    }

    /// `DIR/lod{k}/{x}_{y}.vnode`.
    pub fn path(&self, id: NodeId) -> PathBuf {
        self.dir.join(format!("lod{}", id.lod)).join(format!("{}_{}.vnode", id.x, id.y))
    }

    /// Reads and fully validates a cached node.
    pub fn read(&self, id: NodeId) -> std::result::Result<BakedNode, MissReason> {
        let bytes = std::fs::read(self.path(id)).map_err(|_| MissReason::Missing)?;
        self.decode(id, &bytes)
    }

    fn decode(&self, id: NodeId, bytes: &[u8]) -> std::result::Result<BakedNode, MissReason> {
        if bytes.len() < HEADER_BYTES + CRC_BYTES {
            return Err(MissReason::Corrupt);
        }
        let (body, crc) = bytes.split_at(bytes.len() - CRC_BYTES);
        let crc = u32::from_le_bytes([crc[0], crc[1], crc[2], crc[3]]);
        if crc32fast::hash(body) != crc || body[..4] != MAGIC {
            return Err(MissReason::Corrupt);
        }
        let u32_at = |o: usize| u32::from_le_bytes([body[o], body[o + 1], body[o + 2], body[o + 3]]);
        let u64_at = |o: usize| (u64::from(u32_at(o + 4)) << 32) | u64::from(u32_at(o));
        if u32_at(4) != FORMAT_VERSION {
            return Err(MissReason::Corrupt);
        }
        let keys = [u64_at(8), u64_at(16), u64_at(24), u64_at(32)];
        let file_id = NodeId::new(body[40], u32_at(41), u32_at(45));
        if keys != self.node_keys(id) || file_id != id {
            return Err(MissReason::Stale);
        }
        let len = u32_at(49) as usize;
        if len != BakedNode::serialized_bytes(self.settings.format, self.settings.control.is_some()) {
            return Err(MissReason::Corrupt);
        }
        let payload = zstd::bulk::decompress(&body[HEADER_BYTES..], len).map_err(|_| MissReason::Corrupt)?;
        if payload.len() != len {
            return Err(MissReason::Corrupt);
        }
        match BakedNode::from_bytes(&payload) {
            Some(node) if node.id == id => Ok(node),
            _ => Err(MissReason::Corrupt),
        }
    }

    /// Serialises a node to the file format.
    fn encode(&self, node: &BakedNode) -> Result<Vec<u8>> {
        let payload = node.to_bytes();
        let packed =
            zstd::bulk::compress(&payload, ZSTD_LEVEL).map_err(|e| WorldError::io_write(self.path(node.id), e))?;
        let mut out = Vec::with_capacity(HEADER_BYTES + packed.len() + CRC_BYTES);
        out.extend_from_slice(&MAGIC);
        out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        for k in self.node_keys(node.id) {
            out.extend_from_slice(&k.to_le_bytes());
        }
        out.push(node.id.lod);
        out.extend_from_slice(&node.id.x.to_le_bytes());
        out.extend_from_slice(&node.id.y.to_le_bytes());
        out.extend_from_slice(&(payload.len() as u32).to_le_bytes());
        out.extend_from_slice(&packed);
        let crc = crc32fast::hash(&out);
        out.extend_from_slice(&crc.to_le_bytes());
        Ok(out)
    }

    /// Writes atomically (temp file + rename), so readers never see a
    /// half-written file. Returns the bytes written.
    pub fn write(&self, node: &BakedNode) -> Result<u64> {
        let path = self.path(node.id);
        let dir = path.parent().unwrap_or(&self.dir);
        std::fs::create_dir_all(dir).map_err(|e| WorldError::create_dir(dir, e))?;
        let bytes = self.encode(node)?;
        crate::output::write(&path, &bytes).map_err(|e| WorldError::io_write(&path, e.error))?;
        Ok(bytes.len() as u64)
    }

    /// The cached node if its file is intact and current, else a fresh bake
    /// that replaces the file.
    /// A file that cannot be written is an error (a bake).
    pub fn get_or_bake(&self, id: NodeId) -> Result<(BakedNode, CacheOutcome)> {
        self.get_or_bake_with(id, true)
    }

    /// As [`Self::get_or_bake`], but a cache that cannot be written (a full
    /// disk) is reported once and the node returned uncached; later nodes
    /// are not written: a render goes on without caching.
    pub fn get_or_bake_for_render(&self, id: NodeId) -> Result<(BakedNode, CacheOutcome)> {
        self.get_or_bake_with(id, false)
    }

    fn get_or_bake_with(&self, id: NodeId, must_write: bool) -> Result<(BakedNode, CacheOutcome)> {
        if !self.world.is_valid(id) {
            return Err(WorldError::InvalidNode(id));
        }
        match self.read(id) {
            Ok(node) => Ok((node, CacheOutcome::Hit)),
            Err(reason) => {
                if reason != MissReason::Missing {
                    log::debug!("rebaking {id}: cache file {reason:?}");
                }
                let mut node = bake_node_with(self.source.as_ref(), &self.world, &self.holes, &self.settings, id);
                self.errors.attach(&mut node)?;
                if !node.errors_pending() && !self.unwritable.load(Ordering::Relaxed) {
                    match self.write(&node) {
                        Ok(_) => {}
                        Err(e) if must_write => return Err(e),
                        Err(e) => {
                            if !self.unwritable.swap(true, Ordering::Relaxed) {
                                log::warn!("{e}; the render goes on without caching nodes in {}", self.dir.display());
                            }
                        }
                    }
                }
                Ok((node, CacheOutcome::Baked(reason)))
            }
        }
    }
}
