//! The CPU half of the virtual texture: which sub-texture each region has
//! and where it sits in the indirection, which page each physical tile
//! holds, and the work of one frame (pages to render, indirection writes)
//! from the page requests the GPU listed frames ago. No Vulkan here.

use super::allocator::QuadtreeAllocator;
use super::cache::TileCache;
use super::layout::{pack_sub_texture, wanted_level, PageKey, VtLayout};
use crate::shaders::consts::{
    VT_NONE, VT_REQ_COORD_MASK, VT_REQ_LEVEL_MASK, VT_REQ_X_SHIFT, VT_REQ_Y_SHIFT, VT_STATE_HEADER,
};
use serde::Serialize;
use std::collections::BTreeSet;

/// One region's sub-texture: its finest level and its square in mip 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SubTexture {
    pub k: u32,
    pub offset: [u32; 2],
}

/// A write of the `vt_update` pass: `count` words from `start` of the
/// state buffer (header, sub-texture words, indirection) set to `value`.
/// Applied in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct StateWrite {
    pub start: u32,
    pub count: u32,
    pub value: u32,
    pub pad: u32,
}

/// A page for `vt_pages` to render into `tile`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct PageJob {
    pub tile: u32,
    pub region: u32,
    /// level | x << VT_REQ_X_SHIFT | y << VT_REQ_Y_SHIFT (a request's word).
    pub page: u32,
    /// Its decals: first index in the frame's job decal list | count <<
    /// DECAL_COUNT_SHIFT (0: none).
    pub decals: u32,
}

/// Unpacks a page request (`virtual_texture.glsl` `vt_request`).
pub fn unpack_request(entry: [u32; 2]) -> PageKey {
    PageKey {
        region: entry[0],
        level: entry[1] & VT_REQ_LEVEL_MASK,
        x: (entry[1] >> VT_REQ_X_SHIFT) & VT_REQ_COORD_MASK,
        y: (entry[1] >> VT_REQ_Y_SHIFT) & VT_REQ_COORD_MASK,
    }
}

pub fn pack_page(key: PageKey) -> u32 {
    key.level | key.x << VT_REQ_X_SHIFT | key.y << VT_REQ_Y_SHIFT
}

/// What one frame did, for the report.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct VtCounters {
    /// Distinct pages the newest harvested frame sampled.
    pub requested: u32,
    /// Of those, resident when harvested.
    pub hits: u32,
    pub rendered: u32,
    pub evicted: u32,
    pub resident: u32,
    /// Pages waiting for a tile (misses not rendered yet).
    pub waiting: u32,
    /// Sub-textures that got a smaller level than wanted (the indirection
    /// was full).
    pub squeezed: u32,
    pub sub_textures: u32,
    /// Pages rendered and evicted since the renderer was made.
    pub rendered_total: u64,
    pub evicted_total: u64,
    /// Frame of the newest harvested requests (0: none came back yet).
    pub harvested_frame: u64,
    /// Effect `decals`: decals blended into this frame's pages (a page's
    /// decals each count once), pages dropped by decal edits since the
    /// renderer was made, and decals left out of pages touched by more than
    /// DECAL_MAX_PER_PAGE.
    pub decal_blends: u32,
    pub decal_pages_invalidated: u64,
    pub decals_left_out: u64,
}

impl VtCounters {
    /// Share of the requested pages that were resident.
    pub fn hit_rate(&self) -> f64 {
        if self.requested == 0 {
            1.0
        } else {
            f64::from(self.hits) / f64::from(self.requested)
        }
    }
}

/// What happened to a page (tests follow the cache with these).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PageEvent {
    Rendered(PageKey),
    Evicted(PageKey),
    /// Dropped: what it was rendered from changed.
    Invalidated(PageKey),
}

/// The virtual texture's CPU state.
pub struct VtState {
    pub layout: VtLayout,
    alloc: QuadtreeAllocator,
    subs: Vec<Option<SubTexture>>,
    cache: TileCache,
    misses: BTreeSet<(u32, PageKey)>,
    /// Frame of the newest harvested requests (pages it used are kept).
    harvested: u64,
    pub budget: u32,
    pub counters: VtCounters,
    /// The newest frame that rendered, dropped or moved anything.
    changed: u64,
    /// Tests: every page event, in order, when `Some`.
    pub history: Option<Vec<PageEvent>>,
    writes: Vec<StateWrite>,
}

impl VtState {
    pub fn new(layout: VtLayout, budget: u32) -> VtState {
        VtState {
            layout,
            alloc: QuadtreeAllocator::new(layout.indirection_side),
            subs: vec![None; layout.region_count() as usize],
            cache: TileCache::new(layout.tile_count()),
            misses: BTreeSet::new(),
            harvested: 0,
            budget,
            counters: VtCounters::default(),
            changed: 0,
            history: None,
            writes: Vec::new(),
        }
    }

    pub fn sub_texture(&self, region: u32) -> Option<SubTexture> {
        self.subs[region as usize]
    }

    pub fn cache(&self) -> &TileCache {
        &self.cache
    }

    fn indirection_word(&self, key: PageKey, sub: SubTexture) -> u32 {
        let i = self.layout.indirection_index(key, sub.k, sub.offset);
        (u64::from(VT_STATE_HEADER + self.layout.region_count()) + i) as u32
    }

    fn write(&mut self, start: u32, count: u32, value: u32) {
        self.writes.push(StateWrite { start, count, value, pad: 0 });
    }

    /// Gives each region the level its distance from `camera_xy` asks for
    /// (none beyond `range_m`), moving changed sub-textures to new squares
    /// and mapping the pages they already have there.
    pub fn place_sub_textures(&mut self, frame: u64, camera_xy: [f64; 2], pixel_rad: f64, range_m: f64) {
        let l = self.layout;
        let (mut squeezed, mut count) = (0, 0);
        for r in 0..l.region_count() {
            let o = l.region_origin(r);
            let near = [0, 1].map(|a| camera_xy[a].clamp(o[a], o[a] + l.region_m) - camera_xy[a]);
            let d = near[0].hypot(near[1]);
            let want = (d <= range_m).then(|| wanted_level(l.region_m, d, pixel_rad));
            let have = self.subs[r as usize];
            if want == have.map(|s| s.k) {
                count += u32::from(have.is_some());
                continue;
            }
            if let Some(old) = have {
                self.alloc.free(old.offset, old.k);
            }
            self.changed = frame;
            let placed = want.and_then(|k| {
                (0..=k).rev().find_map(|k| self.alloc.allocate(k).map(|offset| SubTexture { k, offset }))
            });
            if want.is_some() && placed.is_none_or(|p| Some(p.k) != want) {
                squeezed += 1;
            }
            self.subs[r as usize] = placed;
            let word = VT_STATE_HEADER + r;
            match placed {
                None => self.write(word, 1, VT_NONE),
                Some(sub) => {
                    self.clear_square(sub);
                    for (page, tile) in self.cache.pages_of_region(r) {
                        if page.level <= sub.k {
                            let w = self.indirection_word(page, sub);
                            self.write(w, 1, tile);
                        }
                    }
                    self.write(word, 1, pack_sub_texture(sub.offset, sub.k));
                    count += 1;
                }
            }
        }
        self.counters.squeezed = squeezed;
        self.counters.sub_textures = count;
    }

    /// A node of LOD `lod` over `bounds` (x0, y0, x1, y1 m) arrived in
    /// `frame`: drops the pages of the regions it overlaps that were
    /// rendered from coarser nodes (their splat map is no longer the
    /// finest there); returns how many.
    pub fn invalidate(&mut self, bounds: [f64; 4], lod: u8, frame: u64) -> u32 {
        let l = self.layout;
        let inside = |r: u32| {
            let o = l.region_origin(r);
            o[0] < bounds[2] && o[0] + l.region_m > bounds[0] && o[1] < bounds[3] && o[1] + l.region_m > bounds[1]
        };
        let cache = &self.cache;
        let stale: Vec<PageKey> =
            cache.pages().filter(|p| inside(p.region) && cache.source_lod(*p).is_some_and(|s| s > lod)).collect();
        self.drop_pages(&stale, frame)
    }

    /// Drops every resident page `stale` says is stale (its content
    /// changed: a decal edit), to be rendered again; returns how many.
    pub fn invalidate_pages(&mut self, frame: u64, stale: impl Fn(PageKey) -> bool) -> u32 {
        let pages: Vec<PageKey> = self.cache.pages().filter(|p| stale(*p)).collect();
        self.drop_pages(&pages, frame)
    }

    fn drop_pages(&mut self, stale: &[PageKey], frame: u64) -> u32 {
        for page in stale {
            self.cache.remove(*page);
            if let Some(h) = &mut self.history {
                h.push(PageEvent::Invalidated(*page));
            }
            if let Some(sub) = self.subs[page.region as usize].filter(|s| page.level <= s.k) {
                let w = self.indirection_word(*page, sub);
                self.write(w, 1, VT_NONE);
            }
        }
        if !stale.is_empty() {
            self.changed = frame;
        }
        stale.len() as u32
    }

    /// Every page the views of a whole jitter cycle asked for is resident
    /// and nothing changed since: more frames show the same picture.
    pub fn settled(&self) -> bool {
        let cycle = u64::from(crate::shaders::consts::VT_FEEDBACK_STRIDE.pow(2));
        self.misses.is_empty() && self.harvested >= self.changed + cycle && self.harvested > 0
    }

    /// Writes "no page" over every indirection texel of `sub`'s square.
    fn clear_square(&mut self, sub: SubTexture) {
        for m in 0..=sub.k {
            let side = 1u32 << (sub.k - m);
            for y in 0..side {
                let first = PageKey { region: 0, level: sub.k - m, x: 0, y };
                let w = self.indirection_word(first, sub);
                self.write(w, side, VT_NONE);
            }
        }
    }

    /// Takes the page requests of `frame` (read back frames late): touches
    /// the resident ones and remembers the others as misses.
    pub fn harvest(&mut self, frame: u64, requests: &[[u32; 2]]) {
        let mut pages: Vec<PageKey> = requests.iter().map(|&e| unpack_request(e)).collect();
        pages.sort();
        pages.dedup();
        self.misses.clear();
        let mut hits = 0;
        for p in &pages {
            if self.cache.touch(*p, frame) {
                hits += 1;
            } else if self.subs.get(p.region as usize).copied().flatten().is_some_and(|s| p.level <= s.k) {
                // Coarser first: a page's parents serve it meanwhile.
                self.misses.insert((p.level, *p));
            }
        }
        self.harvested = self.harvested.max(frame);
        self.counters.requested = pages.len() as u32;
        self.counters.hits = hits;
    }

    /// This frame's pages to render (at most the budget, coarser levels
    /// first) and every state write due, in order; clears both queues.
    /// `source_lod(region)`: the coarsest LOD among the finest resident
    /// nodes over the region (what its pages are rendered from).
    pub fn plan(&mut self, frame: u64, source_lod: impl Fn(u32) -> u8) -> (Vec<PageJob>, Vec<StateWrite>) {
        let mut jobs = Vec::new();
        let mut evicted = 0;
        while jobs.len() < self.budget as usize {
            let Some((_, page)) = self.misses.pop_first() else { break };
            // Its sub-texture went or shrank since it was asked for.
            let Some(sub) = self.subs[page.region as usize].filter(|s| page.level <= s.k) else { continue };
            // Pages the newest harvested frame used are not given up.
            let Some((tile, old)) = self.cache.insert(page, frame, self.harvested, source_lod(page.region)) else {
                self.misses.insert((page.level, page));
                break;
            };
            if let Some(h) = &mut self.history {
                h.extend(old.map(PageEvent::Evicted));
                h.push(PageEvent::Rendered(page));
            }
            if let Some(old) = old {
                evicted += 1;
                if let Some(sub) = self.subs[old.region as usize].filter(|s| old.level <= s.k) {
                    let w = self.indirection_word(old, sub);
                    self.write(w, 1, VT_NONE);
                }
            }
            let w = self.indirection_word(page, sub);
            self.write(w, 1, tile);
            jobs.push(PageJob { tile, region: page.region, page: pack_page(page), decals: 0 });
        }
        if !jobs.is_empty() {
            self.changed = frame;
        }
        self.counters.rendered = jobs.len() as u32;
        self.counters.evicted = evicted;
        self.counters.rendered_total += jobs.len() as u64;
        self.counters.evicted_total += u64::from(evicted);
        self.counters.harvested_frame = self.harvested;
        self.counters.resident = self.cache.resident();
        self.counters.waiting = self.misses.len() as u32;
        (jobs, std::mem::take(&mut self.writes))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The page (and its tile) the GPU samples for world point `xy` at
    /// `level`, or a coarser one when that page is not resident (as
    /// `vt_find` in virtual_texture.glsl).
    fn lookup(s: &VtState, xy: [f64; 2], level: u32) -> Option<(PageKey, u32)> {
        let l = &s.layout;
        let c = [0, 1].map(|a| (xy[a] / l.region_m).floor());
        if c.iter().zip(l.regions).any(|(&c, n)| c < 0.0 || c >= f64::from(n)) {
            return None;
        }
        let region = c[0] as u32 + c[1] as u32 * l.regions[0];
        let sub = s.subs[region as usize]?;
        let o = l.region_origin(region);
        (0..=level.min(sub.k)).rev().find_map(|lv| {
            let page_m = l.region_m / f64::from(1u32 << lv);
            let p = [0, 1].map(|a| (((xy[a] - o[a]) / page_m).floor() as u32).min((1 << lv) - 1));
            let key = PageKey { region, level: lv, x: p[0], y: p[1] };
            s.cache.tile_of(key).map(|t| (key, t))
        })
    }

    /// The state buffer as the writes leave it.
    fn apply(words: &mut [u32], writes: &[StateWrite]) {
        for w in writes {
            words[w.start as usize..(w.start + w.count) as usize].fill(w.value);
        }
    }

    #[test]
    fn resized_sub_textures_keep_their_pages_and_evictions_unmap() {
        let layout = VtLayout::new([256.0, 256.0], 64.0, 256, 4);
        let mut s = VtState::new(layout, 4);
        let n = (VT_STATE_HEADER + layout.region_count()) as usize + layout.indirection_texels() as usize;
        let mut words = vec![VT_NONE; n];
        let rad = 1e-3;
        s.place_sub_textures(1, [10.0, 10.0], rad, 1000.0);
        let sub = s.sub_texture(0).unwrap();
        assert_eq!(sub.k, 7);
        // Requests for region 0's coarsest pages.
        let req: Vec<[u32; 2]> = (0..2).map(|x| [0, pack_page(PageKey { region: 0, level: 1, x, y: 0 })]).collect();
        s.harvest(1, &req);
        assert_eq!((s.counters.requested, s.counters.hits), (2, 0));
        let (jobs, writes) = s.plan(4, |_| 0);
        apply(&mut words, &writes);
        assert_eq!(jobs.len(), 2);
        let key = PageKey { region: 0, level: 1, x: 1, y: 0 };
        let tile = s.cache().tile_of(key).unwrap();
        assert_eq!(words[s.indirection_word(key, sub) as usize], tile);
        // The camera moves away: region 0 drops to a coarser level in a new
        // square, where its page is mapped again without rendering.
        s.place_sub_textures(5, [250.0, 250.0], rad, 1000.0);
        let moved = s.sub_texture(0).unwrap();
        assert!(moved.k < 7 && moved.k >= 1);
        let (jobs, writes) = s.plan(5, |_| 0);
        apply(&mut words, &writes);
        assert!(jobs.is_empty());
        assert_eq!(words[s.indirection_word(key, moved) as usize], tile);
        assert_eq!(words[VT_STATE_HEADER as usize], pack_sub_texture(moved.offset, moved.k));
        assert_eq!(lookup(&s, [40.0, 10.0], 7).map(|h| h.0), Some(key), "finer levels fall back to the page held");
    }
}
