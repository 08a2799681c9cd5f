//! The finest surface vista can draw, evaluated here from its definition
//! and independently of `vista::reference::FinestSurface`: the world's
//! LOD-0 samples as the bake rounds them (R16), the bicubic Catmull-Rom
//! patch through them evaluated at every quarter-sample lattice point (the
//! deepest refinement below LOD 0), and between those points the two
//! triangles of each lattice quad, split SW-NE where the quad's indices sum
//! to an even number and NW-SE elsewhere (the diamond pattern).

use std::collections::HashMap;
use std::sync::Mutex;
use vista::world::{HeightSource, WorldDesc};

/// Lattice points per LOD-0 sample spacing.
const QUARTERS: i64 = 4;

pub struct Finest<'a> {
    world: WorldDesc,
    src: &'a dyn HeightSource,
    samples: Mutex<HashMap<[i64; 2], f64>>,
}

impl<'a> Finest<'a> {
    pub fn new(world: &WorldDesc, src: &'a dyn HeightSource) -> Self {
        Finest { world: *world, src, samples: Mutex::new(HashMap::new()) }
    }

    /// LOD-0 sample [i, j]: the source at its grid position (clamped to the
    /// extent), through R16 and back.
    fn post(&self, ij: [i64; 2]) -> f64 {
        *self.samples.lock().unwrap().entry(ij).or_insert_with(|| {
            let w = &self.world;
            let x = (w.grid_origin_m[0] + ij[0] as f64 * w.spacing_m).clamp(0.0, w.extent_m[0]);
            let y = (w.grid_origin_m[1] + ij[1] as f64 * w.spacing_m).clamp(0.0, w.extent_m[1]);
            f64::from(w.decode_height(w.encode_height(self.src.sample(x, y))))
        })
    }

    /// The bicubic Catmull-Rom patch at lattice point q (quarter samples):
    /// p(t) = 1/2 [1 t t^2 t^3] M [p-1 p0 p1 p2]^T along both axes.
    fn lattice(&self, q: [i64; 2]) -> f64 {
        const M: [[f64; 4]; 4] =
            [[0.0, 2.0, 0.0, 0.0], [-1.0, 0.0, 1.0, 0.0], [2.0, -5.0, 4.0, -1.0], [-1.0, 3.0, -3.0, 1.0]];
        let base = q.map(|v| v.div_euclid(QUARTERS));
        let t = [0, 1].map(|a| (q[a] - base[a] * QUARTERS) as f64 / QUARTERS as f64);
        let weights = |t: f64| {
            let powers = [1.0, t, t * t, t * t * t];
            let mut w = [0.0; 4];
            for (k, wk) in w.iter_mut().enumerate() {
                *wk = 0.5 * (0..4).map(|r| powers[r] * M[r][k]).sum::<f64>();
            }
            w
        };
        let (wx, wy) = (weights(t[0]), weights(t[1]));
        let mut h = 0.0;
        for (b, wyb) in wy.iter().enumerate() {
            for (a, wxa) in wx.iter().enumerate() {
                h += wxa * wyb * self.post([base[0] + a as i64 - 1, base[1] + b as i64 - 1]);
            }
        }
        h
    }

    /// Height at world (x, y).
    pub fn height(&self, x: f64, y: f64) -> f64 {
        let w = &self.world;
        let u = (x - w.grid_origin_m[0]) / w.spacing_m * QUARTERS as f64;
        let v = (y - w.grid_origin_m[1]) / w.spacing_m * QUARTERS as f64;
        let q = [u.floor() as i64, v.floor() as i64];
        let (fu, fv) = (u - q[0] as f64, v - q[1] as f64);
        let h = |di: i64, dj: i64| self.lattice([q[0] + di, q[1] + dj]);
        let (h00, h10, h01, h11) = (h(0, 0), h(1, 0), h(0, 1), h(1, 1));
        if (q[0] + q[1]).rem_euclid(2) == 0 {
            // SW-NE diagonal: triangles (00, 10, 11) below it, (00, 11, 01) above.
            if fv <= fu {
                h00 + fu * (h10 - h00) + fv * (h11 - h10)
            } else {
                h00 + fv * (h01 - h00) + fu * (h11 - h01)
            }
        } else if fu + fv <= 1.0 {
            // NW-SE diagonal: (00, 10, 01) below it, (10, 11, 01) above.
            h00 + fu * (h10 - h00) + fv * (h01 - h00)
        } else {
            h11 + (1.0 - fu) * (h01 - h11) + (1.0 - fv) * (h10 - h11)
        }
    }
}
