//! GeoTIFF height maps: the same heights as a PNG of the same data, the
//! extent and origin from the tags, PixelIsPoint against PixelIsArea, f32
//! and signed 16-bit bands, no-data samples baked as holes. The files are written here with
//! the `tiff` crate's encoder (stripped; tiled files go through the same
//! decoder call but are not made here: the encoder writes strips only).

use std::path::Path;
use tiff::encoder::colortype;
use vista::world::{GeoTiffSource, HeightSource, Png16Source};
mod geotiff_files;

use geotiff_files::{heights, temp_dir, write_tiff, Tags, TAGS};

fn write_png16(path: &Path, w: u32, h: u32, data: &[u16]) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut enc = png::Encoder::new(file, w, h);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Sixteen);
    let bytes: Vec<u8> = data.iter().flat_map(|v| v.to_be_bytes()).collect();
    enc.write_header().unwrap().write_image_data(&bytes).unwrap();
}

#[test]
fn a_geotiff_has_the_heights_of_the_same_png_and_places_itself() {
    let dir = temp_dir("same");
    let (w, h) = (64, 48);
    let data = heights(w, h);
    let tif = dir.join("dem.tif");
    let png = dir.join("dem.png");
    write_tiff::<colortype::Gray16>(&tif, w, h, &data, &TAGS);
    write_png16(&png, w, h, &data);
    let info = GeoTiffSource::read_header(&tif).unwrap();
    // Extent: 64 x 30 m by 48 x 20 m. Origin (PixelIsArea): the tie point
    // is the north-west corner, so the south-west corner is 48 x 20 m south.
    assert_eq!(info.extent_m(), Some([1920.0, 960.0]));
    assert_eq!(info.origin_m, Some([340_000.0, 5_081_000.0 - 960.0]));
    let extent = info.extent_m().unwrap();
    let tiff = GeoTiffSource::open(&tif, extent).unwrap();
    // The PNG's 0..65535 onto 0..65535 m: the same metres as the TIFF.
    let png = Png16Source::open(&png, extent, [0.0, 65535.0]).unwrap();
    let mut state = 12345u64;
    for _ in 0..2000 {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let x = (state >> 11) as f64 / (1u64 << 53) as f64 * extent[0];
        let y = (state >> 7 & 0xffff) as f64 / 65536.0 * extent[1];
        assert_eq!(tiff.sample(x, y).to_bits(), png.sample(x, y).to_bits(), "at {x}, {y}");
    }
    // Posts: each pixel centre returns its sample exactly.
    assert_eq!(tiff.sample(15.0, 960.0 - 10.0), f32::from(data[0]));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn pixel_is_point_moves_the_origin_by_half_a_pixel() {
    let dir = temp_dir("point");
    let data = heights(8, 4);
    let (area, point) = (dir.join("area.tif"), dir.join("point.tif"));
    // Tied at raster (2, 1), not the corner.
    let tie = [2.0, 1.0, 1000.0, 2000.0];
    write_tiff::<colortype::Gray16>(&area, 8, 4, &data, &Tags { tie, ..TAGS });
    write_tiff::<colortype::Gray16>(&point, 8, 4, &data, &Tags { tie, point: true, ..TAGS });
    let a = GeoTiffSource::read_header(&area).unwrap();
    let p = GeoTiffSource::read_header(&point).unwrap();
    assert!(!a.pixel_is_point && p.pixel_is_point);
    // Area: raster (2, 1) is a pixel corner: west edge 1000 - 2 x 30, north
    // edge 2000 + 1 x 20, south edge 4 x 20 below it.
    assert_eq!(a.origin_m, Some([940.0, 1940.0]));
    // Point: raster (2, 1) is that pixel's centre, half a pixel further in.
    assert_eq!(p.origin_m, Some([925.0, 1950.0]));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn float_and_signed_bands_keep_their_metres() {
    let dir = temp_dir("kinds");
    let f: Vec<f32> = (0..12).map(|k| -411.5 + 100.25 * k as f32).collect();
    let i: Vec<i16> = (0..12).map(|k| -400 + 100 * k as i16).collect();
    let (ft, it) = (dir.join("f.tif"), dir.join("i.tif"));
    write_tiff::<colortype::Gray32Float>(&ft, 4, 3, &f, &TAGS);
    write_tiff::<colortype::GrayI16>(&it, 4, 3, &i, &TAGS);
    let extent = [120.0, 60.0];
    let fs = GeoTiffSource::open(&ft, extent).unwrap();
    let is = GeoTiffSource::open(&it, extent).unwrap();
    for k in 0..12 {
        let (col, row) = ((k % 4) as f64, (k / 4) as f64);
        let (x, y) = ((col + 0.5) * 30.0, 60.0 - (row + 0.5) * 20.0);
        assert_eq!(fs.sample(x, y), f[k], "f32 pixel {k}");
        assert_eq!(is.sample(x, y), f32::from(i[k]), "i16 pixel {k}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// GDAL's "nan" no-data (float maps): its samples are holes, and a map of
/// nothing else is refused as such, not as non-finite heights.
#[test]
fn a_nan_no_data_value_marks_holes() {
    let dir = temp_dir("nan-nodata");
    let tags = Tags { no_data: Some("nan"), ..TAGS };
    let mut f: Vec<f32> = (0..12).map(|k| 100.0 + k as f32).collect();
    f[5] = f32::NAN;
    let (holed, empty) = (dir.join("holed.tif"), dir.join("empty.tif"));
    write_tiff::<colortype::Gray32Float>(&holed, 4, 3, &f, &tags);
    write_tiff::<colortype::Gray32Float>(&empty, 4, 3, &[f32::NAN; 12], &tags);
    let src = GeoTiffSource::open(&holed, [120.0, 60.0]).unwrap();
    // Pixel 5 is (col 1, row 1): x 30..60, y 20..40.
    assert!(src.has_holes() && src.is_hole(45.0, 30.0) && !src.is_hole(15.0, 30.0));
    let err = GeoTiffSource::open(&empty, [120.0, 60.0]).map(|_| ()).expect_err("refused").to_string();
    assert!(err.contains("every sample holds the no-data value NaN"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn no_data_samples_become_holes_in_the_bake() {
    use vista::world::{bake_node, NodeId, WorldDesc, PATCHES_PER_NODE_SIDE, PATCH_HOLE_NONE};
    let dir = temp_dir("nodata");
    // 64 x 64 pixels of 4 m: a 256 m map. Pixel (10, 5) and the whole of
    // row 40 hold no data.
    let (w, h) = (64u32, 64u32);
    let mut data: Vec<i16> = (0..w * h).map(|k| 500 + (k % w) as i16).collect();
    data[(5 * w + 10) as usize] = -9999;
    for i in 0..w {
        data[(40 * w + i) as usize] = -9999;
    }
    let tif = dir.join("holes.tif");
    let tags = Tags { scale: [4.0, 4.0], no_data: Some("-9999"), ..TAGS };
    write_tiff::<colortype::GrayI16>(&tif, w, h, &data, &tags);
    let extent = [256.0, 256.0];
    let src = GeoTiffSource::open(&tif, extent).unwrap();
    assert!(src.has_holes());
    // Pixel (10, 5) covers x 40..44, y 232..236 (row 0 is the north edge,
    // y 252..256); its centre is a hole, its neighbours' centres are not.
    assert!(src.is_hole(42.0, 234.0));
    assert!(!src.is_hole(38.0, 234.0) && !src.is_hole(46.0, 234.0) && !src.is_hole(42.0, 238.0));
    // Filled from the nearer valid neighbour of its row for the resampler:
    // 500 + 9 or 500 + 11 (equally near: the left one).
    assert_eq!(src.sample(42.0, 234.0), 509.0);
    // A whole row without data copies the nearer row (39, the same values).
    assert_eq!(src.sample(2.0, 256.0 - 162.0), 500.0);
    assert!(src.is_hole(2.0, 256.0 - 162.0));

    // The bake cuts them like hole shapes: at 1 m spacing the map is 2 x 2
    // LOD-0 nodes of 128 m; node (0, 1) (north-west) holds pixel (10, 5)
    // (x 40..44, y 232..236) in its patches (4, 13) and (5, 13) of 8 m
    // (x 32..40 and 40..48, y 232..240): the sample at x 40 is on both.
    let world = WorldDesc {
        extent_m: extent,
        height_range_m: [-100.0, 1000.0],
        spacing_m: 1.0,
        lod_count: 2,
        ..WorldDesc::default()
    };
    let node = bake_node(&src, &world, &[], NodeId::new(0, 0, 1));
    let side = PATCHES_PER_NODE_SIDE as usize;
    let holed: Vec<usize> = (0..side * side).filter(|&p| node.patch_holes[p] != PATCH_HOLE_NONE).collect();
    // Row 40 (y 92..96) lies in node (x, 0); pixel (10, 5) is the only
    // no-data in node (0, 1).
    assert_eq!(holed, [13 * side + 4, 13 * side + 5], "patches with holes: {holed:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A tiled little-endian TIFF written by hand (the `tiff` crate's encoder
/// writes strips only): 16-bit samples, uncompressed, 16 x 16 tiles, the
/// right and bottom tiles partly outside the image as TIFF pads them.
fn write_tiled(path: &Path, w: u32, h: u32, data: &[u16], scale: [f64; 2]) {
    const TILE: u32 = 16;
    let (tx, ty) = (w.div_ceil(TILE), h.div_ceil(TILE));
    let mut tiles: Vec<u8> = Vec::new();
    let mut offsets = Vec::new();
    // Header (8 bytes), then the tiles, then the IFD.
    for j in 0..ty {
        for i in 0..tx {
            offsets.push(8 + tiles.len() as u32);
            for y in 0..TILE {
                for x in 0..TILE {
                    let (px, py) = (i * TILE + x, j * TILE + y);
                    let v = if px < w && py < h { data[(py * w + px) as usize] } else { 0 };
                    tiles.extend(v.to_le_bytes());
                }
            }
        }
    }
    let tile_bytes = TILE * TILE * 2;
    let n_tiles = offsets.len() as u32;
    let extra_start = 8 + tiles.len() as u32;
    // Out-of-line values after the tiles: offsets, byte counts, pixel scale.
    let mut extra: Vec<u8> = Vec::new();
    let offsets_at = extra_start;
    offsets.iter().for_each(|o| extra.extend(o.to_le_bytes()));
    let counts_at = extra_start + extra.len() as u32;
    (0..n_tiles).for_each(|_| extra.extend(tile_bytes.to_le_bytes()));
    let scale_at = extra_start + extra.len() as u32;
    [scale[0], scale[1], 0.0f64].iter().for_each(|v| extra.extend(v.to_le_bytes()));
    let ifd_at = extra_start + extra.len() as u32;
    // (tag, type, count, value): type 3 short, 4 long, 12 double.
    let entries: [(u16, u16, u32, u32); 11] = [
        (256, 4, 1, w),
        (257, 4, 1, h),
        (258, 3, 1, 16),
        (259, 3, 1, 1),
        (262, 3, 1, 1),
        (277, 3, 1, 1),
        (322, 4, 1, TILE),
        (323, 4, 1, TILE),
        (324, 4, n_tiles, offsets_at),
        (325, 4, n_tiles, counts_at),
        (33550, 12, 3, scale_at),
    ];
    let mut out: Vec<u8> = b"II*\0".to_vec();
    out.extend(ifd_at.to_le_bytes());
    out.extend(&tiles);
    out.extend(&extra);
    out.extend((entries.len() as u16).to_le_bytes());
    for (tag, kind, count, value) in entries {
        out.extend(tag.to_le_bytes());
        out.extend(kind.to_le_bytes());
        out.extend(count.to_le_bytes());
        // A single short sits in the first two bytes of the value field.
        if kind == 3 && count == 1 {
            out.extend((value as u16).to_le_bytes());
            out.extend([0, 0]);
        } else {
            out.extend(value.to_le_bytes());
        }
    }
    out.extend(0u32.to_le_bytes());
    std::fs::write(path, out).unwrap();
}

#[test]
fn a_tiled_geotiff_reads_as_the_same_heights_as_a_stripped_one() {
    let dir = temp_dir("tiled");
    // 40 x 24: 3 x 2 tiles of 16, the last column and row partial.
    let (w, h) = (40, 24);
    let data = heights(w, h);
    let (tiled, stripped) = (dir.join("tiled.tif"), dir.join("stripped.tif"));
    write_tiled(&tiled, w, h, &data, [30.0, 20.0]);
    write_tiff::<colortype::Gray16>(&stripped, w, h, &data, &TAGS);
    let info = GeoTiffSource::read_header(&tiled).unwrap();
    assert_eq!(info.extent_m(), Some([1200.0, 480.0]));
    let extent = info.extent_m().unwrap();
    let (a, b) = (GeoTiffSource::open(&tiled, extent).unwrap(), GeoTiffSource::open(&stripped, extent).unwrap());
    for (k, &v) in data.iter().enumerate() {
        let (i, j) = ((k % w as usize) as f64, (k / w as usize) as f64);
        let (x, y) = ((i + 0.5) * 30.0, 480.0 - (j + 0.5) * 20.0);
        assert_eq!(a.sample(x, y), f32::from(v), "tiled pixel {k}");
        assert_eq!(b.sample(x, y), f32::from(v), "stripped pixel {k}");
    }
    // A plan times on the first tile (16 x 16).
    let corner = GeoTiffSource::open_corner(&tiled, extent).unwrap();
    assert_eq!((corner.grid().width(), corner.grid().height()), (16, 16));
    let _ = std::fs::remove_dir_all(&dir);
}
