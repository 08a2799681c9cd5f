//! The GPU side of the quadtree: node texture, node description buffer,
//! payload atlases (one texture array per payload kind, a node slot is a
//! layer) and the per-frame upload ring that feeds `quadtree_update`.
//!
//! Resting layouts between passes: the node texture GENERAL (storage writes
//! and reads), the atlases SHADER_READ_ONLY_OPTIMAL (sampled); uploads
//! transition to TRANSFER_DST_OPTIMAL and back.

use super::atlases::{aligned_size, atlas_format, node_upload_bytes, payload_bytes, ATLASES};
pub use super::atlases::{
    atlas_name, AtlasSet, ATLAS_ALBEDO, ATLAS_CONTROL, ATLAS_COUNT, ATLAS_HEIGHT, ATLAS_LAYOUT, ATLAS_NORMAL,
    ATLAS_PATCH_CONES, ATLAS_PATCH_ERRORS, ATLAS_PATCH_HOLES, ATLAS_PATCH_MIN_MAX, ATLAS_SPLAT, ATLAS_VERTEX_BOUNDS,
};
use super::upload_queue::{UploadQueue, Waiting};
use crate::error::{Error, Result};
use crate::frame::per_frame::{copy_name, PerFrame};
use crate::gpu::{vk, Buffer, BufferDesc, Context, Image, ImageDesc, MemoryLocation, Recorder};
use crate::terrain::quadtree::{texture_extent, NodeDesc, QuadtreeShadow, QuadtreeUpdate, FIRST_SLOT, MAX_SLOTS};
use crate::world::{BakedNode, NodeId, PayloadFormat, WorldDesc};

/// Most node payloads copied per frame; later arrivals wait a frame (a
/// node becomes visible to the GPU only once its payload is in the atlas).
pub const MAX_UPLOADS_PER_FRAME: usize = 16;

struct RingSlot {
    updates: Buffer,
    payloads: Buffer,
}

pub struct GpuQuadtree {
    pub shadow: QuadtreeShadow,
    /// One per frame parity (`frame::per_frame`): frame N+1's update writes
    /// the copy frame N's phase-2 culling is not reading.
    node_textures: PerFrame<Image>,
    pub node_descs: Buffer,
    /// f32 LOD error (m) per slot, beside the descriptions.
    pub node_errors: Buffer,
    /// One per `ATLAS_*` index; `None` where the set leaves it out.
    atlases: Vec<Option<Image>>,
    set: AtlasSet,
    format: PayloadFormat,
    ring: Vec<RingSlot>,
    /// The frame being recorded (`begin_frame`): picks the ring slot, so
    /// the ring advances with the frames, not with the uploads.
    frame: u64,
    current: usize,
    /// Payloads to upload: arrivals, and reloads of resident nodes.
    waiting: UploadQueue,
    update_capacity: u32,
    /// Nodes made resident by this frame's `prepare_frame`, with their slots.
    arrived: Vec<(NodeId, u32)>,
    /// Of those, the reloads: a resident node's new payload (an edit).
    reloaded: Vec<NodeId>,
    /// Per ring slot: the frame whose update list it holds, and its length.
    written: Vec<(u64, u32)>,
}

impl GpuQuadtree {
    /// `slots` resident nodes at most; `frames_in_flight` upload buffers (the
    /// caller must not record more frames ahead than that); the atlases of
    /// `set` only; every node added must be baked in `format`.
    pub fn new(
        ctx: &Context,
        world: &WorldDesc,
        slots: u32,
        frames_in_flight: usize,
        set: AtlasSet,
        format: PayloadFormat,
    ) -> Result<Self> {
        if !(1..=MAX_SLOTS).contains(&slots) {
            return Err(Error::BadInput(format!("slot budget {slots} outside 1..={MAX_SLOTS} (slots are 11-bit)")));
        }
        let extent = texture_extent(world);
        // Before the CPU shadow, which is as large as the texture.
        let max = ctx.info().limits.max_image_dimension_2d;
        if extent.iter().any(|&e| e > max) {
            return Err(node_texture_error(ctx, world, extent, None));
        }
        let mut shadow = QuadtreeShadow::new(world, crate::world::slot_capacity(slots));
        // A freed slot waits until the frames that drew its last node are done.
        shadow.set_reuse_delay(frames_in_flight.max(1) as u64);
        let node_textures = node_textures(ctx, world, extent)?;
        let layers = shadow.slot_capacity() + FIRST_SLOT;
        let [node_descs, node_errors] = slot_buffers(ctx, layers)?;
        let atlases = atlases(ctx, set, format, layers)?;
        // Worst case per frame: every slot freed and refilled (texel, desc, error each).
        let update_capacity = 6 * layers;
        let ring = upload_ring(ctx, frames_in_flight, update_capacity, node_upload_bytes(set, format))?;
        let parts = Initial { node_textures: &node_textures, atlases: &atlases, slots: [&node_descs, &node_errors] };
        initialise(ctx, &shadow, parts)?;
        let written = vec![(0, 0); ring.len()];
        Ok(GpuQuadtree {
            shadow,
            node_textures,
            node_descs,
            node_errors,
            atlases,
            set,
            format,
            ring,
            frame: 0,
            current: 0,
            waiting: UploadQueue::default(),
            update_capacity,
            arrived: Vec::new(),
            reloaded: Vec::new(),
            written,
        })
    }

    /// Atlas `i` (`ATLAS_*`), if the set keeps it.
    pub fn atlas(&self, i: usize) -> Option<&Image> {
        self.atlases[i].as_ref()
    }

    /// Atlas `i`, which the caller's pass needs: asking for one the set left
    /// out is a programmer error (the pass should not have been built).
    pub fn required_atlas(&self, i: usize) -> &Image {
        self.atlases[i].as_ref().unwrap_or_else(|| panic!("{} is not kept: its effect is off", ATLASES[i].name))
    }

    /// The atlases kept on the GPU.
    pub fn atlas_set(&self) -> AtlasSet {
        self.set
    }

    /// The normal and albedo atlases' format.
    pub fn payload_format(&self) -> PayloadFormat {
        self.format
    }

    /// The atlases kept, with their names.
    pub fn kept_atlases(&self) -> impl Iterator<Item = (usize, &Image)> {
        self.atlases.iter().enumerate().filter_map(|(i, a)| a.as_ref().map(|a| (i, a)))
    }

    /// Removes a resident (or still waiting) node; its slot is free at once.
    pub fn remove(&mut self, id: NodeId) {
        self.waiting.remove(id);
        self.shadow.remove(id);
    }

    /// Queues an arrived node; it becomes resident when its payload is
    /// uploaded by `record_updates` (at most MAX_UPLOADS_PER_FRAME a frame).
    pub fn add(&mut self, node: BakedNode, lod_bias: i8) {
        assert_eq!(node.format, self.format, "{} baked for other atlases", node.id);
        self.waiting.push(Waiting { node, lod_bias, reload: false });
    }

    /// Queues a new payload for a resident node (its source was edited):
    /// uploaded like an arrival into a fresh slot, which replaces the old
    /// one in the same update, so the node is drawn without a gap; reloads
    /// queued together swap in one update where a frame holds them (see
    /// `upload_queue`). Dropped if the node leaves before then.
    pub fn reload(&mut self, node: BakedNode, lod_bias: i8) {
        assert_eq!(node.format, self.format, "{} baked for other atlases", node.id);
        self.waiting.push(Waiting { node, lod_bias, reload: true });
    }

    /// Slots the GPU resources hold: the budget and the reload slots
    /// ([`crate::world::slot_capacity`]); every per-slot resource of a pass
    /// is this large.
    pub fn slot_capacity(&self) -> u32 {
        self.shadow.slot_capacity()
    }

    /// Whether the next `prepare_frame` has anything to upload or write
    /// (the CPU knows without asking the GPU).
    pub fn has_work(&self) -> bool {
        !self.waiting.is_empty() || self.shadow.has_updates()
    }

    /// Device memory of every resource: (name, bytes, the atlas it holds or
    /// its share of the upload ring is for, if any).
    pub fn memory(&self) -> Vec<(String, u64, Option<usize>)> {
        let mut out = vec![
            (self.node_textures.all()[0].name.clone(), self.node_textures.all()[0].memory_bytes(), None),
            (self.node_textures.all()[1].name.clone(), self.node_textures.all()[1].memory_bytes(), None),
            (self.node_descs.name.clone(), self.node_descs.memory_bytes(), None),
            (self.node_errors.name.clone(), self.node_errors.memory_bytes(), None),
        ];
        for (i, a) in self.kept_atlases() {
            out.push((a.name.clone(), a.memory_bytes(), Some(i)));
        }
        let ring_payload: u64 = self.ring.iter().map(|r| r.payloads.memory_bytes()).sum();
        let per_node = node_upload_bytes(self.set, self.format).max(1);
        for (i, _) in self.kept_atlases() {
            // The payload ring holds each kept kind's bytes side by side.
            let share = ring_payload * aligned_size(i, self.format) / per_node;
            out.push((format!("node_payload_uploads ({})", ATLASES[i].name), share, Some(i)));
        }
        let updates: u64 = self.ring.iter().map(|r| r.updates.memory_bytes()).sum();
        out.push(("quadtree_updates".to_string(), updates, None));
        out
    }

    /// Nodes queued but not uploaded yet.
    pub fn waiting(&self) -> usize {
        self.waiting.len()
    }

    /// Starts frame `frame` (numbers grow by one per recorded frame, from
    /// 1): its uploads use ring slot `frame % ring`, which the caller's
    /// frames-in-flight bound keeps free of older in-flight frames even
    /// when frames without uploads come between.
    pub fn begin_frame(&mut self, frame: u64) {
        assert!(frame > self.frame, "frame {frame} after {}", self.frame);
        self.frame = frame;
        self.node_textures.select(frame);
        self.shadow.begin_frame(frame);
        self.arrived.clear();
        self.reloaded.clear();
    }

    /// Nodes this frame made resident (empty before `prepare_frame`).
    pub fn arrived(&self) -> &[(NodeId, u32)] {
        &self.arrived
    }

    /// Of [`Self::arrived`], the nodes whose payload replaced their own.
    pub fn reloaded(&self) -> &[NodeId] {
        &self.reloaded
    }

    /// The ring slot the current frame's uploads use.
    pub fn upload_slot(&self) -> usize {
        (self.frame % self.ring.len() as u64) as usize
    }

    /// Uploads this frame's payloads and writes the frame's coalesced
    /// changes into `current_updates()`; returns how many there are.
    pub fn prepare_frame(&mut self, rec: &mut Recorder) -> Result<u32> {
        let slot_index = self.upload_slot();
        self.current = slot_index;
        let mut uploaded = Vec::new();
        while uploaded.len() < MAX_UPLOADS_PER_FRAME {
            let (room, free) = (MAX_UPLOADS_PER_FRAME - uploaded.len(), self.shadow.free_slots());
            let Some(w) = self.waiting.next(uploaded.len(), room, free) else { break };
            let resident = self.shadow.slot_of(w.node.id).is_some();
            if resident != w.reload {
                // An arrival already resident, or a reload of a node gone.
                continue;
            }
            let desc = NodeDesc::from_baked(&w.node, w.lod_bias);
            let slot = if w.reload { self.shadow.replace(w.node.id, desc) } else { self.shadow.add(w.node.id, desc) };
            let Some(slot) = slot else {
                self.waiting.push_front(w);
                break;
            };
            if w.reload {
                self.reloaded.push(w.node.id);
            }
            uploaded.push((w.node, slot));
        }
        let ring = &mut self.ring[slot_index];
        let mapped = ring.payloads.mapped_mut().expect("mapped");
        let per_node = node_upload_bytes(self.set, self.format) as usize;
        let kept = |i: &usize| self.set.contains(*i);
        for (i, (node, _)) in uploaded.iter().enumerate() {
            let mut off = i * per_node;
            for (k, bytes) in payload_bytes(node).into_iter().enumerate() {
                if kept(&k) {
                    assert_eq!(
                        bytes.len() as u64,
                        atlas_format(k, self.format).1,
                        "{} of node {}",
                        atlas_name(k),
                        node.id
                    );
                    mapped[off..off + bytes.len()].copy_from_slice(bytes);
                    off += aligned_size(k, self.format) as usize;
                }
            }
        }
        // Only the layers written change layout: they were free since before
        // the oldest frame in flight, so work still sampling the atlases
        // (the last frame's, beside this one's compute) reads other layers.
        let mut copies = Vec::new();
        for (i, (_, slot)) in uploaded.iter().enumerate() {
            let mut off = (i * per_node) as u64;
            for (k, img) in self.atlases.iter().enumerate() {
                if let Some(img) = img {
                    copies.push((off, img, *slot));
                    off += aligned_size(k, self.format);
                }
            }
        }
        rec.copy_into_layers(&ring.payloads, &copies);
        self.arrived = uploaded.iter().map(|(n, slot)| (n.id, *slot)).collect();
        let updates = self.shadow.take_updates();
        assert!(updates.len() as u32 <= self.update_capacity, "{} updates exceed the ring", updates.len());
        let bytes: &[u8] = bytemuck::cast_slice::<QuadtreeUpdate, u8>(&updates);
        ring.updates.mapped_mut().expect("mapped")[..bytes.len()].copy_from_slice(bytes);
        self.written[slot_index] = (self.frame, updates.len() as u32);
        Ok(updates.len() as u32)
    }

    /// The node texture copy of the frame being (or last) recorded.
    pub fn node_texture(&self) -> &Image {
        self.node_textures.current()
    }

    /// The last frame's update list and its length, when it wrote any:
    /// this frame's node texture copy has not seen it yet.
    pub fn previous_updates(&self) -> Option<(&Buffer, u32)> {
        let slot = ((self.frame.checked_sub(1)?) % self.ring.len() as u64) as usize;
        match self.written[slot] {
            (frame, count) if frame + 1 == self.frame && count > 0 => Some((&self.ring[slot].updates, count)),
            _ => None,
        }
    }

    /// The update list written by the last `prepare_frame`.
    pub fn current_updates(&self) -> &Buffer {
        &self.ring[self.current].updates
    }
}

/// A world too large for the device fails where its node texture is made;
/// say what was asked for (a world this size), not which GPU resource.
/// `e` is the allocation's error, None for a texture wider than the device
/// allows.
/// The node texture, one copy per frame parity (`frame::per_frame`).
fn node_textures(ctx: &Context, world: &WorldDesc, extent: [u32; 2]) -> Result<PerFrame<Image>> {
    PerFrame::new(|i| {
        Image::new(
            ctx,
            &ImageDesc {
                name: &copy_name("quadtree_nodes", i),
                format: vk::Format::R16_UINT,
                extent,
                mip_levels: world.lod_count,
                array_layers: 1,
                usage: vk::ImageUsageFlags::STORAGE
                    | vk::ImageUsageFlags::SAMPLED
                    | vk::ImageUsageFlags::TRANSFER_DST
                    | vk::ImageUsageFlags::TRANSFER_SRC,
            },
        )
        .map_err(|e| node_texture_error(ctx, world, extent, Some(e)))
    })
}

/// Per slot: the node descriptions (8 bytes) and errors (4 bytes).
fn slot_buffers(ctx: &Context, layers: u32) -> Result<[Buffer; 2]> {
    let usage =
        vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::TRANSFER_SRC;
    let buffer = |name, bytes: u64| {
        Buffer::new(
            ctx,
            &BufferDesc { name, size: u64::from(layers) * bytes, usage, location: MemoryLocation::GpuOnly },
        )
    };
    Ok([buffer("quadtree_node_descs", 8)?, buffer("quadtree_node_errors", 4)?])
}

/// The payload atlases of `set`, one layer per slot (None: not kept).
fn atlases(ctx: &Context, set: AtlasSet, format: PayloadFormat, layers: u32) -> Result<Vec<Option<Image>>> {
    let mut atlases = Vec::new();
    for (i, a) in ATLASES.iter().enumerate() {
        if !set.contains(i) {
            atlases.push(None);
            continue;
        }
        atlases.push(Some(Image::new(
            ctx,
            &ImageDesc {
                name: a.name,
                format: atlas_format(i, format).0,
                extent: [a.side, a.side],
                mip_levels: 1,
                array_layers: layers,
                usage: vk::ImageUsageFlags::SAMPLED
                    | vk::ImageUsageFlags::TRANSFER_DST
                    | vk::ImageUsageFlags::TRANSFER_SRC,
            },
        )?));
    }
    Ok(atlases)
}

/// The upload ring: per slot the update list and the payloads.
fn upload_ring(ctx: &Context, frames_in_flight: usize, updates: u32, per_node: u64) -> Result<Vec<RingSlot>> {
    let host = |name: &str, size| {
        Buffer::new(
            ctx,
            &BufferDesc {
                name,
                size,
                usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC,
                location: MemoryLocation::CpuToGpu,
            },
        )
    };
    // Two at least: a frame also applies the last frame's list to its
    // node texture copy.
    (0..frames_in_flight.max(2))
        .map(|i| {
            Ok(RingSlot {
                updates: host(&format!("quadtree_updates[{i}]"), u64::from(updates) * 16)?,
                payloads: host(&format!("node_payload_uploads[{i}]"), per_node * MAX_UPLOADS_PER_FRAME as u64)?,
            })
        })
        .collect()
}

/// What starts empty on the GPU.
struct Initial<'a> {
    node_textures: &'a PerFrame<Image>,
    atlases: &'a [Option<Image>],
    /// The descriptions and errors.
    slots: [&'a Buffer; 2],
}

/// Initial contents: every texel empty or invalid, descriptions zero.
fn initialise(ctx: &Context, shadow: &QuadtreeShadow, parts: Initial) -> Result<()> {
    let texels: Vec<u8> = shadow.mips.iter().flat_map(|m| bytemuck::cast_slice::<u16, u8>(m).to_vec()).collect();
    let mut staging = Buffer::new(
        ctx,
        &BufferDesc {
            name: "quadtree_init",
            size: texels.len() as u64,
            usage: vk::BufferUsageFlags::TRANSFER_SRC,
            location: MemoryLocation::CpuToGpu,
        },
    )?;
    staging.mapped_mut().expect("mapped").copy_from_slice(&texels);
    ctx.submit_and_wait(|rec| {
        for a in parts.atlases.iter().flatten() {
            rec.discard_to(a, ATLAS_LAYOUT);
        }
        for node_texture in parts.node_textures.all() {
            rec.discard_to(node_texture, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
            let mut offset = 0;
            for (lod, m) in shadow.mips.iter().enumerate() {
                rec.copy_buffer_to_image(&staging, offset, node_texture, lod as u32, 0);
                offset += (m.len() * 2) as u64;
            }
            rec.transition(node_texture, vk::ImageLayout::GENERAL);
        }
        for b in parts.slots {
            rec.fill_buffer(b, 0);
        }
        Ok(())
    })
}

fn node_texture_error(ctx: &Context, world: &WorldDesc, extent: [u32; 2], e: Option<Error>) -> Error {
    let [w, h] = extent;
    // R16 texels over the mip chain, each mip half the one above.
    let bytes: u64 = (0..world.lod_count).map(|k| u64::from((w >> k).max(1)) * u64::from((h >> k).max(1)) * 2).sum();
    let [sx, sy] = world.sectors();
    let size = if bytes < 1 << 20 {
        format!("{:.1} KiB", bytes as f64 / 1024.0)
    } else {
        format!("{:.0} MiB", bytes as f64 / f64::from(1 << 20))
    };
    let asked = format!(
        "the world's quadtree ({sx} x {sy} sectors of {} m, {} LODs) needs a {w} x {h} node texture, {size} of GPU \
         memory",
        world.sector_size_m(),
        world.lod_count,
    );
    let max = ctx.info().limits.max_image_dimension_2d;
    match e {
        None => Error::BadInput(format!(
            "{asked}; this device allows at most {max} texels per side: a larger spacing or a smaller extent fits"
        )),
        Some(Error::OutOfDeviceMemory) => Error::BadInput(format!("{asked}, more than the device has free")),
        Some(Error::Allocation { source, .. }) => {
            Error::BadInput(format!("{asked}, which failed to allocate: {source}"))
        }
        Some(e) => e,
    }
}
