//! The payloads waiting for `quadtree_update`'s copies, oldest first.
//!
//! Reloads (an edit's new payloads, handed over together by the streamer)
//! are taken as one run where a frame can hold them: a node swapped to the
//! edited ground beside one still drawn from the old would open a crack
//! along their edge. A run larger than a whole frame's uploads or the free
//! slots goes in pieces (better a crack for a frame than a stall).

use crate::world::BakedNode;
use std::collections::VecDeque;

pub struct Waiting {
    pub node: BakedNode,
    pub lod_bias: i8,
    /// A new payload for a resident node: it moves to a fresh slot.
    pub reload: bool,
}

#[derive(Default)]
pub struct UploadQueue {
    waiting: VecDeque<Waiting>,
}

impl UploadQueue {
    pub fn push(&mut self, w: Waiting) {
        if w.reload {
            self.waiting.retain(|o| o.node.id != w.node.id || !o.reload);
        }
        self.waiting.push_back(w);
    }

    /// Takes back what `next` gave but could not place; it goes first.
    pub fn push_front(&mut self, w: Waiting) {
        self.waiting.push_front(w);
    }

    pub fn remove(&mut self, id: crate::world::NodeId) {
        self.waiting.retain(|w| w.node.id != id);
    }

    pub fn len(&self) -> usize {
        self.waiting.len()
    }

    pub fn is_empty(&self) -> bool {
        self.waiting.is_empty()
    }

    /// The next payload to upload after `taken` this frame, with `room`
    /// uploads and `free` slots left; None where the run of reloads at the
    /// front fits the next frame better than what is left of this one.
    pub fn next(&mut self, taken: usize, room: usize, free: usize) -> Option<Waiting> {
        let front = self.waiting.front()?;
        if front.reload && taken > 0 {
            let run = self.waiting.iter().take_while(|w| w.reload).count();
            if run > room.min(free) {
                return None;
            }
        }
        self.waiting.pop_front()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::{bake_node, GridSource, NodeId, WorldDesc};

    fn queue(reloads: &[bool]) -> UploadQueue {
        let world = WorldDesc { extent_m: [512.0, 512.0], spacing_m: 2.0, lod_count: 2, ..WorldDesc::default() };
        let flat = GridSource::new(2, 2, vec![0.0; 4], [512.0; 2]);
        let mut q = UploadQueue::default();
        for (i, &reload) in reloads.iter().enumerate() {
            let node = bake_node(&flat, &world, &[], NodeId { lod: 0, x: i as u32 % 2, y: i as u32 / 2 });
            q.push(Waiting { node, lod_bias: 0, reload });
        }
        q
    }

    /// A run of reloads waits for the next frame rather than split, unless
    /// no frame could hold it.
    #[test]
    fn a_run_of_reloads_goes_in_one_frame_where_one_holds_it() {
        let mut q = queue(&[false, true, true, true]);
        assert!(!q.next(0, 4, 8).unwrap().reload);
        assert!(q.next(1, 2, 8).is_none(), "three reloads, two uploads left: next frame");
        assert!(q.next(1, 3, 2).is_none(), "three reloads, two free slots: next frame");
        assert!((0..3).all(|k| q.next(k, 3 - k, 8).is_some_and(|w| w.reload)), "a fresh frame takes the run");
        let mut big = queue(&[true, true, true]);
        assert!(big.next(0, 2, 2).is_some(), "more than a whole frame holds: in pieces");
        assert_eq!(big.len(), 2);
    }
}
