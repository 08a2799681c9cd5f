//! The GPU quadtree's CPU shadow (Far Cry 5): the node texture (R16_UINT, one
//! mip per LOD, value = node slot) and the node description buffer (2 x u32
//! per slot). The shadow allocates slots and turns a frame's removes and adds
//! into a coalesced list of writes for the `quadtree_update` pass.
//! No Vulkan here.

use crate::shaders::consts as k;
use crate::world::{BakedNode, NodeId, WorldDesc, PATCH_HOLE_NONE};
use std::collections::{BTreeMap, VecDeque};

/// Node texture value: nothing loaded for this node.
pub const EMPTY: u16 = k::NODE_EMPTY as u16;
/// Node texture value: the node can never exist (outside the world).
pub const INVALID: u16 = k::NODE_INVALID as u16;
/// Slot 0 is never allocated: sector data uses 0 for "no node".
pub const FIRST_SLOT: u32 = k::FIRST_SLOT;
/// Slots are 11-bit in sector data, so at most 2047 resident nodes.
pub const MAX_SLOTS: u32 = k::MAX_SLOTS;
/// `QuadtreeUpdate::target` of a description write (else: the mip to write).
pub const TARGET_DESC: u32 = k::UPDATE_TARGET_DESC;
/// `QuadtreeUpdate::target` of a node-error write (f32 bits in word0): the
/// LOD metric does not fit the 2 x u32 description.
pub const TARGET_ERROR: u32 = k::UPDATE_TARGET_ERROR;
const _: () = assert!(EMPTY as u32 == k::NODE_EMPTY && MAX_SLOTS < 1 << k::SLOT_BITS);

/// The packed node reference of the node lists (node_list.glsl `pack_node`).
pub fn node_ref(id: NodeId) -> u32 {
    u32::from(id.lod) << k::NODE_REF_LOD_SHIFT | id.y << k::NODE_REF_Y_SHIFT | id.x
}

/// Inverse of [`node_ref`].
pub fn node_from_ref(n: u32) -> NodeId {
    let coord = |shift: u32| (n >> shift) & k::NODE_REF_COORD_MASK;
    NodeId::new((n >> k::NODE_REF_LOD_SHIFT) as u8, coord(0), coord(k::NODE_REF_Y_SHIFT))
}

/// One write of the `quadtree_update` pass (`QuadtreeUpdate` in the shader).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct QuadtreeUpdate {
    /// Mip (= LOD) of a node-texture write, or TARGET_DESC.
    pub target: u32,
    /// x | y << 16 for a texel; the slot for a description.
    pub coords: u32,
    pub word0: u32,
    pub word1: u32,
}

/// What a node description holds before packing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeDesc {
    /// Encoded (R16 over the world height range) min and max height.
    pub min_height: u16,
    pub max_height: u16,
    pub lod: u8,
    /// Signed LOD bias, -8..=7 (per-node refinement nudge).
    pub lod_bias: i8,
    pub has_holes: bool,
    /// Vertical error (m) of drawing this node instead of its children.
    pub max_error_m: f32,
}

impl NodeDesc {
    pub fn from_baked(node: &BakedNode, lod_bias: i8) -> Self {
        NodeDesc {
            min_height: node.min_height,
            max_height: node.max_height,
            lod: node.id.lod,
            lod_bias,
            // The patch summaries cover every sample of the node.
            has_holes: node.patch_holes.iter().any(|&h| h != PATCH_HOLE_NONE),
            max_error_m: node.max_error_m,
        }
    }

    /// word0 = min | max << 16; word1 = slot (11 bits) | lod (4) << 11 |
    /// bias (4, two's complement) << 15 | flags << 19 (bit 19: has holes).
    pub fn pack(&self, slot: u32) -> [u32; 2] {
        assert!(slot <= MAX_SLOTS && self.lod < 16 && (-8..=7).contains(&self.lod_bias));
        let bias = (self.lod_bias as u32) & 0xF;
        [
            u32::from(self.min_height) | u32::from(self.max_height) << k::HALF_BITS,
            slot | u32::from(self.lod) << k::DESC_LOD_SHIFT
                | bias << k::DESC_BIAS_SHIFT
                | u32::from(self.has_holes) << k::DESC_HOLES_SHIFT,
        ]
    }
}

/// Node texture mip `lod` is `grid` texels square per side; mip 0 is padded
/// to a multiple of 2^(lods-1) so every mip is exactly half the one above
/// (plain Vulkan mip sizes would round 59 sectors down to 29 at LOD 1).
pub fn texture_extent(world: &WorldDesc) -> [u32; 2] {
    world.node_texture_extent()
}

pub struct QuadtreeShadow {
    world: WorldDesc,
    /// Node texture, one row-major level per LOD.
    pub mips: Vec<Vec<u16>>,
    /// Packed descriptions by slot (slot 0 unused).
    pub descs: Vec<[u32; 2]>,
    /// LOD error (m) by slot.
    pub errors: Vec<f32>,
    free: Vec<u32>,
    /// Freed slots and the frame they may be reused from: frames still in
    /// flight (and per-slot state such as visibility bits) name the old node.
    cooling: VecDeque<(u64, u32)>,
    reuse_delay: u64,
    frame: u64,
    /// Pending writes of this frame, coalesced: the last write wins.
    texels: BTreeMap<(u32, u32), u16>,
    desc_writes: BTreeMap<u32, [u32; 2]>,
    error_writes: BTreeMap<u32, f32>,
}

impl QuadtreeShadow {
    /// `slots` resident nodes at most (1..=MAX_SLOTS).
    pub fn new(world: &WorldDesc, slots: u32) -> Self {
        assert!((1..=MAX_SLOTS).contains(&slots), "slot budget {slots} outside 1..={MAX_SLOTS}");
        let [w, h] = texture_extent(world);
        let mips = (0..world.lod_count)
            .map(|lod| {
                let (mw, mh) = (w >> lod, h >> lod);
                (0..mw * mh)
                    .map(|i| {
                        let valid = world.is_valid(NodeId::new(lod as u8, i % mw, i / mw));
                        if valid {
                            EMPTY
                        } else {
                            INVALID
                        }
                    })
                    .collect()
            })
            .collect();
        QuadtreeShadow {
            world: *world,
            mips,
            descs: vec![[0, 0]; (slots + FIRST_SLOT) as usize],
            errors: vec![0.0; (slots + FIRST_SLOT) as usize],
            free: (FIRST_SLOT..slots + FIRST_SLOT).rev().collect(),
            cooling: VecDeque::new(),
            reuse_delay: 0,
            frame: 0,
            texels: BTreeMap::new(),
            desc_writes: BTreeMap::new(),
            error_writes: BTreeMap::new(),
        }
    }

    pub fn extent(&self) -> [u32; 2] {
        texture_extent(&self.world)
    }

    /// The node texture's texel for (lod, x, y): a slot, EMPTY or INVALID.
    pub fn texel(&self, lod: u8, x: u32, y: u32) -> u16 {
        let w = self.extent()[0] >> lod;
        self.mips[lod as usize][(y * w + x) as usize]
    }

    pub fn slot_capacity(&self) -> u32 {
        self.descs.len() as u32 - FIRST_SLOT
    }

    fn texel_index(&self, id: NodeId) -> usize {
        let w = self.extent()[0] >> id.lod;
        (id.y * w + id.x) as usize
    }

    /// Slot of a resident node.
    pub fn slot_of(&self, id: NodeId) -> Option<u32> {
        let v = self.mips[id.lod as usize][self.texel_index(id)];
        (v != EMPTY && v != INVALID).then_some(u32::from(v))
    }

    fn set_texel(&mut self, id: NodeId, value: u16) {
        let i = self.texel_index(id);
        self.mips[id.lod as usize][i] = value;
        self.texels.insert((u32::from(id.lod), id.x | id.y << k::HALF_BITS), value);
    }

    /// Frees `id`'s slot; returns it (None if the node was not resident).
    pub fn remove(&mut self, id: NodeId) -> Option<u32> {
        let slot = self.slot_of(id)?;
        self.set_texel(id, EMPTY);
        self.retire(slot);
        Some(slot)
    }

    /// Clears `slot` and frees it after the reuse delay.
    fn retire(&mut self, slot: u32) {
        self.descs[slot as usize] = [0, 0];
        self.desc_writes.insert(slot, [0, 0]);
        if self.reuse_delay == 0 {
            self.free.push(slot);
        } else {
            self.cooling.push_back((self.frame + self.reuse_delay, slot));
        }
    }

    /// Points `id` at `slot`, which holds `desc` from now on.
    fn place(&mut self, id: NodeId, slot: u32, desc: NodeDesc) {
        self.set_texel(id, slot as u16);
        let packed = desc.pack(slot);
        self.descs[slot as usize] = packed;
        self.desc_writes.insert(slot, packed);
        self.errors[slot as usize] = desc.max_error_m;
        self.error_writes.insert(slot, desc.max_error_m);
    }

    /// Frames a freed slot waits before `add` may hand it out again (0, the
    /// default: at once). Slots already waiting keep their release frame.
    pub fn set_reuse_delay(&mut self, frames: u64) {
        self.reuse_delay = frames;
    }

    /// Starts frame `frame` (one more per recorded frame, called every frame):
    /// a slot freed in frame f is released at frame f + delay.
    pub fn begin_frame(&mut self, frame: u64) {
        assert!(frame >= self.frame, "frame {frame} after frame {}", self.frame);
        self.frame = frame;
        // In freeing order, whatever the delay was, so handout stays deterministic.
        let (ready, waiting): (VecDeque<_>, VecDeque<_>) = self.cooling.drain(..).partition(|&(at, _)| at <= frame);
        self.free.extend(ready.into_iter().map(|(_, slot)| slot));
        self.cooling = waiting;
    }

    /// Moves resident `id` to a fresh slot holding `desc` (a new payload
    /// for it: an edited source) in one coalesced write: the texel names the
    /// new slot, the old one cools like a removed one. None while no slot
    /// is free (or `id` is not resident: the caller drops the payload).
    pub fn replace(&mut self, id: NodeId, desc: NodeDesc) -> Option<u32> {
        let old = self.slot_of(id)?;
        let slot = self.free.pop()?;
        self.place(id, slot, desc);
        self.retire(old);
        Some(slot)
    }

    /// Freed slots still waiting out the reuse delay (neither free nor resident).
    pub fn cooling_count(&self) -> usize {
        self.cooling.len()
    }

    /// Allocates a slot for `id`; None when the budget is full (or the node is
    /// invalid or already resident: programmer errors, asserted).
    pub fn add(&mut self, id: NodeId, desc: NodeDesc) -> Option<u32> {
        assert!(self.world.is_valid(id), "node {id} is outside the world");
        assert!(self.slot_of(id).is_none(), "node {id} is already resident");
        let slot = self.free.pop()?;
        self.place(id, slot, desc);
        Some(slot)
    }

    /// Lowest and highest height (m) of the node in `slot`.
    pub fn height_range(&self, slot: u32) -> [f64; 2] {
        let w = self.descs[slot as usize][0];
        let decode = |v: u32| f64::from(self.world.decode_height(v as u16));
        [decode(w & 0xFFFF), decode(w >> k::HALF_BITS)]
    }

    /// Whether any write waits for `take_updates`.
    /// Slots `add` or `replace` may hand out now.
    pub fn free_slots(&self) -> usize {
        self.free.len()
    }

    pub fn has_updates(&self) -> bool {
        !(self.texels.is_empty() && self.desc_writes.is_empty() && self.error_writes.is_empty())
    }

    /// This frame's writes, order-independent (one per texel and per slot),
    /// so the GPU may apply them in parallel.
    pub fn take_updates(&mut self) -> Vec<QuadtreeUpdate> {
        let texels = std::mem::take(&mut self.texels).into_iter().map(|((lod, coords), v)| QuadtreeUpdate {
            target: lod,
            coords,
            word0: u32::from(v),
            word1: 0,
        });
        let descs = std::mem::take(&mut self.desc_writes).into_iter().map(|(slot, w)| QuadtreeUpdate {
            target: TARGET_DESC,
            coords: slot,
            word0: w[0],
            word1: w[1],
        });
        let errors = std::mem::take(&mut self.error_writes).into_iter().map(|(slot, e)| QuadtreeUpdate {
            target: TARGET_ERROR,
            coords: slot,
            word0: e.to_bits(),
            word1: 0,
        });
        texels.chain(descs).chain(errors).collect()
    }

    /// Resident nodes on the GPU side.
    pub fn resident_count(&self) -> u32 {
        self.slot_capacity() - (self.free.len() + self.cooling.len()) as u32
    }

    /// The slots a frame may read: neither free nor cooling.
    pub fn held_slots(&self) -> Vec<u32> {
        let cooling: Vec<u32> = self.cooling.iter().map(|(_, s)| *s).collect();
        (FIRST_SLOT..self.slot_capacity() + FIRST_SLOT)
            .filter(|s| !self.free.contains(s) && !cooling.contains(s))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pack_places_every_field() {
        let d = NodeDesc {
            min_height: 0x1234,
            max_height: 0xABCD,
            lod: 5,
            lod_bias: -2,
            has_holes: true,
            max_error_m: 0.5,
        };
        let [w0, w1] = d.pack(1000);
        assert_eq!(w0, 0xABCD_1234);
        // slot (11 bits) | lod << 11 | bias << 15 | holes << 19.
        assert_eq!(w1 & 0x7FF, 1000);
        assert_eq!((w1 >> 11) & 0xF, 5);
        assert_eq!((((w1 >> 15) & 0xF) as i8) << 4 >> 4, -2);
        assert_eq!((w1 >> 19) & 1, 1);
    }

    fn small_tree(slots: u32) -> (QuadtreeShadow, Vec<NodeId>) {
        let world = WorldDesc {
            extent_m: [2048.0, 2048.0],
            height_range_m: [0.0, 100.0],
            spacing_m: 1.0,
            lod_count: 2,
            ..WorldDesc::default()
        };
        (QuadtreeShadow::new(&world, slots), world.nodes_at(0))
    }

    fn desc() -> NodeDesc {
        NodeDesc { min_height: 0, max_height: 1, lod: 0, lod_bias: 0, has_holes: false, max_error_m: 1.0 }
    }

    #[test]
    fn delayed_slot_is_reused_only_after_the_delay() {
        let (mut t, n) = small_tree(3);
        t.set_reuse_delay(2);
        t.begin_frame(5);
        let a = t.add(n[0], desc()).unwrap();
        let b = t.add(n[1], desc()).unwrap();
        assert_eq!(t.remove(n[0]), Some(a));
        assert_eq!((t.resident_count(), t.cooling_count()), (1, 1));
        let c = t.add(n[2], desc()).unwrap();
        assert!(c != a && c != b, "frame 5 must take the one free slot, not the cooling one");
        assert_eq!(t.add(n[3], desc()), None, "frame 5: 2 resident + 1 cooling fill the budget of 3");
        t.begin_frame(6);
        assert_eq!(t.add(n[3], desc()), None, "frame 6: still cooling");
        assert_eq!((t.resident_count(), t.cooling_count()), (2, 1));
        t.begin_frame(7);
        assert_eq!(t.cooling_count(), 0);
        assert_eq!(t.add(n[3], desc()), Some(a), "frame 7 = 5 + 2: released");
        assert_eq!(t.resident_count(), 3);
        assert_eq!(t.add(n[4], desc()), None);
    }

    #[test]
    fn delayed_slots_released_late_are_all_freed() {
        let (mut t, n) = small_tree(2);
        t.set_reuse_delay(1);
        t.begin_frame(0);
        t.add(n[0], desc()).unwrap();
        t.add(n[1], desc()).unwrap();
        t.remove(n[0]).unwrap();
        t.begin_frame(0);
        t.remove(n[1]).unwrap();
        assert_eq!((t.resident_count(), t.cooling_count()), (0, 2));
        t.begin_frame(9);
        assert_eq!((t.resident_count(), t.cooling_count()), (0, 0));
        assert!(t.add(n[2], desc()).is_some() && t.add(n[3], desc()).is_some());
        assert_eq!(t.add(n[4], desc()), None);
    }

    #[test]
    fn zero_delay_reuses_a_freed_slot_at_once() {
        for explicit in [false, true] {
            let (mut t, n) = small_tree(2);
            if explicit {
                t.set_reuse_delay(0);
                t.begin_frame(3);
            }
            t.add(n[0], desc()).unwrap();
            let b = t.add(n[1], desc()).unwrap();
            assert_eq!(t.remove(n[1]), Some(b));
            assert_eq!((t.resident_count(), t.cooling_count()), (1, 0));
            assert_eq!(t.add(n[2], desc()), Some(b), "explicit {explicit}: same frame, same slot");
            assert_eq!(t.resident_count(), 2);
        }
    }

    #[test]
    fn padded_extent_halves_exactly() {
        let world = WorldDesc {
            extent_m: [60000.0, 60000.0],
            height_range_m: [454.0, 4810.0],
            spacing_m: 8.0,
            lod_count: 6,
            ..WorldDesc::default()
        };
        let [w, h] = texture_extent(&world);
        assert_eq!([w, h], [64, 64]);
        for lod in 0..6u8 {
            assert!(world.grid(lod)[0] <= w >> lod, "lod {lod}");
        }
    }
}
