//! Writes the control map of `scenes/control-map.toml`: a 16-bit PNG over
//! the default world (10 240 m, 2.5 m texels) in seed 004's layout, painted
//! as a level designer would with two freely picked textures per texel:
//! - everywhere rock (background) under snow (overlay) with a slope
//!   threshold of 0.375: snow lies on ground under about 34 degrees, rock
//!   shows above it;
//! - below 600 m grass instead of snow, over scree;
//! - a road: a winding 8 m band of gravel over rock, with a high threshold
//!   (0.75) so it stays on the steep bits too.
//!
//! `cargo run --release --example control_maps -- [FILE]` (default
//! `scenes/control/default-world.png`).

use std::path::PathBuf;

use vista::world::{control_textures as tex, ControlCode, HeightSource, ProceduralSource, WorldDesc};

const SIDE: u32 = 4096;
const ROAD_HALF_WIDTH_M: f64 = 4.0;

/// The road's centre line: north from the south edge, winding east and
/// west (metres).
fn road_x(y: f64) -> f64 {
    5120.0 + 260.0 * (y / 700.0).sin() + 90.0 * (y / 230.0).sin()
}

fn main() {
    let path = std::env::args().nth(1).map_or_else(|| PathBuf::from("scenes/control/default-world.png"), PathBuf::from);
    let world = WorldDesc::default();
    let (_, source) = ProceduralSource::default_world(1);
    let [ex, ey] = world.extent_m;
    let (dx, dy) = (ex / f64::from(SIDE), ey / f64::from(SIDE));
    let code = |overlay, background, threshold| ControlCode { overlay, background, uv_scale: 0, threshold }.encode();
    let snow = code(tex::SNOW, tex::ROCK, 4);
    let grass = code(tex::GRASS, tex::SCREE, 4);
    let road = code(tex::GRAVEL, tex::ROCK, 7);
    let mut img = image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::new(SIDE, SIDE);
    for (i, j, p) in img.enumerate_pixels_mut() {
        // Texel (i, j), row 0 north: its centre in world metres.
        let (x, y) = ((f64::from(i) + 0.5) * dx, ey - (f64::from(j) + 0.5) * dy);
        let on_road = y < 6000.0 && (x - road_x(y)).abs() <= ROAD_HALF_WIDTH_M + 0.5 * dx;
        p.0[0] = if on_road {
            road
        } else if source.sample(x, y) < 600.0 {
            grass
        } else {
            snow
        };
    }
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    }
    img.save(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    println!("{}", path.display());
}
