//! The CPU half of the virtual texture: which sub-texture each region has
//! and where it sits in the indirection, which page each physical tile
//! holds, and the work of one frame (pages to render, indirection writes)
//! from the page requests the GPU listed frames ago. No Vulkan here.

use super::allocator::QuadtreeAllocator;
use super::cache::{PageSource, TileCache};
use super::layout::{pack_sub_texture, wanted_level, PageKey, VtLayout};
use crate::shaders::consts::{
    VT_FEEDBACK_STRIDE, VT_NONE, VT_REQ_COORD_MASK, VT_REQ_LEVEL_MASK, VT_REQ_X_SHIFT, VT_REQ_Y_SHIFT,
};
use serde::Serialize;
use std::collections::BTreeSet;

/// The feedback's jitter cycle (frames), a bit each in `clean_phases`.
const PHASES: u64 = (VT_FEEDBACK_STRIDE * VT_FEEDBACK_STRIDE) as u64;
const PHASES_ALL: u64 = if PHASES == 64 { u64::MAX } else { (1 << PHASES) - 1 };
const _: () = assert!(PHASES <= 64, "a bit per phase");

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
    /// Regions within the range (along both axes) outside the window
    /// (`window_m` smaller than the view's reach): no sub-texture.
    pub beyond_window: u32,
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
    /// Per window slot: the region it holds and that region's sub-texture.
    subs: Vec<Option<(u32, SubTexture)>>,
    cache: TileCache,
    misses: BTreeSet<(u32, PageKey)>,
    /// Frame of the newest harvested requests (pages it used are kept).
    harvested: u64,
    pub budget: u32,
    pub counters: VtCounters,
    /// The newest frame that rendered, dropped or moved anything.
    changed: u64,
    /// Feedback phases (frame % VT_FEEDBACK_STRIDE^2, a bit each) whose
    /// requests, made after `changed`, came back without a miss.
    clean_phases: u64,
    /// Tests: every page event, in order, when `Some`.
    pub history: Option<Vec<PageEvent>>,
    writes: Vec<StateWrite>,
}

impl VtState {
    pub fn new(layout: VtLayout, budget: u32) -> VtState {
        VtState {
            layout,
            alloc: QuadtreeAllocator::new(layout.indirection_side),
            subs: vec![None; layout.slots() as usize],
            cache: TileCache::new(layout.tile_count()),
            misses: BTreeSet::new(),
            harvested: 0,
            budget,
            counters: VtCounters::default(),
            changed: 0,
            clean_phases: 0,
            history: None,
            writes: Vec::new(),
        }
    }

    pub fn sub_texture(&self, region: u32) -> Option<SubTexture> {
        if region >= self.layout.region_count() {
            return None;
        }
        self.subs[self.layout.slot_of(region) as usize].filter(|s| s.0 == region).map(|s| s.1)
    }

    pub fn cache(&self) -> &TileCache {
        &self.cache
    }

    fn indirection_word(&self, key: PageKey, sub: SubTexture) -> u32 {
        let i = self.layout.indirection_index(key, sub.k, sub.offset);
        (u64::from(self.layout.indirection_base()) + i) as u32
    }

    fn write(&mut self, start: u32, count: u32, value: u32) {
        self.writes.push(StateWrite { start, count, value, pad: 0 });
    }

    /// Gives each region of the window around `camera_xy` the level its
    /// distance asks for (none beyond `range_m`), moving changed
    /// sub-textures to new squares and mapping the pages they already have
    /// there; a region that left the window gives up its slot. The walk is
    /// the window's, not the world's.
    pub fn place_sub_textures(&mut self, frame: u64, camera_xy: [f64; 2], pixel_rad: f64, range_m: f64) {
        let l = self.layout;
        let origin = l.window_origin(camera_xy);
        let (mut squeezed, mut count) = (0, 0);
        for r in l.window_regions(origin) {
            let slot = l.slot_of(r);
            if let Some((_, old)) = self.subs[slot as usize].filter(|s| s.0 != r) {
                self.release(slot, old, frame);
            }
            let o = l.region_origin(r);
            let near = [0, 1].map(|a| camera_xy[a].clamp(o[a], o[a] + l.region_m) - camera_xy[a]);
            let d = near[0].hypot(near[1]);
            let want = (d <= range_m).then(|| wanted_level(l.region_m, d, pixel_rad));
            let have = self.subs[slot as usize].map(|s| s.1);
            if want == have.map(|s| s.k) {
                count += u32::from(have.is_some());
                continue;
            }
            if let Some(old) = have {
                self.release(slot, old, frame);
            }
            self.changed(frame);
            let placed = want.and_then(|k| {
                (0..=k).rev().find_map(|k| self.alloc.allocate(k).map(|offset| SubTexture { k, offset }))
            });
            if want.is_some() && placed.is_none_or(|p| Some(p.k) != want) {
                squeezed += 1;
            }
            if let Some(sub) = placed {
                self.subs[slot as usize] = Some((r, sub));
                self.map_sub_texture(r, slot, sub);
                count += 1;
            }
        }
        self.counters.squeezed = squeezed;
        self.counters.sub_textures = count;
        self.counters.beyond_window = l.beyond_window(origin, camera_xy, range_m);
    }

    /// Empties `slot` (holding `old`): the GPU sees no sub-texture there
    /// before its square is given to another.
    fn release(&mut self, slot: u32, old: SubTexture, frame: u64) {
        self.alloc.free(old.offset, old.k);
        self.subs[slot as usize] = None;
        self.write(self.layout.sub_word(slot), 1, VT_NONE);
        self.changed(frame);
    }

    /// Clears `sub`'s square, maps region `r`'s resident pages into it, and
    /// only then names the region and the sub-texture in `slot` (writes
    /// apply in order, a frame may stop after any of them).
    fn map_sub_texture(&mut self, r: u32, slot: u32, sub: SubTexture) {
        self.clear_square(sub);
        for (page, tile) in self.cache.pages_of_region(r) {
            if page.level <= sub.k {
                let w = self.indirection_word(page, sub);
                self.write(w, 1, tile);
            }
        }
        self.write(self.layout.region_word(slot), 1, r);
        self.write(self.layout.sub_word(slot), 1, pack_sub_texture(sub.offset, sub.k));
    }

    /// A node of LOD `lod` over `bounds` (x0, y0, x1, y1 m) arrived in
    /// `frame`: drops the pages overlapping it that were rendered from
    /// coarser nodes (their splat map is no longer the finest there), and,
    /// for a `reload` (a stamp edit's new payload of a resident node), those
    /// rendered from nodes of its own LOD too (the page's source names the
    /// node, whose data changed under the same id); returns how many.
    pub fn invalidate(&mut self, bounds: [f64; 4], lod: u8, reload: bool, frame: u64) -> u32 {
        let l = self.layout;
        let inside = |p: &PageKey| {
            let r = l.padded_rect(*p);
            r[0] < bounds[2] && r[2] > bounds[0] && r[1] < bounds[3] && r[3] > bounds[1]
        };
        let cache = &self.cache;
        let stale: Vec<PageKey> = cache
            .pages()
            .filter(|p| inside(p) && cache.source(*p).is_some_and(|s| s.lod > lod || (reload && s.lod == lod)))
            .collect();
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
            if let Some(sub) = self.sub_texture(page.region).filter(|s| page.level <= s.k) {
                let w = self.indirection_word(*page, sub);
                self.write(w, 1, VT_NONE);
            }
        }
        if !stale.is_empty() {
            self.changed(frame);
        }
        stale.len() as u32
    }

    /// Every phase of the feedback's jitter cycle came back without a miss
    /// since anything changed: every pixel's pages are resident, and more
    /// frames show the same picture. Counted by phase, not by frames: a
    /// readback that was not back in time is dropped (how many depends on
    /// the device's pace), and a phase it skipped was never checked.
    pub fn settled(&self) -> bool {
        self.misses.is_empty() && self.clean_phases == PHASES_ALL
    }

    /// Something the pictures sample changed in `frame`: every phase is to
    /// be checked again.
    fn changed(&mut self, frame: u64) {
        self.changed = frame;
        self.clean_phases = 0;
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

    /// Takes the page requests of `frame` (read back frames late): drops
    /// the resident ones whose `source` changed since they were rendered
    /// (nodes left from under them; `source` gives `None` while streaming
    /// is under way: the nodes may come back, and the page with them),
    /// touches the others and remembers the rest as misses.
    /// `whole`: the frame sampled every pixel, so a clean one checks every
    /// phase.
    pub fn harvest(
        &mut self,
        frame: u64,
        requests: &[[u32; 2]],
        whole: bool,
        source: impl Fn(PageKey) -> Option<PageSource>,
    ) {
        let mut pages: Vec<PageKey> = requests.iter().map(|&e| unpack_request(e)).collect();
        pages.sort();
        pages.dedup();
        let stale: Vec<PageKey> = pages
            .iter()
            .copied()
            .filter(|p| self.cache.source(*p).is_some_and(|s| source(*p).is_some_and(|n| n != s)))
            .collect();
        self.drop_pages(&stale, frame);
        self.misses.clear();
        let mut hits = 0;
        for p in &pages {
            if self.cache.touch(*p, frame) {
                hits += 1;
            } else if self.sub_texture(p.region).is_some_and(|s| p.level <= s.k) {
                // Coarser first: a page's parents serve it meanwhile.
                self.misses.insert((p.level, *p));
            }
        }
        self.harvested = self.harvested.max(frame);
        if frame > self.changed && self.misses.is_empty() {
            self.clean_phases |= if whole { PHASES_ALL } else { 1 << (frame % PHASES) };
        }
        self.counters.requested = pages.len() as u32;
        self.counters.hits = hits;
    }

    /// This frame's pages to render (at most the budget, coarser levels
    /// first) and every state write due, in order; clears both queues.
    /// `source(page)`: what the page is rendered from now.
    pub fn plan(&mut self, frame: u64, source: impl Fn(PageKey) -> PageSource) -> (Vec<PageJob>, Vec<StateWrite>) {
        let mut jobs = Vec::new();
        let mut evicted = 0;
        while jobs.len() < self.budget as usize {
            let Some((_, page)) = self.misses.pop_first() else { break };
            // Its sub-texture went or shrank since it was asked for.
            let Some(sub) = self.sub_texture(page.region).filter(|s| page.level <= s.k) else { continue };
            // Pages the newest harvested frame used are not given up.
            let Some((tile, old)) = self.cache.insert(page, frame, self.harvested, source(page)) else {
                self.misses.insert((page.level, page));
                break;
            };
            if let Some(h) = &mut self.history {
                h.extend(old.map(PageEvent::Evicted));
                h.push(PageEvent::Rendered(page));
            }
            if let Some(old) = old {
                evicted += 1;
                if let Some(sub) = self.sub_texture(old.region).filter(|s| old.level <= s.k) {
                    let w = self.indirection_word(old, sub);
                    self.write(w, 1, VT_NONE);
                }
            }
            let w = self.indirection_word(page, sub);
            self.write(w, 1, tile);
            jobs.push(PageJob { tile, region: page.region, page: pack_page(page), decals: 0 });
        }
        if !jobs.is_empty() {
            self.changed(frame);
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
    use crate::shaders::consts::{VT_STATE_HEADER, VT_SUB_COORD_MASK, VT_SUB_K_SHIFT, VT_SUB_Y_SHIFT};

    /// Region `region`'s sub-texture as the state words name it (as
    /// `vt_sub_texture` in virtual_texture.glsl reads them).
    fn word_sub(l: &VtLayout, words: &[u32], region: u32) -> Option<SubTexture> {
        let w = words[7];
        let [x, y] = l.region_xy(region);
        let slot = x % w + (y % w) * w;
        let sub = words[(VT_STATE_HEADER + slot) as usize];
        if words[(VT_STATE_HEADER + w * w + slot) as usize] != region || sub == VT_NONE {
            return None;
        }
        let offset = [sub & VT_SUB_COORD_MASK, (sub >> VT_SUB_Y_SHIFT) & VT_SUB_COORD_MASK];
        Some(SubTexture { k: sub >> VT_SUB_K_SHIFT, offset })
    }

    /// The page (and its tile) the GPU samples for world point `xy` at
    /// `level`, or a coarser one when that page is not resident (as
    /// `vt_find` in virtual_texture.glsl), read from the state words.
    fn lookup(l: &VtLayout, words: &[u32], xy: [f64; 2], level: u32) -> Option<(PageKey, u32)> {
        let c = [0, 1].map(|a| (xy[a] / l.region_m).floor());
        if c.iter().zip(l.regions).any(|(&c, n)| c < 0.0 || c >= f64::from(n)) {
            return None;
        }
        let region = c[0] as u32 + c[1] as u32 * l.regions[0];
        let sub = word_sub(l, words, region)?;
        let o = l.region_origin(region);
        let base = u64::from(VT_STATE_HEADER + 2 * words[7] * words[7]);
        (0..=level.min(sub.k)).rev().find_map(|lv| {
            let page_m = l.region_m / f64::from(1u32 << lv);
            let p = [0, 1].map(|a| (((xy[a] - o[a]) / page_m).floor() as u32).min((1 << lv) - 1));
            let key = PageKey { region, level: lv, x: p[0], y: p[1] };
            let tile = words[(base + l.indirection_index(key, sub.k, sub.offset)) as usize];
            (tile != VT_NONE).then_some((key, tile))
        })
    }

    /// A state buffer as `record_init` leaves it (the header's window word
    /// is all the lookups read).
    fn fresh_words(l: &VtLayout) -> Vec<u32> {
        let mut words = vec![VT_NONE; l.state_words() as usize];
        words[7] = l.window;
        words
    }

    /// The state buffer as the writes leave it.
    fn apply(words: &mut [u32], writes: &[StateWrite]) {
        for w in writes {
            words[w.start as usize..(w.start + w.count) as usize].fill(w.value);
        }
    }

    #[test]
    fn resized_sub_textures_keep_their_pages_and_evictions_unmap() {
        let layout = VtLayout::new([256.0, 256.0], 64.0, 256, 4, 1000.0);
        let mut s = VtState::new(layout, 4);
        let mut words = fresh_words(&layout);
        let rad = 1e-3;
        s.place_sub_textures(1, [10.0, 10.0], rad, 1000.0);
        let sub = s.sub_texture(0).unwrap();
        assert_eq!(sub.k, 7);
        // Requests for region 0's coarsest pages.
        let req: Vec<[u32; 2]> = (0..2).map(|x| [0, pack_page(PageKey { region: 0, level: 1, x, y: 0 })]).collect();
        s.harvest(1, &req, false, |_| None);
        assert_eq!((s.counters.requested, s.counters.hits), (2, 0));
        let (jobs, writes) = s.plan(4, |_| PageSource::default());
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
        let (jobs, writes) = s.plan(5, |_| PageSource::default());
        apply(&mut words, &writes);
        assert!(jobs.is_empty());
        assert_eq!(words[s.indirection_word(key, moved) as usize], tile);
        assert_eq!(words[VT_STATE_HEADER as usize], pack_sub_texture(moved.offset, moved.k));
        let held = lookup(&layout, &words, [40.0, 10.0], 7).map(|h| h.0);
        assert_eq!(held, Some(key), "finer levels fall back to the page held");
    }

    /// Nebula's window on a world of 4096 x 4096 regions (the 262 km
    /// continent at 64 m): the per-region state is the window's, a camera
    /// flying across hands slots from the regions it leaves to those it
    /// reaches, and the state words (read as the shader reads them) give
    /// every region what the CPU gave it: its sub-texture inside the
    /// window and in range, none elsewhere.
    #[test]
    fn the_window_follows_the_camera_across_a_continent() {
        let region_m = 64.0;
        let layout = VtLayout::new([262_144.0; 2], region_m, 2048, 4, 1024.0);
        assert_eq!((layout.window, layout.regions), (17, [4096, 4096]));
        let mut s = VtState::new(layout, 4);
        assert_eq!(s.subs.len(), 17 * 17, "state per window slot, not per region");
        let mut words = fresh_words(&layout);
        let (rad, range) = (1e-3, 400.0);
        let seen_region = |s: &VtState, words: &[u32], camera: [f64; 2]| {
            let c = [0, 1].map(|a| (camera[a] / region_m).floor() as i64);
            let origin = layout.window_origin(camera);
            for dy in -12..=12 {
                for dx in -12..=12 {
                    let (x, y) = (c[0] + dx, c[1] + dy);
                    if x < 0 || y < 0 || x >= 4096 || y >= 4096 {
                        continue;
                    }
                    let r = (x + y * 4096) as u32;
                    let inside = [x, y].iter().zip(origin).all(|(&v, o)| v >= i64::from(o) && v < i64::from(o + 17));
                    let o = layout.region_origin(r);
                    let near = [0, 1].map(|a| camera[a].clamp(o[a], o[a] + region_m) - camera[a]);
                    let want = inside && near[0].hypot(near[1]) <= range;
                    assert_eq!(s.sub_texture(r).is_some(), want, "region ({x}, {y}), camera {camera:?}");
                    assert_eq!(word_sub(&layout, words, r), s.sub_texture(r), "region ({x}, {y}): the words agree");
                }
            }
        };
        // A flight from the south-west corner diagonally, then a jump.
        let mut cameras: Vec<[f64; 2]> =
            (0..60).map(|i| [10.0 + 97.0 * f64::from(i), 5.0 + 61.0 * f64::from(i)]).collect();
        cameras.extend([[200_000.0, 150_000.0], [262_000.0, 262_000.0], [3000.0, 4000.0]]);
        for (f, &camera) in cameras.iter().enumerate() {
            s.place_sub_textures(f as u64 + 1, camera, rad, range);
            let (_, writes) = s.plan(f as u64 + 1, |_| PageSource::default());
            apply(&mut words, &writes);
            assert_eq!(s.counters.beyond_window, 0, "a 1024 m window holds a 400 m range");
            seen_region(&s, &words, camera);
        }
        // A range beyond the window is counted, not silently dropped.
        s.place_sub_textures(99, [100_000.0; 2], rad, 1500.0);
        let reach = (2.0 * 1500.0 / region_m).ceil() as u32;
        assert!(s.counters.beyond_window >= reach * reach - 17 * 17 - 4 * reach);
    }

    /// A state with one sub-texture, one of its pages and a request for it.
    fn one_page() -> (VtState, PageKey, [[u32; 2]; 1]) {
        let layout = VtLayout::new([256.0, 256.0], 64.0, 256, 4, 1000.0);
        let mut s = VtState::new(layout, 4);
        s.place_sub_textures(1, [10.0, 10.0], 1e-3, 1000.0);
        let key = PageKey { region: 0, level: 1, x: 0, y: 0 };
        (s, key, [[0, pack_page(key)]])
    }

    /// A page is rendered again when its nodes changed under it, once
    /// streaming rests (`source` gives `None` before), and settling waits
    /// for every feedback phase to come back clean after that.
    #[test]
    fn a_page_whose_nodes_changed_is_rendered_again_once_streaming_rests() {
        let (mut s, key, req) = one_page();
        let (made, moved) = (PageSource { lod: 0, nodes: 1 }, PageSource { lod: 1, nodes: 2 });
        s.harvest(1, &req, false, |_| None);
        assert_eq!(s.plan(2, |_| made).0.len(), 1);
        for f in 3..3 + PHASES {
            s.harvest(f, &req, false, |_| None);
            assert!(s.plan(f, |_| made).0.is_empty(), "kept while the nodes may come back");
        }
        assert!(s.settled());
        let f = 3 + PHASES;
        s.harvest(f, &req, false, |_| Some(moved));
        assert!(!s.settled(), "a changed page is a miss");
        assert_eq!(s.plan(f, |_| moved).0.len(), 1, "rendered again");
        assert_eq!(s.cache().source(key), Some(moved));
        for g in f + 1..f + PHASES {
            s.harvest(g, &req, false, |_| Some(moved));
            assert!(!s.settled(), "phase {} not yet checked since the change", g % PHASES);
        }
        s.harvest(f + PHASES, &req, false, |_| Some(moved));
        assert!(s.settled());
    }

    /// A frame whose feedback sampled every pixel checks every phase: one
    /// clean one after a change settles it; one with a miss does not.
    #[test]
    fn a_whole_frame_checks_every_phase_at_once() {
        let (mut s, _, req) = one_page();
        let made = PageSource { lod: 0, nodes: 1 };
        s.harvest(1, &req, true, |_| None);
        assert!(!s.settled(), "a miss");
        assert_eq!(s.plan(2, |_| made).0.len(), 1);
        s.harvest(2, &req, true, |_| None);
        assert!(!s.settled(), "frame 2 was recorded before the page was made");
        s.harvest(3, &req, true, |_| None);
        assert!(s.settled(), "one clean whole frame after the change");
    }
}
