//! Height map loaders: real data, every bad input, and a mutation fuzz.

mod common;

use common::Rng;
use std::io::Cursor;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use image::{ImageBuffer, ImageFormat, Luma, Rgb};
use vista::world::*;

fn montblanc_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/montblanc.png")
}

/// A fresh directory for this test's files.
fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("vista_world_{name}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn png_bytes<P: image::PixelWithColorType>(img: &ImageBuffer<P, Vec<P::Subpixel>>) -> Vec<u8>
where
    [P::Subpixel]: image::EncodableLayout,
{
    let mut out = Cursor::new(Vec::new());
    img.write_to(&mut out, ImageFormat::Png).unwrap();
    out.into_inner()
}

fn small_png16() -> Vec<u8> {
    let img = ImageBuffer::<Luma<u16>, _>::from_fn(9, 7, |x, y| Luma([(x * 7000 + y * 300) as u16]));
    png_bytes(&img)
}

/// Recomputes every chunk's CRC so mutations reach the decoder proper.
fn fix_png_crcs(bytes: &mut [u8]) {
    let mut pos = 8;
    while pos + 12 <= bytes.len() {
        let len = u32::from_be_bytes(bytes[pos..pos + 4].try_into().unwrap()) as usize;
        let end = pos + 8 + len;
        if end + 4 > bytes.len() {
            break;
        }
        let crc = crc32fast::hash(&bytes[pos + 4..end]);
        bytes[end..end + 4].copy_from_slice(&crc.to_be_bytes());
        pos = end + 4;
    }
}

/// A 16-bit gray PNG whose IHDR claims `w` x `h` (with a correct CRC).
fn png_with_dims(w: u32, h: u32) -> Vec<u8> {
    let mut b = small_png16();
    b[16..20].copy_from_slice(&w.to_be_bytes());
    b[20..24].copy_from_slice(&h.to_be_bytes());
    fix_png_crcs(&mut b);
    b
}

fn exr_bytes(dir: &Path, name: &str, w: usize, h: usize, data: &[f32]) -> (PathBuf, Vec<u8>) {
    let p = dir.join(name);
    write_height_exr(&p, w, h, data).unwrap();
    let bytes = std::fs::read(&p).unwrap();
    (p, bytes)
}

const EXTENT: [f64; 2] = [1000.0, 800.0];
const RANGE: [f32; 2] = [0.0, 100.0];

#[test]
fn montblanc_loads_and_reproduces_pixels() {
    let path = montblanc_path();
    let src = Png16Source::open(&path, [60_000.0, 60_000.0], [454.0, 4810.0]).unwrap();
    let world = WorldDesc {
        extent_m: [60_000.0, 60_000.0],
        height_range_m: [454.0, 4810.0],
        spacing_m: 8.0,
        lod_count: 6,
        ..WorldDesc::default()
    };
    world.validate().unwrap();
    assert_eq!((src.grid().width(), src.grid().height()), (647, 647));
    let roots = world.roots();
    assert_eq!(roots.len(), 4);
    assert!(roots.iter().all(|&r| world.is_valid(r)));
    assert!(!world.is_valid(NodeId::new(0, 59, 3)));
    assert!(!world.is_valid(NodeId::new(2, 15, 0)));
    assert!(world.node_at(0, 60_001.0, 10.0).is_none());
    assert_eq!(world.node_at(0, 60_000.0, 0.0), Some(NodeId::new(0, 58, 0)));

    // Independent decode of the raw pixels.
    let raw = image::open(&path).unwrap().into_luma16();
    for (i, j) in [(0u32, 0u32), (300, 200), (646, 646), (123, 600)] {
        let v = raw.get_pixel(i, j)[0];
        let expect = 454.0 + f64::from(v) / 65535.0 * (4810.0 - 454.0);
        let [x, y] = src.grid().pixel_center_m(i as usize, j as usize);
        let got = f64::from(src.sample(x, y));
        assert!((got - expect).abs() <= 1e-3 * expect, "pixel {i},{j}: {got} vs {expect}");
    }
    // Row 0 is north: pixel (0, 0) sits at the max-y edge.
    let [_, y0] = src.grid().pixel_center_m(0, 0);
    assert!(y0 > 59_900.0);

    // A root bakes with sane numbers.
    let node = bake_node(&src, &world, &[], roots[0]);
    assert!(node.max_height > node.min_height);
    let src: std::sync::Arc<dyn HeightSource> = std::sync::Arc::new(src);
    let e = vista::world::ErrorTree::new(&world, src, None).unwrap().node(roots[0]).unwrap();
    assert!(e.node_m > 1.0 && e.node_m < 2000.0, "{}", e.node_m);
}

#[test]
fn bad_inputs_give_specific_errors() {
    let dir = temp_dir("bad");
    let write = |name: &str, bytes: &[u8]| {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    };
    let open = |p: &Path| Png16Source::open(p, EXTENT, RANGE);

    let missing = dir.join("nope.png");
    match open(&missing) {
        Err(e @ WorldError::FileNotFound { .. }) => {
            assert!(e.to_string().contains("nope.png"), "{e}")
        }
        other => panic!("missing file: {other:?}"),
    }
    assert!(matches!(ExrSource::open(&dir.join("nope.exr"), EXTENT), Err(WorldError::FileNotFound { .. })));

    let gray8 = ImageBuffer::<Luma<u8>, _>::from_pixel(4, 4, Luma([9u8]));
    let p = write("gray8.png", &png_bytes(&gray8));
    assert!(matches!(open(&p), Err(WorldError::WrongPixelFormat { .. })), "8-bit");

    let rgb16 = ImageBuffer::<Rgb<u16>, _>::from_pixel(4, 4, Rgb([1u16, 2, 3]));
    let p = write("rgb16.png", &png_bytes(&rgb16));
    let e = open(&p).unwrap_err();
    assert!(matches!(e, WorldError::WrongPixelFormat { .. }), "rgb16: {e}");
    assert!(e.to_string().contains("16-bit RGB"), "{e}");

    let good = small_png16();
    assert!(open(&write("good.png", &good)).is_ok());
    let p = write("trunc.png", &good[..good.len() / 2]);
    assert!(matches!(open(&p), Err(WorldError::Corrupt { .. })), "truncated");
    let p = write("empty.png", &[]);
    assert!(matches!(open(&p), Err(WorldError::Corrupt { .. })), "empty file");

    for (w, h) in [(0, 7), (9, 0), (100_000, 100_000), (u32::MAX, 1)] {
        let p = write("dims.png", &png_with_dims(w, h));
        match open(&p) {
            Err(WorldError::BadDimensions { width, height, .. }) => {
                assert_eq!((width, height), (w as u64, h as u64))
            }
            other => panic!("{w}x{h}: {other:?}"),
        }
    }

    // Caller parameters.
    assert!(matches!(
        Png16Source::from_bytes(&good, Path::new("m"), [0.0, 1.0], RANGE),
        Err(WorldError::InvalidDesc(_))
    ));
    assert!(matches!(
        Png16Source::from_bytes(&good, Path::new("m"), EXTENT, [5.0, 1.0]),
        Err(WorldError::InvalidDesc(_))
    ));

    // EXR: good, NaN/inf, multi-channel, truncated.
    let mut data: Vec<f32> = (0..12).map(|v| v as f32 - 3.5).collect();
    let (p, _) = exr_bytes(&dir, "good.exr", 4, 3, &data);
    let src = ExrSource::open(&p, EXTENT).unwrap();
    assert_eq!(src.grid().pixel(0, 0), -3.5);
    data[2] = f32::NAN;
    data[5] = f32::INFINITY;
    data[7] = f32::NEG_INFINITY;
    let (p, bytes) = exr_bytes(&dir, "nan.exr", 4, 3, &data);
    match ExrSource::open(&p, EXTENT) {
        Err(WorldError::NonFiniteHeights { count, .. }) => assert_eq!(count, 3),
        other => panic!("nan exr: {other:?}"),
    }
    let p = write("trunc.exr", &bytes[..bytes.len() - 10]);
    assert!(matches!(ExrSource::open(&p, EXTENT), Err(WorldError::Corrupt { .. })));

    let p = dir.join("rgba.exr");
    exr::prelude::write_rgba_file(&p, 4, 4, |_, _| (0.5f32, 0.5f32, 0.5f32, 1.0f32)).unwrap();
    assert!(matches!(ExrSource::open(&p, EXTENT), Err(WorldError::WrongPixelFormat { .. })));
    // A PNG is not an EXR and vice versa.
    assert!(matches!(ExrSource::from_bytes(&good, Path::new("x"), EXTENT), Err(WorldError::Corrupt { .. })));
    let _ = std::fs::remove_dir_all(&dir);
}

fn mutate(rng: &mut Rng, base: &[u8]) -> Vec<u8> {
    let mut b = base.to_vec();
    match rng.index(4) {
        0 => b.truncate(rng.index(b.len())),
        1 => {
            let at = rng.index(b.len());
            let extra: Vec<u8> = (0..rng.index(16) + 1).map(|_| rng.next_u64() as u8).collect();
            b.splice(at..at, extra);
        }
        _ => {
            for _ in 0..rng.index(8) + 1 {
                let at = rng.index(b.len());
                b[at] = match rng.index(3) {
                    0 => rng.next_u64() as u8,
                    1 => b[at] ^ (1 << rng.index(8)),
                    _ => [0u8, 0xff, 0x7f, 0x80][rng.index(4)],
                };
            }
        }
    }
    b
}

#[test]
fn fuzzed_files_never_panic() {
    let dir = temp_dir("fuzz");
    let png = small_png16();
    let data: Vec<f32> = (0..30).map(|v| (v as f32).sin() * 50.0).collect();
    let (_, exr) = exr_bytes(&dir, "base.exr", 6, 5, &data);
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let (mut ok, mut err) = (0, 0);
    for i in 0..300u32 {
        let mut p = mutate(&mut rng, &png);
        if i.is_multiple_of(2) {
            fix_png_crcs(&mut p);
        }
        let e = mutate(&mut rng, &exr);
        let result = catch_unwind(AssertUnwindSafe(|| {
            let a = Png16Source::from_bytes(&p, Path::new("fuzz.png"), EXTENT, RANGE);
            let b = ExrSource::from_bytes(&e, Path::new("fuzz.exr"), EXTENT);
            // Whatever loaded must also sample finitely.
            if let Ok(s) = &a {
                assert!(s.sample(1.0, 2.0).is_finite());
            }
            if let Ok(s) = &b {
                assert!(s.sample(1.0, 2.0).is_finite());
            }
            [a.is_ok(), b.is_ok()]
        }));
        let r = result.unwrap_or_else(|_| panic!("iteration {i} panicked"));
        for o in r {
            if o {
                ok += 1
            } else {
                err += 1
            }
        }
    }
    println!("fuzz: {ok} loaded, {err} rejected");
    assert!(err > 0);
    let _ = std::fs::remove_dir_all(&dir);
}
