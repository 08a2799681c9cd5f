//! Height maps given on the command line: their kind told by content
//! (PNG, OpenEXR, GeoTIFF), opened with the height range the user gave or
//! the file holds, and that range checked against the samples.

use std::io::Read as _;
use std::path::Path;
use std::sync::Arc;

use anyhow::{bail, Context as _, Result};
use vista::world::{ExrSource, GeoTiffSource, GridSource, HeightSource, Png16Source, WorldDesc};

/// First bytes of a PNG and an OpenEXR file: files are told apart by
/// content, so a misnamed file still loads (or fails naming its real kind).
pub(crate) const PNG_MAGIC: [u8; 4] = [0x89, b'P', b'N', b'G'];
pub(crate) const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];
/// TIFF and BigTIFF, little- and big-endian.
pub(crate) const TIFF_MAGIC: [[u8; 4]; 4] = [*b"II*\0", *b"MM\0*", *b"II+\0", *b"MM\0+"];

/// A height range the user chose, and where: `--height-range` or the scene.
#[derive(Clone, Copy)]
pub(crate) struct GivenRange {
    pub(crate) range: [f32; 2],
    pub(crate) origin: &'static str,
}

impl GivenRange {
    pub(crate) fn new(range: [f32; 2], origin: &'static str) -> Self {
        GivenRange { range, origin }
    }
}

impl std::fmt::Display for GivenRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [lo, hi] = self.range;
        // As the user wrote it: two arguments, or a TOML array.
        if self.origin.starts_with("--") {
            write!(f, "{} {lo} {hi}", self.origin)
        } else {
            write!(f, "{} [{lo}, {hi}]", self.origin)
        }
    }
}

/// Pixels a side of the corner a plan times a PNG world's bake on: 2 MiB.
pub(crate) const TIMING_CORNER: u32 = 1024;

/// A height map's kind, by its first bytes.
#[derive(Clone, Copy, PartialEq)]
pub(crate) enum MapKind {
    Png,
    Exr,
    Tiff,
}

/// A regular file's first four bytes, if it has them (never opens a FIFO,
/// which would block: `heightmap_kind` then refuses it).
pub(crate) fn magic(path: &Path) -> Option<[u8; 4]> {
    vista::world::require_regular_file(path).ok()?;
    let mut m = [0u8; 4];
    std::fs::File::open(path).ok()?.read_exact(&mut m).ok()?;
    Some(m)
}

/// Reads the first bytes only: a wrong file or a missing argument is told
/// before the plan, and no pixel is read.
pub(crate) fn heightmap_kind(path: &Path, what: &str, height_range: Option<GivenRange>) -> Result<MapKind> {
    if path.is_dir() {
        bail!("{what} {} is a directory, expected a PNG, EXR or GeoTIFF height map file", path.display());
    }
    if let Err(e) = vista::world::require_regular_file(path) {
        if e.kind() != std::io::ErrorKind::NotFound {
            bail!("{what} {} {e}: give a PNG, EXR or GeoTIFF height map file", path.display());
        }
    }
    let mut magic = [0u8; 4];
    let mut file = std::fs::File::open(path).with_context(|| format!("heightmap file {}", path.display()))?;
    if let Err(e) = file.read_exact(&mut magic) {
        if e.kind() == std::io::ErrorKind::UnexpectedEof {
            bail!("{what} {} is too short to be a PNG, EXR or GeoTIFF file", path.display());
        }
        return Err(e).with_context(|| format!("reading {what} {}", path.display()));
    }
    match magic {
        PNG_MAGIC if height_range.is_none() => {
            bail!("{what} {} is a PNG: give --height-range LO HI (metres of 0 and 65535)", path.display())
        }
        PNG_MAGIC => Ok(MapKind::Png),
        EXR_MAGIC => Ok(MapKind::Exr),
        m if TIFF_MAGIC.contains(&m) => Ok(MapKind::Tiff),
        _ => bail!("{what} {} is neither a PNG, an OpenEXR nor a GeoTIFF file (by its first bytes)", path.display()),
    }
}

/// `geometry` was checked and planned; its height range is the given one
/// (a placeholder without one: an EXR's data decides it).
pub(crate) fn open_heightmap(
    path: &Path,
    kind: MapKind,
    geometry: WorldDesc,
    height_range: Option<GivenRange>,
    clamp: bool,
) -> Result<(WorldDesc, Arc<dyn HeightSource>)> {
    match (kind, height_range) {
        (MapKind::Png, Some(given)) => {
            let source = Png16Source::open(path, geometry.extent_m, given.range)?;
            Ok((geometry.with_posts(source.grid().pixel_size_m()), Arc::new(source)))
        }
        (MapKind::Png, None) => unreachable!("heightmap_kind refuses a PNG without a height range"),
        (MapKind::Tiff, _) => {
            let source = GeoTiffSource::open(path, geometry.extent_m)?;
            Ok((ranged(source.grid(), path, geometry, height_range, clamp)?, Arc::new(source)))
        }
        (MapKind::Exr, _) => {
            let source = ExrSource::open(path, geometry.extent_m)?;
            Ok((ranged(source.grid(), path, geometry, height_range, clamp)?, Arc::new(source)))
        }
    }
}

/// `geometry` with the height range of a map whose data decide it (EXR,
/// GeoTIFF): the given one, checked against the data, or one fitted to
/// them; its posts on the map's.
pub(crate) fn ranged(
    grid: &GridSource,
    path: &Path,
    geometry: WorldDesc,
    height_range: Option<GivenRange>,
    clamp: bool,
) -> Result<WorldDesc> {
    let range = match height_range {
        Some(given) => checked_range(grid, path, given, clamp)?,
        None => auto_range(grid),
    };
    let desc = WorldDesc { height_range_m: range, ..geometry }.with_posts(grid.pixel_size_m());
    // The geometry was checked; only the range is new here.
    desc.validate().with_context(|| format!("height range of {}", path.display()))?;
    Ok(desc)
}

/// The user's range for an EXR, refused if it would clip pixels (heights
/// are clamped to the range when encoded, silently) unless `clamp`.
pub(crate) fn checked_range(grid: &GridSource, path: &Path, given: GivenRange, clamp: bool) -> Result<[f32; 2]> {
    let [lo, hi] = given.range;
    let fit = grid.fit(given.range);
    let file = path.display();
    let (n, total) = (fit.outside, fit.total);
    if n > 0 && !clamp {
        let fix = if given.origin.starts_with("--") {
            "widen it or pass --clamp-heights"
        } else {
            "widen it, or set clamp_heights = true in [world] or pass --clamp-heights"
        };
        bail!("{given} clips {n} of {total} samples of {file} (min {:.1} m, max {:.1} m); {fix}", fit.min, fit.max);
    }
    if n > 0 {
        eprintln!("note: {n} of {total} samples of {file} lie outside {given} and are clamped to {lo}..{hi} m");
        return Ok(given.range);
    }
    // Every pixel fits, but Catmull-Rom may still overshoot between them.
    let [rlo, rhi] = grid.resampled_range();
    if rlo < lo || rhi > hi {
        eprintln!(
            "warning: {given} holds every sample of {file}, but resampling between them reaches {rlo:.1}..{rhi:.1} m, \
             which is clamped; leave the range out to have it fitted"
        );
    }
    Ok(given.range)
}

/// The range an EXR gets when none is given: every value the resampler can
/// produce, overshoot next to cliffs included (see
/// [`vista::world::GridSource::resampled_range`]), so no height is clamped;
/// a flat map is widened to 1 m around its middle so lo < hi.
pub(crate) fn auto_range(grid: &GridSource) -> [f32; 2] {
    let [lo, hi] = grid.resampled_range();
    if hi - lo < 1.0 {
        let mid = lo + (hi - lo) / 2.0;
        [mid - 0.5, mid + 0.5]
    } else {
        [lo, hi]
    }
}
