//! CPU twin of the sun shadow texture (sun_shadows.comp, sun_shadow.glsl):
//! the same march in f64 over any height function, where its texels lie,
//! and the visibility ramp `lighting_resolve` applies. Tests compare the
//! GPU's texture with it; an exact shadow ray is the reference's business
//! ([`crate::reference::raycast`]).

use crate::world::{NodeId, WorldDesc, NODE_QUADS};
use glam::{DVec2, DVec3};

/// Stored where nothing can occlude (`SUN_SHADOW_NONE`).
pub const NONE: f64 = -1.0e30;

/// Distance of step `i` of `n` (`sun_shadow_step`).
pub fn step(i: u32, n: u32, first: f64, last: f64) -> f64 {
    if n <= 1 {
        return last;
    }
    let f = f64::from(i) / f64::from(n - 1);
    first + (last - first) * f * f
}

/// The march's settings, as `sun_shadows` takes them.
#[derive(Debug, Clone, Copy)]
pub struct March {
    /// Horizontal unit vector towards the sun.
    pub dir: DVec2,
    /// tan(elevation).
    pub rise: f64,
    pub steps: u32,
    pub reach_m: f64,
    /// The world's highest possible point (m).
    pub ceiling_m: f64,
}

impl March {
    /// From the unit vector towards the sun (not straight up).
    pub fn new(sun: DVec3, steps: u32, reach_m: f64, ceiling_m: f64) -> March {
        let h = sun.truncate();
        let len = h.length();
        assert!(len > 1e-9, "the sun is overhead: there is no march direction");
        March { dir: h / len, rise: sun.z / len, steps, reach_m, ceiling_m }
    }

    /// (threshold height relative to the ground `height(p)`, occluder
    /// distance) at `p`; `first` is the node's sample spacing.
    pub fn threshold(&self, p: DVec2, first: f64, height: impl Fn(DVec2) -> Option<f64>) -> (f64, f64) {
        self.threshold_over(p, first, &height, &|q, _| height(q))
    }

    /// As [`March::threshold`], the march reading `occluder` at each step's
    /// point and distance (the ground and what stands on it: the canopy,
    /// which counts from a distance) and the point on the `ground`.
    pub fn threshold_over(
        &self,
        p: DVec2,
        first: f64,
        ground: &dyn Fn(DVec2) -> Option<f64>,
        occluder: &dyn Fn(DVec2, f64) -> Option<f64>,
    ) -> (f64, f64) {
        let Some(h0) = ground(p) else { return (NONE, 0.0) };
        let last = if self.rise > 0.0 { self.reach_m.min((self.ceiling_m - h0) / self.rise) } else { self.reach_m };
        let mut best = (NONE, 0.0);
        if last <= first {
            return best;
        }
        for i in 0..self.steps {
            let d = step(i, self.steps, first, last);
            if let Some(h) = occluder(p + self.dir * d, d) {
                if h - d * self.rise > best.0 {
                    best = (h - d * self.rise, d);
                }
            }
        }
        if best.0 == NONE {
            return best;
        }
        (best.0 - h0, best.1)
    }
}

/// World position of texel `t` (0..side-1 per axis) of `node`'s texture.
pub fn texel_position(world: &WorldDesc, node: NodeId, side: u32, t: [u32; 2]) -> DVec2 {
    let spacing = world.node_spacing_m(node.lod);
    let node_m = spacing * f64::from(NODE_QUADS);
    let origin = DVec2::new(f64::from(node.x), f64::from(node.y)) * node_m + DVec2::from(world.grid_origin_m);
    let local = DVec2::new(f64::from(t[0]), f64::from(t[1])) * (f64::from(NODE_QUADS) / f64::from(side - 1));
    origin + local * spacing
}

/// Share of the sun seen at height `z` (`sun_visibility`).
pub fn visibility(z: f64, h: f64, dist: f64, penumbra: f64) -> f64 {
    let width = dist * penumbra;
    if width <= 0.0 {
        return if z >= h { 1.0 } else { 0.0 };
    }
    (0.5 + (z - h) / width).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_run_from_the_spacing_to_the_last() {
        assert_eq!(step(0, 24, 0.5, 400.0), 0.5);
        assert_eq!(step(23, 24, 0.5, 400.0), 400.0);
        assert_eq!(step(0, 1, 0.5, 400.0), 400.0);
    }

    #[test]
    fn a_wall_shadows_below_its_top_minus_the_rise() {
        // A 30 m wall starting 19.5 m towards a 45-degree sun: its near
        // face's top sets the threshold, 30 - 19.5 m above the ground.
        let sun = DVec3::new(1.0, 0.0, 1.0).normalize();
        let m = March::new(sun, 4096, 1000.0, 40.0);
        let wall = |p: DVec2| Some(if (19.5..=40.0).contains(&p.x) { 30.0 } else { 0.0 });
        let (h, d) = m.threshold(DVec2::ZERO, 0.5, wall);
        assert!((h - (30.0 - 19.5)).abs() < 0.1 && (d - 19.5).abs() < 0.1, "{h} at {d}");
        assert_eq!(visibility(0.0, h, d, 0.0), 0.0);
        assert_eq!(visibility(11.0, h, d, 0.0), 1.0);
    }
}
