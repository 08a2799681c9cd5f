//! Case 9: bad input fuzzing. A seeded mutation loop over valid 16-bit PNG
//! and float EXR height maps: every mutated file loads or fails with a
//! typed, one-line `WorldError`; nothing panics, and the process's peak
//! memory stays bounded (sizes are checked before pixels are allocated).
//! Scene files are fuzzed the same way by the command line
//! (tools/vista/scene.rs), whose parser they belong to.

use super::{CaseReport, Form};
use crate::error::Result;
use crate::world::{write_height_exr, ExrSource, Png16Source, WorldError};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

/// Peak resident memory the process may reach: the inputs are 64x48
/// images, so anything near this means a decoder trusted a size.
pub const PEAK_MEMORY_BOUND_MIB: u64 = 1024;

/// xorshift64*: seeded, the same on every machine.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    fn below(&mut self, n: u32) -> u32 {
        (self.next_u64() % u64::from(n)) as u32
    }

    fn index(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
}

#[derive(Debug, Default, Clone, Copy)]
pub struct Counts {
    pub loaded: usize,
    pub rejected: usize,
    pub panics: usize,
    pub bad_messages: usize,
}

/// `cases` mutations per format (the quick form: 3000, the full: 200 000;
/// `VISTA_FUZZ_CASES` overrides both for nightly runs).
pub fn run(form: Form) -> Result<CaseReport> {
    let mut r = CaseReport::new(9, "bad input fuzzing");
    r.measured =
        "panics, multi-line errors; peak process memory, over seeded mutations of PNG16 and EXR height maps".into();
    r.bound = format!("0 panics, 0; < {PEAK_MEMORY_BOUND_MIB} MiB");
    r.why = "every failure must be a typed one-line error, and no decoder may allocate from a size it has not checked"
        .into();
    let cases = std::env::var("VISTA_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(form.pick(3000, 200_000));
    let label = Path::new("fuzzed");
    let png = valid_png();
    // Mutations of even length keep valid CRCs (about half of them).
    let p = fuzz(
        "png",
        &png,
        0x9e37_79b9,
        cases,
        |b| {
            let mut b = b.to_vec();
            if b.len() % 2 == 0 {
                repair_png_crcs(&mut b);
            }
            Png16Source::from_bytes(&b, label, [640.0, 480.0], [0.0, 100.0]).map(|_| ())
        },
        &mut r,
    );
    let exr = valid_exr()?;
    let e =
        fuzz("exr", &exr, 0x5851_f42d, cases, |b| ExrSource::from_bytes(b, label, [640.0, 480.0]).map(|_| ()), &mut r);
    let peak = peak_memory_mib();
    for (what, c) in [("png", p), ("exr", e)] {
        r.details.push(format!(
            "{what}: {cases} mutations, {} loaded, {} rejected, {} panics",
            c.loaded, c.rejected, c.panics
        ));
    }
    r.details.push(format!("peak resident memory of the process {peak} MiB"));
    let (panics, messages) = (p.panics + e.panics, p.bad_messages + e.bad_messages);
    r.worst = format!("{panics} panics, {messages}; {peak} MiB");
    // Both outcomes must occur, or the mutations never reached the checks.
    let reached = p.loaded > 0 && p.rejected > 0 && e.rejected > 0;
    if !reached {
        r.details.push("the mutations did not reach both sides of the checks".into());
    }
    r.pass = panics == 0 && messages == 0 && peak < PEAK_MEMORY_BOUND_MIB && reached;
    Ok(r)
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
fn fuzz(
    name: &str,
    valid: &[u8],
    seed: u64,
    cases: usize,
    load: impl Fn(&[u8]) -> Result<(), WorldError>,
    r: &mut CaseReport,
) -> Counts {
    let mut rng = Rng(seed);
    let mut n = Counts::default();
    for case in 0..cases {
        let input = mutate(&mut rng, valid);
        match catch_unwind(AssertUnwindSafe(|| load(&input))) {
            Ok(Ok(())) => n.loaded += 1,
            Ok(Err(e)) => {
                let msg = e.to_string();
                if msg.is_empty() || msg.contains('\n') {
                    n.bad_messages += 1;
                    r.details.push(format!("{name} case {case}: not one line: {msg:?}"));
                }
                n.rejected += 1;
            }
            Err(_) => {
                let file = std::env::temp_dir().join(format!("vista-fuzz-{name}-{seed}-{case}.bin"));
                let _ = std::fs::write(&file, &input);
                n.panics += 1;
                r.details.push(format!("{name} case {case} (seed {seed}) panicked; input saved to {}", file.display()));
            }
        }
    }
    n
}

fn valid_png() -> Vec<u8> {
    let pixels: Vec<u16> = (0..64 * 48).map(|i| (i * 37 % 65536) as u16).collect();
    let img = image::ImageBuffer::<image::Luma<u16>, _>::from_raw(64, 48, pixels).expect("a valid test image");
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).expect("a valid test image");
    out.into_inner()
}

fn valid_exr() -> Result<Vec<u8>> {
    let path = std::env::temp_dir().join(format!("vista-fuzz-{}.exr", std::process::id()));
    let heights: Vec<f32> = (0..64 * 48).map(|i| (i as f32 * 0.37).sin() * 100.0).collect();
    write_height_exr(&path, 64, 48, &heights)?;
    let bytes = std::fs::read(&path).map_err(|e| crate::Error::BadInput(format!("{}: {e}", path.display())))?;
    let _ = std::fs::remove_file(&path);
    Ok(bytes)
}
