//! GeoTIFF elevation models: one band of 16-bit integers (metres, signed or
//! not) or 32-bit floats, stripped or tiled, any compression the `tiff`
//! crate decodes (deflate, LZW, PackBits, none). The tags that place the
//! map (pixel scale, tie point, raster type) are read with the header, so
//! a plan knows the world's extent without reading a pixel. GDAL's no-data
//! samples become holes, cut like a hole shape (their heights are filled
//! from valid neighbours for the resampler).
//!
//! Raster type: with PixelIsArea (GeoTIFF's default) the tie point is a
//! pixel's corner; with PixelIsPoint it is the pixel's centre, the post
//! itself. vista's world puts a map's posts at its pixel centres either way
//! ([`GridSource`]); the raster type moves where the world's south-west
//! corner lies in map coordinates ([`GeoTiffInfo::origin_m`]) by half a
//! pixel, so a camera or hole given in map coordinates lands on the right
//! post.

use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};

use tiff::decoder::{Decoder, DecodingResult, Limits};
use tiff::tags::Tag;

use super::error::{Result, WorldError};
use super::layout::{MAX_ABS_HEIGHT_M, MAX_IMAGE_SIDE};
use super::png16::check_params;
use super::source::{GridSource, HeightSource};

/// GeoKey of the raster type in the GeoKeyDirectory.
const GT_RASTER_TYPE_GEO_KEY: u16 = 1025;
const RASTER_PIXEL_IS_POINT: u16 = 2;

/// What the header says, before any pixel is read.
#[derive(Clone, Debug, PartialEq)]
pub struct GeoTiffInfo {
    pub width: u32,
    pub height: u32,
    /// Metres per pixel along x and y (ModelPixelScale), if tagged.
    pub pixel_m: Option<[f64; 2]>,
    /// Map coordinates of the world's south-west corner (the outer edge of
    /// the south-west pixel), if tie point and scale are tagged.
    pub origin_m: Option<[f64; 2]>,
    /// PixelIsPoint (the tie point is a post) rather than PixelIsArea.
    pub pixel_is_point: bool,
    /// GDAL's no-data value, if tagged.
    pub no_data: Option<f64>,
}

impl GeoTiffInfo {
    /// The map's extent in metres from its pixel scale.
    pub fn extent_m(&self) -> Option<[f64; 2]> {
        self.pixel_m.map(|[sx, sy]| [sx * f64::from(self.width), sy * f64::from(self.height)])
    }
}

/// A GeoTIFF's heights: kept 16-bit where they are (a DEM's own size in
/// memory), f32 otherwise.
#[derive(Clone, Debug)]
pub struct GeoTiffSource {
    grid: GridSource,
    info: GeoTiffInfo,
}

fn decoder(path: &Path) -> Result<Decoder<BufReader<File>>> {
    super::require_regular_file(path).map_err(|e| WorldError::io(path, e))?;
    let file = File::open(path).map_err(|e| WorldError::io(path, e))?;
    let d = Decoder::new(BufReader::new(file)).map_err(|e| WorldError::corrupt(path, e))?;
    // The size is checked against MAX_IMAGE_SIDE before any pixel buffer
    // exists; the crate's own default caps a 16384² map.
    Ok(d.with_limits(Limits::unlimited()))
}

fn wrong_format(path: &Path, found: String) -> WorldError {
    WorldError::WrongPixelFormat {
        path: PathBuf::from(path),
        expected: "one-band GeoTIFF of 16-bit integers or 32-bit floats",
        found,
    }
}

impl GeoTiffSource {
    /// The header and placement tags only.
    pub fn read_header(path: &Path) -> Result<GeoTiffInfo> {
        Self::read_info(&mut decoder(path)?, path)
    }

    fn read_info(d: &mut Decoder<BufReader<File>>, path: &Path) -> Result<GeoTiffInfo> {
        let (width, height) = d.dimensions().map_err(|e| WorldError::corrupt(path, e))?;
        if width == 0 || height == 0 || width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
            let (width, height) = (u64::from(width), u64::from(height));
            return Err(WorldError::BadDimensions { path: path.into(), width, height, max: MAX_IMAGE_SIDE });
        }
        match d.colortype().map_err(|e| WorldError::corrupt(path, e))? {
            tiff::ColorType::Gray(16) | tiff::ColorType::Gray(32) => {}
            other => return Err(wrong_format(path, format!("{other:?}"))),
        }
        let doubles = |d: &mut Decoder<BufReader<File>>, tag| -> Result<Option<Vec<f64>>> {
            match d.find_tag(tag).map_err(|e| WorldError::corrupt(path, e))? {
                Some(v) => v.into_f64_vec().map(Some).map_err(|e| WorldError::corrupt(path, e)),
                None => Ok(None),
            }
        };
        let scale = doubles(d, Tag::ModelPixelScaleTag)?;
        let tie = doubles(d, Tag::ModelTiepointTag)?;
        let keys = match d.find_tag(Tag::GeoKeyDirectoryTag).map_err(|e| WorldError::corrupt(path, e))? {
            Some(v) => v.into_u16_vec().map_err(|e| WorldError::corrupt(path, e))?,
            None => Vec::new(),
        };
        // Header (4 shorts), then entries of 4: key, location, count, value.
        let pixel_is_point = keys
            .get(4..)
            .unwrap_or(&[])
            .chunks_exact(4)
            .any(|k| k[0] == GT_RASTER_TYPE_GEO_KEY && k[1] == 0 && k[3] == RASTER_PIXEL_IS_POINT);
        let no_data = match d.find_tag(Tag::GdalNodata).map_err(|e| WorldError::corrupt(path, e))? {
            Some(v) => {
                let text = v.into_string().map_err(|e| WorldError::corrupt(path, e))?;
                let text = text.trim_matches(char::from(0)).trim();
                Some(text.parse::<f64>().map_err(|_| WorldError::corrupt(path, format!("no-data value {text:?}")))?)
            }
            None => None,
        };
        let pixel_m = match scale.as_deref() {
            Some([sx, sy, ..]) if *sx > 0.0 && *sy > 0.0 && sx.is_finite() && sy.is_finite() => Some([*sx, *sy]),
            Some(s) => return Err(WorldError::corrupt(path, format!("pixel scale {s:?}"))),
            None => None,
        };
        let origin_m = match (tie.as_deref(), pixel_m) {
            (Some([i, j, _, x, y, ..]), Some([sx, sy])) => {
                // The tie point's raster position, in pixels from the
                // north-west corner of the north-west pixel.
                let half = if pixel_is_point { 0.5 } else { 0.0 };
                let west = x - (i + half) * sx;
                let north = y + (j + half) * sy;
                Some([west, north - sy * f64::from(height)])
            }
            _ => None,
        };
        Ok(GeoTiffInfo { width, height, pixel_m, origin_m, pixel_is_point, no_data })
    }

    /// Reads the map; it covers `extent_m` (from [`GeoTiffInfo::extent_m`]
    /// or the caller), row 0 north.
    pub fn open(path: &Path, extent_m: [f64; 2]) -> Result<Self> {
        check_params(extent_m, [0.0, 1.0])?;
        let mut d = decoder(path)?;
        let info = Self::read_info(&mut d, path)?;
        let image = d.read_image().map_err(|e| WorldError::corrupt(path, e))?;
        let grid = to_grid(image, (info.width as usize, info.height as usize), &info, path, extent_m)?;
        Ok(GeoTiffSource { grid, info })
    }

    /// The map's first strip or tile only, stretched over `extent_m`: the
    /// same per-sample work as the whole map, for timing a bake without
    /// reading it (a DEM's strips and tiles are a few rows or 256² to 512²).
    pub fn open_corner(path: &Path, extent_m: [f64; 2]) -> Result<Self> {
        check_params(extent_m, [0.0, 1.0])?;
        let mut d = decoder(path)?;
        let info = Self::read_info(&mut d, path)?;
        let (cw, ch) = d.chunk_data_dimensions(0);
        let chunk = d.read_chunk(0).map_err(|e| WorldError::corrupt(path, e))?;
        let grid = to_grid(chunk, (cw as usize, ch as usize), &info, path, extent_m)?;
        Ok(GeoTiffSource { grid, info })
    }

    pub fn grid(&self) -> &GridSource {
        &self.grid
    }

    pub fn info(&self) -> &GeoTiffInfo {
        &self.info
    }
}

/// Decoded samples (`w` x `h`, row 0 north) as a grid over `extent_m`;
/// no-data samples become holes.
fn to_grid(
    image: DecodingResult,
    (w, h): (usize, usize),
    info: &GeoTiffInfo,
    path: &Path,
    extent_m: [f64; 2],
) -> Result<GridSource> {
    let (grid, mask) = match image {
        DecodingResult::U16(mut values) if values.len() == w * h => {
            let mask = fill_no_data(&mut values, w, info.no_data, |v| f64::from(*v), path)?;
            // Metres as stored: 0..65535 onto 0..65535 m, scale 1.
            (GridSource::from_u16(w, h, values, [0.0, 65535.0], extent_m), mask)
        }
        DecodingResult::I16(mut values) if values.len() == w * h => {
            let mask = fill_no_data(&mut values, w, info.no_data, |v| f64::from(*v), path)?;
            // Shifted into u16: -32768 m at 0.
            let shifted = values.into_iter().map(|v| (i32::from(v) + 32768) as u16).collect();
            (GridSource::from_u16(w, h, shifted, [-32768.0, 32767.0], extent_m), mask)
        }
        DecodingResult::F32(mut values) if values.len() == w * h => {
            let mask = fill_no_data(&mut values, w, info.no_data, |v| f64::from(*v), path)?;
            let non_finite = values.iter().filter(|v| !v.is_finite()).count();
            if non_finite > 0 {
                return Err(WorldError::NonFiniteHeights { path: path.into(), count: non_finite });
            }
            let huge = values.iter().filter(|v| v.abs() > MAX_ABS_HEIGHT_M).count();
            if huge > 0 {
                return Err(WorldError::HugeHeights { path: path.into(), count: huge, limit: MAX_ABS_HEIGHT_M });
            }
            (GridSource::new(w, h, values, extent_m), mask)
        }
        other => return Err(wrong_format(path, format!("{} samples", sample_kind(&other)))),
    };
    Ok(match mask {
        Some(mask) => grid.with_no_data(mask),
        None => grid,
    })
}

/// Marks the samples equal to `no_data` (one bit each, row-major) and
/// gives each the nearest valid value of its row (else the nearest row
/// with one), so the resampler near a hole's edge reads terrain, not the
/// sentinel (often -32768 m). `None` where no sample is no-data.
fn fill_no_data<T: Copy>(
    values: &mut [T],
    w: usize,
    no_data: Option<f64>,
    as_f64: impl Fn(&T) -> f64,
    path: &Path,
) -> Result<Option<Vec<u64>>> {
    let Some(n) = no_data else { return Ok(None) };
    let mut mask = vec![0u64; values.len().div_ceil(64)];
    // GDAL writes "nan" for float maps: NaN equals nothing, so test it apart.
    let is_no_data = |x: f64| x == n || (n.is_nan() && x.is_nan());
    for (k, v) in values.iter().enumerate() {
        if is_no_data(as_f64(v)) {
            mask[k / 64] |= 1 << (k % 64);
        }
    }
    if mask.iter().all(|&m| m == 0) {
        return Ok(None);
    }
    let hole = |k: usize| mask[k / 64] >> (k % 64) & 1 == 1;
    let mut valid_rows = Vec::new();
    for (j, row) in values.chunks_mut(w).enumerate() {
        let valid: Vec<usize> = (0..w).filter(|&i| !hole(j * w + i)).collect();
        if valid.is_empty() {
            continue;
        }
        valid_rows.push(j);
        // Each hole takes the nearer valid sample of its row.
        for i in 0..w {
            if hole(j * w + i) {
                row[i] = row[nearest(&valid, i)];
            }
        }
    }
    if valid_rows.is_empty() {
        return Err(WorldError::AllNoData { path: path.to_path_buf(), value: n });
    }
    // Rows without a valid sample copy the nearest row that has one.
    for j in 0..values.len() / w {
        if valid_rows.binary_search(&j).is_err() {
            let from = nearest(&valid_rows, j);
            values.copy_within(from * w..from * w + w, j * w);
        }
    }
    Ok(Some(mask))
}

/// The element of `sorted` (ascending, not empty) nearest to `x`, the
/// lower on a tie.
fn nearest(sorted: &[usize], x: usize) -> usize {
    let p = sorted.partition_point(|&v| v < x);
    match (p.checked_sub(1).map(|q| sorted[q]), sorted.get(p)) {
        (Some(l), Some(&r)) if r - x < x - l => r,
        (Some(l), _) => l,
        (None, Some(&r)) => r,
        (None, None) => unreachable!("nearest in an empty list"),
    }
}

fn sample_kind(r: &DecodingResult) -> &'static str {
    match r {
        DecodingResult::U8(_) => "8-bit",
        DecodingResult::U16(_) | DecodingResult::I16(_) => "16-bit (size mismatch)",
        DecodingResult::U32(_) | DecodingResult::I32(_) => "32-bit integer",
        DecodingResult::U64(_) | DecodingResult::I64(_) => "64-bit integer",
        DecodingResult::F32(_) => "32-bit float (size mismatch)",
        DecodingResult::F64(_) => "64-bit float",
        _ => "unsupported",
    }
}

impl HeightSource for GeoTiffSource {
    fn sample(&self, x_m: f64, y_m: f64) -> f32 {
        self.grid.sample(x_m, y_m)
    }

    fn sample_row(&self, xs: &[f64], y_m: f64, out: &mut [f32]) {
        self.grid.sample_row(xs, y_m, out)
    }

    fn id_hash(&self) -> u64 {
        self.grid.id_hash()
    }

    fn region_hash(&self, bounds_m: [f64; 4]) -> u64 {
        self.grid.region_hash(bounds_m)
    }

    fn range_in(&self, bounds_m: [f64; 4]) -> Option<[f32; 2]> {
        self.grid.range_in(bounds_m)
    }

    fn is_hole(&self, x_m: f64, y_m: f64) -> bool {
        self.grid.is_hole(x_m, y_m)
    }

    fn has_holes(&self) -> bool {
        self.grid.has_holes()
    }
}
