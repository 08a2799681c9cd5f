//! 16-bit grayscale PNG height maps of any size.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use image::{DynamicImage, ImageReader};

use super::error::{Result, WorldError};
use super::layout::MAX_IMAGE_SIDE;
use super::source::{GridSource, HeightSource};

/// The 8-byte PNG file signature.
const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];
/// Signature + IHDR length + "IHDR" + width + height + depth + colour type.
const IHDR_PREFIX_LEN: usize = 26;
/// PNG colour type 0: grayscale without alpha.
const PNG_GRAY: u8 = 0;

/// A 16-bit grayscale PNG whose full 0..65535 range maps linearly to
/// `height_range_m` and whose image covers `extent_m` (row 0 north).
#[derive(Clone, Debug)]
pub struct Png16Source {
    grid: GridSource,
}

impl Png16Source {
    /// Reads and validates `path`.
    /// Decoded straight from the file (not from a copy of it in memory):
    /// the peak is the 16-bit pixels themselves, 2 bytes a sample.
    pub fn open(path: &Path, extent_m: [f64; 2], height_range_m: [f32; 2]) -> Result<Self> {
        let (w, h) = Self::header(path)?;
        check_params(extent_m, height_range_m)?;
        let file = std::fs::File::open(path).map_err(|e| WorldError::io(path, e))?;
        let mut reader = ImageReader::new(std::io::BufReader::new(file));
        reader.set_format(image::ImageFormat::Png);
        reader.no_limits();
        let img = reader.decode().map_err(|e| WorldError::corrupt(path, e))?;
        Self::from_image(img, (w, h), path, extent_m, height_range_m)
    }

    /// At most `side` x `side` pixels from the map's north-west corner,
    /// decoded row by row (the rest of the file is never decompressed into
    /// memory), stretched over `extent_m`: the same per-sample work as the
    /// whole map, for timing a bake without reading it. `None` for an
    /// interlaced file, whose rows do not come in order.
    pub fn open_corner(path: &Path, side: u32, extent_m: [f64; 2], height_range_m: [f32; 2]) -> Result<Option<Self>> {
        let (w, h) = Self::header(path)?;
        check_params(extent_m, height_range_m)?;
        let file = std::fs::File::open(path).map_err(|e| WorldError::io(path, e))?;
        let mut reader =
            png::Decoder::new(std::io::BufReader::new(file)).read_info().map_err(|e| WorldError::corrupt(path, e))?;
        if reader.info().interlaced {
            return Ok(None);
        }
        let (cw, ch) = (w.min(side) as usize, h.min(side) as usize);
        let mut values = Vec::with_capacity(cw * ch);
        while values.len() < cw * ch {
            let row = reader.next_row().map_err(|e| WorldError::corrupt(path, e))?;
            let row = row.ok_or_else(|| WorldError::corrupt(path, "fewer rows than its header says"))?;
            values.extend(row.data().chunks_exact(2).take(cw).map(|b| u16::from_be_bytes([b[0], b[1]])));
        }
        Ok(Some(Png16Source { grid: GridSource::from_u16(cw, ch, values, height_range_m, extent_m) }))
    }

    /// The map's size, from its header alone (what plans need).
    pub fn header(path: &Path) -> Result<(u32, u32)> {
        super::require_regular_file(path).map_err(|e| WorldError::io(path, e))?;
        let mut head = [0u8; IHDR_PREFIX_LEN];
        let mut file = std::fs::File::open(path).map_err(|e| WorldError::io(path, e))?;
        std::io::Read::read_exact(&mut file, &mut head)
            .map_err(|_| WorldError::corrupt(path, "not a PNG file (shorter than its header)"))?;
        let size = check_header(&head, path)?;
        check_chunks(&mut file, path)?;
        Ok(size)
    }

    /// Decodes an in-memory PNG; `label` names it in errors.
    pub fn from_bytes(bytes: &[u8], label: &Path, extent_m: [f64; 2], height_range_m: [f32; 2]) -> Result<Self> {
        check_params(extent_m, height_range_m)?;
        let (w, h) = check_header(bytes, label)?;
        let mut reader = ImageReader::new(Cursor::new(bytes));
        reader.set_format(image::ImageFormat::Png);
        reader.no_limits();
        let img = reader.decode().map_err(|e| WorldError::corrupt(label, e))?;
        Self::from_image(img, (w, h), label, extent_m, height_range_m)
    }

    fn from_image(
        img: DynamicImage,
        (w, h): (u32, u32),
        label: &Path,
        extent_m: [f64; 2],
        height_range_m: [f32; 2],
    ) -> Result<Self> {
        let DynamicImage::ImageLuma16(img) = img else {
            // The header said 16-bit gray; a decoder disagreeing means the
            // file lies about itself.
            return Err(WorldError::corrupt(label, "pixel data does not match the header"));
        };
        if (img.width(), img.height()) != (w, h) {
            return Err(WorldError::corrupt(label, "decoded size differs from header"));
        }
        let grid = GridSource::from_u16(w as usize, h as usize, img.into_raw(), height_range_m, extent_m);
        Ok(Png16Source { grid })
    }

    /// The decoded grid, heights in metres.
    pub fn grid(&self) -> &GridSource {
        &self.grid
    }

    pub fn into_grid(self) -> GridSource {
        self.grid
    }
}

impl HeightSource for Png16Source {
    fn sample(&self, x_m: f64, y_m: f64) -> f32 {
        self.grid.sample(x_m, y_m)
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
}

/// Rejects bad caller parameters with a message naming them.
pub(crate) fn check_params(extent_m: [f64; 2], height_range_m: [f32; 2]) -> Result<()> {
    if extent_m.iter().any(|e| !e.is_finite() || *e <= 0.0) {
        return Err(WorldError::InvalidDesc(format!(
            "height map extent must be finite and positive, got {extent_m:?}"
        )));
    }
    let [lo, hi] = height_range_m;
    if !lo.is_finite() || !hi.is_finite() || lo >= hi {
        return Err(WorldError::InvalidDesc(format!("height range must be finite with lo < hi, got {lo}..{hi}")));
    }
    Ok(())
}

/// Walks the chunk list to IEND by lengths alone (a seek each, no data
/// read): a truncated file is refused by commands that read only headers
/// (`vista memory`, plans), as decoding would refuse it. Chunk CRCs are the
/// decoder's to check.
fn check_chunks(file: &mut std::fs::File, label: &Path) -> Result<()> {
    use std::io::{Read, Seek, SeekFrom};
    let len = file.metadata().map_err(|e| WorldError::io(label, e))?.len();
    let mut at = 8u64;
    while at + 12 <= len {
        let mut head = [0u8; 8];
        file.seek(SeekFrom::Start(at))
            .and_then(|_| file.read_exact(&mut head))
            .map_err(|e| WorldError::io(label, e))?;
        let chunk = u64::from(u32::from_be_bytes([head[0], head[1], head[2], head[3]]));
        let end = at + 12 + chunk;
        if end > len {
            let name = String::from_utf8_lossy(&head[4..8]).into_owned();
            return Err(WorldError::corrupt(
                label,
                format!("chunk {name} at byte {at} ends at byte {end}, the file has {len}"),
            ));
        }
        if &head[4..8] == b"IEND" {
            return Ok(());
        }
        at = end;
    }
    Err(WorldError::corrupt(label, format!("no IEND chunk in its {len} bytes")))
}

/// Reads the IHDR chunk by hand so size and pixel format are checked before
/// the decoder allocates anything.
fn check_header(bytes: &[u8], label: &Path) -> Result<(u32, u32)> {
    if bytes.len() < IHDR_PREFIX_LEN || bytes[..8] != PNG_SIGNATURE || &bytes[12..16] != b"IHDR" {
        return Err(WorldError::corrupt(label, "not a PNG file (bad signature or header)"));
    }
    let be = |o: usize| u32::from_be_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    let (w, h) = (be(16), be(20));
    if w == 0 || h == 0 || w > MAX_IMAGE_SIDE || h > MAX_IMAGE_SIDE {
        return Err(WorldError::BadDimensions {
            path: PathBuf::from(label),
            width: u64::from(w),
            height: u64::from(h),
            max: MAX_IMAGE_SIDE,
        });
    }
    let (depth, colour) = (bytes[24], bytes[25]);
    if depth != 16 || colour != PNG_GRAY {
        let kind = match colour {
            0 => "gray",
            2 => "RGB",
            3 => "palette",
            4 => "gray+alpha",
            6 => "RGBA",
            _ => "unknown colour type",
        };
        return Err(WorldError::WrongPixelFormat {
            path: PathBuf::from(label),
            expected: "16-bit grayscale PNG",
            found: format!("{depth}-bit {kind}"),
        });
    }
    Ok((w, h))
}
