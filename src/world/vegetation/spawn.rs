//! What grows in a cell: the brushes of the cell's material offer their
//! types; a type is eligible where the slope, the sun's share and the
//! resource suit it (seed 004: "compare with the values assigned to the
//! vegetation types to filter them out; where resource exceeds a
//! threshold, pick a type and spawn it, scaled by how close the conditions
//! are to perfect"). Trees and bushes: at most one instance a cell, chosen
//! by the entries' densities from a hash of the seed and the cell. Grass:
//! a bit per type (the occurrence maps are made of them).

use super::field::HeightField;
use super::params::{Entry, VegetationKind, VegetationParams};
use crate::world::hash::Fnv64;

/// A tree or bush (32 bytes, the layout a GPU instance buffer takes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Instance {
    /// World metres from the south-west corner; z: the ground there.
    pub position: [f32; 3],
    pub yaw_rad: f32,
    pub scale: f32,
    /// Index into the params' types.
    pub ty: u32,
    /// RGBA8 (linear), the crown's tint: drier is yellower.
    pub tint: u32,
    pub cell: u32,
}

/// A cell's conditions.
#[derive(Clone, Copy, Debug)]
pub struct Conditions {
    pub slope_deg: f64,
    pub altitude_m: f64,
    pub sun: f64,
    pub resource: f64,
}

/// Whether type `ty` tolerates `c`.
pub fn eligible(params: &VegetationParams, ty: usize, c: &Conditions) -> bool {
    let t = &params.types[ty];
    (t.slope_deg[0]..=t.slope_deg[1]).contains(&c.slope_deg)
        && (t.altitude_m[0]..=t.altitude_m[1]).contains(&c.altitude_m)
        && (t.sun[0]..=t.sun[1]).contains(&c.sun)
        && c.resource >= t.resource
}

/// How close `c` is to type `ty`'s perfect conditions (0..1).
pub fn suitability(params: &VegetationParams, ty: usize, c: &Conditions) -> f64 {
    let t = &params.types[ty];
    let water = (c.resource / t.ideal_resource).min(t.ideal_resource / c.resource.max(1e-9)).clamp(0.0, 1.0);
    let sun = 1.0 - (c.sun - t.ideal_sun).abs().min(1.0);
    water * sun
}

/// Uniform numbers in [0, 1) for cell `cell`, stream `k`.
fn random(seed: u32, cell: u64, k: u64) -> f64 {
    let h = Fnv64::new().u64(u64::from(seed)).u64(cell).u64(k).finish();
    (h >> 11) as f64 / (1u64 << 53) as f64
}

/// The grass types' bits of a cell whose material offers `entries`.
pub fn grass_bits(params: &VegetationParams, entries: &[Entry], c: &Conditions) -> u16 {
    entries
        .iter()
        .filter(|e| params.types[e.ty].kind == VegetationKind::Grass && e.density > 0.0 && eligible(params, e.ty, c))
        .fold(0, |b, e| b | 1 << e.ty)
}

/// The tree or bush that grows in cell (i, j), if any.
pub fn instance(
    params: &VegetationParams,
    field: &HeightField,
    entries: &[Entry],
    (i, j): (usize, usize),
    c: &Conditions,
) -> Option<Instance> {
    let cell = field.index(i, j) as u64;
    let u = random(params.seed, cell, 0);
    let mut acc = 0.0;
    let chosen = entries.iter().filter(|e| params.types[e.ty].kind != VegetationKind::Grass).find(|e| {
        acc += e.density;
        u < acc
    })?;
    if !eligible(params, chosen.ty, c) {
        return None;
    }
    let fit = suitability(params, chosen.ty, c);
    let [lo, hi] = chosen.scale;
    let spread = 1.0 + chosen.scale_var * (2.0 * random(params.seed, cell, 1) - 1.0);
    let (x, y) = (
        (i as f64 + 0.1 + 0.8 * random(params.seed, cell, 2)) * field.cell_m,
        (j as f64 + 0.1 + 0.8 * random(params.seed, cell, 3)) * field.cell_m,
    );
    let dry = (1.0 - (c.resource / params.types[chosen.ty].ideal_resource).min(1.0)) as f32;
    let rgb = [0.85 + 0.15 * dry, 1.0 - 0.1 * dry, 0.85 - 0.35 * dry].map(|v| (v * 255.0).round() as u32);
    Some(Instance {
        position: [x as f32, y as f32, field.bilinear(x, y) as f32],
        yaw_rad: (random(params.seed, cell, 4) * std::f64::consts::TAU) as f32,
        scale: ((lo + (hi - lo) * fit) * spread) as f32,
        ty: chosen.ty as u32,
        tint: rgb[0] | rgb[1] << 8 | rgb[2] << 16 | 255 << 24,
        cell: cell as u32,
    })
}
