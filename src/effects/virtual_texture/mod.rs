//! Adaptive virtual texturing (effect `virtual_texture`; seed 001 after Far
//! Cry 4, as Far Cry 5 uses it in seed 000): the splat material blend is
//! rendered once into cached pages and the frame samples the finished
//! material. Per frame:
//! - the CPU ([`state`]) reads the page requests of a finished frame from
//!   the readback ring, sizes each region's sub-texture by its distance and
//!   places it in the indirection ([`allocator`]), and picks up to a budget
//!   of missing pages (coarser first) for tiles of the cache ([`cache`]);
//! - `vt_update` applies the indirection and sub-texture writes, `vt_pages`
//!   renders the picked pages (with effect `decals`, blending the [`decals`]
//!   touching each), `vt_feedback` lists the pages this frame's
//!   pixels sample (copied into the ring, read frames later, never waited
//!   for), and `gbuffer_tiles`' virtual-texture flavour samples the cache.
//!
//! Owned GPU objects, destroyed in field order after the passes: the state
//! buffer (header, sub-texture words, indirection), the page statuses, the
//! request list, the write and job staging buffers, the two cache images,
//! the readback ring and the decals' objects ([`decal_gpu`]); each is
//! dropped through the context's deferred destruction, so frames in flight
//! keep them.

pub mod decal_meshes;
pub mod frame;
pub mod kind;
pub mod vt_feedback;
pub mod vt_pages;
pub mod vt_update;

pub mod allocator;
pub mod cache;
pub mod decal_gpu;
pub mod decal_mesh;
pub mod decals;
pub mod layout;
pub mod state;
pub mod stats;

use crate::effects::virtual_texture::vt_feedback::{FeedbackTargets, VtFeedback, VtFeedbackPush};
use crate::effects::virtual_texture::vt_pages::{PageTargets, VtPages};
use crate::effects::virtual_texture::vt_update::VtUpdate;
use crate::error::Result;
use crate::gpu::{vk, Buffer, BufferDesc, Context, Image, ImageDesc, MemoryLocation, Recorder};
use crate::passes::gbuffer_tiles::VtBindings;
use crate::shaders::consts::{
    DECAL_COUNT_SHIFT, DECAL_MAX_PER_PAGE, VT_MAX_JOBS, VT_MAX_WRITES, VT_NONE, VT_REQUEST_CAPACITY, VT_STATE_HEADER,
};
use crate::world::NodeId;
use cache::PageSource;
use decal_gpu::DecalResources;
use decals::{Decal, DecalSet};
use layout::VtLayout;
use serde::Serialize;
use state::{PageJob, StateWrite, VtCounters, VtState};

/// The scene's virtual-texture parameters (`[effects.virtual_texture]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct VtParams {
    /// Side of a region, each with its own sub-texture (m).
    pub region_m: f64,
    /// Physical cache (both images), MiB.
    pub cache_mb: u32,
    /// Pages rendered per frame at most.
    pub pages_per_frame: u32,
    /// Texels per side of the indirection's mip 0 (a power of two).
    pub indirection: u32,
    /// Side of the window around the camera whose regions can hold
    /// sub-textures (m); at least twice the view's reach (the near
    /// flavour's far end over the corner's secant) or `beyond_window`
    /// counts the regions left out.
    pub window_m: f64,
    /// Tests only (feature `test-hooks`): pages hold the position code of
    /// each texel (region, page, level, texel) instead of the material.
    #[cfg(feature = "test-hooks")]
    pub position_code: bool,
}

impl VtParams {
    fn position_coded(&self) -> bool {
        #[cfg(feature = "test-hooks")]
        return self.position_code;
        #[cfg(not(feature = "test-hooks"))]
        false
    }
}

impl Default for VtParams {
    fn default() -> Self {
        VtParams {
            region_m: 64.0,
            cache_mb: 64,
            pages_per_frame: 16,
            indirection: 2048,
            window_m: 2048.0,
            #[cfg(feature = "test-hooks")]
            position_code: false,
        }
    }
}

/// Bytes of the request list (header of 4 words, then the entries).
const REQUEST_BYTES: u64 = 16 + VT_REQUEST_CAPACITY as u64 * 8;

struct Slot {
    buffer: Buffer,
    frame: u64,
    ctx_frame: u64,
    pending: bool,
    /// Its feedback sampled every pixel.
    whole: bool,
}

/// Where the camera is, for sizing the sub-textures.
#[derive(Debug, Clone, Copy)]
pub struct VtCamera {
    pub xy: [f64; 2],
    /// Radians one pixel spans (vertically, at the image centre).
    pub pixel_rad: f64,
    /// Regions farther than this have no sub-texture (the splat flavour's
    /// reach).
    pub range_m: f64,
    /// The target's size (pixels).
    pub size: [u32; 2],
}

/// One frame's virtual-texture work, planned before recording.
pub struct VtFrame {
    pub frame: u64,
    pub writes: Vec<StateWrite>,
    pub jobs: Vec<PageJob>,
    /// The readback slot its requests go to.
    slot: usize,
    /// The first frame: the buffers are initialised first.
    pub init: bool,
    /// Effect `decals`: the decal indices of the jobs (each job's word
    /// points into it), and the decal and point lists where they changed
    /// since the last frame that rendered pages.
    pub job_decals: Vec<u32>,
    pub decal_lists: Option<(Vec<decals::DecalGpu>, Vec<[f32; 4]>)>,
}

/// Effect `decals`: the decals, their GPU objects, and whether the lists
/// wait to be uploaded.
struct Decals {
    set: DecalSet,
    gpu: DecalResources,
    /// The lists changed since a frame last uploaded them.
    dirty: bool,
}

/// What a page over `rect` (x0, y0, x1, y1 m) is rendered from now: the
/// coarsest of the finest resident LODs over it, the first level whose
/// nodes over it are all resident (a resident node's ancestors are
/// resident, so a point's finest resident LOD is at most l exactly where
/// its level-l node is; the world's LOD count where none is), and a hash
/// of the resident nodes over it, which fix the finest data at every
/// point: the page the GPU renders from them.
fn page_source(terrain: &crate::terrain::Terrain, rect: [f64; 4]) -> PageSource {
    use std::hash::{Hash, Hasher};
    let world = &terrain.world;
    let lods = world.lod_count as u8;
    let [ex, ey] = world.extent_m;
    let (lo, hi) = ([rect[0].max(0.0), rect[1].max(0.0)], [rect[2].min(ex), rect[3].min(ey)]);
    let nodes = |l: u8| {
        let span = world.node_at(l, lo[0], lo[1]).zip(world.node_at(l, hi[0], hi[1]));
        span.into_iter()
            .flat_map(move |(a, b)| (a.y..=b.y).flat_map(move |y| (a.x..=b.x).map(move |x| NodeId::new(l, x, y))))
    };
    let resident = |n: &NodeId| terrain.tree.shadow.slot_of(*n).is_some();
    let lod = (0..lods).find(|&l| nodes(l).all(|n| resident(&n))).unwrap_or(lods);
    let mut h = std::hash::DefaultHasher::new();
    (0..lods.min(lod + 1)).flat_map(nodes).filter(resident).for_each(|n| n.hash(&mut h));
    PageSource { lod, nodes: h.finish() }
}

/// The virtual texture's GPU objects, passes and CPU state.
pub struct VirtualTexture {
    feedback: VtFeedback,
    update: VtUpdate,
    pages: VtPages,
    pub(crate) state_buffer: Buffer,
    status: Buffer,
    /// This frame's page requests (count, 3 words, then the entries).
    pub(crate) requests: Buffer,
    writes_staging: Buffer,
    jobs_staging: Buffer,
    pub(crate) cache_albedo: Image,
    pub(crate) cache_detail: Image,
    ring: Vec<Slot>,
    next: usize,
    pub state: VtState,
    /// Writes left for later frames.
    writes: Vec<StateWrite>,
    /// The feedback's push constants of the newest frame (tests).
    pub(crate) last_push: Option<VtFeedbackPush>,
    /// An offline render settling: the feedback samples every pixel
    /// ([`VirtualTexture::set_catch_up`]).
    catch_up: bool,
    initialized: bool,
    decals: Option<Decals>,
    /// Effect `decals` with a displacement decal: their meshes' pass.
    pub decal_meshes: Option<decal_meshes::DecalMeshPass>,
    /// This frame's plan (`FrameEffect::plan`).
    frame: Option<VtFrame>,
}

fn buffer(
    ctx: &Context,
    name: &str,
    size: u64,
    usage: vk::BufferUsageFlags,
    location: MemoryLocation,
) -> Result<Buffer> {
    Buffer::new(ctx, &BufferDesc { name, size, usage, location })
}

impl VirtualTexture {
    /// `decals`: effect `decals` (the page renderer's DECALS variant).
    pub fn new(
        ctx: &Context,
        extent_m: [f64; 2],
        params: VtParams,
        frames_in_flight: usize,
        decals: Option<&DecalSet>,
    ) -> Result<Self> {
        let decals = match decals {
            Some(set) => Some(Decals { set: set.clone(), gpu: DecalResources::new(ctx, set)?, dirty: true }),
            None => None,
        };
        let layout = VtLayout::new(extent_m, params.region_m, params.indirection, params.cache_mb, params.window_m);
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        let words = layout.state_words();
        let image = |name| {
            Image::new(
                ctx,
                &ImageDesc {
                    name,
                    format: vk::Format::R8G8B8A8_UNORM,
                    extent: layout.cache_texels(),
                    mip_levels: 1,
                    array_layers: 1,
                    usage: vk::ImageUsageFlags::STORAGE
                        | vk::ImageUsageFlags::SAMPLED
                        | vk::ImageUsageFlags::TRANSFER_SRC,
                },
            )
        };
        let mut ring = Vec::new();
        for i in 0..frames_in_flight.max(1) + 1 {
            let name = format!("vt_requests_readback[{i}]");
            let buffer =
                buffer(ctx, &name, REQUEST_BYTES, vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuToCpu)?;
            ring.push(Slot { buffer, frame: 0, ctx_frame: 0, pending: false, whole: false });
        }
        Ok(VirtualTexture {
            feedback: VtFeedback::new(ctx)?,
            update: VtUpdate::new(ctx)?,
            pages: VtPages::new(ctx, params.position_coded(), decals.is_some())?,
            state_buffer: buffer(
                ctx,
                "vt_state",
                words * 4,
                storage | vk::BufferUsageFlags::TRANSFER_SRC,
                MemoryLocation::GpuOnly,
            )?,
            status: buffer(ctx, "vt_page_status", layout.indirection_texels() * 4, storage, MemoryLocation::GpuOnly)?,
            requests: buffer(
                ctx,
                "vt_requests",
                REQUEST_BYTES,
                storage | vk::BufferUsageFlags::TRANSFER_SRC,
                MemoryLocation::GpuOnly,
            )?,
            writes_staging: buffer(ctx, "vt_writes", u64::from(VT_MAX_WRITES) * 16, storage, MemoryLocation::GpuOnly)?,
            jobs_staging: buffer(ctx, "vt_jobs", u64::from(VT_MAX_JOBS) * 16, storage, MemoryLocation::GpuOnly)?,
            cache_albedo: image("vt_cache_albedo")?,
            cache_detail: image("vt_cache_detail")?,
            ring,
            next: 0,
            state: VtState::new(layout, params.pages_per_frame.min(VT_MAX_JOBS)),
            writes: Vec::new(),
            last_push: None,
            catch_up: false,
            initialized: false,
            decals,
            decal_meshes: None,
            frame: None,
        })
    }

    /// Tests only (feature `test-hooks`): the indirection and sub-texture
    /// state the shaders read.
    #[cfg(feature = "test-hooks")]
    pub fn state_buffer(&self) -> &Buffer {
        &self.state_buffer
    }

    /// Tests only (feature `test-hooks`): this frame's page requests.
    #[cfg(feature = "test-hooks")]
    pub fn requests(&self) -> &Buffer {
        &self.requests
    }

    /// Tests only (feature `test-hooks`): the physical cache's albedo and
    /// detail images.
    #[cfg(feature = "test-hooks")]
    pub fn cache_images(&self) -> [&Image; 2] {
        [&self.cache_albedo, &self.cache_detail]
    }

    /// Tests only (feature `test-hooks`): the newest frame's feedback push.
    #[cfg(feature = "test-hooks")]
    pub fn last_push(&self) -> Option<VtFeedbackPush> {
        self.last_push
    }

    /// While on, the feedback samples every pixel (64 times the jitter's
    /// samples: about 35 ms a frame at 960 x 540 on lavapipe), so one clean
    /// frame after the last change settles it, where the jitter cycle
    /// takes VT_FEEDBACK_STRIDE^2 frames: for a render that waits to settle.
    pub fn set_catch_up(&mut self, on: bool) {
        self.catch_up = on;
    }

    pub fn layout(&self) -> &VtLayout {
        &self.state.layout
    }

    pub fn counters(&self) -> VtCounters {
        self.state.counters
    }

    pub fn pipeline_labels(&self) -> [&str; 3] {
        [self.update.pipeline_label(), self.pages.pipeline_label(), self.feedback.pipeline_label()]
    }

    /// (name, bytes) of every GPU object but the decals'.
    pub fn memory(&self) -> Vec<(String, u64)> {
        let mut v: Vec<(String, u64)> =
            [&self.state_buffer, &self.status, &self.requests, &self.writes_staging, &self.jobs_staging]
                .iter()
                .map(|b| (b.name.clone(), b.memory_bytes()))
                .collect();
        v.extend([&self.cache_albedo, &self.cache_detail].iter().map(|i| (i.name.clone(), i.memory_bytes())));
        v.push(("vt_requests_readback".into(), self.ring.iter().map(|s| s.buffer.memory_bytes()).sum()));
        v
    }

    /// (name, bytes) of the decals' GPU objects (effect `decals`).
    pub fn decal_memory(&self) -> Vec<(String, u64)> {
        self.decals.iter().flat_map(|d| d.gpu.memory()).collect()
    }

    /// Effect `decals`: the decals whose lists an earlier frame uploaded
    /// (what other passes may read this frame; None while an edit waits).
    pub fn uploaded_decals(&self) -> Option<&[Decal]> {
        self.decals.as_ref().filter(|d| !d.dirty).map(|d| &d.set.decals[..])
    }

    /// Effect `decals`: the textures (fixed at creation; empty when off).
    pub fn decal_textures(&self) -> &[decals::DecalTexture] {
        self.decals.as_ref().map_or(&[], |d| &d.set.textures[..])
    }

    /// Effect `decals`: their GPU objects.
    pub fn decal_resources(&self) -> Option<&DecalResources> {
        self.decals.as_ref().map(|d| &d.gpu)
    }

    /// Effect `decals`: the decals drawn into the pages (empty when off).
    pub fn decals(&self) -> &[Decal] {
        self.decals.as_ref().map_or(&[], |d| &d.set.decals)
    }

    /// Effect `decals`: replaces the decal list (same textures); the
    /// resident pages that an added, removed or changed decal touches,
    /// before or after, are dropped and rendered again from frame `frame`
    /// on. Returns how many were dropped.
    pub fn set_decals(&mut self, decals: Vec<Decal>, frame: u64) -> Result<u32> {
        let Some(d) = &mut self.decals else {
            return Err(crate::error::Error::BadInput("effect decals is off in this renderer".into()));
        };
        let next = DecalSet { textures: d.set.textures.clone(), decals };
        next.check()?;
        let old = &d.set.decals;
        let n = old.len().max(next.decals.len());
        let changed: Vec<&Decal> = (0..n)
            .filter(|&i| old.get(i) != next.decals.get(i))
            .flat_map(|i| old.get(i).into_iter().chain(next.decals.get(i)))
            .collect();
        let layout = self.state.layout;
        let dropped = self.state.invalidate_pages(frame, |key| {
            let rect = layout.padded_rect(key);
            changed.iter().any(|c| c.touches(rect, layout.texel_m(key.level)))
        });
        self.state.counters.decal_pages_invalidated += u64::from(dropped);
        d.set = next;
        d.dirty = true;
        Ok(dropped)
    }

    /// Each job's decals (those touching its padded tile, grown by a texel
    /// for the blended edge), in order, at most DECAL_MAX_PER_PAGE.
    fn assign_decals(&mut self, jobs: &mut [PageJob]) -> Vec<u32> {
        let mut list = Vec::new();
        let (mut blends, mut over) = (0, 0);
        if let Some(d) = &self.decals {
            let layout = self.state.layout;
            for job in jobs {
                let key = state::unpack_request([job.region, job.page]);
                let first = list.len() as u32;
                let mine: Vec<u32> = d.set.touching(layout.padded_rect(key), layout.texel_m(key.level)).collect();
                let kept = mine.len().min(DECAL_MAX_PER_PAGE as usize);
                over += mine.len() - kept;
                list.extend(&mine[..kept]);
                job.decals = first | (kept as u32) << DECAL_COUNT_SHIFT;
                blends += kept as u32;
            }
        }
        if over > 0 {
            log::warn!("{over} decal(s) left out of pages touched by more than {DECAL_MAX_PER_PAGE}");
        }
        self.state.counters.decal_blends = blends;
        self.state.counters.decals_left_out += over as u64;
        list
    }

    /// See [`VtState::settled`]; and no state write waits for a later frame.
    pub fn settled(&self) -> bool {
        self.state.settled() && self.writes.is_empty()
    }

    /// What `gbuffer_tiles`' virtual-texture flavour samples.
    pub fn bindings(&self) -> VtBindings<'_> {
        VtBindings { state: &self.state_buffer, albedo: &self.cache_albedo, detail: &self.cache_detail }
    }

    /// Before recording frame `frame` (`ctx_frame`: the context's number of
    /// it): takes the requests of every finished frame, places the
    /// sub-textures for a camera at `camera_xy` whose pixels span
    /// `pixel_rad`, out to `range_m`, plans the frame's pages and writes
    /// (at most VT_MAX_WRITES; the rest wait, in order) and claims the
    /// ring slot its requests go to.
    /// `terrain`: the streamed nodes (arrivals make pages rendered from
    /// coarser data again; pages are rendered from the finest resident).
    pub fn begin_frame(
        &mut self,
        ctx: &Context,
        frame: u64,
        ctx_frame: u64,
        camera: VtCamera,
        terrain: &crate::terrain::Terrain,
    ) -> VtFrame {
        let push = match self.catch_up {
            true => VtFeedbackPush::whole(frame, camera.size),
            false => VtFeedbackPush::for_frame(frame, camera.size),
        };
        self.last_push = Some(push);
        let (layout, at_rest) = (self.state.layout, terrain.settled());
        let done = ctx.frames_completed();
        let mut slots: Vec<&mut Slot> = self.ring.iter_mut().filter(|s| s.pending && s.ctx_frame <= done).collect();
        slots.sort_by_key(|s| s.frame);
        for slot in slots {
            slot.pending = false;
            let bytes = slot.buffer.mapped().expect("GpuToCpu buffers are mapped");
            let words: &[u32] = bytemuck::cast_slice(bytes);
            let n = words[0].min(VT_REQUEST_CAPACITY) as usize;
            let entries: Vec<[u32; 2]> = words[4..4 + 2 * n].chunks_exact(2).map(|c| [c[0], c[1]]).collect();
            let source = |page| at_rest.then(|| page_source(terrain, layout.padded_rect(page)));
            self.state.harvest(slot.frame, &entries, slot.whole, source);
        }
        let world = terrain.world;
        // Pages are rendered from the finest resident nodes: one that
        // arrives finer than a page's source, or is reloaded with new data,
        // makes it stale (one leaving
        // from under a page is caught once streaming rests, when the page
        // is asked for again: its source differs, `harvest`).
        let reloaded = terrain.tree.reloaded();
        for &(node, _) in terrain.tree.arrived() {
            self.state.invalidate(node.bounds_m(&world), node.lod, reloaded.contains(&node), frame);
        }
        self.state.place_sub_textures(frame, camera.xy, camera.pixel_rad, camera.range_m);
        let (mut jobs, writes) = self.state.plan(frame, |page| page_source(terrain, layout.padded_rect(page)));
        let job_decals = self.assign_decals(&mut jobs);
        let decal_lists = match &mut self.decals {
            Some(d) if !jobs.is_empty() && d.dirty => {
                d.dirty = false;
                Some(d.set.gpu_words())
            }
            _ => None,
        };
        self.writes.extend(writes);
        let n = self.writes.len().min(VT_MAX_WRITES as usize);
        let slot = self.next;
        self.next = (self.next + 1) % self.ring.len();
        let s = &mut self.ring[slot];
        if s.pending {
            log::debug!("page requests of frame {} were not back in time and are dropped", s.frame);
        }
        (s.frame, s.ctx_frame, s.pending, s.whole) = (frame, ctx_frame, true, push.is_whole());
        VtFrame {
            frame,
            writes: self.writes.drain(..n).collect(),
            jobs,
            slot,
            init: !std::mem::replace(&mut self.initialized, true),
            job_decals,
            decal_lists,
        }
    }

    /// First frame only: no sub-texture, no status, the header.
    pub fn record_init(&self, rec: &mut Recorder) {
        let l = self.state.layout;
        let texels = l.cache_texels();
        let header: [u32; VT_STATE_HEADER as usize] = [
            l.regions[0],
            l.regions[1],
            l.indirection_side,
            l.cache_tiles[0],
            (l.region_m as f32).to_bits(),
            (texels[0] as f32).to_bits(),
            (texels[1] as f32).to_bits(),
            l.window,
        ];
        rec.fill_buffer(&self.state_buffer, VT_NONE);
        rec.fill_buffer(&self.status, 0);
        rec.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::ALL_TRANSFER);
        rec.update_buffer(&self.state_buffer, 0, bytemuck::cast_slice(&header));
        rec.discard_to(&self.cache_albedo, vk::ImageLayout::GENERAL);
        rec.discard_to(&self.cache_detail, vk::ImageLayout::GENERAL);
        rec.barrier(vk::PipelineStageFlags2::ALL_COMMANDS, vk::PipelineStageFlags2::ALL_COMMANDS);
    }

    pub fn record_update(&self, rec: &mut Recorder, writes: &[StateWrite]) {
        self.update.record(rec, &self.state_buffer, &self.writes_staging, writes);
    }

    #[allow(clippy::too_many_arguments)]
    pub fn record_pages(
        &self,
        rec: &mut Recorder,
        f: &VtFrame,
        terrain: crate::passes::terrain_query::VistaTerrain,
        sector_data: &Buffer,
        tree: &crate::terrain::gpu_quadtree::GpuQuadtree,
        m: &crate::passes::gbuffer_tiles::MaterialBindings,
    ) {
        let out = PageTargets {
            state: &self.state_buffer,
            jobs: &self.jobs_staging,
            albedo: &self.cache_albedo,
            detail: &self.cache_detail,
        };
        if let Some(d) = &self.decals {
            d.gpu.record_upload(rec, f.decal_lists.as_ref(), &f.job_decals);
        }
        let decals = self.decals.as_ref().map(|d| &d.gpu);
        self.pages.record(rec, &f.jobs, &out, terrain, sector_data, tree, m, decals);
    }

    /// The feedback of `f`'s frame, and its copy into the slot it claimed.
    pub fn record_feedback(
        &self,
        rec: &mut Recorder,
        f: &VtFrame,
        view: &Buffer,
        targets: &crate::passes::terrain_geometry::RenderTargets,
        gbuffer: &crate::targets::gbuffer::GBuffer,
    ) {
        let out = FeedbackTargets { state: &self.state_buffer, status: &self.status, requests: &self.requests };
        let push = self.last_push.expect("begin_frame came first");
        assert_eq!(push.size, gbuffer.size(), "the frame's size");
        self.feedback.record(rec, view, targets, gbuffer, &out, push);
        rec.copy_buffer_region(&self.requests, 0, &self.ring[f.slot].buffer, 0, REQUEST_BYTES);
        // The host reads the slot frames later: its own barrier to the host
        // stage (ALL_COMMANDS does not include the host), so the readback
        // holds whatever the frame records after it. The second one orders
        // the next frame's writes of `requests` after the copy's read.
        rec.transfer_to_host_barrier();
        rec.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::ALL_COMMANDS);
    }
}
