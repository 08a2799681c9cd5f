//! What a grid's heights span: its pixels against a chosen range, and every
//! value the Catmull-Rom resampler can produce between them.
//!
//! Catmull-Rom has negative lobes, so next to a cliff it overshoots the
//! pixels' min/max. Baked heights are R16 over the world's height range and
//! clamp outside it, so a range taken from the pixels alone would flatten
//! every overshooting peak and pit. The resampler itself is left as it is
//! (a monotone one would change every baked world); instead the automatic
//! range is widened to a bound of the overshoot, computed per cell.

use rayon::prelude::*;

use super::source::{catmull_rom, GridSource};

/// Pixels of a grid that fall outside a height range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RangeFit {
    /// Pixels below the range's low end or above its high end.
    pub outside: usize,
    /// All pixels.
    pub total: usize,
    /// The lowest and highest pixel, metres.
    pub min: f32,
    pub max: f32,
}

impl GridSource {
    /// How many pixels `range` (lo, hi metres) would clip, and the pixels'
    /// extremes, for a message that says by how much.
    pub fn fit(&self, range: [f32; 2]) -> RangeFit {
        let [lo, hi] = range;
        let mut fit = RangeFit { outside: 0, total: 0, min: f32::INFINITY, max: f32::NEG_INFINITY };
        for j in 0..self.height() {
            for i in 0..self.width() {
                let v = self.pixel(i, j);
                fit.outside += usize::from(v < lo || v > hi);
                fit.total += 1;
                fit.min = fit.min.min(v);
                fit.max = fit.max.max(v);
            }
        }
        fit
    }

    /// A range (lo, hi metres) that holds every value [`HeightSource::sample`]
    /// returns anywhere, overshoot included; equal to the pixels' min/max
    /// where the data do not overshoot, up to a relative 1e-6 margin.
    ///
    /// Per cell between four pixel centres the resampler is
    /// `f(u, v) = Σa wu_a(u) · c_a(v)`, where `c_a` is column a's cubic in v.
    /// Each `c_a` is bounded exactly (endpoints and the derivative's roots);
    /// since `wu_1, wu_2 >= 0 >= wu_0, wu_3`, f is at most the Catmull-Rom
    /// cubic through (min c_0, max c_1, max c_2, min c_3), whose maximum is
    /// again exact. The bound is tight for data varying along one axis (a
    /// straight cliff) and never below the truth. A plain 4x4 analytic bound
    /// (overshoot <= 0.28 of the neighbourhood's range) would be safe too but
    /// spend a quarter of the R16 precision on every cliff.
    ///
    /// [`HeightSource::sample`]: super::HeightSource::sample
    pub fn resampled_range(&self) -> [f32; 2] {
        self.resampled_range_of([0, 0, self.width() - 1, self.height() - 1])
    }

    /// As [`Self::resampled_range`], over the cells between pixel columns
    /// `i0..=i1` and rows `j0..=j1` only (`[i0, j0, i1, j1]`, inclusive).
    pub fn resampled_range_of(&self, pixels: [usize; 4]) -> [f32; 2] {
        let [i0, j0, i1, j1] = pixels;
        assert!(i0 <= i1 && i1 < self.width() && j0 <= j1 && j1 < self.height(), "pixels {pixels:?} outside the grid");
        let (w, h) = (self.width(), self.height());
        // A single row or column never leaves its pixel centres on that axis.
        let (tu, tv) = (if w > 1 { 1.0 } else { 0.0 }, if h > 1 { 1.0 } else { 0.0 });
        let at = |i: isize, j: isize| {
            f64::from(self.pixel(i.clamp(0, w as isize - 1) as usize, j.clamp(0, h as isize - 1) as usize))
        };
        // Cells per axis (cell i lies between pixels i and i + 1); a single
        // pixel still has one (degenerate) cell.
        let cells =
            |a: usize, b: usize, n: usize| a.min(n.saturating_sub(2))..b.max(a + 1).min(n.saturating_sub(1).max(1));
        let (cells_u, cells_v) = (cells(i0, i1, w), cells(j0, j1, h));
        let (lo, hi) = cells_v
            .into_par_iter()
            .map(|jv| {
                // Range of every column's cubic over this row of cells.
                let jv = jv as isize;
                let first = cells_u.start as isize - 1;
                let cols: Vec<(f64, f64)> = (first..cells_u.end as isize + 2)
                    .map(|i| cubic_range([at(i, jv - 1), at(i, jv), at(i, jv + 1), at(i, jv + 2)], tv))
                    .collect();
                let mut out = (f64::INFINITY, f64::NEG_INFINITY);
                for iu in 0..cells_u.len() {
                    let c = &cols[iu..iu + 4];
                    let upper = cubic_range([c[0].0, c[1].1, c[2].1, c[3].0], tu).1;
                    let lower = cubic_range([c[0].1, c[1].0, c[2].0, c[3].1], tu).0;
                    out = (out.0.min(lower), out.1.max(upper));
                }
                out
            })
            .reduce(|| (f64::INFINITY, f64::NEG_INFINITY), |a, b| (a.0.min(b.0), a.1.max(b.1)));
        // Covers the f64 evaluation order and the rounding to f32 (at most
        // 2^-24 relative), so a sample rounded the same way stays inside.
        let margin = 1e-6 * lo.abs().max(hi.abs()).max(1.0);
        [(lo - margin) as f32, (hi + margin) as f32]
    }
}

/// Min and max of the 1D Catmull-Rom interpolant through `p` for t in
/// [0, t_max]: at the ends and where its derivative vanishes.
fn cubic_range(p: [f64; 4], t_max: f64) -> (f64, f64) {
    let eval = |t: f64| catmull_rom(t).iter().zip(p).map(|(w, v)| w * v).sum::<f64>();
    // f(t) = a t³ + b t² + c t + p1, from the weights' polynomial form.
    let a = 0.5 * (-p[0] + 3.0 * p[1] - 3.0 * p[2] + p[3]);
    let b = 0.5 * (2.0 * p[0] - 5.0 * p[1] + 4.0 * p[2] - p[3]);
    let c = 0.5 * (p[2] - p[0]);
    let mut range = (p[1].min(eval(t_max)), p[1].max(eval(t_max)));
    let mut visit = |t: f64| {
        if t > 0.0 && t < t_max {
            let v = eval(t);
            range = (range.0.min(v), range.1.max(v));
        }
    };
    // Roots of 3a t² + 2b t + c.
    if a.abs() > 1e-12 * (b.abs() + c.abs()) {
        let disc = b * b - 3.0 * a * c;
        if disc >= 0.0 {
            let s = disc.sqrt();
            visit((-b + s) / (3.0 * a));
            visit((-b - s) / (3.0 * a));
        }
    } else if b != 0.0 {
        visit(-c / (2.0 * b));
    }
    range
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::HeightSource;

    /// Every sample on a fine lattice (pixel centres and 15 points between
    /// each pair) and its min/max.
    fn dense_extremes(g: &GridSource, extent: [f64; 2]) -> (f32, f32) {
        let (nx, ny) = (g.width() * 16, g.height() * 16);
        let mut out = (f32::INFINITY, f32::NEG_INFINITY);
        for j in 0..=ny {
            for i in 0..=nx {
                let v = g.sample(extent[0] * i as f64 / nx as f64, extent[1] * j as f64 / ny as f64);
                out = (out.0.min(v), out.1.max(v));
            }
        }
        out
    }

    #[test]
    fn a_step_overshoots_by_the_one_dimensional_amount_and_stays_inside() {
        // A 0 -> 100 m step along x: the 1D Catmull-Rom cubic through
        // (0, 0, 0, 100) is 50 (t³ - t²), minimum at t = 2/3:
        // 50 (8/27 - 12/27) = -200/27 = -7.407 m; mirrored +107.407 m.
        let (w, h) = (8, 6);
        let data: Vec<f32> = (0..w * h).map(|k| if k % w < 4 { 0.0 } else { 100.0 }).collect();
        let g = GridSource::new(w, h, data, [80.0, 60.0]);
        let [lo, hi] = g.resampled_range();
        let expect = 200.0 / 27.0;
        assert!((lo + expect).abs() < 1e-3 && (hi - 100.0 - expect).abs() < 1e-3, "{lo}..{hi}");
        let (mn, mx) = dense_extremes(&g, [80.0, 60.0]);
        assert!(mn >= lo && mx <= hi, "samples {mn}..{mx} outside {lo}..{hi}");
        // The lattice hits t = 0.6875 and 0.3125, near the extremes.
        assert!(mn < -7.0 && mx > 107.0, "the step overshoots: {mn}..{mx}");
    }

    #[test]
    fn a_spike_and_random_data_never_leave_the_bound() {
        let (w, h) = (9, 7);
        let mut data = vec![10.0f32; w * h];
        data[3 * w + 4] = 500.0;
        let spike = GridSource::new(w, h, data, [90.0, 70.0]);
        let mut seed = 7u64;
        let noise: Vec<f32> = (0..w * h)
            .map(|_| {
                seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                (seed >> 40) as f32 / 16.0 - 300.0
            })
            .collect();
        let noisy = GridSource::new(w, h, noise, [90.0, 70.0]);
        for g in [spike, noisy] {
            let [lo, hi] = g.resampled_range();
            let (mn, mx) = dense_extremes(&g, [90.0, 70.0]);
            assert!(mn >= lo && mx <= hi, "samples {mn}..{mx} outside {lo}..{hi}");
            let fit = g.fit([lo, hi]);
            assert!(fit.min >= lo && fit.max <= hi && fit.outside == 0);
        }
    }

    #[test]
    fn flat_and_linear_data_keep_their_pixel_range() {
        // A ramp is reproduced exactly by Catmull-Rom: no overshoot, so the
        // range is the pixels' own (plus the 1e-6 relative margin).
        let data: Vec<f32> = (0..5 * 4).map(|k| (k % 5) as f32 * 25.0 - 50.0).collect();
        let g = GridSource::new(5, 4, data, [50.0, 40.0]);
        let [lo, hi] = g.resampled_range();
        assert!((lo + 50.0).abs() <= 1e-4 && (hi - 50.0).abs() <= 1e-4, "{lo}..{hi}");
        let one = GridSource::new(1, 1, vec![42.0], [10.0, 10.0]);
        let [lo, hi] = one.resampled_range();
        assert!(lo <= 42.0 && hi >= 42.0 && hi - lo < 1e-3, "{lo}..{hi}");
    }

    #[test]
    fn fit_counts_pixels_outside() {
        let g = GridSource::new(3, 2, vec![-12.0, 0.0, 5.0, 10.0, 1000.0, 1520.5], [3.0, 2.0]);
        // Below 0: -12; above 1000: 1520.5 (1000 itself is inside).
        assert_eq!(g.fit([0.0, 1000.0]), RangeFit { outside: 2, total: 6, min: -12.0, max: 1520.5 });
        assert_eq!(g.fit([-20.0, 2000.0]).outside, 0);
    }
}
