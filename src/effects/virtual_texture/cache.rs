//! The physical cache's tiles: which page each holds, and which to give up.
//! Least recently used goes first, where "used" is the newest frame whose
//! page requests named the page: the feedback pass lists every page a
//! frame sampled (seed 001 names only new pages and so cannot tell a page
//! still in view from one left behind). The eviction scans the tiles for
//! the oldest stamp: a few thousand tiles and a budget of a few dozen pages
//! per frame make that cheaper than keeping a list in order on every touch.

use super::layout::PageKey;
use std::collections::HashMap;

/// What a page was rendered from: the coarsest of the finest resident
/// LODs over its padded tile, and a hash of the resident nodes over it
/// (the same nodes make the same page, whenever it was rendered).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PageSource {
    pub lod: u8,
    pub nodes: u64,
}

#[derive(Debug, Clone, Copy)]
struct Tile {
    page: Option<PageKey>,
    /// Frame of the newest request for the page (or of its rendering).
    used: u64,
    source: PageSource,
}

/// The tiles of the cache and the page each holds.
#[derive(Debug, Clone)]
pub struct TileCache {
    tiles: Vec<Tile>,
    by_page: HashMap<PageKey, u32>,
    free: Vec<u32>,
}

impl TileCache {
    pub fn new(tiles: u32) -> TileCache {
        TileCache {
            tiles: vec![Tile { page: None, used: 0, source: PageSource::default() }; tiles as usize],
            by_page: HashMap::new(),
            free: (0..tiles).rev().collect(),
        }
    }

    pub fn capacity(&self) -> u32 {
        self.tiles.len() as u32
    }

    pub fn resident(&self) -> u32 {
        self.by_page.len() as u32
    }

    /// The tile holding `page`.
    pub fn tile_of(&self, page: PageKey) -> Option<u32> {
        self.by_page.get(&page).copied()
    }

    /// The page `tile` holds.
    pub fn page_of(&self, tile: u32) -> Option<PageKey> {
        self.tiles[tile as usize].page
    }

    /// Marks `page` used in `frame`; false when it is not resident.
    pub fn touch(&mut self, page: PageKey, frame: u64) -> bool {
        let Some(&t) = self.by_page.get(&page) else { return false };
        let tile = &mut self.tiles[t as usize];
        tile.used = tile.used.max(frame);
        true
    }

    /// What `page` was rendered from (see `insert`).
    pub fn source(&self, page: PageKey) -> Option<PageSource> {
        self.tile_of(page).map(|t| self.tiles[t as usize].source)
    }

    /// A tile for `page`, rendered from `source`:
    /// a free one, else the least recently used one not
    /// used since `protect` (whose page is returned as evicted). `None`
    /// when every tile was used at or after `protect` (the cache is smaller
    /// than what the view samples).
    pub fn insert(
        &mut self,
        page: PageKey,
        frame: u64,
        protect: u64,
        source: PageSource,
    ) -> Option<(u32, Option<PageKey>)> {
        debug_assert!(!self.by_page.contains_key(&page));
        let (tile, evicted) = match self.free.pop() {
            Some(t) => (t, None),
            None => {
                let (t, old) = self
                    .tiles
                    .iter()
                    .enumerate()
                    .filter(|(_, t)| t.used < protect)
                    .min_by_key(|(i, t)| (t.used, *i))
                    .map(|(i, t)| (i as u32, t.page))?;
                if let Some(p) = old {
                    self.by_page.remove(&p);
                }
                (t, old)
            }
        };
        self.tiles[tile as usize] = Tile { page: Some(page), used: frame, source };
        self.by_page.insert(page, tile);
        Some((tile, evicted))
    }

    /// Drops `page` (its content is stale); its tile becomes free.
    pub fn remove(&mut self, page: PageKey) -> Option<u32> {
        let t = self.by_page.remove(&page)?;
        self.tiles[t as usize] = Tile { page: None, used: 0, source: PageSource::default() };
        self.free.push(t);
        Some(t)
    }

    /// Every resident page, in no order.
    pub fn pages(&self) -> impl Iterator<Item = PageKey> + '_ {
        self.by_page.keys().copied()
    }

    /// Every resident page of `region`.
    pub fn pages_of_region(&self, region: u32) -> Vec<(PageKey, u32)> {
        let mut v: Vec<(PageKey, u32)> =
            self.by_page.iter().filter(|(p, _)| p.region == region).map(|(p, t)| (*p, *t)).collect();
        v.sort();
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn page(x: u32) -> PageKey {
        PageKey { region: 0, level: 7, x, y: 0 }
    }

    #[test]
    fn the_least_recently_used_page_goes_first_and_recent_ones_stay() {
        let mut c = TileCache::new(3);
        for (f, x) in [(1, 0), (2, 1), (3, 2)] {
            assert_eq!(c.insert(page(x), f, f, PageSource::default()).unwrap().1, None);
        }
        assert!(c.touch(page(0), 4));
        // Page 1 is the oldest now.
        let (t, evicted) = c.insert(page(3), 5, 5, PageSource::default()).unwrap();
        assert_eq!(evicted, Some(page(1)));
        assert_eq!(c.tile_of(page(3)), Some(t));
        assert_eq!(c.tile_of(page(1)), None);
        // Everything used at or after frame 3 is protected: no room.
        assert!(c.insert(page(4), 6, 3, PageSource::default()).is_none());
        assert_eq!(c.resident(), 3);
        assert_eq!(c.remove(page(0)), Some(0));
        assert_eq!(c.insert(page(4), 6, 3, PageSource::default()).unwrap(), (0, None), "a freed tile is reused first");
    }
}
