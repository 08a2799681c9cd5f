//! Pictures of a generated grid a user can look at, a pixel a cell,
//! north up: `resource.png` (dry brown to wet blue, logarithmic up to the
//! 99th percentile), `sun.png` (the lit share of the day, black to white),
//! `vegetation.png` (a hillshade tinted by the ground's material, green
//! where a grass type may grow, a tree or bush a 3 x 3 dot in its type's
//! colour: a forest reads as a dark mass, as on a map).

use image::{Rgb, RgbImage};

use super::params::{VegetationKind, VegetationParams};
use super::Generated;

/// The materials' tints ([`crate::world::Material`] ids): grass, rock,
/// snow, scree, sand.
const GROUND: [[u8; 3]; 5] = [[200, 205, 170], [170, 170, 170], [250, 250, 255], [190, 175, 150], [225, 205, 150]];

/// The types' dot colours, in order (then repeated).
const PALETTE: [[u8; 3]; 6] =
    [[16, 64, 32], [70, 120, 30], [150, 130, 40], [120, 40, 110], [30, 90, 120], [160, 70, 30]];

/// Lambert shade (0..1) of each cell lit from the north-west, 45 degrees
/// up: the classic cartographic hillshade.
pub fn hillshade(g: &Generated) -> Vec<f32> {
    let [w, h] = g.size;
    let at = |i: isize, j: isize| {
        f64::from(g.z[j.clamp(0, h as isize - 1) as usize * w + i.clamp(0, w as isize - 1) as usize])
    };
    let light = glam::DVec3::new(-1.0, 1.0, 2f64.sqrt()).normalize();
    (0..w * h)
        .map(|k| {
            let (i, j) = ((k % w) as isize, (k / w) as isize);
            let dx = (at(i + 1, j) - at(i - 1, j)) / (2.0 * g.cell_m);
            let dy = (at(i, j + 1) - at(i, j - 1)) / (2.0 * g.cell_m);
            glam::DVec3::new(-dx, -dy, 1.0).normalize().dot(light).max(0.0) as f32
        })
        .collect()
}

fn image_of(g: &Generated, mut colour: impl FnMut(usize) -> [u8; 3]) -> RgbImage {
    let [w, h] = g.size;
    RgbImage::from_fn(w as u32, h as u32, |x, y| {
        let k = (h - 1 - y as usize) * w + x as usize;
        Rgb(if g.hole[k] { [0, 0, 0] } else { colour(k) })
    })
}

fn lerp(a: [u8; 3], b: [u8; 3], t: f32) -> [u8; 3] {
    [0, 1, 2].map(|c| (f32::from(a[c]) + (f32::from(b[c]) - f32::from(a[c])) * t.clamp(0.0, 1.0)).round() as u8)
}

/// `resource.png`, `sun.png` and `vegetation.png`, named.
pub fn pictures(params: &VegetationParams, g: &Generated) -> [(&'static str, RgbImage); 3] {
    let mut sorted: Vec<f32> = g.resource.iter().zip(&g.hole).filter(|(_, h)| !**h).map(|(r, _)| *r).collect();
    sorted.sort_by(f32::total_cmp);
    let top = sorted.get(sorted.len() * 99 / 100).copied().unwrap_or(1.0).max(1.0 + 1e-3);
    let resource = image_of(g, |k| lerp([190, 165, 120], [20, 60, 170], (1.0 + g.resource[k]).ln() / (1.0 + top).ln()));
    let sun = image_of(g, |k| [(g.sun[k] * 255.0).round() as u8; 3]);
    [("resource.png", resource), ("sun.png", sun), ("vegetation.png", vegetation_image(params, g))]
}

/// The hillshade tinted by material, grass in green, the instances' dots.
fn vegetation_image(params: &VegetationParams, g: &Generated) -> RgbImage {
    let shade = hillshade(g);
    let [w, h] = g.size;
    let mut dots = vec![None; g.z.len()];
    for i in &g.instances {
        let (ci, cj) = ((i.cell as usize % w) as isize, (i.cell as usize / w) as isize);
        for (di, dj) in (-1..=1).flat_map(|a| (-1..=1).map(move |b| (a, b))) {
            let (x, y) = (ci + di, cj + dj);
            if x >= 0 && y >= 0 && (x as usize) < w && (y as usize) < h {
                dots[y as usize * w + x as usize] = Some(PALETTE[i.ty as usize % PALETTE.len()]);
            }
        }
    }
    let grass = params.types.iter().enumerate().filter(|(_, t)| t.kind == VegetationKind::Grass);
    let grass_mask = grass.fold(0u16, |m, (ty, _)| m | 1 << ty);
    image_of(g, |k| {
        let tint = GROUND[usize::from(g.material[k]).min(4)];
        let lit = 0.3 + 0.7 * shade[k];
        let base = tint.map(|c| (f32::from(c) * lit).round() as u8);
        let ground = if g.grass[k] & grass_mask != 0 { lerp(base, [110, 180, 80], 0.5) } else { base };
        dots[k].unwrap_or(ground)
    })
}
