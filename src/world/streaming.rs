//! Streaming residency after Far Cry 5: a ring of each LOD around the
//! camera, roots always resident, nearest-first within a slot budget.
//!
//! [`Residency`] is the bookkeeping (what is wanted, pending, resident);
//! [`Streamer`] ties it to a [`Loader`] and tells the GPU side, per frame,
//! which payloads arrived and which resident nodes to remove.

use std::collections::{HashMap, HashSet};

use super::error::{Result, WorldError};
use super::layout::{NodeId, WorldDesc};
use super::loader::Loader;
use super::payload::BakedNode;

/// Streaming parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResidencyConfig {
    /// Most nodes holding a slot (resident or loading), roots included.
    pub budget: usize,
    /// LOD k is wanted where its node centre is within
    /// `ring_factor * node_size_k` of the camera (xy).
    pub ring_factor: f64,
    /// A held node is dropped only beyond `hysteresis * ring`.
    pub hysteresis: f64,
}

impl Default for ResidencyConfig {
    fn default() -> Self {
        ResidencyConfig { budget: 512, ring_factor: 1.75, hysteresis: 1.25 }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Slot {
    Pending,
    Resident,
}

/// What an [`Residency::update`] decided.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ResidencyChanges {
    /// Newly wanted nodes to load, highest priority first.
    pub adds: Vec<NodeId>,
    /// Resident nodes dropped this frame (free their GPU slots), finest
    /// first so no node goes before its children.
    pub removes: Vec<NodeId>,
    /// Nodes dropped while still loading: no GPU slot, cancel the load.
    pub cancels: Vec<NodeId>,
}

/// What to do with a payload that finished loading.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Arrival {
    /// Now resident: upload it.
    Accept,
    /// Its parent is not resident yet; offer it again later.
    Defer,
    /// No longer wanted: drop it.
    Discard,
}

/// Which nodes hold slots. Invariants after every call: slots used
/// (pending and resident) never exceed the budget; the resident set
/// contains each resident node's parent; once loaded, roots stay resident.
pub struct Residency {
    world: WorldDesc,
    config: ResidencyConfig,
    roots: Vec<NodeId>,
    slots: HashMap<NodeId, Slot>,
    failed: HashSet<NodeId>,
}

impl Residency {
    pub fn new(world: &WorldDesc, config: ResidencyConfig) -> Result<Self> {
        world.validate()?;
        let c = config;
        if !(c.ring_factor.is_finite() && c.ring_factor >= 0.75) {
            // Below ~0.71 a child's ring would poke outside its parent's.
            return Err(WorldError::InvalidConfig(format!(
                "ring factor must be finite and >= 0.75, got {}",
                c.ring_factor
            )));
        }
        if !(c.hysteresis.is_finite() && c.hysteresis >= 1.0) {
            return Err(WorldError::InvalidConfig(format!("hysteresis must be finite and >= 1, got {}", c.hysteresis)));
        }
        let roots = world.roots();
        if roots.len() > c.budget {
            return Err(WorldError::BudgetTooSmall { roots: roots.len(), budget: c.budget });
        }
        Ok(Residency { world: *world, config, roots, slots: HashMap::new(), failed: HashSet::new() })
    }

    pub fn world(&self) -> &WorldDesc {
        &self.world
    }

    pub fn config(&self) -> &ResidencyConfig {
        &self.config
    }

    pub fn roots(&self) -> &[NodeId] {
        &self.roots
    }

    /// Slots in use: resident plus loading.
    pub fn slots_used(&self) -> usize {
        self.slots.len()
    }

    /// Nodes requested from the loader and not yet arrived.
    pub fn pending_count(&self) -> usize {
        self.slots.values().filter(|s| **s == Slot::Pending).count()
    }

    pub fn is_resident(&self, id: NodeId) -> bool {
        self.slots.get(&id) == Some(&Slot::Resident)
    }

    pub fn is_pending(&self, id: NodeId) -> bool {
        self.slots.get(&id) == Some(&Slot::Pending)
    }

    /// Resident nodes, unordered.
    pub fn resident(&self) -> impl Iterator<Item = NodeId> + '_ {
        self.slots.iter().filter(|(_, s)| **s == Slot::Resident).map(|(id, _)| *id)
    }

    /// Recomputes the wanted set for a camera position (metres; z unused)
    /// and returns the difference to the current slots.
    pub fn update(&mut self, camera_pos_m: [f64; 3]) -> ResidencyChanges {
        let cam = [camera_pos_m[0], camera_pos_m[1]];
        // Top-down: a node is a candidate only if its parent is one.
        let mut candidates = Vec::new();
        let mut stack = self.roots.clone();
        while let Some(n) = stack.pop() {
            for c in self.world.valid_children(n) {
                if self.failed.contains(&c) {
                    continue;
                }
                let ring = self.config.ring_factor * self.world.node_size_m(c.lod);
                let limit = if self.slots.contains_key(&c) { ring * self.config.hysteresis } else { ring };
                let b = self.world.bounds_m(c);
                let centre = [(b[0] + b[2]) * 0.5, (b[1] + b[3]) * 0.5];
                if dist(cam, centre) <= limit {
                    candidates.push((dist_to_box(cam, b), c));
                    stack.push(c);
                }
            }
        }
        // Nearest first, coarser first on ties: a parent is never closer
        // than its child, so parents always come before their children.
        candidates.sort_by(|a, b| a.0.total_cmp(&b.0).then(b.1.lod.cmp(&a.1.lod)));
        let mut selected: HashSet<NodeId> = self.roots.iter().copied().collect();
        let mut order = self.roots.clone();
        for (_, c) in candidates {
            if selected.len() >= self.config.budget {
                break;
            }
            if selected.contains(&c.parent()) {
                selected.insert(c);
                order.push(c);
            }
        }

        let mut changes = ResidencyChanges::default();
        let mut dropped: Vec<(NodeId, Slot)> =
            self.slots.iter().filter(|(id, _)| !selected.contains(id)).map(|(id, s)| (*id, *s)).collect();
        dropped.sort_by_key(|(id, _)| (id.lod, id.x, id.y));
        for (id, slot) in dropped {
            self.slots.remove(&id);
            match slot {
                Slot::Resident => changes.removes.push(id),
                Slot::Pending => changes.cancels.push(id),
            }
        }
        for id in order {
            if let std::collections::hash_map::Entry::Vacant(e) = self.slots.entry(id) {
                e.insert(Slot::Pending);
                changes.adds.push(id);
            }
        }
        changes
    }

    /// A requested payload finished loading.
    pub fn on_loaded(&mut self, id: NodeId) -> Arrival {
        if self.slots.get(&id) != Some(&Slot::Pending) {
            return Arrival::Discard;
        }
        let is_root = u32::from(id.lod) + 1 == self.world.lod_count;
        if !is_root && !self.is_resident(id.parent()) {
            return Arrival::Defer;
        }
        self.slots.insert(id, Slot::Resident);
        Arrival::Accept
    }

    /// A requested load failed: free its slot and never ask for it again
    /// (its subtree is then never wanted either).
    pub fn on_failed(&mut self, id: NodeId) {
        if self.slots.get(&id) == Some(&Slot::Pending) {
            self.slots.remove(&id);
        }
        self.failed.insert(id);
    }
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

fn dist_to_box(p: [f64; 2], b: [f64; 4]) -> f64 {
    let dx = (b[0] - p[0]).max(p[0] - b[2]).max(0.0);
    let dy = (b[1] - p[1]).max(p[1] - b[3]).max(0.0);
    dx.hypot(dy)
}

/// One frame of streaming for the GPU side: apply `removed` (free slots)
/// then upload `arrived`.
#[derive(Debug, Default)]
pub struct StreamFrame {
    pub arrived: Vec<BakedNode>,
    pub removed: Vec<NodeId>,
    pub failed: Vec<(NodeId, WorldError)>,
}

/// Residency driven by a loader.
pub struct Streamer {
    residency: Residency,
    loader: Loader,
    /// Loaded payloads waiting for their parent to become resident.
    parked: HashMap<NodeId, BakedNode>,
}

impl Streamer {
    pub fn new(residency: Residency, loader: Loader) -> Self {
        Streamer { residency, loader, parked: HashMap::new() }
    }

    pub fn residency(&self) -> &Residency {
        &self.residency
    }

    /// Never blocks: updates the wanted set, queues loads and collects
    /// whatever finished.
    pub fn frame(&mut self, camera_pos_m: [f64; 3]) -> StreamFrame {
        let changes = self.residency.update(camera_pos_m);
        for id in &changes.cancels {
            self.loader.cancel(*id);
            self.parked.remove(id);
        }
        for id in &changes.adds {
            self.loader.request(*id);
        }
        let mut frame = StreamFrame { removed: changes.removes, ..StreamFrame::default() };
        for (id, result) in self.loader.poll() {
            match result {
                Ok(node) => {
                    self.parked.insert(id, node);
                }
                Err(e) => {
                    self.residency.on_failed(id);
                    frame.failed.push((id, e));
                }
            }
        }
        // Coarsest first so a parent accepted now lets its children in.
        let mut ids: Vec<NodeId> = self.parked.keys().copied().collect();
        ids.sort_by_key(|id| std::cmp::Reverse(id.lod));
        for id in ids {
            match self.residency.on_loaded(id) {
                Arrival::Accept => frame.arrived.extend(self.parked.remove(&id)),
                Arrival::Discard => {
                    self.parked.remove(&id);
                }
                Arrival::Defer => {}
            }
        }
        frame
    }
}
