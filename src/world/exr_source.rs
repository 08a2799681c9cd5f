//! Single-channel float OpenEXR height maps (metres, negative allowed).

use std::io::Cursor;
use std::path::{Path, PathBuf};

use exr::prelude::*;

use super::error::{Result, WorldError};
use super::layout::MAX_IMAGE_SIDE;
use super::png16::check_params;
use super::source::{GridSource, HeightSource};

/// An EXR whose only channel holds heights in metres; the image covers
/// `extent_m`, row 0 north.
#[derive(Clone, Debug)]
pub struct ExrSource {
    grid: GridSource,
}

impl ExrSource {
    pub fn open(path: &Path, extent_m: [f64; 2]) -> Result<Self> {
        super::require_regular_file(path).map_err(|e| WorldError::io(path, e))?;
        let bytes = std::fs::read(path).map_err(|e| WorldError::io(path, e))?;
        Self::from_bytes(&bytes, path, extent_m)
    }

    /// Decodes an in-memory EXR; `label` names it in errors.
    pub fn from_bytes(bytes: &[u8], label: &Path, extent_m: [f64; 2]) -> Result<Self> {
        check_params(extent_m, [0.0, 1.0])?;
        let (w, h) = check_header(bytes, label)?;
        let image = read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .non_parallel()
            .from_buffered(Cursor::new(bytes))
            .map_err(|e| WorldError::corrupt(label, e))?;
        let layer = &image.layer_data;
        if layer.size.0 != w || layer.size.1 != h || layer.channel_data.list.len() != 1 {
            return Err(WorldError::corrupt(label, "layer differs from its header"));
        }
        let samples = &layer.channel_data.list[0].sample_data;
        if matches!(samples, FlatSamples::U32(_)) {
            return Err(wrong_format(label, "a u32 channel".into()));
        }
        let heights: Vec<f32> = samples.values_as_f32().collect();
        if heights.len() != w * h {
            return Err(WorldError::corrupt(label, "sample count differs from size"));
        }
        let bad = heights.iter().filter(|v| !v.is_finite()).count();
        if bad > 0 {
            return Err(WorldError::NonFiniteHeights { path: PathBuf::from(label), count: bad });
        }
        let limit = crate::world::MAX_ABS_HEIGHT_M;
        let huge = heights.iter().filter(|v| v.abs() > limit).count();
        if huge > 0 {
            return Err(WorldError::HugeHeights { path: PathBuf::from(label), count: huge, limit });
        }
        Ok(ExrSource { grid: GridSource::new(w, h, heights, extent_m) })
    }

    pub fn grid(&self) -> &GridSource {
        &self.grid
    }
}

impl HeightSource for ExrSource {
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

fn wrong_format(label: &Path, found: String) -> WorldError {
    WorldError::WrongPixelFormat { path: PathBuf::from(label), expected: "single-channel float EXR", found }
}

/// Reads only the headers so size and channels are checked before any
/// pixel allocation.
fn check_header(bytes: &[u8], label: &Path) -> Result<(usize, usize)> {
    let meta = MetaData::read_from_buffered(Cursor::new(bytes), false).map_err(|e| WorldError::corrupt(label, e))?;
    let header = meta.headers.first().ok_or_else(|| WorldError::corrupt(label, "no layers"))?;
    let (w, h) = (header.layer_size.0, header.layer_size.1);
    let max = MAX_IMAGE_SIDE as usize;
    if w == 0 || h == 0 || w > max || h > max {
        return Err(WorldError::BadDimensions {
            path: PathBuf::from(label),
            width: w as u64,
            height: h as u64,
            max: MAX_IMAGE_SIDE,
        });
    }
    if header.deep {
        return Err(wrong_format(label, "deep data".into()));
    }
    let channels = header.channels.list.len();
    if channels != 1 {
        return Err(wrong_format(label, format!("{channels} channels")));
    }
    if header.channels.list[0].sample_type == SampleType::U32 {
        return Err(wrong_format(label, "a u32 channel".into()));
    }
    Ok((w, h))
}

/// Writes `heights` (row 0 north, `width * height` values) as a
/// single-channel f32 EXR, the format [`ExrSource`] reads.
pub fn write_height_exr(path: &Path, width: usize, height: usize, heights: &[f32]) -> Result<()> {
    assert_eq!(heights.len(), width * height, "height grid size mismatch");
    let channel = AnyChannel::new("Y", FlatSamples::F32(heights.to_vec()));
    let layer = Layer::new(
        (width, height),
        LayerAttributes::named("height"),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(SmallVec::from_vec(vec![channel])),
    );
    let image = Image::from_layer(layer);
    crate::output::write_with(path, |w| {
        image.write().non_parallel().to_buffered(w).map_err(|e| match e {
            exr::error::Error::Io(io) => io,
            other => std::io::Error::other(other),
        })
    })
    .map_err(|e| WorldError::io_write(path, e.error))
}
