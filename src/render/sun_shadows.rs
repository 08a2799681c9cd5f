//! The `shadows` effect's parameters and its update schedule: which resident
//! nodes get their sun shadow texture (re)made this frame. A node that
//! arrives is shadowed in the frame it becomes resident (at most
//! `MAX_UPLOADS_PER_FRAME` a frame), so every resident slot always holds its
//! own node's texture. Its heights also change what the nodes down-sun of
//! it see (a march reads the finest resident heights: a ridge drawn coarse
//! when they were marched may be finer now), so every resident node whose
//! marches could cross it is made stale. When the sun moves, every resident
//! node is stale. Stale nodes are redone `update_budget` a frame, oldest
//! first, until all are current. With no arrival and a static sun nothing
//! is scheduled: the pass is skipped (the report says idle).
//!
//! Why per resident node and not a clipmap around the camera: the texture
//! then follows streaming (made once per arrival, dropped with the node),
//! covers exactly what is drawn at the detail it is drawn at, and a camera
//! that moves costs nothing; a clipmap would re-march its rings as the
//! camera moves and resolve distant terrain no better than a node does.

use crate::shaders::consts;
use crate::terrain::gpu_quadtree::MAX_UPLOADS_PER_FRAME;
use crate::world::NodeId;
use std::collections::BTreeMap;

/// Largest `update_budget`: the job list holds the budget plus a frame's
/// uploads.
pub const MAX_UPDATE_BUDGET: u32 = consts::SUN_SHADOW_MAX_JOBS - MAX_UPLOADS_PER_FRAME as u32;

/// Parameters of the `shadows` effect (scene keys of the same names).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadowParams {
    /// Texels per node side (2..=SUN_SHADOW_MAX_SIDE), corner-aligned: texel
    /// 0 and the last lie on the node's edges.
    pub resolution: u32,
    /// Height samples per texel's march towards the sun.
    pub steps: u32,
    /// Nodes re-marched per frame while the sun moves.
    pub update_budget: u32,
    /// The sun's angular diameter (degrees): the penumbra widens with the
    /// occluder's distance by this spread ([`ShadowParams::penumbra`]); 0: a
    /// hard edge.
    pub softness_deg: f32,
    /// Farthest a march looks (m); it also stops where the ray clears the
    /// world's highest point.
    pub reach_m: f32,
}

impl Default for ShadowParams {
    fn default() -> Self {
        // The real sun is 0.53 degrees across.
        ShadowParams { resolution: 65, steps: 24, update_budget: 16, softness_deg: 0.53, reach_m: 20_000.0 }
    }
}

impl ShadowParams {
    /// Penumbra height per metre of occluder distance with the sun at
    /// `elevation_deg`: the spread of tan(elevation) over the sun's disc.
    pub fn penumbra(&self, elevation_deg: f64) -> f32 {
        let half = f64::from(self.softness_deg) * 0.5;
        let top = (elevation_deg + half).clamp(-89.9, 89.9).to_radians().tan();
        let bottom = (elevation_deg - half).clamp(-89.9, 89.9).to_radians().tan();
        (top - bottom) as f32
    }
}

/// One node's march this frame (`SunShadowJob` in sun_shadows.comp).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SunShadowJob {
    pub slot: u32,
    pub lod: u32,
    pub x: u32,
    pub y: u32,
}

impl SunShadowJob {
    pub fn new(node: NodeId, slot: u32) -> Self {
        SunShadowJob { slot, lod: u32::from(node.lod), x: node.x, y: node.y }
    }
}

/// What the schedule knows of a resident node: where it lies (x0, y0, x1,
/// y1 in metres) and its lowest and highest height.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeExtent {
    pub bounds_m: [f64; 4],
    pub min_m: f64,
    pub max_m: f64,
}

/// The sun a schedule marches for: the unit vector towards it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MarchSun {
    pub dir: [f32; 3],
    /// Longest march (m).
    pub reach_m: f64,
}

impl MarchSun {
    /// How far towards the sun a march from a point at `low_m` can still
    /// meet terrain as high as `high_m`.
    fn reach_between(&self, low_m: f64, high_m: f64) -> f64 {
        let [x, y, z] = self.dir.map(f64::from);
        let rise = z / x.hypot(y).max(1e-12);
        if rise <= 0.0 {
            return self.reach_m;
        }
        ((high_m - low_m).max(0.0) / rise).min(self.reach_m)
    }
}

/// Which resident node's texture was made for which sun.
#[derive(Debug, Default)]
pub struct ShadowSchedule {
    /// Slot -> (node, sun version its texture was made for; 0: stale for
    /// another reason, redone first).
    made: BTreeMap<u32, (NodeId, u64)>,
    sun: Option<[f32; 3]>,
    version: u64,
}

/// Whether a march from somewhere in `from` towards the sun (horizontal
/// unit `u`) for up to `reach` metres can enter `to`: the rectangle `from`
/// swept towards the sun meets `to` (bounding boxes, so conservative).
fn sweep_meets(from: [f64; 4], u: [f64; 2], reach: f64, to: [f64; 4]) -> bool {
    let lo = [from[0].min(from[0] + u[0] * reach), from[1].min(from[1] + u[1] * reach)];
    let hi = [from[2].max(from[2] + u[0] * reach), from[3].max(from[3] + u[1] * reach)];
    lo[0] < to[2] && to[0] < hi[0] && lo[1] < to[3] && to[1] < hi[1]
}

impl ShadowSchedule {
    /// This frame's jobs: every `arrived` node (node, slot), then up to
    /// `budget` of the stale resident nodes, oldest first. `resident` says
    /// where a node is resident now (evicted nodes are forgotten) and its
    /// extent.
    pub fn plan(
        &mut self,
        sun: MarchSun,
        budget: u32,
        arrived: &[(NodeId, u32)],
        resident: impl Fn(NodeId) -> Option<(u32, NodeExtent)>,
    ) -> Vec<SunShadowJob> {
        if self.sun != Some(sun.dir) {
            self.sun = Some(sun.dir);
            self.version += 1;
        }
        self.made.retain(|slot, (node, _)| resident(*node).map(|(s, _)| s) == Some(*slot));
        let [x, y, _] = sun.dir.map(f64::from);
        let len = x.hypot(y);
        let u = if len > 1e-12 { [x / len, y / len] } else { [0.0, 0.0] };
        for &(new, _) in arrived {
            let Some((_, n)) = resident(new) else { continue };
            for (node, version) in self.made.values_mut() {
                let Some((_, m)) = resident(*node) else { continue };
                if sweep_meets(m.bounds_m, u, sun.reach_between(m.min_m, n.max_m), n.bounds_m) {
                    *version = 0;
                }
            }
        }
        let mut jobs: Vec<SunShadowJob> = arrived.iter().map(|&(node, slot)| SunShadowJob::new(node, slot)).collect();
        for &(node, slot) in arrived {
            self.made.insert(slot, (node, self.version));
        }
        let mut stale: Vec<(u64, u32, NodeId)> =
            self.made.iter().filter(|(_, (_, v))| *v != self.version).map(|(&s, &(n, v))| (v, s, n)).collect();
        stale.sort();
        for (_, slot, node) in stale.into_iter().take(budget as usize) {
            jobs.push(SunShadowJob::new(node, slot));
            self.made.insert(slot, (node, self.version));
        }
        jobs
    }

    /// Resident nodes whose texture predates the current sun.
    pub fn stale(&self) -> usize {
        self.made.values().filter(|(_, v)| *v != self.version).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn penumbra_is_the_slope_spread_of_the_disc() {
        let p = ShadowParams { softness_deg: 2.0, ..ShadowParams::default() };
        let want = 31f64.to_radians().tan() - 29f64.to_radians().tan();
        assert!((f64::from(p.penumbra(30.0)) - want).abs() < 1e-6);
        assert_eq!(ShadowParams { softness_deg: 0.0, ..p }.penumbra(30.0), 0.0);
    }

    /// Node (0, i, 0) is the 100 m square at x = 100 i, 0..10 m high,
    /// resident in slot i + 1.
    fn row(n: NodeId) -> Option<(u32, NodeExtent)> {
        let x = 100.0 * f64::from(n.x);
        Some((n.x + 1, NodeExtent { bounds_m: [x, 0.0, x + 100.0, 100.0], min_m: 0.0, max_m: 10.0 }))
    }

    fn sun(dir: [f32; 3]) -> MarchSun {
        MarchSun { dir, reach_m: 1e4 }
    }

    #[test]
    fn arrivals_at_once_then_the_budget_oldest_first_then_idle() {
        let mut s = ShadowSchedule::default();
        let nodes: Vec<(NodeId, u32)> = (0..10).map(|i| (NodeId::new(0, i, 0), i + 1)).collect();
        let overhead = sun([0.0, 0.0, 1.0]);
        assert_eq!(s.plan(overhead, 4, &nodes, row).len(), 10, "arrivals ignore the budget");
        assert!(s.plan(overhead, 4, &[], row).is_empty(), "static sun: idle");
        let moved = sun([0.0, 0.6, 0.8]);
        let frames: Vec<usize> = (0..4).map(|_| s.plan(moved, 4, &[], row).len()).collect();
        assert_eq!(frames, [4, 4, 2, 0], "ceil(10 / 4) frames, then idle");
        // Evicted nodes are forgotten.
        let only_three = |n: NodeId| if n.x < 3 { row(n) } else { None };
        assert_eq!(s.plan(sun([1.0, 0.0, 0.0]), 16, &[], only_three).len(), 3);
        assert_eq!(s.stale(), 0);
    }

    #[test]
    fn an_arrival_makes_the_nodes_down_sun_of_it_stale() {
        let mut s = ShadowSchedule::default();
        let nodes: Vec<(NodeId, u32)> = (0..10).map(|i| (NodeId::new(0, i, 0), i + 1)).collect();
        // The sun in the east at 45 degrees: a 10 m high node shadows at
        // most 10 m west of it, so only its western neighbour can see it.
        let east = sun([0.707, 0.0, 0.707]);
        s.plan(east, 16, &nodes, row);
        // Node 5 arrives again (a slot reused): node 4 is stale, no other.
        let again = [(NodeId::new(0, 5, 0), 6)];
        let jobs = s.plan(east, 16, &again, row);
        let slots: Vec<u32> = jobs.iter().map(|j| j.slot).collect();
        assert_eq!(slots, [6, 5], "the arrival, then its western neighbour");
    }
}
