// Per-patch LOD selection, shared by select_patches (which decides each
// listed patch's level), cull_patches and cull_occluded (which draw it).
//
// The traversal lists nodes fine enough for the target; select_patches
// then draws each of their patches from the coarsest ancestor (up to
// MAX_COARSEN levels up) whose patch error still meets the target, and
// refines LOD-0 patches below the samples (2x, 4x) where LOD 0 does not.
// Errors are monotone (the error tree), so an ancestor that meets the
// target covers descendants that do too, and the patches of one ancestor
// patch agree: the first of them (the block's representative) draws it.
//
// Seams: a patch is drawn at most MAX_LOD_DELTA levels coarser than any
// neighbour, which stitching handles. Coarsening is capped per node at
// MAX_LOD_DELTA levels above the finest neighbouring node (read from the
// LOD map along the node's edges), refinement at MAX_LOD_DELTA levels
// below the neighbouring patches' coarse levels; where node LODs
// themselves differ by more the finer node is lifted instead (counted as
// a conflict).
//
// The inputs are declared here, with the bindings every includer shares.
#ifndef VISTA_LOD_SELECT_GLSL
#define VISTA_LOD_SELECT_GLSL

#include "node_list.glsl"
#include "terrain_view.glsl"

// Patches per node side (world PATCHES_PER_NODE_SIDE) and quads per patch side.
layout(constant_id = 1) const uint PATCHES_PER_SIDE = 16u;
layout(constant_id = 2) const uint PATCH_QUADS = 8u;

struct SelectHeader {
    uint conflicts;      // listed nodes next to one more than MAX_LOD_DELTA LODs coarser (lifted)
    uint refined;        // LOD-0 patches asking to be refined below the samples this frame
    uint refine_capped;  // of those, refused by MAX_REFINED_PATCHES
    uint coarsened;      // listed patches drawn from an ancestor
};

layout(set = 0, binding = 0, std430) readonly buffer TraverseOutput {
    TraverseHeader header;
    uvec2 nodes[];
} traverse_out;
layout(set = 0, binding = 1, std430) readonly buffer View { TerrainView v; } view;
layout(set = 0, binding = 2, r8ui) uniform readonly uimage2D lod_map;
layout(set = 0, binding = 3) uniform utexture2DArray patch_min_max;
layout(set = 0, binding = 6) uniform sampler nearest;
layout(set = 0, binding = 11) uniform utexture2D node_texture;
layout(set = 0, binding = 12) uniform texture2DArray patch_errors;
#ifdef SELECT_WRITES
layout(set = 0, binding = 13, std430) buffer Select {
#else
layout(set = 0, binding = 13, std430) readonly buffer Select {
#endif
    SelectHeader header;
    int levels[];
} select_levels;

// Each listed node's patch has two levels in `select_levels.levels`, at
// 2 i and 2 i + 1 (i = slot * 64 + patch): its coarse level (the node's LOD
// plus the levels it is coarsened by) and, for a LOD-0 patch not coarsened,
// its drawn level (-r when refined r levels below the samples).
int select_index(uint slot, uint index) {
    uint per_side = PATCHES_PER_SIDE;
    return int(slot * per_side * per_side + index);
}

uint node_slot(uint lod, ivec2 cell) {
    return texelFetch(usampler2D(node_texture, nearest), cell, int(lod)).r;
}

// Camera-relative box of patch `pxy` of node `cell` at `lod` (slot `slot`):
// exact LOD-0 sample indices across, the baked height range up, padded so
// f32 rounding never shrinks it.
void patch_box(uint lod, ivec2 cell, ivec2 pxy, uint slot, out vec3 lo, out vec3 hi) {
    uint per_side = PATCHES_PER_SIDE, quads = PATCH_QUADS;
    int node_samples = int(per_side * quads);
    ivec2 s0 = (cell * node_samples + pxy * int(quads)) << lod;
    ivec2 s1 = s0 + (int(quads) << lod);
    uvec2 mm = texelFetch(usampler2DArray(patch_min_max, nearest), ivec3(pxy, int(slot)), 0).xy;
    lo = vec3(view_rel_xy(s0, view.v.camera_sample, view.v.camera_frac, view.v.spacing_m),
              view.v.height_lo + float(mm.x) * view.v.height_scale - view.v.camera_z);
    hi = vec3(view_rel_xy(s1, view.v.camera_sample, view.v.camera_frac, view.v.spacing_m),
              view.v.height_lo + float(mm.y) * view.v.height_scale - view.v.camera_z);
    vec3 pad = 1e-4 * (abs(lo) + abs(hi)) + 1e-3;
    lo -= pad;
    hi += pad;
}

// Error (m) of patch `pxy` of a node: x drawn at its own level, y drawn 2x
// refined (LOD 0 only).
vec2 patch_error(uint slot, ivec2 pxy) {
    return texelFetch(sampler2DArray(patch_errors, nearest), ivec3(pxy, int(slot)), 0).xy;
}

#include "projected_error.glsl"

bool meets_target(float err, vec3 lo, vec3 hi) {
    return projected_px(err, lo, hi) <= view.v.lod_params.x;
}

// The patch of an ancestor `a` levels up covering patch `pxy` of node `cell`.
void ancestor_patch(ivec2 cell, ivec2 pxy, uint a, out ivec2 anc_cell, out ivec2 anc_pxy) {
    uint per_side = PATCHES_PER_SIDE;
    ivec2 g = (cell * int(per_side) + pxy) >> a;
    anc_cell = cell >> a;
    anc_pxy = g - anc_cell * int(per_side);
}

// The level at which the region holding LOD-0 sample q is drawn: the coarse
// level, or with `refined` the drawn one; NO_LEVEL where no listed node
// covers it.
int level_at(ivec2 q, bool refined) {
    uint per_side = PATCHES_PER_SIDE, quads = PATCH_QUADS;
    int node_samples = int(per_side * quads);
    if (any(lessThan(q, ivec2(0)))) {
        return int(NO_LEVEL);
    }
    ivec2 sector = q / node_samples;
    if (sector.x >= int(view.v.lod_map_w) || sector.y >= int(view.v.lod_map_h)) {
        return int(NO_LEVEL);
    }
    uint lod = imageLoad(lod_map, sector).r;
    if (lod == NO_LOD) {
        return int(NO_LEVEL);
    }
    ivec2 cell = q / (node_samples << lod);
    ivec2 pxy = (q / (int(quads) << lod)) - cell * int(per_side);
    uint slot = node_slot(lod, cell);
    int i = select_index(slot, uint(pxy.y * int(per_side) + pxy.x));
    int coarse = select_levels.levels[2 * i];
    return (!refined || coarse > 0) ? coarse : select_levels.levels[2 * i + 1];
}

#endif
