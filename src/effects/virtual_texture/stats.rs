//! The virtual texture's numbers after a frame (`stats.json`'s
//! `virtual_texture`, `vista render`'s lines).

use super::state::VtCounters;
use super::VirtualTexture;
use serde::Serialize;

/// The virtual texture after the last recorded frame.
#[derive(Debug, Clone, Serialize)]
pub struct VtStats {
    #[serde(flatten)]
    pub counters: VtCounters,
    /// Share of the requested pages that were resident.
    pub hit_rate: f64,
    pub cache_tiles: u32,
    /// Bytes of the state buffer (sub-textures and indirection), the page
    /// statuses and the cache images.
    pub indirection_bytes: u64,
    pub status_bytes: u64,
    pub cache_bytes: u64,
    /// Effect `decals`: decals drawn into the pages (0: off).
    pub decals: u32,
}

impl VtStats {
    pub fn of(vt: &VirtualTexture) -> VtStats {
        let [indirection_bytes, status_bytes, cache_bytes] = vt.layout().memory_bytes();
        let counters = vt.counters();
        VtStats {
            counters,
            hit_rate: counters.hit_rate(),
            cache_tiles: vt.layout().tile_count(),
            indirection_bytes,
            status_bytes,
            cache_bytes,
            decals: vt.decals().len() as u32,
        }
    }
}

impl VtStats {
    /// What `vista render` prints of them.
    pub fn lines(&self) -> Vec<String> {
        let (c, mib) = (&self.counters, |b: u64| b as f64 / f64::from(1u32 << 20));
        let mut out = vec![format!(
            "virtual texture: {} sub-textures ({} squeezed by a full indirection); frame {} (read back) sampled {} \
             pages, {} resident (hit rate {:.1} %); this frame rendered {} and evicted {} ({} and {} in all), \
             {} of {} tiles resident, {} pages waiting; indirection {:.1} MiB, page status {:.1} MiB, cache {:.1} MiB",
            c.sub_textures,
            c.squeezed,
            c.harvested_frame,
            c.requested,
            c.hits,
            100.0 * self.hit_rate,
            c.rendered,
            c.evicted,
            c.rendered_total,
            c.evicted_total,
            c.resident,
            self.cache_tiles,
            c.waiting,
            mib(self.indirection_bytes),
            mib(self.status_bytes),
            mib(self.cache_bytes)
        )];
        if c.beyond_window > 0 {
            out.push(format!(
                "virtual texture: {} regions within the view's reach lie outside the sub-texture window and are shaded \
                 without pages (raise [effects.virtual_texture] window_m)",
                c.beyond_window
            ));
        }
        if self.decals > 0 {
            out.push(format!(
                "decals: {} drawn into the pages; this frame's pages blended {} (a page's decals each once); \
                 {} pages dropped by decal edits, {} decals left out of pages touched by too many",
                self.decals, c.decal_blends, c.decal_pages_invalidated, c.decals_left_out
            ));
        }
        out
    }
}
