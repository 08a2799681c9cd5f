//! Bad input fuzzing (stability case 9): a seeded mutation loop over valid
//! 16-bit PNG and float EXR height maps. Every mutated file must load or
//! fail with a typed, one-line `WorldError`; nothing may panic, and the
//! process's peak memory stays bounded (sizes are checked before pixels are
//! allocated). The normal run tries `DEFAULT_CASES` per format; the nightly
//! form sets `VISTA_FUZZ_CASES`, e.g.
//! `VISTA_FUZZ_CASES=200000 cargo test --release --test fuzz_inputs`.
//! Scene files are fuzzed the same way in tools/vista/scene.rs.

mod common;

use common::Rng;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;
use vista::world::{write_height_exr, ExrSource, Png16Source, WorldError};

const DEFAULT_CASES: usize = 3000;
/// Peak resident memory the whole test process may reach: the inputs are
/// 64x48 images, so anything near this means a decoder trusted a size.
const PEAK_MEMORY_BOUND_MIB: u64 = 1024;

fn cases() -> usize {
    std::env::var("VISTA_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(DEFAULT_CASES)
}

/// One random edit of `data`: bit flips, byte overwrites with boundary
/// values, truncation, insertion, chunk duplication or a swapped run.
fn mutate(rng: &mut Rng, data: &[u8]) -> Vec<u8> {
    let mut d = data.to_vec();
    for _ in 0..1 + rng.below(4) {
        let n = d.len().max(1);
        match rng.below(6) {
            0 => {
                let i = rng.index(n);
                if let Some(b) = d.get_mut(i) {
                    *b ^= 1 << rng.below(8);
                }
            }
            1 => {
                let i = rng.index(n);
                let v = [0x00, 0xFF, 0x7F, 0x80, 0x01][rng.index(5)];
                if let Some(b) = d.get_mut(i) {
                    *b = v;
                }
            }
            2 => d.truncate(rng.index(n)),
            3 => {
                let i = rng.index(n + 1).min(d.len());
                let extra: Vec<u8> = (0..1 + rng.below(16)).map(|_| rng.below(256) as u8).collect();
                d.splice(i..i, extra);
            }
            4 => {
                let (a, len) = (rng.index(n), 1 + rng.index(64));
                let chunk: Vec<u8> = d.iter().skip(a).take(len).copied().collect();
                let at = rng.index(d.len() + 1).min(d.len());
                d.splice(at..at, chunk);
            }
            _ => {
                // A 4-byte field (a size, a CRC, an offset) set to an extreme.
                let i = rng.index(n);
                let v = [u32::MAX, 0, 0x7FFF_FFFF, 65536][rng.index(4)].to_be_bytes();
                for (k, b) in v.iter().enumerate() {
                    if let Some(x) = d.get_mut(i + k) {
                        *x = *b;
                    }
                }
            }
        }
    }
    d
}

/// Recomputes the CRC of every whole chunk after the PNG signature, so a
/// mutation reaches the header and pixel checks instead of the CRC check.
fn repair_png_crcs(d: &mut [u8]) {
    let mut at = 8;
    while at + 12 <= d.len() {
        let len = u32::from_be_bytes([d[at], d[at + 1], d[at + 2], d[at + 3]]) as usize;
        let Some(end) = (at + 8).checked_add(len).filter(|&e| e + 4 <= d.len()) else {
            return;
        };
        let crc = crc32fast::hash(&d[at + 4..end]).to_be_bytes();
        d[end..end + 4].copy_from_slice(&crc);
        at = end + 4;
    }
}

fn peak_memory_mib() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let kib = status.lines().find(|l| l.starts_with("VmHWM:")).and_then(|l| l.split_whitespace().nth(1));
    kib.and_then(|k| k.parse::<u64>().ok()).unwrap_or(0) / 1024
}

/// Runs `load` on `cases` mutations of `valid`; returns (loaded, rejected).
fn fuzz(name: &str, valid: &[u8], seed: u64, load: impl Fn(&[u8]) -> Result<(), WorldError>) -> (usize, usize) {
    let mut rng = Rng(seed);
    let (mut ok, mut rejected) = (0, 0);
    for case in 0..cases() {
        let input = mutate(&mut rng, valid);
        match catch_unwind(AssertUnwindSafe(|| load(&input))) {
            Ok(Ok(())) => ok += 1,
            Ok(Err(e)) => {
                let msg = e.to_string();
                assert!(!msg.is_empty() && !msg.contains('\n'), "{name} case {case}: not one line: {msg:?}");
                rejected += 1;
            }
            Err(_) => {
                let file = std::env::temp_dir().join(format!("vista-fuzz-{name}-{seed}-{case}.bin"));
                let _ = std::fs::write(&file, &input);
                panic!("{name} case {case} (seed {seed}) panicked; input saved to {}", file.display());
            }
        }
    }
    (ok, rejected)
}

fn valid_png() -> Vec<u8> {
    let pixels: Vec<u16> = (0..64 * 48).map(|i| (i * 37 % 65536) as u16).collect();
    let img = image::ImageBuffer::<image::Luma<u16>, _>::from_raw(64, 48, pixels).unwrap();
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

fn valid_exr() -> Vec<u8> {
    let path = std::env::temp_dir().join(format!("vista-fuzz-{}.exr", std::process::id()));
    let heights: Vec<f32> = (0..64 * 48).map(|i| (i as f32 * 0.37).sin() * 100.0).collect();
    write_height_exr(&path, 64, 48, &heights).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let _ = std::fs::remove_file(&path);
    bytes
}

#[test]
fn mutated_height_maps_load_or_fail_with_a_typed_error() {
    let label = Path::new("fuzzed");
    let png = valid_png();
    // Mutations of even length keep valid CRCs (about half of them).
    let (ok, bad) = fuzz("png", &png, 0x9e37_79b9, |b| {
        let mut b = b.to_vec();
        if b.len() % 2 == 0 {
            repair_png_crcs(&mut b);
        }
        Png16Source::from_bytes(&b, label, [640.0, 480.0], [0.0, 100.0]).map(|_| ())
    });
    println!("png: {ok} loaded, {bad} rejected");
    assert!(ok > 0 && bad > 0, "the mutations reach past the checks and into them: {ok} loaded, {bad} rejected");
    let exr = valid_exr();
    let (ok, bad) = fuzz("exr", &exr, 0x5851_f42d, |b| ExrSource::from_bytes(b, label, [640.0, 480.0]).map(|_| ()));
    println!("exr: {ok} loaded, {bad} rejected");
    assert!(bad > 0, "the mutations reach the checks: {ok} loaded, {bad} rejected");
    let peak = peak_memory_mib();
    println!("peak resident memory {peak} MiB");
    assert!(peak < PEAK_MEMORY_BOUND_MIB, "peak memory {peak} MiB: a decoder allocated from a fuzzed size");
}
