//! One pass per file; the pass, its shader and its timer label share a name.

pub mod asset_draw;
pub mod classify_tiles;
pub mod cull_occluded;
pub mod cull_patches;
pub mod debug_view;
pub mod decal_meshes;
pub mod gbuffer_tiles;
pub mod grass_draw;
pub mod grass_pigment;
pub mod grass_place;
pub mod hiz_build;
pub mod lighting_resolve;
pub mod lod_map;
pub mod prefix_sum;
pub mod quadtree_update;
pub mod sector_data;
pub mod select_patches;
pub mod sun_shadows;
pub mod terrain_geometry;
pub mod terrain_holes;
pub mod terrain_query;
pub mod traverse;
pub mod vt_feedback;
pub mod vt_pages;
pub mod vt_update;
