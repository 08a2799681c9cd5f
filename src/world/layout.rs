//! World geometry: the sector grid, the node quadtree and height encoding.
//!
//! Conventions: the world's min corner is the origin, x grows east, y grows
//! north, z is height. LOD-0 sample (i, j) of the whole world lies at
//! `grid_origin + (i, j) * spacing` ([`WorldDesc::sample_pos`]); node sample
//! (i, j) at `bounds.min + (i, j) * node_spacing`, stored at texel
//! `texel_index(i, j)`, so row 0 of every payload is the node's south edge.
//! The grid origin is 0 except for a height map whose pixel size is a whole
//! multiple of the spacing: then the vertices sit on the map's posts (its
//! pixel centres, half a pixel in from the world's edge) and the drawn
//! surface passes through every sample of the data ([`WorldDesc::with_posts`]).

use std::fmt;

use serde::{Deserialize, Serialize};

use super::error::{Result, WorldError};
use super::hash::Fnv64;

/// Quads per node side; Far Cry 5's 128x128-quad sector.
pub const NODE_QUADS: u32 = 128;
/// Samples per node side: one more than quads so neighbours share edges.
pub const NODE_SAMPLES: usize = NODE_QUADS as usize + 1;
/// Patches per node side: a patch is the unit of GPU culling and drawing.
pub const PATCHES_PER_NODE_SIDE: u32 = 16;
/// Patches per node.
pub const PATCHES_PER_NODE: usize = (PATCHES_PER_NODE_SIDE * PATCHES_PER_NODE_SIDE) as usize;
/// Normal cones per node side: one per `CONE_BLOCK_PATCHES` x
/// `CONE_BLOCK_PATCHES` patches (see `world::cones`).
pub const CONE_BLOCKS_PER_NODE_SIDE: u32 = PATCHES_PER_NODE_SIDE / crate::shaders::consts::CONE_BLOCK_PATCHES;
/// Normal cones per node.
pub const CONE_BLOCKS_PER_NODE: usize = (CONE_BLOCKS_PER_NODE_SIDE * CONE_BLOCKS_PER_NODE_SIDE) as usize;
/// Quads per patch side (128 / 16).
pub const PATCH_QUADS: u32 = NODE_QUADS / PATCHES_PER_NODE_SIDE;
/// Samples per patch side.
pub const PATCH_SAMPLES: usize = PATCH_QUADS as usize + 1;
/// Splat map texels per node side: one per second sample keeps it small.
pub const SPLAT_RES: usize = 65;
/// Most LODs a world may have; keeps `NodeId::lod` and GPU bit fields small
/// (quadtree_update binds one storage image per LOD).
pub const MAX_LOD_COUNT: u32 = crate::shaders::consts::MAX_NODE_LODS;
/// Most sectors per world side: beyond this coordinates overflow GPU fields.
pub const MAX_SECTORS_PER_SIDE: u64 = 1 << 20;
/// Most roots per side of a world whose LOD count is not given and whose
/// extent they tile exactly ([`WorldDesc::lods_for`]): five, so the default
/// 10 240 m world is exactly 5 x 5 roots of 2 048 m.
pub const DEFAULT_MAX_ROOTS_PER_SIDE: u32 = 5;
/// Largest accepted source image side, checked before any pixel allocation.
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// Geometry of a world. See the module docs for axis conventions.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct WorldDesc {
    /// World size in metres along x and y.
    pub extent_m: [f64; 2],
    /// Heights representable by the R16_UNORM height maps: (lo, hi) metres.
    pub height_range_m: [f32; 2],
    /// Distance between LOD-0 samples in metres.
    pub spacing_m: f64,
    /// Number of quadtree levels; LOD `lod_count - 1` nodes are the roots.
    pub lod_count: u32,
    /// Where LOD-0 sample (0, 0) lies, metres from the world's south-west
    /// corner along x and y: 0 in general, less than one spacing; half a
    /// pixel (modulo the spacing) where the vertices sit on a height map's
    /// posts.
    #[serde(default)]
    pub grid_origin_m: [f64; 2],
}

/// Heights beyond this many metres are refused: 100 times Mount Everest, so
/// a height map in other units (millimetres, raw sensor counts) is caught,
/// and the span of any accepted range stays finite in f32.
pub const MAX_ABS_HEIGHT_M: f32 = 1e6;

impl Default for WorldDesc {
    /// The default procedural world: Far Cry 5's 10 km map at 0.5 m.
    fn default() -> Self {
        WorldDesc {
            extent_m: [10_240.0, 10_240.0],
            height_range_m: [0.0, 1600.0],
            spacing_m: 0.5,
            // WorldDesc::lods_for the extent: 5 x 5 roots of 2 048 m.
            lod_count: 6,
            grid_origin_m: [0.0, 0.0],
        }
    }
}

/// A quadtree cell: LOD and cell coordinates in that LOD's grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct NodeId {
    pub lod: u8,
    pub x: u32,
    pub y: u32,
}

impl fmt::Display for NodeId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "lod{}/{}_{}", self.lod, self.x, self.y)
    }
}

impl NodeId {
    pub fn new(lod: u8, x: u32, y: u32) -> Self {
        NodeId { lod, x, y }
    }

    /// The cell one LOD coarser that contains this one (not checked against
    /// the world's LOD count).
    pub fn parent(&self) -> NodeId {
        NodeId::new(self.lod + 1, self.x / 2, self.y / 2)
    }

    /// The four cells one LOD finer, SW, SE, NW, NE. Some may be invalid
    /// where the world extent is not a multiple of the node size.
    pub fn children(&self) -> Option<[NodeId; 4]> {
        let lod = self.lod.checked_sub(1)?;
        let (x, y) = (self.x * 2, self.y * 2);
        Some([
            NodeId::new(lod, x, y),
            NodeId::new(lod, x + 1, y),
            NodeId::new(lod, x, y + 1),
            NodeId::new(lod, x + 1, y + 1),
        ])
    }

    /// Bounds in metres, [min x, min y, max x, max y]; see
    /// [`WorldDesc::bounds_m`].
    pub fn bounds_m(&self, world: &WorldDesc) -> [f64; 4] {
        world.bounds_m(*self)
    }

    /// Whether `self` is `other` or lies inside it.
    pub fn is_within(&self, other: &NodeId) -> bool {
        if self.lod > other.lod {
            return false;
        }
        let shift = other.lod - self.lod;
        self.x >> shift == other.x && self.y >> shift == other.y
    }
}

impl WorldDesc {
    /// Side of the node texture's mip 0 (one texel per LOD 0 node of the
    /// root grid): the GPU quadtree's texture and a plan's estimate of it.
    pub fn node_texture_extent(&self) -> [u32; 2] {
        let root = self.grid(self.root_lod());
        let scale = 1u32 << self.root_lod();
        [root[0] * scale, root[1] * scale]
    }

    /// Checks every field; the rest of the module assumes a validated desc.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(WorldError::InvalidDesc(m));
        for (axis, e) in ["x", "y"].iter().zip(self.extent_m) {
            if !e.is_finite() || e <= 0.0 {
                return bad(format!("extent {axis} must be finite and positive, got {e}"));
            }
        }
        let s = self.spacing_m;
        if !s.is_finite() || s <= 0.0 {
            return bad(format!("spacing must be finite and positive, got {s}"));
        }
        let [lo, hi] = self.height_range_m;
        if !lo.is_finite() || !hi.is_finite() || lo >= hi {
            return bad(format!("height range must be finite with lo < hi, got {lo}..{hi}"));
        }
        if lo.abs() > MAX_ABS_HEIGHT_M || hi.abs() > MAX_ABS_HEIGHT_M {
            return bad(format!(
                "height range {lo}..{hi} reaches beyond +-{MAX_ABS_HEIGHT_M:e} m (heights must be metres)"
            ));
        }
        if !(1..=MAX_LOD_COUNT).contains(&self.lod_count) {
            return bad(format!("lod count must be 1..={MAX_LOD_COUNT}, got {}", self.lod_count));
        }
        for (axis, o) in ["x", "y"].iter().zip(self.grid_origin_m) {
            if !(o.is_finite() && (0.0..s).contains(&o)) {
                return bad(format!("grid origin {axis} must lie within one spacing of the corner, got {o}"));
            }
        }
        for e in self.extent_m {
            let sectors = (e / self.sector_size_m()).ceil();
            if sectors.is_nan() || sectors > MAX_SECTORS_PER_SIDE as f64 {
                return bad(format!("{sectors} sectors per side exceeds the limit of {MAX_SECTORS_PER_SIDE}"));
            }
        }
        Ok(())
    }

    /// The default LOD count of an extent: coarse roots, so the far field
    /// can be drawn coarsely where the error allows and the roots (always
    /// resident) hold few slots. The most LODs whose roots tile the extent
    /// exactly with at most `DEFAULT_MAX_ROOTS_PER_SIDE` a side (no part
    /// of a root outside the world for the hole path to cut away): the
    /// default 10 240 m world at 0.5 m gets 6, 5 x 5 roots of 2 048 m. When
    /// none does, the fewest LODs with at most 2 roots a side (Mont Blanc's
    /// 60 km at 8 m: 6, 2 x 2 roots of 32 km), at most [`MAX_LOD_COUNT`].
    pub fn lods_for(extent_m: [f64; 2], spacing_m: f64) -> u32 {
        let sector = f64::from(NODE_QUADS) * spacing_m;
        let sectors = extent_m.map(|e| (e / sector).ceil().max(1.0) as u64);
        let roots = |l: u32| sectors.map(|s| s.div_ceil(1 << (l - 1)));
        let exact = (1..=MAX_LOD_COUNT).rev().find(|&l| {
            let r = roots(l);
            r.iter().all(|&n| n <= u64::from(DEFAULT_MAX_ROOTS_PER_SIDE))
                && sectors.iter().all(|s| s % (1 << (l - 1)) == 0)
        });
        exact
            .unwrap_or_else(|| (1..=MAX_LOD_COUNT).find(|&l| roots(l).iter().all(|&n| n <= 2)).unwrap_or(MAX_LOD_COUNT))
    }

    /// Side of a LOD-0 node in metres.
    pub fn sector_size_m(&self) -> f64 {
        f64::from(NODE_QUADS) * self.spacing_m
    }

    /// Side of a node at `lod` in metres.
    pub fn node_size_m(&self, lod: u8) -> f64 {
        self.sector_size_m() * f64::from(1u32 << lod)
    }

    /// Distance between samples of a node at `lod`.
    pub fn node_spacing_m(&self, lod: u8) -> f64 {
        self.spacing_m * f64::from(1u32 << lod)
    }

    /// LOD-0 nodes per side (x, y): enough for the samples from the grid
    /// origin to cover the extent.
    pub fn sectors(&self) -> [u32; 2] {
        let s = self.sector_size_m();
        [0, 1].map(|a| ((self.extent_m[a] - self.grid_origin_m[a]) / s).ceil().max(1.0) as u32)
    }

    /// The world with its LOD-0 vertices on the posts (pixel centres) of a
    /// height map of `pixel_m` metres per pixel, where that is a whole
    /// multiple of the spacing (within 1e-9); otherwise unchanged (the map
    /// is resampled between its posts).
    pub fn with_posts(self, pixel_m: [f64; 2]) -> Self {
        let s = self.spacing_m;
        let origin = pixel_m.map(|p| {
            let ratio = p / s;
            if (ratio - ratio.round()).abs() < 1e-9 && ratio.round() >= 1.0 {
                (0.5 * p).rem_euclid(s)
            } else {
                f64::NAN
            }
        });
        if origin.iter().any(|o| o.is_nan()) {
            return self;
        }
        WorldDesc { grid_origin_m: origin, ..self }
    }

    /// Whether the LOD-0 vertices sit on a height map's posts.
    pub fn on_posts(&self) -> bool {
        self.grid_origin_m != [0.0, 0.0]
    }

    /// World position (x or y, metres) of grid line `index` of a grid of
    /// `step` metres anchored at the grid origin: the one formula the bake,
    /// the error tree and the references use, so a sample lies at the same
    /// bits whichever of them asks.
    pub fn grid_pos(&self, axis: usize, index: i64, step: f64) -> f64 {
        self.grid_origin_m[axis] + index as f64 * step
    }

    /// World position of LOD-0 sample (i, j).
    pub fn sample_pos(&self, i: i64, j: i64) -> [f64; 2] {
        [self.grid_pos(0, i, self.spacing_m), self.grid_pos(1, j, self.spacing_m)]
    }

    /// Cells per side at `lod`: ceil(sectors / 2^lod).
    pub fn grid(&self, lod: u8) -> [u32; 2] {
        self.sectors().map(|s| s.div_ceil(1u32 << lod))
    }

    /// LOD of the always-resident roots.
    pub fn root_lod(&self) -> u8 {
        (self.lod_count - 1) as u8
    }

    /// A cell is valid iff it intersects the world extent. Every cell of the
    /// ceil-sized grid does, because `(sectors - 1) * sector < extent`.
    pub fn is_valid(&self, node: NodeId) -> bool {
        if u32::from(node.lod) >= self.lod_count {
            return false;
        }
        let [gx, gy] = self.grid(node.lod);
        node.x < gx && node.y < gy
    }

    /// Valid children of a node (empty at LOD 0).
    pub fn valid_children(&self, node: NodeId) -> Vec<NodeId> {
        node.children().map(|c| c.into_iter().filter(|&c| self.is_valid(c)).collect()).unwrap_or_default()
    }

    /// All valid nodes at the root LOD; together they cover the extent.
    pub fn roots(&self) -> Vec<NodeId> {
        self.nodes_at(self.root_lod())
    }

    /// All valid nodes at `lod`, row by row.
    pub fn nodes_at(&self, lod: u8) -> Vec<NodeId> {
        let [gx, gy] = self.grid(lod);
        (0..gy).flat_map(|y| (0..gx).map(move |x| NodeId::new(lod, x, y))).collect()
    }

    /// Node bounds in metres: [min x, min y, max x, max y]. Partial cells
    /// extend past the extent; their samples there clamp to the edge.
    pub fn bounds_m(&self, node: NodeId) -> [f64; 4] {
        let s = self.node_size_m(node.lod);
        let [ox, oy] = self.grid_origin_m;
        let (x0, y0) = (ox + f64::from(node.x) * s, oy + f64::from(node.y) * s);
        [x0, y0, x0 + s, y0 + s]
    }

    /// The valid node at `lod` containing a point, if the point is inside
    /// the extent.
    pub fn node_at(&self, lod: u8, x_m: f64, y_m: f64) -> Option<NodeId> {
        let [ex, ey] = self.extent_m;
        if !(0.0..=ex).contains(&x_m) || !(0.0..=ey).contains(&y_m) {
            return None;
        }
        let s = self.node_size_m(lod);
        let [gx, gy] = self.grid(lod);
        let [ox, oy] = self.grid_origin_m;
        let x = (((x_m - ox) / s).max(0.0) as u32).min(gx - 1);
        let y = (((y_m - oy) / s).max(0.0) as u32).min(gy - 1);
        Some(NodeId::new(lod, x, y))
    }

    /// Hash of every field; part of the cache key.
    pub fn hash(&self) -> u64 {
        Fnv64::new()
            .f64(self.extent_m[0])
            .f64(self.extent_m[1])
            .f64(f64::from(self.height_range_m[0]))
            .f64(f64::from(self.height_range_m[1]))
            .f64(self.spacing_m)
            .u64(u64::from(self.lod_count))
            .f64(self.grid_origin_m[0])
            .f64(self.grid_origin_m[1])
            .finish()
    }

    /// Height in metres to R16_UNORM over the height range (clamped).
    pub fn encode_height(&self, h_m: f32) -> u16 {
        encode_height(h_m, self.height_range_m)
    }

    /// R16_UNORM value back to metres.
    pub fn decode_height(&self, v: u16) -> f32 {
        decode_height(v, self.height_range_m)
    }
}

/// Height in metres to R16_UNORM over `range` (lo, hi); clamps outside it
/// and maps NaN to lo so a bad sample cannot poison a bake.
pub fn encode_height(h_m: f32, range: [f32; 2]) -> u16 {
    let [lo, hi] = range;
    let t = ((h_m - lo) / (hi - lo)).clamp(0.0, 1.0);
    if t.is_nan() {
        return 0;
    }
    (t * 65535.0).round() as u16
}

/// R16_UNORM value to metres over `range` (lo, hi), as the GPU decodes it.
pub fn decode_height(v: u16, range: [f32; 2]) -> f32 {
    let [lo, hi] = range;
    lo + (f32::from(v) / 65535.0) * (hi - lo)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_at_and_hash() {
        let w = WorldDesc::default();
        assert_eq!(w.node_at(0, 65.0, 1.0), Some(NodeId::new(0, 1, 0)));
        assert_eq!(w.node_at(5, 10_240.0, 10_240.0), Some(NodeId::new(5, 4, 4)));
        assert_eq!(w.node_at(0, -1.0, 1.0), None);
        assert_eq!(w.node_at(0, f64::NAN, 1.0), None);
        let other = WorldDesc { spacing_m: 1.0, ..w };
        assert_ne!(w.hash(), other.hash());
        // Stable across runs and compilers: FNV-1a 64 over the fields' little-
        // endian bytes, recomputed here by a second, plain implementation.
        let mut bytes = Vec::new();
        for v in [w.extent_m[0], w.extent_m[1], 0.0, 1600.0, w.spacing_m] {
            bytes.extend(v.to_bits().to_le_bytes());
        }
        bytes.extend(u64::from(w.lod_count).to_le_bytes());
        bytes.extend([0u8; 16]);
        let fnv = bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3));
        assert_eq!(w.hash(), fnv);
        assert!(NodeId::new(0, 5, 6).is_within(&NodeId::new(2, 1, 1)));
    }

    #[test]
    fn the_lod_count_follows_the_extent() {
        // 160 sectors of 64 m: 5 x 5 roots at 6 LODs (2 048 m each), the
        // default world's count.
        assert_eq!(WorldDesc::lods_for([10_240.0, 10_240.0], 0.5), 6);
        assert_eq!(WorldDesc::default().lod_count, WorldDesc::lods_for(WorldDesc::default().extent_m, 0.5));
        // 640 sectors: 8 LODs, 5 x 5 roots of 8 192 m (not 20 x 20 at 6).
        assert_eq!(WorldDesc::lods_for([40_960.0, 40_960.0], 0.5), 8);
        // Mont Blanc at 8 m: 59 sectors of 1 024 m (a prime: no exact
        // tiling), 2 x 2 roots of 32 km at 6 LODs.
        assert_eq!(WorldDesc::lods_for([60_000.0, 60_000.0], 8.0), 6);
        // 1563 sectors: 2 roots a side would need 11 LODs; the most is 10.
        assert_eq!(WorldDesc::lods_for([100_000.0, 100_000.0], 0.5), MAX_LOD_COUNT);
        assert_eq!(WorldDesc::lods_for([100.0, 100.0], 1.0), 1);
        assert_eq!(WorldDesc::lods_for([1e9, 1e9], 0.5), MAX_LOD_COUNT);
    }

    #[test]
    fn posts_put_the_vertices_on_pixel_centres() {
        let w = WorldDesc { extent_m: [640.0, 320.0], spacing_m: 2.0, lod_count: 3, ..WorldDesc::default() };
        // 2 m pixels: half a pixel in; 4 m pixels: 2 m = one spacing = 0.
        let p = w.with_posts([2.0, 2.0]);
        assert_eq!(p.grid_origin_m, [1.0, 1.0]);
        assert_eq!(w.with_posts([6.0, 6.0]).grid_origin_m, [1.0, 1.0]);
        assert_eq!(w.with_posts([4.0, 4.0]), w);
        // Not a whole multiple of the spacing: resampled, unchanged.
        assert_eq!(w.with_posts([3.0, 2.0]), w);
        assert_eq!(w.with_posts([1.0, 1.0]), w);
        // Pixel (i, j) of a 320 x 160 map is centred at (2i + 1, 320 - 2j - 1): sample (i, 159 - j).
        assert_eq!(p.sample_pos(0, 0), [1.0, 1.0]);
        assert_eq!(p.sample_pos(319, 159), [639.0, 319.0]);
        // 319 quads of 2 m from the first post to the last: 3 sectors of 256 m.
        assert_eq!(p.sectors(), [3, 2]);
        assert_eq!(p.node_at(0, 0.5, 0.5), Some(NodeId::new(0, 0, 0)));
        assert_eq!(p.node_at(0, 257.5, 1.0), Some(NodeId::new(0, 1, 0)));
        assert_eq!(p.node_at(0, 513.5, 1.0), Some(NodeId::new(0, 2, 0)));
        p.validate().unwrap();
        assert!(WorldDesc { grid_origin_m: [2.0, 0.0], ..w }.validate().is_err());
        assert!(!NodeId::new(0, 5, 6).is_within(&NodeId::new(2, 1, 0)));
    }
}
