//! Terrain holes (cave mouths, tunnels): samples inside get albedo alpha 0.

use serde::{Deserialize, Serialize};

use super::hash::Fnv64;

/// A region of the world with no terrain surface, in world metres.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Hole {
    Circle {
        center_m: [f64; 2],
        radius_m: f64,
    },
    /// A simple or self-intersecting polygon, even-odd rule.
    Polygon(Vec<[f64; 2]>),
}

impl Hole {
    /// The same hole moved by `-origin_m`: from the caller's coordinates
    /// (a world placed at `origin_m`) into the world's own.
    pub fn relative_to(&self, origin_m: [f64; 2]) -> Hole {
        let m = |p: &[f64; 2]| [p[0] - origin_m[0], p[1] - origin_m[1]];
        match self {
            Hole::Circle { center_m, radius_m } => Hole::Circle { center_m: m(center_m), radius_m: *radius_m },
            Hole::Polygon(pts) => Hole::Polygon(pts.iter().map(m).collect()),
        }
    }

    pub fn contains(&self, x: f64, y: f64) -> bool {
        match self {
            Hole::Circle { center_m, radius_m } => {
                let (dx, dy) = (x - center_m[0], y - center_m[1]);
                dx * dx + dy * dy <= radius_m * radius_m
            }
            Hole::Polygon(pts) => {
                let mut inside = false;
                let n = pts.len();
                for i in 0..n {
                    let [xi, yi] = pts[i];
                    let [xj, yj] = pts[(i + n - 1) % n];
                    if (yi > y) != (yj > y) && x < (xj - xi) * (y - yi) / (yj - yi) + xi {
                        inside = !inside;
                    }
                }
                inside
            }
        }
    }

    /// Axis-aligned bounds [min x, min y, max x, max y], used to skip the
    /// per-sample test for nodes far from every hole.
    pub fn bounds(&self) -> [f64; 4] {
        match self {
            Hole::Circle { center_m, radius_m } => {
                [center_m[0] - radius_m, center_m[1] - radius_m, center_m[0] + radius_m, center_m[1] + radius_m]
            }
            Hole::Polygon(pts) => {
                pts.iter().fold([f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY], |b, p| {
                    [b[0].min(p[0]), b[1].min(p[1]), b[2].max(p[0]), b[3].max(p[1])]
                })
            }
        }
    }
}

/// Hash of a hole list; part of the cache key.
pub fn holes_hash(holes: &[Hole]) -> u64 {
    let mut h = Fnv64::new().u64(holes.len() as u64);
    for hole in holes {
        match hole {
            Hole::Circle { center_m, radius_m } => {
                h = h.u64(1).f64(center_m[0]).f64(center_m[1]).f64(*radius_m);
            }
            Hole::Polygon(pts) => {
                h = h.u64(2).u64(pts.len() as u64);
                for p in pts {
                    h = h.f64(p[0]).f64(p[1]);
                }
            }
        }
    }
    h.finish()
}
