//! Writes the stamp maps the example scenes use (`scenes/stamps/*.png`):
//! analytic shapes as 16-bit grayscale PNGs, 0..65535 for 0..1.
//!
//! `cargo run --release --example stamp_maps -- [DIR]` (default
//! `scenes/stamps`).

use std::path::PathBuf;

const SIDE: u32 = 256;

/// An impact crater: a bowl (0 at its floor) inside a raised rim (1 at
/// r = 0.5 of the half-side) whose ejecta blanket falls back to 0.5 at the
/// square's edge; with `offset = -height / 2` and `blend = "add"` the
/// ground outside is unchanged.
fn crater(r: f64) -> f64 {
    if r <= 0.4 {
        0.75 * (r / 0.4).powi(2)
    } else if r <= 0.5 {
        let t = (r - 0.4) / 0.1;
        0.75 + 0.25 * t * t * (3.0 - 2.0 * t)
    } else {
        0.5 + 0.5 * (-((r - 0.5) / 0.15).powi(2)).exp()
    }
}

/// A ridged mountain: a Gaussian dome with three radial ridges, 0 at the
/// edge.
fn mountain(r: f64, angle: f64) -> f64 {
    let dome = (-(r / 0.45).powi(2) * 2.5).exp();
    let ridges = 0.15 * (3.0 * angle).cos().max(0.0) * (1.0 - r).max(0.0);
    ((dome + ridges * dome.sqrt()) / 1.15 - 0.005).clamp(0.0, 1.0)
}

fn write(dir: &std::path::Path, name: &str, f: impl Fn(f64, f64) -> f64) {
    let mut img = image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::new(SIDE, SIDE);
    for (x, y, p) in img.enumerate_pixels_mut() {
        // Pixel centres over [-1, 1]^2 (r = 1 at the middle of each edge).
        let u = (f64::from(x) + 0.5) / f64::from(SIDE) * 2.0 - 1.0;
        let v = 1.0 - (f64::from(y) + 0.5) / f64::from(SIDE) * 2.0;
        let r = (u * u + v * v).sqrt();
        p.0[0] = (f(r, v.atan2(u)).clamp(0.0, 1.0) * 65535.0).round() as u16;
    }
    let path = dir.join(name);
    img.save(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    println!("{}", path.display());
}

fn main() {
    let dir = std::env::args().nth(1).map_or_else(|| PathBuf::from("scenes/stamps"), PathBuf::from);
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    write(&dir, "crater.png", |r, _| crater(r));
    write(&dir, "mountain.png", mountain);
}
