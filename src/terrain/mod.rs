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

mod atlases;
mod budget;
pub mod gpu_quadtree;
pub mod patch_grid;
pub mod quadtree;
pub mod selection;
mod upload_queue;

pub use budget::{default_gpu_budget, max_slots, slots_for_budget};

use crate::error::Result;
use crate::gpu::Context;
use crate::terrain::gpu_quadtree::{AtlasSet, GpuQuadtree, ATLAS_COUNT};
use crate::terrain::selection::TraverseParams;
use crate::world::vertex_bounds_cache::{compute_cached, BoundsOrigin};
use crate::world::{
    bake_node_with, BakeSettings, BakedNode, ErrorTree, HeightSource, Hole, Limits, LoadFate, LoadFn, Loader,
    MemoryReport, NodeCache, NodeId, RefineWant, Residency, ResidencyConfig, Streamer, WorldDesc, WorldError,
    WorldPlan,
};
use serde::Serialize;
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

#[derive(Debug, Clone)]
pub struct TerrainOptions {
    /// Resident node slots (Far Cry 5: ~500); at most 2047.
    pub slots: u32,
    pub frames_in_flight: usize,
    /// Threads loading (baking) nodes; 0 loads each requested node at once
    /// on the thread that streams (slower frames, but the same resident set
    /// on every run, as golden images need).
    pub loader_threads: usize,
    /// Bake lazily into this cache directory (reused across runs); `None`
    /// bakes in memory only.
    pub cache_dir: Option<PathBuf>,
    /// Also keep the families right around the camera (for motion); off,
    /// only the LOD criterion decides what is resident (exact test sets).
    pub ring_prefetch: bool,
    /// Payload atlases kept on the GPU (the renderer: those its effects read).
    pub atlases: AtlasSet,
    /// What a world may cost ([`WorldPlan`]); the device's own limits are
    /// added from the context.
    pub limits: Limits,
    /// Texel formats and material rules of the bake.
    pub bake: BakeSettings,
    /// Produces the payloads instead of baking from the source (and the
    /// cache): an engine's own asset pipeline, or a test's failing loads.
    /// Its nodes must be baked with `bake`'s payload format.
    pub load: Option<CustomLoad>,
    /// Loads of a node before it is given up, and the retry backoff
    /// ([`ResidencyConfig`]).
    pub max_load_attempts: u32,
    pub retry_frames: u64,
    /// The world's error tree, shared with other renderers of the world and
    /// usually prepared beforehand ([`ErrorTree::prepare`]); `None` makes
    /// one (cached under `cache_dir`, else in memory) whose roots are
    /// computed as their first nodes load. Must be the tree of this world
    /// and source.
    pub errors: Option<Arc<ErrorTree>>,
    /// Draw with the per-triangle rule: the world's per-vertex bounds are
    /// computed whole when the loader is made
    /// ([`crate::world::vertex_bounds`]) and attached to every node.
    pub vertex_bounds: bool,
}

/// A caller's node loader (see [`TerrainOptions::load`]).
#[derive(Clone)]
pub struct CustomLoad(pub Arc<LoadFn>);

impl std::fmt::Debug for CustomLoad {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("CustomLoad(..)")
    }
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
            bake: BakeSettings::default(),
            load: None,
            max_load_attempts: ResidencyConfig::default().max_load_attempts,
            retry_frames: ResidencyConfig::default().retry_frames,
            limits: Limits::default(),
            errors: None,
            vertex_bounds: false,
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
        max_roots: Some(u64::from(options.slots / 4)),
        ..options.limits.clone()
    };
    let plan = WorldPlan::new(world, None).with_format(options.bake.format).with_slots(options.slots);
    plan.check(&limits).map_err(crate::world::WorldError::from)?;
    Ok(())
}

/// Streaming counters after the last frame.
#[derive(Debug, Clone, Default, Serialize)]
pub struct TerrainStats {
    pub resident: usize,
    pub loading: usize,
    pub waiting_upload: usize,
    /// Loads that failed (each attempt counts).
    pub failed: usize,
    /// Loads requested again after a failure.
    pub retried: usize,
    /// Nodes whose every attempt failed: their parents draw instead.
    pub gave_up: usize,
    /// Failed nodes waiting for their retry's backoff.
    pub retry_waiting: usize,
    pub arrived_total: usize,
}

pub struct Terrain {
    pub world: WorldDesc,
    streamer: Streamer,
    /// How payloads are made: what a new source needs for a new loader.
    recipe: LoaderRecipe,
    errors: Arc<ErrorTree>,
    pub tree: GpuQuadtree,
    stats: TerrainStats,
    ring_prefetch: bool,
    /// The residency budget (`TerrainOptions::slots`).
    slots: u32,
    paused: bool,
    /// Payloads came in the last stream: their error bounds have not been
    /// through a residency update yet, so the next one may want more.
    unweighed: bool,
    /// A root given up: every later frame reports it.
    root_failure: Option<(NodeId, u32, String)>,
    /// Resident roots loaded with pending errors (roots made on demand),
    /// kept to attach their numbers once a child's load has made the tile.
    pending_roots: HashMap<NodeId, BakedNode>,
    /// Where the per-triangle rule's bounds came from (none: not that rule).
    bounds_origin: Option<BoundsOrigin>,
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
        options.bake.materials.validate()?;
        let tree = GpuQuadtree::new(
            ctx,
            world,
            options.slots,
            options.frames_in_flight,
            options.atlases,
            options.bake.format,
        )?;
        let config = ResidencyConfig {
            budget: options.slots as usize,
            max_load_attempts: options.max_load_attempts,
            retry_frames: options.retry_frames,
            ..ResidencyConfig::default()
        };
        let residency = Residency::new(world, config)?;
        let errors = match &options.errors {
            Some(e) => {
                assert!(
                    e.is_for(world, source.as_ref()),
                    "TerrainOptions::errors: the tree of another world or source"
                );
                // The rule's bounds are made for the whole world at once,
                // and a pending root would be drawn without them.
                if options.vertex_bounds && e.roots_on_demand() {
                    return Err(crate::error::Error::BadInput(
                        "TerrainOptions: the per-triangle rule needs the whole error tree (not roots on demand)".into(),
                    ));
                }
                Arc::clone(e)
            }
            None => Arc::new(ErrorTree::new(world, Arc::clone(&source), options.cache_dir.as_deref())?),
        };
        let recipe = LoaderRecipe {
            world: *world,
            holes,
            bake: options.bake.clone(),
            cache_dir: options.cache_dir.clone(),
            threads: options.loader_threads,
            custom: options.load.clone(),
            vertex_bounds: options.vertex_bounds,
        };
        let (loader, bounds_origin) = recipe.loader(source, Arc::clone(&errors))?;
        Ok(Terrain {
            world: *world,
            bounds_origin,
            streamer: Streamer::new(residency, loader),
            recipe,
            errors,
            tree,
            stats: TerrainStats::default(),
            ring_prefetch: options.ring_prefetch,
            slots: options.slots,
            paused: false,
            unweighed: false,
            root_failure: None,
            pending_roots: HashMap::new(),
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
    /// Fails (this frame and every later one) once a root is given up.
    pub fn stream(&mut self, params: &TraverseParams) -> Result<(), WorldError> {
        if let Some((node, attempts, cause)) = &self.root_failure {
            return Err(WorldError::RootUnavailable { node: *node, attempts: *attempts, cause: cause.clone() });
        }
        if self.paused {
            return Ok(());
        }
        let cam = &params.cameras[0];
        // Load a family a little before the traversal would refine into it.
        let want = RefineWant {
            camera: *cam,
            target_error_px: f64::from(params.target_error_px),
            prefetch: 0.75,
            ring_factor: if self.ring_prefetch { 0.75 } else { 0.0 },
            infinite_known: self.bounds_origin.is_some(),
        };
        let s = self.streamer.frame(cam.position_m, Some(&want));
        for id in &s.removed {
            self.tree.remove(*id);
        }
        self.stats.arrived_total += s.arrived.len();
        self.unweighed = !s.arrived.is_empty() || !s.reloaded.is_empty();
        for node in s.arrived {
            self.note_pending(&node);
            self.tree.add(node, 0);
        }
        for node in s.reloaded {
            self.note_pending(&node);
            self.tree.reload(node, 0);
        }
        self.attach_made_roots()?;
        let root_lod = self.world.root_lod();
        for ((id, e), fate) in s.failed.iter().zip(&s.fates) {
            log::error!("node {id} failed to load ({fate:?}): {e}");
            if let LoadFate::GaveUp { attempts } = *fate {
                if id.lod == root_lod && self.root_failure.is_none() {
                    self.root_failure = Some((*id, attempts, e.to_string()));
                }
            }
        }
        let r = self.streamer.residency();
        let counts = r.failure_counts();
        self.stats.failed = counts.failures;
        self.stats.retried = counts.retries;
        self.stats.gave_up = counts.gave_up;
        self.stats.retry_waiting = r.retry_waiting();
        self.stats.loading = r.pending_count();
        self.stats.resident = r.slots_used() - self.stats.loading;
        match &self.root_failure {
            Some((node, attempts, cause)) => {
                Err(WorldError::RootUnavailable { node: *node, attempts: *attempts, cause: cause.clone() })
            }
            None => Ok(()),
        }
    }

    /// Keeps a root that came with pending errors until its tile is made.
    fn note_pending(&mut self, node: &BakedNode) {
        if node.id.lod == self.world.root_lod() && node.errors_pending() {
            self.pending_roots.insert(node.id, node.clone());
        } else {
            self.pending_roots.remove(&node.id);
        }
    }

    /// Pending roots whose tile a child's load has made get their numbers
    /// (read from the tile, no load) and replace their resident payload.
    fn attach_made_roots(&mut self) -> Result<(), WorldError> {
        let made: Vec<NodeId> = self.pending_roots.keys().copied().filter(|r| self.errors.root_at_hand(*r)).collect();
        for id in made {
            let mut node = self.pending_roots.remove(&id).expect("listed");
            self.errors.attach(&mut node)?;
            self.streamer.renew_bounds(&node);
            self.tree.reload(node, 0);
            self.unweighed = true;
        }
        Ok(())
    }

    /// Roots resident with pending errors ([`ErrorTree::with_roots_on_demand`]):
    /// the ones no view has refined into yet.
    pub fn pending_roots(&self) -> usize {
        self.pending_roots.len()
    }

    /// The world's error tree (shared with [`TerrainOptions::errors`]).
    pub fn errors(&self) -> &ErrorTree {
        &self.errors
    }

    /// Loads every resident node whose bake reads `region` ([min x, min
    /// y, max x, max y] metres: [`crate::world::bake_region`]) again: each
    /// is drawn from its old payload until the new one is uploaded, then
    /// swapped in one update (no gap). For a caller's loader whose data
    /// changed there; an edited height source goes through
    /// [`Self::replace_source`]. Returns how many nodes reload.
    pub fn invalidate(&mut self, region: [f64; 4]) -> usize {
        let touched = touches(self.world, region);
        let ids: Vec<NodeId> = self.streamer.residency().resident().filter(|id| touched(*id)).collect();
        ids.iter().filter(|id| self.streamer.reload(**id)).count()
    }

    /// The world's height source was edited (a stamp added, moved or
    /// removed) over `region`: payloads are made from `source` from now on
    /// (the error tree keeps the roots the edit leaves alone), loads under
    /// way are made again from it, and the resident nodes the edit touches
    /// reload ([`Self::invalidate`]). Refused for a caller's loader
    /// ([`TerrainOptions::load`]), which does not read the source.
    /// `bake`: new bake settings too (a stamp's control map edited), of
    /// the same payload format and materials mode; `None` keeps them.
    pub fn replace_source(
        &mut self,
        source: Arc<dyn HeightSource>,
        bake: Option<BakeSettings>,
        region: [f64; 4],
    ) -> Result<usize> {
        let bad = |m: &str| Err(crate::error::Error::BadInput(format!("replace_source: {m}")));
        if self.recipe.custom.is_some() {
            return bad("this terrain's payloads come from the caller's loader, not a height source");
        }
        if let Some(bake) = bake {
            let old = &self.recipe.bake;
            if bake.format != old.format || bake.control.is_some() != old.control.is_some() {
                return bad("the payload format and the materials mode stay what the renderer was built with");
            }
            self.recipe.bake = bake;
        }
        let errors = Arc::new(self.errors.edited(Arc::clone(&source), self.recipe.cache_dir.as_deref())?);
        let (loader, bounds_origin) = self.recipe.loader(source, Arc::clone(&errors))?;
        self.bounds_origin = bounds_origin;
        self.streamer.replace_loader(loader, touches(self.world, region));
        self.errors = errors;
        Ok(self.invalidate(region))
    }

    /// Streaming counters; `waiting_upload` is what `quadtree_update` has
    /// not uploaded yet.
    /// Where the per-triangle rule's bounds came from (none: per patch).
    pub fn bounds_origin(&self) -> Option<&BoundsOrigin> {
        self.bounds_origin.as_ref()
    }

    /// The residency budget: nodes that may be resident at once.
    pub fn slots(&self) -> u32 {
        self.slots
    }

    pub fn stats(&self) -> TerrainStats {
        TerrainStats { waiting_upload: self.tree.waiting(), ..self.stats.clone() }
    }

    /// True once nothing is loading, waiting for a retry or for upload,
    /// and the last stream weighed every payload's bounds (one that came
    /// in that stream, a reload's taller mountain say, may want children
    /// in the next). Nodes given up do not hold it back; a root given up
    /// is an error from [`Terrain::stream`], and never settles.
    pub fn settled(&self) -> bool {
        self.stats.loading == 0 && self.idle_but_loads()
    }

    /// Nothing but loads may be under way: no reload, retry or upload
    /// waits, and the last stream's payloads are weighed.
    fn idle_but_loads(&self) -> bool {
        !self.unweighed
            && self.streamer.reloading() == 0
            && self.stats.retry_waiting == 0
            && self.tree.waiting() == 0
            && self.root_failure.is_none()
    }

    /// Only loads are under way: nothing waits for upload, a reload, a
    /// retry or a residency update. A frame drawn now draws the last one
    /// again, so an offline render may [`Self::wait_for_load`] instead.
    pub fn only_loading(&self) -> bool {
        self.stats.loading > 0 && self.idle_but_loads()
    }

    /// Blocks until a load finishes or `timeout` passes: the cores go to
    /// the loader threads (a payload's bake, a root's error tile).
    pub fn wait_for_load(&self, timeout: std::time::Duration) -> bool {
        self.streamer.wait_for_load(timeout)
    }

    /// Memory of the resident payloads, CPU and GPU side; payload kinds no
    /// effect reads are baked (CPU) but not kept on the GPU.
    pub fn memory_report(&self) -> MemoryReport {
        let mut report = MemoryReport::for_format(self.stats.resident, self.tree.payload_format());
        if self.tree.atlas_set().contains(crate::terrain::gpu_quadtree::ATLAS_CONTROL) {
            report = report.with_control();
        }
        if self.tree.atlas_set().contains(crate::terrain::gpu_quadtree::ATLAS_VERTEX_BOUNDS) {
            report = report.with_vertex_bounds();
        }
        mask_memory(report, self.tree.atlas_set())
    }
}

/// Whether node `id`'s bake reads anything in `region`.
fn touches(world: WorldDesc, region: [f64; 4]) -> impl Fn(NodeId) -> bool {
    move |id| {
        let r = crate::world::bake_region(&world, id);
        r[0] <= region[2] && r[2] >= region[0] && r[1] <= region[3] && r[3] >= region[1]
    }
}

/// What a terrain's loader is made from (again, when its source changes).
struct LoaderRecipe {
    world: WorldDesc,
    holes: Vec<Hole>,
    bake: BakeSettings,
    cache_dir: Option<PathBuf>,
    threads: usize,
    custom: Option<CustomLoad>,
    vertex_bounds: bool,
}

impl LoaderRecipe {
    /// Payloads from the caller's loader, the cache folder or a bake in
    /// memory, each with the world's errors (and with the per-triangle
    /// rule, its vertices' bounds, computed here for the whole world).
    /// The bounds are cached beside the error tree's tiles (the world's
    /// other whole-world numbers); the origin says whether they were read.
    fn loader(&self, source: Arc<dyn HeightSource>, errors: Arc<ErrorTree>) -> Result<(Loader, Option<BoundsOrigin>)> {
        let (bounds, origin) = match self.vertex_bounds {
            true => {
                let dir = errors.dir().map(|d| d.join("vertex-bounds"));
                let (tree, origin) = compute_cached(&self.world, source.as_ref(), &self.holes, dir.as_deref())?;
                log::info!("per-vertex bounds {origin}");
                (Some(Arc::new(tree)), Some(origin))
            }
            false => (None, None),
        };
        let load = self.load_fn(source, errors)?;
        let load: Arc<LoadFn> = match bounds {
            Some(b) => Arc::new(move |id| {
                let mut node = load(id)?;
                b.attach(&mut node);
                Ok(node)
            }),
            None => load,
        };
        Ok((Loader::new(self.threads, load)?, origin))
    }

    fn load_fn(&self, source: Arc<dyn HeightSource>, errors: Arc<ErrorTree>) -> Result<Arc<LoadFn>> {
        Ok(match (&self.custom, &self.cache_dir) {
            (Some(load), _) => {
                // A caller's payloads without errors get the world's.
                let load = Arc::clone(&load.0);
                Arc::new(move |id| {
                    let mut node = load(id)?;
                    if node.max_error_m.is_infinite() {
                        errors.attach(&mut node)?;
                    }
                    Ok(node)
                })
            }
            (None, Some(dir)) => {
                let (w, holes, bake) = (self.world, self.holes.clone(), self.bake.clone());
                let cache = NodeCache::with_settings(dir, w, source, holes, bake)?.with_errors(errors);
                Arc::new(move |id| cache.get_or_bake_for_render(id).map(|(node, _)| node))
            }
            (None, None) => {
                let (w, holes, settings) = (self.world, self.holes.clone(), self.bake.clone());
                Arc::new(move |id| {
                    let mut node = bake_node_with(&*source, &w, &holes, &settings, id);
                    errors.attach(&mut node)?;
                    Ok(node)
                })
            }
        })
    }
}

/// `report` with the GPU bytes of the atlases not in `set` taken out.
pub fn mask_memory(mut report: MemoryReport, set: AtlasSet) -> MemoryReport {
    // The report lists the atlas kinds first, in `ATLAS_*` order.
    for (i, k) in report.kinds.iter_mut().enumerate().take(ATLAS_COUNT) {
        if !set.contains(i) {
            k.gpu_bytes = 0;
            k.gpu_format = "not kept (effect off)";
        }
    }
    report
}
