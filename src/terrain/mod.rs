//! The terrain's data on both sides of the bus: streaming residency on the
//! CPU (lazy baking on loader threads, optional disk cache) feeding the GPU
//! quadtree (node texture, descriptions, payload atlases) through queued
//! uploads. [`Terrain`] is the facade; the passes that read it are recorded
//! by `render::TerrainRenderer`. Nothing here waits for the GPU.
//!
//! - [`quadtree`]: the CPU shadow of the node texture and descriptions;
//! - [`gpu_quadtree`]: the GPU resources and their upload queue;
//! - [`selection`]: what LOD selection is asked for and returns;
//! - [`patch_grid`]: the index pattern of one patch.

pub mod gpu_quadtree;
pub mod patch_grid;
pub mod quadtree;
pub mod selection;

use crate::error::Result;
use crate::gpu::Context;
use crate::terrain::gpu_quadtree::{AtlasSet, GpuQuadtree, ATLAS_COUNT};
use crate::terrain::selection::TraverseParams;
use crate::world::{
    bake_node, HeightSource, Hole, Limits, LoadFn, Loader, MemoryReport, NodeCache, RefineWant, Residency,
    ResidencyConfig, Streamer, WorldDesc, WorldPlan,
};
use serde::Serialize;
use std::path::PathBuf;
use std::sync::Arc;

#[derive(Debug, Clone)]
pub struct TerrainOptions {
    /// Resident node slots (Far Cry 5: ~500); at most 1023.
    pub slots: u32,
    pub frames_in_flight: usize,
    pub loader_threads: usize,
    /// Bake lazily into this cache directory (reused across runs); `None`
    /// bakes in memory only.
    pub cache_dir: Option<PathBuf>,
    /// Also keep the families right around the camera (for motion); off,
    /// only the LOD criterion decides what is resident (exact test sets).
    pub ring_prefetch: bool,
    /// Payload atlases kept on the GPU (the renderer keeps only those its
    /// effects read).
    pub atlases: AtlasSet,
    /// What a world may cost ([`WorldPlan`]); the device's own limits are
    /// added from the context.
    pub limits: Limits,
}

impl Default for TerrainOptions {
    fn default() -> Self {
        let threads = std::thread::available_parallelism().map_or(2, |n| n.get()).max(1);
        TerrainOptions {
            slots: 512,
            frames_in_flight: 2,
            loader_threads: threads,
            cache_dir: None,
            ring_prefetch: true,
            atlases: AtlasSet::ALL,
            limits: Limits::default(),
        }
    }
}

/// Refuses a world over `options.limits` or the device's limits, before
/// the quadtree's shadow and texture (sized by the world) are allocated.
pub fn check_plan(ctx: &Context, world: &WorldDesc, options: &TerrainOptions) -> Result<()> {
    world.validate()?;
    let device = &ctx.info().limits;
    let limits = Limits {
        max_image_dimension_2d: Some(device.max_image_dimension_2d),
        max_image_array_layers: Some(device.max_image_array_layers),
        ..options.limits.clone()
    };
    let plan = WorldPlan::new(world, None).with_slots(options.slots);
    plan.check(&limits).map_err(crate::world::WorldError::from)?;
    Ok(())
}

/// Streaming counters after the last frame.
#[derive(Debug, Clone, Default, Serialize)]
pub struct TerrainStats {
    pub resident: usize,
    pub loading: usize,
    pub waiting_upload: usize,
    pub failed: usize,
    pub arrived_total: usize,
}

pub struct Terrain {
    pub world: WorldDesc,
    streamer: Streamer,
    pub tree: GpuQuadtree,
    stats: TerrainStats,
    ring_prefetch: bool,
    paused: bool,
}

impl Terrain {
    pub fn new(
        ctx: &Context,
        world: &WorldDesc,
        source: Arc<dyn HeightSource>,
        holes: Vec<Hole>,
        options: &TerrainOptions,
    ) -> Result<Self> {
        check_plan(ctx, world, options)?;
        let tree = GpuQuadtree::new(ctx, world, options.slots, options.frames_in_flight, options.atlases)?;
        let config = ResidencyConfig { budget: options.slots as usize, ..ResidencyConfig::default() };
        let residency = Residency::new(world, config)?;
        let threads = options.loader_threads.max(1);
        let loader = match &options.cache_dir {
            Some(dir) => Loader::with_cache(threads, Arc::new(NodeCache::new(dir, *world, source, holes)?))?,
            None => {
                let w = *world;
                let load: Arc<LoadFn> = Arc::new(move |id| Ok(bake_node(&*source, &w, &holes, id)));
                Loader::new(threads, load)?
            }
        };
        Ok(Terrain {
            world: *world,
            streamer: Streamer::new(residency, loader),
            tree,
            stats: TerrainStats::default(),
            ring_prefetch: options.ring_prefetch,
            paused: false,
        })
    }

    /// The resident nodes (loaded, possibly still waiting for upload), sorted.
    pub fn resident_nodes(&self) -> Vec<crate::world::NodeId> {
        let r = self.streamer.residency();
        let mut v: Vec<_> = r.resident().filter(|id| !r.is_pending(*id)).collect();
        v.sort();
        v
    }

    /// Stops (or resumes) streaming: the resident set stays as it is while
    /// the camera moves. Tests use it to compare renderers over one set.
    pub fn pause_streaming(&mut self, paused: bool) {
        self.paused = paused;
    }

    /// Streams around the first camera: evicted nodes leave the GPU
    /// quadtree, arrived ones are queued for upload by `quadtree_update`.
    pub fn stream(&mut self, params: &TraverseParams) {
        if self.paused {
            return;
        }
        let cam = &params.cameras[0];
        // Load a family a little before the traversal would refine into it.
        let want = RefineWant {
            pixels_per_tan: cam.pixels_per_tan,
            target_error_px: f64::from(params.target_error_px),
            prefetch: 0.75,
            ring_factor: if self.ring_prefetch { 0.75 } else { 0.0 },
        };
        let s = self.streamer.frame(cam.position_m, Some(&want));
        for id in &s.removed {
            self.tree.remove(*id);
        }
        self.stats.arrived_total += s.arrived.len();
        for node in s.arrived {
            self.tree.add(node, 0);
        }
        for (id, e) in &s.failed {
            log::error!("node {id} failed to load: {e}");
        }
        self.stats.failed += s.failed.len();
        let r = self.streamer.residency();
        self.stats.loading = r.pending_count();
        self.stats.resident = r.slots_used() - self.stats.loading;
    }

    /// Streaming counters; `waiting_upload` is what `quadtree_update` has
    /// not uploaded yet.
    pub fn stats(&self) -> TerrainStats {
        TerrainStats { waiting_upload: self.tree.waiting(), ..self.stats.clone() }
    }

    /// True once nothing is loading or waiting for upload.
    pub fn settled(&self) -> bool {
        self.stats.loading == 0 && self.tree.waiting() == 0
    }

    /// Memory of the resident payloads, CPU and GPU side; payload kinds no
    /// effect reads are baked (CPU) but not kept on the GPU.
    pub fn memory_report(&self) -> MemoryReport {
        let mut r = MemoryReport::new(self.stats.resident);
        let set = self.tree.atlas_set();
        // The report lists the atlas kinds first, in `ATLAS_*` order.
        for (i, k) in r.kinds.iter_mut().enumerate().take(ATLAS_COUNT) {
            if !set.contains(i) {
                k.gpu_bytes = 0;
                k.gpu_format = "not kept (effect off)";
            }
        }
        r
    }
}
