//! GeoTIFF test maps written with the `tiff` crate's encoder (stripped),
//! shared by the library's tests/geotiff.rs and the command line's
//! tests/cli_geotiff.rs.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use tiff::encoder::{colortype, TiffEncoder};
use tiff::tags::Tag;

pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vista-geotiff-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// Where and how a test map is placed.
pub struct Tags {
    pub scale: [f64; 2],
    /// Raster position (i, j) tied to map position (x, y).
    pub tie: [f64; 4],
    pub point: bool,
    pub no_data: Option<&'static str>,
}

pub const TAGS: Tags =
    Tags { scale: [30.0, 20.0], tie: [0.0, 0.0, 340_000.0, 5_081_000.0], point: false, no_data: None };

pub fn write_tiff<C: colortype::ColorType>(path: &Path, w: u32, h: u32, data: &[C::Inner], t: &Tags)
where
    [C::Inner]: tiff::encoder::TiffValue,
{
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut enc = TiffEncoder::new(file).unwrap();
    let mut img = enc.new_image::<C>(w, h).unwrap();
    let e = img.encoder();
    e.write_tag(Tag::ModelPixelScaleTag, &[t.scale[0], t.scale[1], 0.0][..]).unwrap();
    e.write_tag(Tag::ModelTiepointTag, &[t.tie[0], t.tie[1], 0.0, t.tie[2], t.tie[3], 0.0][..]).unwrap();
    // Version 1.1.0, one key: GTRasterTypeGeoKey = 1 (area) or 2 (point).
    e.write_tag(Tag::GeoKeyDirectoryTag, &[1u16, 1, 0, 1, 1025, 0, 1, if t.point { 2 } else { 1 }][..]).unwrap();
    if let Some(n) = t.no_data {
        e.write_tag(Tag::GdalNodata, n).unwrap();
    }
    img.write_data(data).unwrap();
}

/// Heights with every kind of neighbourhood: a ramp, a ripple and noise.
pub fn heights(w: u32, h: u32) -> Vec<u16> {
    let mut state = 0x9e37_79b9_u32;
    (0..w * h)
        .map(|k| {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            let (i, j) = ((k % w) as f64, (k / w) as f64);
            (1000.0 + 20.0 * i + 300.0 * (j * 0.3).sin() + f64::from(state % 50)) as u16
        })
        .collect()
}
