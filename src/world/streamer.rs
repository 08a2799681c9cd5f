//! [`Streamer`]: a [`Residency`] driven by a [`Loader`]; tells the GPU side,
//! per frame, which payloads arrived, which resident nodes reload and which
//! leave.
//!
//! An edit's reloads are handed over together: a node swapped to the edited
//! ground beside one still drawn from the old would open a crack along
//! their shared edge (a stamp's wall seen through), so reloaded payloads
//! wait until every reload of the edit is back, and no new arrival (made
//! from the edited source) is accepted meanwhile.

use std::collections::{HashMap, HashSet};

use super::error::WorldError;
use super::layout::NodeId;
use super::loader::Loader;
use super::payload::BakedNode;
use super::streaming::{Arrival, LoadFate, RefineWant, Residency};

/// One frame of streaming for the GPU side: apply `removed` (free slots)
/// then upload `arrived` and `reloaded`.
#[derive(Debug, Default)]
pub struct StreamFrame {
    pub arrived: Vec<BakedNode>,
    /// New payloads of resident nodes asked for by [`Streamer::reload`]:
    /// every reload under way, handed over in one frame.
    pub reloaded: Vec<BakedNode>,
    pub removed: Vec<NodeId>,
    /// Loads that failed this frame, and what becomes of each node.
    pub failed: Vec<(NodeId, WorldError)>,
    pub fates: Vec<LoadFate>,
}

/// Residency driven by a loader.
pub struct Streamer {
    residency: Residency,
    loader: Loader,
    /// Loaded payloads waiting for their parent to become resident (or
    /// for the reloads under way to be back).
    parked: HashMap<NodeId, BakedNode>,
    /// Resident nodes whose payload is being made again ([`Self::reload`]):
    /// they stay drawn until every one of them is back.
    reloading: HashSet<NodeId>,
    /// Reloaded payloads back while others are still being made.
    reloaded: HashMap<NodeId, BakedNode>,
}

impl Streamer {
    pub fn new(residency: Residency, loader: Loader) -> Self {
        Streamer { residency, loader, parked: HashMap::new(), reloading: HashSet::new(), reloaded: HashMap::new() }
    }

    /// Makes every payload with `loader` from now on (the source was
    /// edited): loads under way, payloads parked for which `stale` is true
    /// and every reload not handed over yet (back or not: those back were
    /// made from the old source) are asked of it again; the old loader's
    /// queue is dropped with it.
    pub fn replace_loader(&mut self, loader: Loader, stale: impl Fn(NodeId) -> bool) {
        self.loader = loader;
        self.parked.retain(|id, _| !stale(*id));
        let held: Vec<NodeId> = self.reloaded.drain().map(|(id, _)| id).collect();
        self.reloading.extend(held);
        let pending: Vec<NodeId> = self.residency.pending().filter(|id| !self.parked.contains_key(id)).collect();
        for id in pending.into_iter().chain(self.reloading.iter().copied()) {
            self.loader.request(id);
        }
    }

    /// Loads resident `id` again (its source changed); the payload comes
    /// back in [`StreamFrame::reloaded`], with every other reload asked
    /// for meanwhile, while the old one stays drawn. False when `id` is not
    /// resident (a pending load gets the new source anyway).
    pub fn reload(&mut self, id: NodeId) -> bool {
        if !self.residency.is_resident(id) {
            return false;
        }
        if self.reloading.insert(id) {
            self.reloaded.remove(&id);
            self.loader.request(id);
        }
        true
    }

    /// A resident node's payload was replaced outside the loader (a root's
    /// errors attached once made): streaming weighs its new bounds.
    pub fn renew_bounds(&mut self, node: &BakedNode) {
        note_bounds(&mut self.residency, node);
    }

    /// Blocks until a load finishes or `timeout` passes (a caller with
    /// nothing to do until one does: [`Loader::wait`]).
    pub fn wait_for_load(&self, timeout: std::time::Duration) -> bool {
        self.loader.wait(timeout)
    }

    /// Reloads not handed over yet.
    pub fn reloading(&self) -> usize {
        self.reloading.len()
    }

    pub fn residency(&self) -> &Residency {
        &self.residency
    }

    /// Never blocks: updates the wanted set (rings, and `want`'s error
    /// criterion on resident nodes), queues loads and collects whatever
    /// finished.
    pub fn frame(&mut self, camera_pos_m: [f64; 3], want: Option<&RefineWant>) -> StreamFrame {
        let changes = self.residency.update_with(camera_pos_m, want);
        for id in &changes.cancels {
            self.loader.cancel(*id);
            self.parked.remove(id);
        }
        for id in &changes.removes {
            if self.reloading.remove(id) {
                self.loader.cancel(*id);
            }
            self.reloaded.remove(id);
        }
        for id in &changes.adds {
            self.loader.request(*id);
        }
        let mut frame = StreamFrame { removed: changes.removes, ..StreamFrame::default() };
        for (id, result) in self.loader.poll() {
            if self.reloading.remove(&id) && self.residency.is_resident(id) {
                self.reload_back(id, result);
                continue;
            }
            match result {
                Ok(node) => {
                    self.parked.insert(id, node);
                }
                Err(e) => {
                    frame.fates.push(self.residency.on_failed(id));
                    frame.failed.push((id, e));
                }
            }
        }
        if self.reloading.is_empty() {
            self.hand_over_reloads(&mut frame);
            self.accept_parked(&mut frame);
        }
        frame
    }

    /// A reload came back: kept until the others are, or, failed, the old
    /// payload stays (better stale than missing).
    fn reload_back(&mut self, id: NodeId, result: Result<BakedNode, WorldError>) {
        match result {
            Ok(node) => {
                self.reloaded.insert(id, node);
            }
            Err(e) => log::error!("node {id} could not be reloaded (its old payload stays): {e}"),
        }
    }

    fn hand_over_reloads(&mut self, frame: &mut StreamFrame) {
        for (id, node) in self.reloaded.drain() {
            if self.residency.is_resident(id) {
                note_bounds(&mut self.residency, &node);
                frame.reloaded.push(node);
            }
        }
    }

    /// Parked payloads whose parent is in, coarsest first so a parent
    /// accepted now lets its children in.
    fn accept_parked(&mut self, frame: &mut StreamFrame) {
        let mut ids: Vec<NodeId> = self.parked.keys().copied().collect();
        ids.sort_by_key(|id| std::cmp::Reverse(id.lod));
        for id in ids {
            match self.residency.on_loaded(id) {
                Arrival::Accept => {
                    if let Some(node) = self.parked.remove(&id) {
                        note_bounds(&mut self.residency, &node);
                        frame.arrived.push(node);
                    }
                }
                Arrival::Discard => {
                    self.parked.remove(&id);
                }
                Arrival::Defer => {}
            }
        }
    }
}

fn note_bounds(residency: &mut Residency, node: &BakedNode) {
    let w = *residency.world();
    let z = [w.decode_height(node.min_height), w.decode_height(node.max_height)];
    residency.note_bounds(node.id, node.max_error_m, z);
}
