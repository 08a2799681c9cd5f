//! CPU side of the terrain: world geometry, height sources, node bakes, the
//! on-disk node cache, streaming residency and memory accounting. No Vulkan
//! here; the GPU layer consumes [`BakedNode`]s and [`ResidencyChanges`].

mod bake;
mod bake_claim;
mod bake_run;
pub mod bintree;
pub mod bintree_dense;
mod cache;
mod cones;
mod control_map;
mod erosion;
mod error;
mod error_quantile;
mod error_tile;
mod errors;
mod exr_source;
mod geotiff;
mod hash;
mod holes;
mod input_file;
mod layout;
mod loader;
mod manifest;
mod material_rules;
mod memory;
mod noise;
mod payload;
mod plan;
mod plan_display;
mod png16;
mod procedural;
mod progress;
mod projection;
mod resample_bound;
mod shard;
mod source;
mod stamps;
mod streamer;
mod streaming;
mod texels;
pub mod vegetation;
pub mod vertex_bounds;
pub mod vertex_bounds_cache;
pub(crate) mod vertex_bounds_exact;
mod vertex_bounds_fine;
pub mod vertex_rule;

pub use bake::{bake_node, bake_node_with, BakeSettings};
pub use bake_claim::{claim_folder, CLAIM_FILE};
pub use bake_run::{bake_shard, bake_world, nodes_in_region, BakeStats, NodeFile};
pub use cache::{
    bake_region, default_cache_dir, estimated_file_bytes, uncompressed_file_bytes, CacheOutcome, MissReason, NodeCache,
};
pub use cones::{cone_contains, fit_cone, patch_triangle_normals, NormalCone};
pub use control_map::{
    control_map_texels, nearest_threshold, slope01, textures as control_textures, ControlBake, ControlCode,
    ControlLooks, ControlMap, ControlRules, ControlSource, StampControl, CONTROL_TEXTURES, SLOPE_THRESHOLDS, UV_SCALES,
};
pub use error::{Result, WorldError};
pub use error_tile::diamond;
pub use errors::{
    selection_error, ErrorTree, NodeErrors, PreparedErrors, TreeCounts, DEFAULT_HELD_TILE_BYTES, TILE_BYTES_PER_PATCH,
};
pub use exr_source::{write_height_exr, ExrSource};
pub use geotiff::{GeoTiffInfo, GeoTiffSource};
pub use holes::{holes_hash, Hole};
pub use input_file::{require_regular_file, resolve_relative};
pub use layout::{
    decode_height, encode_height, NodeId, WorldDesc, CONE_BLOCKS_PER_NODE, CONE_BLOCKS_PER_NODE_SIDE, MAX_ABS_HEIGHT_M,
    MAX_IMAGE_SIDE, MAX_LOD_COUNT, MAX_SECTORS_PER_SIDE, NODE_QUADS, NODE_SAMPLES, PATCHES_PER_NODE,
    PATCHES_PER_NODE_SIDE, PATCH_QUADS, PATCH_SAMPLES, SPLAT_RES,
};
pub use loader::{LoadFn, Loader};
pub use manifest::{
    manifest_path, verify, ForeignManifest, ShardManifest, ShardVerdict, VerifyReport, MANIFEST_VERSION,
};
pub use material_rules::{MaterialRules, Site};
pub use memory::{node_cpu_bytes, MemoryReport, PayloadSize};
pub use payload::{BakedNode, Material, PATCH_HOLE_ALL, PATCH_HOLE_NONE, PATCH_HOLE_SOME};
pub use plan::{
    bytes as human_bytes, slot_capacity, Limits, PlanError, TimeBasis, WorldPlan, DEFAULT_MAX_BAKE_DISK_BYTES,
    DEFAULT_MAX_SECTORS_PER_SIDE, DEFAULT_SLOTS, NODE_BAKE_THREAD_SECONDS, RELOAD_SLOTS,
};
pub use plan_display::{ErrorMemory, LARGE_ERROR_MEMORY};
pub use png16::Png16Source;
pub use procedural::{FlowNetwork, ProceduralSource, SHAPE_NODES};
pub use progress::{Progress, ProgressEvent, ProgressFn, Reporter, Work};
pub use projection::TraverseCamera;
pub use resample_bound::RangeFit;
pub use shard::{ShardError, ShardPlan, ShardSplit, MAX_SHARDS, UNITS_PER_SHARD};
pub use source::{GridSource, Ground, HeightSource};
pub use stamps::{load_stamp_map, Stamp, StampBlend, StampPlacement, StampedSource};
pub use streamer::{StreamFrame, Streamer};
pub use streaming::{
    Arrival, FailureCounts, LoadFate, RefineWant, Residency, ResidencyChanges, ResidencyConfig, MAX_LOAD_ATTEMPTS,
};
pub use texels::{
    pack_normal, texel_index, unpack_normal, PayloadFormat, TexelKind, ATLAS_BORDER, ATLAS_SIDE, ATLAS_TEXELS,
    NORMAL_OCCLUSION, NORMAL_SMOOTHNESS, NORMAL_X, NORMAL_Y,
};
