//! A patch's high quantile of its per-quad errors, bounded from above with a
//! log histogram: the error tree's second number beside the largest error.
//!
//! The knob's promise is about pixels: at most 1 % of them off by more than
//! the target (and none by more than twice it). A patch whose quads are
//! within the target but for 1 % of its area keeps the first half wherever
//! it is drawn; only the largest error needs the full guarantee, at twice
//! the target. Selecting by the largest error alone measured about a third
//! of the asked error at 1 px, paid in triangles (docs/accuracy.md).

/// Bins per octave (the top 2 mantissa bits of an f32).
const BINS_PER_OCTAVE_LOG2: u32 = 2;
/// The first bin holds everything below 2^-20 m (a micrometre).
const FIRST_EXPONENT: u32 = 127 - 20;
/// 32 octaves: up to 2^12 m; the last bin holds everything above.
const BINS: usize = 32 << BINS_PER_OCTAVE_LOG2;
/// The quantile kept: 99 % of a patch's quads lie within it.
const QUANTILE: f64 = 0.99;

const SHIFT: u32 = 23 - BINS_PER_OCTAVE_LOG2;
const BASE: u32 = FIRST_EXPONENT << BINS_PER_OCTAVE_LOG2;

/// Counts of per-quad errors (metres) in bins of a quarter of their octave
/// (a value's bin ends at most 25 % above it).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Histogram(Box<[u32; BINS]>);

impl Default for Histogram {
    fn default() -> Self {
        Histogram(Box::new([0; BINS]))
    }
}

impl Histogram {
    pub fn add(&mut self, error_m: f32) {
        self.0[bin(error_m)] += 1;
    }

    pub fn merge(&mut self, other: &Histogram) {
        for (a, b) in self.0.iter_mut().zip(other.0.iter()) {
            *a += b;
        }
    }

    /// An upper bound of the `QUANTILE` of the counted errors, never above
    /// `max_m` (their largest, tracked exactly by the caller).
    pub fn quantile(&self, max_m: f32) -> f32 {
        let total: u64 = self.0.iter().map(|&c| u64::from(c)).sum();
        let need = (QUANTILE * total as f64).ceil() as u64;
        let mut seen = 0u64;
        for (b, &c) in self.0.iter().enumerate() {
            seen += u64::from(c);
            if seen >= need.max(1) {
                return if b + 1 == BINS { max_m } else { upper_edge(b).min(max_m) };
            }
        }
        max_m
    }
}

fn bin(error_m: f32) -> usize {
    // Errors are >= 0; NaN never reaches here (the sources refuse it).
    let key = error_m.max(0.0).to_bits() >> SHIFT;
    (key.saturating_sub(BASE) as usize).min(BINS - 1)
}

/// The smallest value of bin `b + 1`: every value of bin `b` is below it.
fn upper_edge(b: usize) -> f32 {
    f32::from_bits((BASE + b as u32 + 1) << SHIFT)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bins_hold_their_values_below_an_upper_edge_at_most_25_percent_above() {
        for &v in &[1e-7f32, 1e-6, 3.3e-4, 0.01, 0.49, 0.5, 1.0, 7.3, 100.0, 4095.0] {
            let b = bin(v);
            assert!(v < upper_edge(b), "{v} in bin {b} with edge {}", upper_edge(b));
            if v >= 2f32.powi(-20) {
                assert!(upper_edge(b) <= v * 1.25 * 1.0001, "{v}: edge {}", upper_edge(b));
            }
        }
        assert_eq!(bin(1e9), BINS - 1);
        assert_eq!(bin(0.0), 0);
    }

    #[test]
    fn the_quantile_bounds_the_99th_percentile_and_never_exceeds_the_largest() {
        let mut h = Histogram::default();
        let values: Vec<f32> = (1..=1000).map(|i| i as f32 * 0.001).collect();
        values.iter().for_each(|&v| h.add(v));
        let q = h.quantile(1.0);
        // 990 of the 1000 values are <= 0.990.
        assert!((0.990..=0.990 * 1.25).contains(&q), "{q}");
        assert!(values.iter().filter(|&&v| v <= q).count() >= 990);
        // A few outliers do not move it; the largest caps it.
        let mut h = Histogram::default();
        (0..999).for_each(|_| h.add(0.01));
        h.add(50.0);
        assert!(h.quantile(50.0) < 0.02);
        let mut h = Histogram::default();
        h.add(0.3);
        assert_eq!(h.quantile(0.3), 0.3);
    }
}
