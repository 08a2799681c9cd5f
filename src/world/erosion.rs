//! Water and gravity on a coarse grid of the world: what shapes the
//! procedural generator's large forms before its fine octaves go on top.
//!
//! Each round routes water (a priority flood from the border: every node
//! drains to the border, a closed basin fills to its spill level and
//! becomes a flat floor), cuts along the flow (the stream-power law, solved
//! implicitly from the lowest node up, so any step is stable), then lets
//! ground steeper than its angle of repose slide to the nodes below it
//! (talus). Every loop runs in a fixed order: the same heights give the
//! same result, bit for bit, in any process.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// Rounds of flow, cutting and sliding.
const ROUNDS: usize = 24;
/// Stream-power coefficient per round, with the drained area in grid cells
/// and distances in spacings (so the same whatever the spacing): a node
/// draining `n` cells closes `f / (1 + f)` of its height above its
/// receiver per round, `f = K * n^M` (over a diagonal's `sqrt 2`).
const K: f64 = 0.04;
/// Exponent of the drained area in the stream-power law.
const M: f64 = 0.5;
/// The angle of repose of loose rock (about 35 degrees), as a gradient.
const TALUS_GRADIENT: f64 = 0.7;
/// Share of the excess over the angle of repose that slides per pass.
const SLIDE: f64 = 0.25;
/// Sliding passes per round.
const SLIDE_PASSES: usize = 2;
/// Rise per node across a filled basin, metres: enough that every node's
/// water has a lower receiver, far below what a picture shows.
const FILL_EPSILON_M: f64 = 1e-3;

/// A node the flood raised more than this (metres) lies in a lake.
const LAKE_M: f64 = 0.01;
/// The eight neighbours, (dx, dy).
const NEIGHBOURS: [(isize, isize); 8] = [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)];

/// A grid of heights in metres, `nx` by `ny` nodes `spacing_m` apart.
pub(super) struct Terrain {
    pub nx: usize,
    pub ny: usize,
    pub spacing_m: f64,
    pub heights_m: Vec<f64>,
}

/// What the water and gravity left, per node.
pub(super) struct Shaped {
    /// The node each node's water flows to; border nodes name themselves.
    pub receivers: Vec<u32>,
    /// Area draining through the node, in grid cells (itself included).
    pub drained_cells: Vec<f64>,
    /// How far the last flood raised the node (a basin's flat floor), metres.
    pub filled_m: Vec<f64>,
    /// Rock that slid onto the node over all rounds (talus), metres.
    pub talus_m: Vec<f64>,
}

impl Terrain {
    /// Erodes the heights in place.
    pub fn erode(&mut self) -> Shaped {
        let mut talus_m = vec![0.0; self.heights_m.len()];
        for _ in 0..ROUNDS {
            let before = self.heights_m.clone();
            self.flood();
            let lake: Vec<bool> = self.heights_m.iter().zip(&before).map(|(a, b)| a - b > LAKE_M).collect();
            let (order, receivers) = self.steepest();
            let drained = self.drained_cells(&order);
            self.cut(&order, &receivers, &drained, &lake);
            for _ in 0..SLIDE_PASSES {
                self.slide(&mut talus_m);
            }
        }
        let before = self.heights_m.clone();
        self.flood();
        let (order, receivers) = self.steepest();
        let drained_cells = self.drained_cells(&order);
        let filled_m = self.heights_m.iter().zip(&before).map(|(a, b)| a - b).collect();
        Shaped { receivers, drained_cells, filled_m, talus_m }
    }

    fn neighbour(&self, k: usize, (dx, dy): (isize, isize)) -> Option<usize> {
        let (x, y) = ((k % self.nx) as isize + dx, (k / self.nx) as isize + dy);
        let inside = x >= 0 && y >= 0 && (x as usize) < self.nx && (y as usize) < self.ny;
        inside.then(|| y as usize * self.nx + x as usize)
    }

    fn on_border(&self, k: usize) -> bool {
        let (x, y) = (k % self.nx, k / self.nx);
        x == 0 || y == 0 || x + 1 == self.nx || y + 1 == self.ny
    }

    /// Priority flood from the border (Barnes et al. 2014, with epsilon):
    /// raises every closed basin to its spill level plus a slope of
    /// [`FILL_EPSILON_M`] per node, so every inner node has a lower
    /// neighbour.
    fn flood(&mut self) {
        let n = self.heights_m.len();
        let mut seen = vec![false; n];
        let mut open = BinaryHeap::new();
        for k in (0..n).filter(|&k| self.on_border(k)) {
            seen[k] = true;
            open.push(Lowest(self.heights_m[k], k as u32));
        }
        while let Some(Lowest(h, k)) = open.pop() {
            for d in NEIGHBOURS {
                let Some(j) = self.neighbour(k as usize, d) else { continue };
                if seen[j] {
                    continue;
                }
                seen[j] = true;
                self.heights_m[j] = self.heights_m[j].max(h + FILL_EPSILON_M);
                open.push(Lowest(self.heights_m[j], j as u32));
            }
        }
    }

    /// The nodes from the lowest up (ties by index) and each inner node's
    /// steepest lower neighbour; border nodes are outlets (their own).
    fn steepest(&self) -> (Vec<u32>, Vec<u32>) {
        let h = &self.heights_m;
        let mut order: Vec<u32> = (0..h.len() as u32).collect();
        order.sort_unstable_by(|&a, &b| h[a as usize].total_cmp(&h[b as usize]).then(a.cmp(&b)));
        let receivers = (0..h.len())
            .map(|k| {
                let mut best = (0.0, k);
                if !self.on_border(k) {
                    for (j, drop) in self.drops(k) {
                        if drop > best.0 {
                            best = (drop, j);
                        }
                    }
                }
                best.1 as u32
            })
            .collect();
        (order, receivers)
    }

    /// Each lower neighbour of `k` and the gradient down to it.
    fn drops(&self, k: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        NEIGHBOURS.into_iter().filter_map(move |d| {
            let j = self.neighbour(k, d)?;
            let dist = spacings(d);
            let drop = (self.heights_m[k] - self.heights_m[j]) / dist;
            (drop > 0.0).then_some((j, drop))
        })
    }

    /// Each node's drained area in grid cells: its own plus what its
    /// higher neighbours pass on, each split over all its lower neighbours
    /// by gradient (multiple flow directions: channels that do not follow
    /// the grid's eight directions). Border nodes pass nothing on.
    fn drained_cells(&self, order: &[u32]) -> Vec<f64> {
        let mut area = vec![1.0; order.len()];
        for &k in order.iter().rev() {
            let k = k as usize;
            if self.on_border(k) {
                continue;
            }
            let total: f64 = self.drops(k).map(|(_, d)| d).sum();
            for (j, drop) in self.drops(k) {
                area[j] += area[k] * drop / total;
            }
        }
        area
    }

    /// One implicit step of the stream-power law along the flow, from the
    /// lowest node up (a receiver is always lower than its donors): `h = (h + f h_r) / (1 + f)` with `f = K A^M / d`, so a node
    /// never cuts below its receiver.
    /// A filled basin (a lake) is not cut: its water crosses it along the
    /// fill's tiny slope, which would carve straight channels.
    fn cut(&mut self, order: &[u32], receivers: &[u32], drained: &[f64], lake: &[bool]) {
        for &k in order {
            let (k, r) = (k as usize, receivers[k as usize] as usize);
            if r == k || lake[k] {
                continue;
            }
            let d =
                (((r % self.nx) as isize - (k % self.nx) as isize), ((r / self.nx) as isize - (k / self.nx) as isize));
            let f = K * drained[k].powf(M) / spacings(d);
            self.heights_m[k] = (self.heights_m[k] + f * self.heights_m[r]) / (1.0 + f);
        }
    }

    /// Ground steeper than the angle of repose moves a share of its
    /// largest excess down, split over every neighbour it stands too high
    /// above by that neighbour's excess (all nodes at once, from the
    /// heights before the pass: no direction of the grid is favoured).
    fn slide(&mut self, talus_m: &mut [f64]) {
        let mut delta = vec![0.0; self.heights_m.len()];
        let mut over = Vec::with_capacity(8);
        for k in 0..self.heights_m.len() {
            over.clear();
            for d in NEIGHBOURS {
                let Some(j) = self.neighbour(k, d) else { continue };
                let dist = self.spacing_m * spacings(d);
                let excess = self.heights_m[k] - self.heights_m[j] - TALUS_GRADIENT * dist;
                if excess > 0.0 {
                    over.push((j, excess));
                }
            }
            let total: f64 = over.iter().map(|o| o.1).sum();
            let largest = over.iter().map(|o| o.1).fold(0.0, f64::max);
            for &(j, excess) in &over {
                let moved = SLIDE * 0.5 * largest * excess / total;
                delta[k] -= moved;
                delta[j] += moved;
                talus_m[j] += moved;
            }
        }
        for (h, d) in self.heights_m.iter_mut().zip(delta) {
            *h += d;
        }
    }
}

/// How many grid spacings a step to neighbour `d` spans.
fn spacings((dx, dy): (isize, isize)) -> f64 {
    if dx != 0 && dy != 0 {
        std::f64::consts::SQRT_2
    } else {
        1.0
    }
}

/// A flood entry: the lowest height first, then the lowest index (so ties
/// pop in one order everywhere).
struct Lowest(f64, u32);

impl PartialEq for Lowest {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Lowest {}
impl PartialOrd for Lowest {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Lowest {
    fn cmp(&self, other: &Self) -> Ordering {
        other.0.total_cmp(&self.0).then(other.1.cmp(&self.1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bowl with a notch: its water must leave through the notch.
    #[test]
    fn a_closed_bowl_fills_to_its_spill_level_and_drains_to_the_border() {
        let (nx, ny) = (9, 9);
        let mut heights_m: Vec<f64> = (0..nx * ny)
            .map(|k| {
                let (x, y) = ((k % nx) as f64 - 4.0, (k / nx) as f64 - 4.0);
                10.0 + (x * x + y * y).sqrt().min(4.0) * 5.0
            })
            .collect();
        // The notch: a channel at 12 m from (4, 3) out to the border at (4, 0).
        for y in 0..4 {
            heights_m[y * nx + 4] = 12.0;
        }
        let mut t = Terrain { nx, ny, spacing_m: 10.0, heights_m };
        t.flood();
        let (order, receivers) = t.steepest();
        assert_eq!(order.len(), nx * ny);
        for k in 0..nx * ny {
            let mut at = k;
            for _ in 0..nx * ny {
                let r = receivers[at] as usize;
                assert!(t.heights_m[r] < t.heights_m[at] || r == at, "water at {at} climbs to {r}");
                if r == at {
                    break;
                }
                at = r;
            }
            assert!(t.on_border(at), "water from {k} ends at {at}, inside");
        }
        // The bowl's floor (10 m) filled to the notch's 12 m.
        assert!((t.heights_m[4 * nx + 4] - 12.0).abs() < 0.01, "{}", t.heights_m[4 * nx + 4]);
    }
}
