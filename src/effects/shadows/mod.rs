//! The `shadows` effect's update schedule (its parameters are the pass's,
//! `effects::shadows::sun_shadows`): which resident nodes get their sun shadow texture
//! (re)made this frame. A node that arrives is shadowed in the frame it
//! becomes resident (at most `MAX_UPLOADS_PER_FRAME` a frame), so every
//! resident slot always holds its
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

pub mod frame;
pub mod kind;
pub mod sun_shadows;

use crate::effects::shadows::sun_shadows::{march_sun, SunShadowJob};
use crate::world::NodeId;
use std::collections::BTreeMap;

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
        let [_, _, rise] = march_sun(glam::DVec3::from(self.dir.map(f64::from)));
        let rise = f64::from(rise);
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
    /// Slots holding another node's texture (after `restart`), until made.
    unmade: std::collections::BTreeSet<u32>,
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
        let made = &self.made;
        self.unmade.retain(|slot| made.contains_key(slot));
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
            self.unmade.remove(&slot);
        }
        let mut stale: Vec<(u64, u32, NodeId)> =
            self.made.iter().filter(|(_, (_, v))| *v != self.version).map(|(&s, &(n, v))| (v, s, n)).collect();
        stale.sort();
        for (_, slot, node) in stale.into_iter().take(budget as usize) {
            jobs.push(SunShadowJob::new(node, slot));
            self.made.insert(slot, (node, self.version));
            self.unmade.remove(&slot);
        }
        jobs
    }

    /// Forgets what was made: every node of `resident` (node, slot) is
    /// stale, its slot perhaps holding another node's texture (after frames
    /// that made no shadows, where nodes arrived unmarched), until made.
    pub fn restart(&mut self, resident: &[(NodeId, u32)]) {
        self.made = resident.iter().map(|&(node, slot)| (slot, (node, 0))).collect();
        self.unmade = self.made.keys().copied().collect();
    }

    /// Every resident slot holds its own node's texture (none is left
    /// from before a `restart`): the shadows may be shown.
    pub fn ready(&self) -> bool {
        self.unmade.is_empty()
    }

    /// Resident nodes whose texture predates the current sun.
    pub fn stale(&self) -> usize {
        self.made.values().filter(|(_, v)| *v != self.version).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
