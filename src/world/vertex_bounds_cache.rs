//! A disk cache of a world's per-vertex bounds ([`super::vertex_bounds`]).
//! They read every LOD-0 sample and every level (over 8 minutes for the
//! default world on 2 cores) and depend only on the world, its source and
//! its holes, so one file per such triple is kept beside the error tree's
//! tiles and read back in place of the computation.
//!
//! Layout (little-endian): magic, version, four keys (world, source, holes,
//! the rule's arithmetic), the lattice's sides and its LOD-0 nodes' count,
//! their refinement bounds (3 f32 each), then bands of 256 rows (`BAND_ROWS`),
//! each a `u64` length, a crc32 and the zstd of the band's planes: height
//! codes (u16: the stored heights are R16 decoded), error and reach (f32
//! bits), flags (hole 1, empty 2). Bands are packed on their own, so they
//! are packed and unpacked in parallel, a batch at a time.

use super::holes::{holes_hash, Hole};
use super::layout::WorldDesc;
use super::source::HeightSource;
use super::vertex_bounds::{NodeRefine, VertexBoundsTree};
use super::WorldError;
use crate::shaders::consts::REFINE_LEVELS;
use rayon::prelude::*;
use std::fmt;
use std::io::{BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

const MAGIC: [u8; 4] = *b"VVB\0";
/// Raised whenever the bounds' arithmetic changes: older files are then
/// recomputed (they are keyed by it).
const ARITHMETIC: u64 = 1;
/// Added for worlds whose lattice passes their edge: version 1 read the
/// samples past it as holes, which version 2 continues from the edge
/// (`vertex_bounds`); the other worlds' numbers are the same bits.
const PAST_EDGE: u64 = 1;
const FORMAT: u32 = 1;
const BAND_ROWS: usize = 256;
/// Bytes a sample takes unpacked: code, error, reach, flags.
const SAMPLE_BYTES: usize = 2 + 4 + 4 + 1;

/// Whether a lattice sample of `world` lies outside its extent.
fn lattice_passes_edge(world: &WorldDesc) -> bool {
    let [w, h] = VertexBoundsTree::lattice_side(world);
    let (first, last) = (world.sample_pos(0, 0), world.sample_pos(w as i64 - 1, h as i64 - 1));
    let slack = world.spacing_m * 1e-6;
    (0..2).any(|a| first[a] < -slack || last[a] > world.extent_m[a] + slack)
}

/// Where a world's bounds came from ([`compute_cached`]).
#[derive(Clone, Debug)]
pub struct BoundsOrigin {
    /// The cache file (none: no cache folder).
    pub file: Option<PathBuf>,
    /// Read from `file` (else computed).
    pub read: bool,
    pub seconds: f64,
    /// Why an existing file was not read, or the file not written.
    pub note: Option<String>,
}

impl fmt::Display for BoundsOrigin {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let verb = if self.read { "read" } else { "computed" };
        write!(f, "{verb} in {:.1} s", self.seconds)?;
        match (&self.file, self.read, &self.note) {
            (None, _, _) => write!(f, " (no cache folder)"),
            (Some(p), true, _) => write!(f, " from {}", p.display()),
            (Some(p), false, None) => write!(f, ", cached in {}", p.display()),
            (Some(p), false, Some(n)) => write!(f, " ({}: {n})", p.display()),
        }
    }
}

/// The bounds of `world` from `source` with `holes`: read from `dir` when
/// a file of the same keys is there and whole, else computed and written
/// there (a file that cannot be written is reported in the origin, not an
/// error: the bounds are still good).
pub fn compute_cached(
    world: &WorldDesc,
    source: &dyn HeightSource,
    holes: &[Hole],
    dir: Option<&Path>,
) -> Result<(VertexBoundsTree, BoundsOrigin), WorldError> {
    let start = Instant::now();
    let arithmetic = ARITHMETIC + if lattice_passes_edge(world) { PAST_EDGE } else { 0 };
    let keys = [world.hash(), source.id_hash(), holes_hash(holes), arithmetic ^ u64::from(REFINE_LEVELS) << 32];
    let file = dir.map(|d| d.join(format!("{:016x}{:016x}{:016x}.vvb", keys[0], keys[1], keys[2])));
    let mut note = None;
    if let Some(path) = &file {
        match read(path, world, keys) {
            Ok(tree) => {
                let origin = BoundsOrigin { file, read: true, seconds: start.elapsed().as_secs_f64(), note };
                return Ok((tree, origin));
            }
            Err(Miss::Absent) => {}
            Err(Miss::Unusable(why)) => note = Some(format!("not read: {why}; recomputed")),
        }
    }
    let tree = VertexBoundsTree::compute(world, source, holes)?;
    if let Some(path) = &file {
        if let Err(e) = write(path, &tree, keys) {
            note = Some(format!("not cached: {e}"));
        }
    }
    Ok((tree, BoundsOrigin { file, read: false, seconds: start.elapsed().as_secs_f64(), note }))
}

enum Miss {
    Absent,
    Unusable(String),
}

impl From<std::io::Error> for Miss {
    fn from(e: std::io::Error) -> Self {
        match e.kind() {
            std::io::ErrorKind::NotFound => Miss::Absent,
            std::io::ErrorKind::UnexpectedEof => Miss::Unusable("cut short".into()),
            _ => Miss::Unusable(e.to_string()),
        }
    }
}

fn header(keys: [u64; 4], side: [usize; 2], nodes: usize) -> Vec<u8> {
    let mut out = MAGIC.to_vec();
    out.extend_from_slice(&FORMAT.to_le_bytes());
    let words = keys.into_iter().chain([side[0] as u64, side[1] as u64, nodes as u64, BAND_ROWS as u64]);
    for k in words {
        out.extend_from_slice(&k.to_le_bytes());
    }
    out
}

fn write(path: &Path, tree: &VertexBoundsTree, keys: [u64; 4]) -> Result<(), WorldError> {
    let dir = path.parent().expect("a cache file has a folder");
    std::fs::create_dir_all(dir).map_err(|e| WorldError::create_dir(dir, e))?;
    let parts = tree.parts();
    crate::output::write_with(path, |w| {
        w.write_all(&header(keys, parts.side, parts.lod0_refine.len()))?;
        for r in parts.lod0_refine {
            for v in [r.error_m, r.z_lo_m, r.z_hi_m] {
                w.write_all(&v.to_le_bytes())?;
            }
        }
        let band = BAND_ROWS * parts.side[0];
        let bands = parts.error.len().div_ceil(band);
        for batch in (0..bands).collect::<Vec<_>>().chunks(rayon::current_num_threads() * 2) {
            let packed: Vec<std::io::Result<Vec<u8>>> = batch
                .par_iter()
                .map(|b| pack(tree, &parts, b * band..((b + 1) * band).min(parts.error.len())))
                .collect();
            for p in packed {
                let p = p?;
                w.write_all(&(p.len() as u64).to_le_bytes())?;
                w.write_all(&crc32fast::hash(&p).to_le_bytes())?;
                w.write_all(&p)?;
            }
        }
        Ok(())
    })
    .map_err(|e| WorldError::io_write(path, e.error))
}

fn pack(tree: &VertexBoundsTree, parts: &Parts<'_>, range: std::ops::Range<usize>) -> std::io::Result<Vec<u8>> {
    let mut raw = Vec::with_capacity(range.len() * SAMPLE_BYTES);
    let world = tree.world();
    for z in &parts.z[range.clone()] {
        let code = world.encode_height(*z);
        if world.decode_height(code).to_bits() != z.to_bits() {
            return Err(std::io::Error::other(format!("height {z} m is not a stored (R16) height")));
        }
        raw.extend_from_slice(&code.to_le_bytes());
    }
    for v in parts.error[range.clone()].iter().chain(&parts.reach[range.clone()]) {
        raw.extend_from_slice(&v.to_le_bytes());
    }
    let flags = parts.hole[range.clone()].iter().zip(&parts.empty[range]);
    raw.extend(flags.map(|(h, e)| u8::from(*h) | u8::from(*e) << 1));
    zstd::bulk::compress(&raw, 1)
}

/// The arrays a file holds, borrowed from a tree.
pub(super) struct Parts<'a> {
    pub side: [usize; 2],
    pub z: &'a [f32],
    pub hole: &'a [bool],
    pub error: &'a [f32],
    pub reach: &'a [f32],
    pub empty: &'a [bool],
    pub lod0_refine: &'a [NodeRefine],
}

/// The arrays a file fills, owned.
pub(super) struct OwnedParts {
    pub side: [usize; 2],
    pub z: Vec<f32>,
    pub hole: Vec<bool>,
    pub error: Vec<f32>,
    pub reach: Vec<f32>,
    pub empty: Vec<bool>,
    pub lod0_refine: Vec<NodeRefine>,
}

fn read(path: &Path, world: &WorldDesc, keys: [u64; 4]) -> Result<VertexBoundsTree, Miss> {
    let mut r = BufReader::with_capacity(1 << 20, std::fs::File::open(path)?);
    let mut head = vec![0u8; 8 + 8 * 8];
    r.read_exact(&mut head)?;
    let word = |i: usize| u64::from_le_bytes(head[8 + 8 * i..16 + 8 * i].try_into().unwrap());
    let format = head[..4] == MAGIC && head[4..8] == FORMAT.to_le_bytes() && word(7) == BAND_ROWS as u64;
    if !format || (0..4).any(|i| word(i) != keys[i]) {
        return Err(Miss::Unusable("another format or other keys".into()));
    }
    let side = [word(4) as usize, word(5) as usize];
    let expected = VertexBoundsTree::lattice_side(world);
    if side != expected || word(6) as usize != VertexBoundsTree::lod0_nodes(world) {
        return Err(Miss::Unusable(format!(
            "a {} x {} lattice, not {} x {}",
            side[0], side[1], expected[0], expected[1]
        )));
    }
    let mut refine = vec![0u8; 12 * word(6) as usize];
    r.read_exact(&mut refine)?;
    let f = |b: &[u8]| f32::from_le_bytes(b.try_into().unwrap());
    let lod0_refine = refine
        .chunks_exact(12)
        .map(|c| NodeRefine { error_m: f(&c[..4]), z_lo_m: f(&c[4..8]), z_hi_m: f(&c[8..]) })
        .collect();
    let n = side[0] * side[1];
    let mut p = OwnedParts {
        side,
        z: vec![0.0; n],
        hole: vec![false; n],
        error: vec![0.0; n],
        reach: vec![0.0; n],
        empty: vec![false; n],
        lod0_refine,
    };
    read_bands(&mut r, world, &mut p)?;
    if r.read(&mut [0u8])? != 0 {
        return Err(Miss::Unusable("bytes past its end".into()));
    }
    Ok(VertexBoundsTree::from_parts(*world, p))
}

/// Reads every band into `p`, a batch of bands at a time (read in order,
/// unpacked in parallel into their rows).
fn read_bands(r: &mut impl Read, world: &WorldDesc, p: &mut OwnedParts) -> Result<(), Miss> {
    let band = BAND_ROWS * p.side[0];
    let n = p.error.len();
    let batch = band * rayon::current_num_threads() * 2;
    for start in (0..n).step_by(batch) {
        let end = (start + batch).min(n);
        let mut packed = Vec::new();
        for _ in (start..end).step_by(band) {
            let mut len_crc = [0u8; 12];
            r.read_exact(&mut len_crc)?;
            let len = u64::from_le_bytes(len_crc[..8].try_into().unwrap());
            if len > (band * SAMPLE_BYTES) as u64 * 2 + 1024 {
                return Err(Miss::Unusable(format!("a band of {len} bytes")));
            }
            let mut bytes = vec![0u8; len as usize];
            r.read_exact(&mut bytes)?;
            if crc32fast::hash(&bytes).to_le_bytes() != len_crc[8..] {
                return Err(Miss::Unusable("a band's checksum differs".into()));
            }
            packed.push(bytes);
        }
        let rows = p.z[start..end]
            .par_chunks_mut(band)
            .zip(p.error[start..end].par_chunks_mut(band))
            .zip(p.reach[start..end].par_chunks_mut(band))
            .zip(p.hole[start..end].par_chunks_mut(band).zip(p.empty[start..end].par_chunks_mut(band)));
        rows.zip(packed.par_iter()).try_for_each(|((((z, error), reach), (hole, empty)), bytes)| {
            unpack(world, bytes, z, error, reach, hole, empty)
        })?;
    }
    Ok(())
}

fn unpack(
    world: &WorldDesc,
    bytes: &[u8],
    z: &mut [f32],
    error: &mut [f32],
    reach: &mut [f32],
    hole: &mut [bool],
    empty: &mut [bool],
) -> Result<(), Miss> {
    let k = z.len();
    let raw =
        zstd::bulk::decompress(bytes, k * SAMPLE_BYTES).map_err(|_| Miss::Unusable("a band is not zstd".into()))?;
    if raw.len() != k * SAMPLE_BYTES {
        return Err(Miss::Unusable("a band of another size".into()));
    }
    let (codes, rest) = raw.split_at(2 * k);
    let (errors, rest) = rest.split_at(4 * k);
    let (reaches, flags) = rest.split_at(4 * k);
    let f = |b: &[u8]| f32::from_le_bytes(b.try_into().unwrap());
    for i in 0..k {
        z[i] = world.decode_height(u16::from_le_bytes([codes[2 * i], codes[2 * i + 1]]));
        error[i] = f(&errors[4 * i..4 * i + 4]);
        reach[i] = f(&reaches[4 * i..4 * i + 4]);
        (hole[i], empty[i]) = (flags[i] & 1 != 0, flags[i] & 2 != 0);
    }
    Ok(())
}
