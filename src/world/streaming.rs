//! Streaming residency after Far Cry 5: roots always resident, and a family
//! wanted wherever its resident parent's projected error exceeds the
//! renderer's target ([`RefineWant`]), plus a small ring of each LOD around
//! the camera for motion. Nodes are loaded and evicted in sibling families
//! (the traversal refines a node only when all its valid children are
//! resident, so a lone child is useless). When the slot budget cannot hold
//! every wanted family, slots go where they remove the most projected
//! error: families in the view first, then by their parent's projected
//! error in pixels, a held family counting `hysteresis` times its own so
//! that near-equal ones do not churn; without a criterion, nearest first.
//!
//! A failed load is retried after a backoff counted in frames (so the
//! schedule is deterministic), up to [`ResidencyConfig::max_load_attempts`];
//! then the node is given up: its parent keeps drawing, or, for a root,
//! the caller gets an error (nothing could draw there).
//!
//! [`Residency`] is the bookkeeping (what is wanted, pending, resident);
//! [`super::Streamer`] ties it to a loader.

use std::collections::{HashMap, HashSet};

use super::error::{Result, WorldError};
use super::layout::{NodeId, WorldDesc};
use super::projection::TraverseCamera;

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
    /// Loads of one node, the first included, before it is given up.
    pub max_load_attempts: u32,
    /// Backoff after the n-th failed load of a node: it is not wanted again
    /// for `retry_frames << (n - 1)` frames (updates). With the defaults (4
    /// attempts, 2 frames) the retries come 2, 4 and 8 frames after the
    /// failures, and the fourth failure gives the node up.
    pub retry_frames: u64,
}

impl Default for ResidencyConfig {
    fn default() -> Self {
        ResidencyConfig { budget: 512, ring_factor: 1.75, hysteresis: 1.25, max_load_attempts: 4, retry_frames: 2 }
    }
}

/// The renderer's LOD criterion as streaming sees it: a resident node whose
/// projected vertical error ([`TraverseCamera::projected_px`], the bound
/// the traversal uses) exceeds `prefetch * target_error_px` pixels wants
/// its children loaded (prefetch below 1 loads them a little before the
/// traversal asks for them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefineWant {
    /// The drawing camera (its frustum decides what is in view).
    pub camera: TraverseCamera,
    pub target_error_px: f64,
    pub prefetch: f64,
    /// Ring factor replacing the config's while this criterion decides: the
    /// ring then only keeps the families right around the camera (for
    /// motion), so the budget goes where the error asks for detail; 0
    /// turns the rings off (tests that need an exact resident set).
    pub ring_factor: f64,
    /// An infinite node error is known: a hole under the node (the
    /// per-triangle rule's bounds, made for the whole world before the
    /// first frame), wanted like any other error in view or out of it.
    /// Off, it is a root's error not made yet, wanted only in view.
    pub infinite_known: bool,
}

/// What streaming keeps of a resident node to apply [`RefineWant`].
#[derive(Clone, Copy, Debug, PartialEq)]
struct NodeBounds {
    max_error_m: f32,
    z: [f32; 2],
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

/// Most loads of one node (the backoff doubles per failure: 2^31 frames
/// is already "never").
pub const MAX_LOAD_ATTEMPTS: u32 = 32;

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

/// A family that may be loaded (children of `parent`).
struct Candidate {
    in_view: bool,
    /// Higher first: the parent's projected error (px), or minus its
    /// distance without a criterion.
    score: f64,
    /// The parent's distance from the camera (m, horizontal): nearer first
    /// on ties.
    near: f64,
    parent: NodeId,
    family: Vec<NodeId>,
}

/// A node whose last load failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct FailedNode {
    /// Failed loads so far.
    attempts: u32,
    /// Frame from which it may be wanted again; `None`: given up.
    retry_at: Option<u64>,
}

/// What became of a failed load.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LoadFate {
    /// Wanted again from frame `at_frame` (the `attempts`-th load failed).
    Retry { attempts: u32, at_frame: u64 },
    /// `attempts` loads failed: never wanted again.
    GaveUp { attempts: u32 },
}

/// Failed loads so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FailureCounts {
    /// Loads that failed (every attempt).
    pub failures: usize,
    /// Loads requested again after a failure.
    pub retries: usize,
    /// Nodes given up after `max_load_attempts` failures.
    pub gave_up: usize,
}

/// Which nodes hold slots. Invariants after every call: slots used
/// (pending and resident) never exceed the budget; the resident set
/// contains each resident node's parent; once loaded, roots stay resident.
pub struct Residency {
    world: WorldDesc,
    config: ResidencyConfig,
    roots: Vec<NodeId>,
    slots: HashMap<NodeId, Slot>,
    failed: HashMap<NodeId, FailedNode>,
    counts: FailureCounts,
    /// Updates so far: the clock of the retry backoff.
    frame: u64,
    bounds: HashMap<NodeId, NodeBounds>,
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
        if !(1..=MAX_LOAD_ATTEMPTS).contains(&c.max_load_attempts) {
            return Err(WorldError::InvalidConfig(format!(
                "max load attempts must be 1..={MAX_LOAD_ATTEMPTS}, got {}",
                c.max_load_attempts
            )));
        }
        let roots = world.roots();
        if roots.len() > c.budget {
            return Err(WorldError::BudgetTooSmall { roots: roots.len(), budget: c.budget });
        }
        Ok(Residency {
            world: *world,
            config,
            roots,
            slots: HashMap::new(),
            failed: HashMap::new(),
            counts: FailureCounts::default(),
            frame: 0,
            bounds: HashMap::new(),
        })
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

    /// A load of `id` failed and it is not wanted now: waiting for its
    /// retry, or given up (then with its subtree, never again).
    pub fn is_failed(&self, id: NodeId) -> bool {
        self.failed.get(&id).is_some_and(|f| f.retry_at.is_none_or(|t| t > self.frame))
    }

    /// `id` failed `max_load_attempts` times and is never wanted again.
    pub fn gave_up(&self, id: NodeId) -> bool {
        self.failed.get(&id).is_some_and(|f| f.retry_at.is_none())
    }

    /// Nodes waiting for the backoff before their retry.
    pub fn retry_waiting(&self) -> usize {
        self.failed.values().filter(|f| f.retry_at.is_some_and(|t| t > self.frame)).count()
    }

    /// A root given up, if any: nothing can draw where it lies.
    pub fn root_given_up(&self) -> Option<NodeId> {
        self.roots.iter().copied().find(|r| self.gave_up(*r))
    }

    pub fn failure_counts(&self) -> FailureCounts {
        self.counts
    }

    pub fn is_pending(&self, id: NodeId) -> bool {
        self.slots.get(&id) == Some(&Slot::Pending)
    }

    /// Nodes requested from the loader and not yet arrived, unordered.
    pub fn pending(&self) -> impl Iterator<Item = NodeId> + '_ {
        self.slots.iter().filter(|(_, s)| **s == Slot::Pending).map(|(id, _)| *id)
    }

    /// Resident nodes, unordered.
    pub fn resident(&self) -> impl Iterator<Item = NodeId> + '_ {
        self.slots.iter().filter(|(_, s)| **s == Slot::Resident).map(|(id, _)| *id)
    }

    /// Recomputes the wanted set for a camera position (metres; z unused)
    /// from the rings alone and returns the difference to the current slots.
    pub fn update(&mut self, camera_pos_m: [f64; 3]) -> ResidencyChanges {
        self.update_with(camera_pos_m, None)
    }

    /// As [`Residency::update`], also wanting the children of every resident
    /// node whose projected error `want` finds too large. Families come
    /// whole or not at all, in priority order (module docs).
    pub fn update_with(&mut self, camera_pos_m: [f64; 3], want: Option<&RefineWant>) -> ResidencyChanges {
        self.frame += 1;
        let candidates = self.candidates(camera_pos_m, want);
        let mut selected: HashSet<NodeId> = self.roots.iter().copied().collect();
        let mut order: Vec<NodeId> = self.roots.iter().copied().filter(|r| !self.is_failed(*r)).collect();
        for c in candidates {
            if selected.len() + c.family.len() > self.config.budget {
                continue;
            }
            if selected.contains(&c.parent) {
                selected.extend(c.family.iter().copied());
                order.extend(c.family);
            }
        }
        self.apply(selected, order)
    }

    /// Families that may be loaded, best first. Top-down: a family is a
    /// candidate only if its parent's is one.
    fn candidates(&self, camera_pos_m: [f64; 3], want: Option<&RefineWant>) -> Vec<Candidate> {
        let cam = [camera_pos_m[0], camera_pos_m[1]];
        let mut out = Vec::new();
        // Each node with its parent family's score: a family never sorts
        // before its parent's (below).
        let mut stack: Vec<(NodeId, f64)> = self.roots.iter().map(|r| (*r, f64::INFINITY)).collect();
        while let Some((n, cap)) = stack.pop() {
            if self.is_failed(n) {
                continue;
            }
            let family: Vec<NodeId> =
                self.world.valid_children(n).into_iter().filter(|c| !self.is_failed(*c)).collect();
            if family.is_empty() {
                continue;
            }
            let held = family.iter().any(|c| self.slots.contains_key(c));
            // With an error criterion the rings only prefetch around the
            // camera; without one they decide alone.
            let in_ring = family.iter().any(|c| {
                let factor = want.map_or(self.config.ring_factor, |w| w.ring_factor);
                let ring = factor * self.world.node_size_m(c.lod);
                let limit = if held { ring * self.config.hysteresis } else { ring };
                let b = self.world.bounds_m(*c);
                dist(cam, [(b[0] + b[2]) * 0.5, (b[1] + b[3]) * 0.5]) <= limit
            });
            let (error_px, in_view) = match want {
                Some(w) => self.projected(n, w),
                None => (0.0, true),
            };
            // A parent whose error is not known yet (a root made on demand,
            // [`super::ErrorTree::with_roots_on_demand`]) wants its family
            // only in view: its tile is made when the family loads.
            let known_or_seen = error_px.is_finite() || in_view || want.is_some_and(|w| w.infinite_known);
            // The families right around the camera count as in view: those
            // behind it are drawn at the edges of the view and cap, through
            // the seams, how finely the patches at the camera's feet may be
            // drawn. (A ring family's parent's family is in the ring too.)
            let in_view = in_view || in_ring;
            let wanted = want.is_some_and(|w| {
                // Held families stay until their error falls well below the target.
                let threshold = w.target_error_px * w.prefetch / if held { self.config.hysteresis } else { 1.0 };
                error_px > threshold && known_or_seen
            });
            if in_ring || wanted {
                let score = match want {
                    Some(_) => error_px * if held { self.config.hysteresis } else { 1.0 },
                    // Nearest first.
                    None => -dist_to_box(cam, self.world.bounds_m(n)),
                }
                .min(cap);
                let near = dist_to_box(cam, self.world.bounds_m(n));
                out.push(Candidate { in_view, score, near, parent: n, family: family.clone() });
                stack.extend(family.into_iter().map(|c| (c, score)));
            }
        }
        // A family's score is capped at its parent family's (the errors are
        // monotone with the error tree's numbers, but not always with the
        // per-triangle rule's refinement bounds: a node over the world's
        // edge has an infinite one, its parent may not), and the view holds
        // a child only if it holds the parent: a family sorts after its
        // parent's (a family ahead of its parent's would never be taken).
        // Coarser first on ties, then nearer (pending roots' errors tie at
        // infinity).
        out.sort_by(|a, b| {
            b.in_view
                .cmp(&a.in_view)
                .then(b.score.total_cmp(&a.score))
                .then(b.parent.lod.cmp(&a.parent.lod))
                .then(a.near.total_cmp(&b.near))
        });
        out
    }

    /// Resident node `n`'s projected error (px; 0 before its bounds are
    /// known) and whether the view holds its box.
    fn projected(&self, n: NodeId, w: &RefineWant) -> (f64, bool) {
        let b = self.world.bounds_m(n);
        let Some(nb) = self.bounds.get(&n) else {
            let (lo, hi) = ([b[0], b[1], f64::MIN], [b[2], b[3], f64::MAX]);
            return (0.0, w.camera.sees(lo, hi));
        };
        let lo = [b[0], b[1], f64::from(nb.z[0])];
        let hi = [b[2], b[3], f64::from(nb.z[1])];
        (w.camera.projected_px(f64::from(nb.max_error_m), lo, hi), w.camera.sees(lo, hi))
    }

    /// Makes `selected` the slots: drops the rest (finest first), adds the
    /// new ones in `order`.
    fn apply(&mut self, selected: HashSet<NodeId>, order: Vec<NodeId>) -> ResidencyChanges {
        let mut changes = ResidencyChanges::default();
        let mut dropped: Vec<(NodeId, Slot)> =
            self.slots.iter().filter(|(id, _)| !selected.contains(id)).map(|(id, s)| (*id, *s)).collect();
        dropped.sort_by_key(|(id, _)| (id.lod, id.x, id.y));
        for (id, slot) in dropped {
            self.slots.remove(&id);
            self.bounds.remove(&id);
            match slot {
                Slot::Resident => changes.removes.push(id),
                Slot::Pending => changes.cancels.push(id),
            }
        }
        for id in order {
            if let std::collections::hash_map::Entry::Vacant(e) = self.slots.entry(id) {
                e.insert(Slot::Pending);
                changes.adds.push(id);
                self.counts.retries += usize::from(self.failed.contains_key(&id));
            }
        }
        changes
    }

    /// Records a resident node's error and height range (metres), which
    /// [`RefineWant`] needs to decide on its children.
    pub fn note_bounds(&mut self, id: NodeId, max_error_m: f32, z_m: [f32; 2]) {
        if self.is_resident(id) {
            self.bounds.insert(id, NodeBounds { max_error_m, z: z_m });
        }
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
        self.failed.remove(&id);
        Arrival::Accept
    }

    /// A requested load failed: free its slot; it (and its subtree) is not
    /// wanted until its backoff ends, or never again once it has failed
    /// `max_load_attempts` times.
    pub fn on_failed(&mut self, id: NodeId) -> LoadFate {
        if self.slots.get(&id) == Some(&Slot::Pending) {
            self.slots.remove(&id);
        }
        self.counts.failures += 1;
        let f = self.failed.entry(id).or_insert(FailedNode { attempts: 0, retry_at: None });
        f.attempts += 1;
        if f.attempts >= self.config.max_load_attempts {
            f.retry_at = None;
            self.counts.gave_up += 1;
            return LoadFate::GaveUp { attempts: f.attempts };
        }
        let backoff = self.config.retry_frames.saturating_mul(1 << (f.attempts - 1));
        let at_frame = self.frame.saturating_add(backoff);
        f.retry_at = Some(at_frame);
        LoadFate::Retry { attempts: f.attempts, at_frame }
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
