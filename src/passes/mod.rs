//! One pass per file; the pass, its shader and its timer label share a name.

pub mod classify_tiles;
pub mod counters;
pub mod cull_occluded;
pub mod cull_patches;
pub mod debug_view;
pub mod emit_fine;
pub mod emit_triangles;
pub mod gbuffer_tiles;
pub mod hiz_build;
pub mod lighting_resolve;
pub mod lod_map;
pub mod prefix_sum;
pub mod quadtree_update;
pub mod sector_data;
pub mod select_patches;
pub mod terrain_geometry;
pub mod terrain_holes;
pub mod terrain_query;
pub mod terrain_sink;
pub mod terrain_triangles;
pub mod traverse;
pub mod triangle_lists;
