//! A loaded world's error tree, as the commands make it: whole before
//! the first frame (benchmarks, goldens) or with its roots on demand
//! (`vista render`, `vista view`).

use std::path::Path;
use std::sync::Arc;

use anyhow::Result;
use vista::world::ErrorTree;

use crate::world_args::{plan_error_is_input, LoadedWorld};

impl LoadedWorld {
    /// The world's error tree (every node's error needs every LOD-0 sample
    /// under its root, so the whole tree is made before rendering), read
    /// from `cache/errors` (`--cache`, else [`vista::world::default_cache_dir`]) or
    /// computed there, with progress on stderr and one line saying which.
    /// The world is first checked against the device (as
    /// `TerrainRenderer::new` would), so a world no renderer can hold is
    /// refused before its tree is made.
    pub fn errors(&self, ctx: &vista::gpu::Context, cache: Option<&Path>) -> Result<Arc<ErrorTree>> {
        let tree = self.checked_tree(ctx, cache)?;
        crate::world_notes::note_error_tree_time(&self.desc, tree.uncached_roots());
        let p = tree.prepare(crate::progress::auto());
        let place = place(&tree);
        let mib = |b: u64| b as f64 / f64::from(1 << 20);
        eprintln!(
            "error tree: {} roots, {} read, {} computed in {:.1} s; {place}; {:.0} MiB in memory of {:.0} MiB for the whole tree{}",
            p.roots,
            p.read,
            p.roots - p.read,
            p.seconds,
            mib(tree.memory_bytes()),
            mib(ErrorTree::whole_bytes(&self.desc)),
            if tree.dir().is_some() { " (tiles past the budget are read again from the folder when a node asks)" } else { "" }
        );
        Ok(Arc::new(tree))
    }

    /// The world's error tree with roots made on demand
    /// ([`ErrorTree::with_roots_on_demand`]): no root's tile before the
    /// first frame; a root's tile is read from `cache/errors` or computed
    /// in the loader threads when a view first refines into that root, so
    /// ground no view reaches is never computed. For `vista render` and
    /// `vista view` (benchmarks and goldens prepare the whole tree, so
    /// their timings hold none of it). The world is checked against the
    /// device first, as for [`Self::errors`].
    pub fn errors_on_demand(&self, ctx: &vista::gpu::Context, cache: Option<&Path>) -> Result<Arc<ErrorTree>> {
        let tree = self.checked_tree(ctx, cache)?.with_roots_on_demand();
        let roots = self.desc.roots().len();
        let cached = roots - tree.uncached_roots();
        let place = place(&tree);
        eprintln!(
            "error tree: {cached} of {roots} roots' tiles at hand; the others are made while streaming, when a view \
             first refines into their root ({place})"
        );
        Ok(Arc::new(tree))
    }

    /// Makes now, on every core, the tiles of the roots `view` sees (boxes
    /// over the world's whole height range: what streaming sees of a
    /// pending root). A render from one camera refines into each of them
    /// anyway; made before the first frame they do not take the cores from
    /// the frames that upload the nodes. The other roots stay on demand.
    pub fn prepare_roots_in_view(&self, tree: &ErrorTree, view: &vista::render::View) {
        let camera = view.relative_to(self.origin_m).traverse_camera();
        let [lo, hi] = self.desc.height_range_m.map(f64::from);
        let seen = |r: &vista::world::NodeId| {
            let b = self.desc.bounds_m(*r);
            camera.sees([b[0], b[1], lo], [b[2], b[3], hi])
        };
        let roots: Vec<_> = self.desc.roots().into_iter().filter(seen).collect();
        let p = tree.prepare_roots(roots, crate::progress::auto());
        eprintln!(
            "error tree: the {} roots the first view sees made before the first frame ({} read, {} computed in {:.1} s)",
            p.roots,
            p.read,
            p.roots - p.read,
            p.seconds
        );
    }

    /// An empty tree of this world, cached under `cache` (else the user's
    /// cache folder), once the world is checked against the device (as
    /// `TerrainRenderer::new` would): a world no renderer can hold is
    /// refused before any of its tree is made.
    fn checked_tree(&self, ctx: &vista::gpu::Context, cache: Option<&Path>) -> Result<ErrorTree> {
        let terrain = vista::terrain::TerrainOptions {
            bake: self.bake.clone(),
            limits: self.limits.clone(),
            ..vista::terrain::TerrainOptions::default()
        };
        vista::terrain::check_plan(ctx, &self.desc, &terrain).map_err(plan_error_is_input)?;
        let dir = cache.map(Path::to_path_buf).or_else(vista::world::default_cache_dir);
        Ok(ErrorTree::new(&self.desc, Arc::clone(&self.source), dir.as_deref())?)
    }
}

/// Where a tree's tiles go, in the `error tree:` lines' words.
fn place(tree: &ErrorTree) -> String {
    match tree.dir() {
        Some(d) => format!("cached in {}", d.display()),
        None => "in memory only ($VISTA_CACHE is empty)".to_string(),
    }
}
