//! The generator's water: every cell starts with one unit of resource
//! (rain), and each iteration moves a share of a cell's resource to its
//! lower neighbours (of eight), split by how far each lies below it (drop
//! over distance). The share is `flow` where the steepest drop reaches
//! `flow_slope_deg`, proportionally less on gentler ground: flats keep
//! their rain, slopes shed it. Seed 004: "from each cell's slopes to its
//! neighbours, decrease/increase resource values (sedimentation)".
//!
//! Nothing is made or lost: a cell with no lower neighbour keeps its
//! resource, and the grid's edge is closed. Holes hold none and take none.
//! Each iteration reads the last one's grid only (a gather, in any order),
//! so a cell's value after k iterations depends on the cells within k of
//! it: a window k cells wider than a tile gives the tile exactly.

use super::field::HeightField;

const NEIGHBOURS: [(isize, isize); 8] = [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)];

/// A rectangle of cells: `lo` and `size` in the field's cells.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Window {
    pub lo: [usize; 2],
    pub size: [usize; 2],
}

impl Window {
    /// `core` grown by `halo` cells each way, clipped to the field.
    pub fn around(core: Window, halo: usize, field: [usize; 2]) -> Window {
        let lo = [core.lo[0].saturating_sub(halo), core.lo[1].saturating_sub(halo)];
        let hi = [0, 1].map(|a| (core.lo[a] + core.size[a] + halo).min(field[a]));
        Window { lo, size: [hi[0] - lo[0], hi[1] - lo[1]] }
    }

    pub fn contains(&self, i: isize, j: isize) -> bool {
        i >= self.lo[0] as isize
            && j >= self.lo[1] as isize
            && i < (self.lo[0] + self.size[0]) as isize
            && j < (self.lo[1] + self.size[1]) as isize
    }
}

/// How fast resource leaves a cell: `flow` (0..1) at and above the slope
/// `full_slope_deg`, in proportion to the steepest drop's gradient below it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Flow {
    pub share: f64,
    pub full_slope_deg: f64,
}

/// Cell (i, j)'s shares to its eight neighbours (field indices): each
/// lower one gets its drop's part of the cell's share.
fn shares(field: &HeightField, i: usize, j: usize, flow: Flow) -> [f64; 8] {
    let mut out = [0.0; 8];
    if field.hole[field.index(i, j)] {
        return out;
    }
    let z = field.at(i as isize, j as isize);
    let (mut sum, mut steepest) = (0.0, 0.0f64);
    for (k, (di, dj)) in NEIGHBOURS.iter().enumerate() {
        let (ni, nj) = (i as isize + di, j as isize + dj);
        if ni < 0 || nj < 0 || ni >= field.size[0] as isize || nj >= field.size[1] as isize {
            continue;
        }
        if field.hole[field.index(ni as usize, nj as usize)] {
            continue;
        }
        let drop = (z - field.at(ni, nj)) / ((di * di + dj * dj) as f64).sqrt();
        if drop > 0.0 {
            out[k] = drop;
            sum += drop;
            steepest = steepest.max(drop);
        }
    }
    if sum > 0.0 {
        let speed = (steepest / field.cell_m / flow.full_slope_deg.to_radians().tan()).min(1.0);
        out.iter_mut().for_each(|s| *s *= flow.share * speed / sum);
    }
    out
}

/// The resource of every cell of `window` after `iterations`, row-major
/// over the window. Exact for the cells at least `iterations` cells inside
/// the window's edges that are not the field's (beyond a window's edge
/// nothing flows in).
pub fn flow(field: &HeightField, window: Window, iterations: u32, flow: Flow) -> Vec<f64> {
    let [w, h] = window.size;
    let mut share = Vec::with_capacity(w * h);
    for j in 0..h {
        for i in 0..w {
            share.push(shares(field, window.lo[0] + i, window.lo[1] + j, flow));
        }
    }
    let mut r: Vec<f64> = (0..w * h)
        .map(|k| if field.hole[field.index(window.lo[0] + k % w, window.lo[1] + k / w)] { 0.0 } else { 1.0 })
        .collect();
    let mut next = vec![0.0; w * h];
    for _ in 0..iterations {
        for j in 0..h {
            for i in 0..w {
                let k = j * w + i;
                let out: f64 = share[k].iter().sum();
                let mut v = r[k] * (1.0 - out);
                // From each neighbour: its share towards this cell (the
                // opposite direction in its own list).
                for (n, (di, dj)) in NEIGHBOURS.iter().enumerate() {
                    let (ni, nj) = (i as isize + di, j as isize + dj);
                    if ni < 0 || nj < 0 || ni >= w as isize || nj >= h as isize {
                        continue;
                    }
                    let nk = nj as usize * w + ni as usize;
                    v += r[nk] * share[nk][7 - n];
                }
                next[k] = v;
            }
        }
        std::mem::swap(&mut r, &mut next);
    }
    r
}
