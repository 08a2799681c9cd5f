//! Effect `grass`'s placement, on the CPU: grass.glsl's cell hash and
//! point and `grass_place`'s keep test, step for step, so the tests can
//! compare every tuft the GPU placed.

use crate::effects::grass::GrassParams;

/// PCG-based 3D integer hash, one lane kept (hashed_noise.glsl's `pcg3d_x`).
pub fn pcg3d_x(v: [u32; 3]) -> u32 {
    let mut v = v.map(|x| x.wrapping_mul(1_664_525).wrapping_add(1_013_904_223));
    for round in 0..2 {
        v[0] = v[0].wrapping_add(v[1].wrapping_mul(v[2]));
        v[1] = v[1].wrapping_add(v[2].wrapping_mul(v[0]));
        v[2] = v[2].wrapping_add(v[0].wrapping_mul(v[1]));
        if round == 0 {
            v = v.map(|x| x ^ (x >> 16));
        }
    }
    v[0]
}

/// grass.glsl's `grass_cell_hash`.
pub fn cell_hash(cell: [i32; 2], seed: u32) -> [u32; 2] {
    let c = cell.map(|c| c as u32);
    [pcg3d_x([c[0], c[1], seed]), pcg3d_x([c[0], c[1], seed ^ 0x5BD1_E995])]
}

/// The ground under a candidate tuft, as the CPU twin's caller knows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Ground {
    pub material: u32,
    pub hole: bool,
}

/// A tuft the CPU twin places.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TuftCpu {
    pub cell: [i32; 2],
    pub xy: [f32; 2],
    pub material: u32,
    /// Rotation (0..255 of a turn) and lean (0..255), as the GPU packs them.
    pub rotation: u32,
    pub lean: u32,
    /// Its distance to the camera lies within a millimetre of the radius:
    /// the GPU's square root may decide it the other way.
    pub borderline: bool,
}

/// Where one cell's tuft would stand (grass.glsl, exact in f32).
pub fn cell_point(cell: [i32; 2], cell_m: f32, seed: u32) -> [f32; 2] {
    let h = cell_hash(cell, seed)[0];
    let jitter = [(h & 0xFFFF) as f32, (h >> 16) as f32].map(|j| j * (1.0 / 65536.0));
    [0, 1].map(|i| (cell[i] as f32 + jitter[i]) * cell_m)
}

/// The placement's CPU twin: every tuft `grass_place` keeps before
/// culling, for the camera at `camera_xy` (the GPU's f32). `ground(p)`
/// says the material at `p` and whether it is a hole, or None where no
/// terrain is found; `holes`: whether holes cut (the frame's switch).
/// The vegetation's occurrence map, when the params hold one, skips cells
/// as `grass_place` does.
pub fn place_cpu(
    params: &GrassParams,
    camera_xy: [f32; 2],
    holes: bool,
    ground: impl Fn([f32; 2]) -> Option<Ground>,
) -> Vec<TuftCpu> {
    let grid = params.grid(camera_xy);
    let rules = params.rules_gpu();
    let mut out = Vec::new();
    for y in 0..grid.side as i32 {
        for x in 0..grid.side as i32 {
            let cell = [grid.cell0[0] + x, grid.cell0[1] + y];
            let p = cell_point(cell, params.cell_m, params.seed);
            let d = f64::from(p[0] - camera_xy[0]).hypot(f64::from(p[1] - camera_xy[1]));
            let borderline = (d - f64::from(params.radius_m)).abs() < 1e-3;
            if d >= f64::from(params.radius_m) && !borderline {
                continue;
            }
            if params.occurrence.as_ref().is_some_and(|o| !o.bit(p)) {
                continue;
            }
            let Some(g) = ground(p) else { continue };
            let h = cell_hash(cell, params.seed);
            let keep = (h[1] >> 8) as f32 * (1.0 / 16_777_216.0);
            if keep >= rules[g.material as usize].density || (holes && g.hole) {
                continue;
            }
            let lean = h[0].wrapping_mul(0x9E37_79B9) >> 24;
            out.push(TuftCpu { cell, xy: p, material: g.material, rotation: h[1] & 0xFF, lean, borderline });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Known values of the published PCG3D (Jarzynski and Olano) lane x.
    #[test]
    fn the_hash_is_pcg3d() {
        // Derived by hand from the definition for v = (0, 0, 0): each lane
        // starts at 1013904223; x += y*z etc. (wrapping), then the shift.
        let s = 1_013_904_223u32;
        let mut v = [s, s, s];
        v[0] = v[0].wrapping_add(v[1].wrapping_mul(v[2]));
        v[1] = v[1].wrapping_add(v[2].wrapping_mul(v[0]));
        v[2] = v[2].wrapping_add(v[0].wrapping_mul(v[1]));
        let v = v.map(|x| x ^ (x >> 16));
        let x = v[0].wrapping_add(v[1].wrapping_mul(v[2]));
        assert_eq!(pcg3d_x([0, 0, 0]), x);
        assert_ne!(cell_hash([1, 2], 1), cell_hash([2, 1], 1));
    }

    #[test]
    fn a_cell_keeps_its_point_and_the_grid_covers_the_radius() {
        let p = GrassParams::default();
        assert_eq!(cell_point([-3, 7], 0.5, 1), cell_point([-3, 7], 0.5, 1));
        let q = cell_point([-3, 7], 0.5, 1);
        assert!((-1.5..-1.0).contains(&q[0]) && (3.5..4.0).contains(&q[1]), "{q:?}");
        let g = p.grid([100.3, 50.7]);
        let lo = g.cell0.map(|c| c as f32 * p.cell_m);
        let hi = g.cell0.map(|c| (c + g.side as i32) as f32 * p.cell_m);
        assert!(lo[0] <= 100.3 - p.radius_m && hi[0] >= 100.3 + p.radius_m);
        assert!(lo[1] <= 50.7 - p.radius_m && hi[1] >= 50.7 + p.radius_m);
    }
}
