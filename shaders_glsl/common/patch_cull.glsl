// Patch culling shared by cull_patches (phase 1) and cull_occluded (phase
// 2): one workgroup per listed node, one thread per patch (8x8). Both
// phases run the same frustum / cone / hole stages on the same inputs, so
// they agree on which patches survive them; only the occlusion decision
// differs (last frame's visibility bit, or the depth pyramid).
#ifndef VISTA_PATCH_CULL_GLSL
#define VISTA_PATCH_CULL_GLSL

#include "node_list.glsl"
#include "terrain_view.glsl"
#include "patch_list.glsl"

// Patches per node side (world PATCHES_PER_NODE_SIDE) and quads per patch side.
layout(constant_id = 1) const uint PATCHES_PER_SIDE = 8u;
layout(constant_id = 2) const uint PATCH_QUADS = 16u;

layout(set = 0, binding = 0, std430) readonly buffer TraverseOutput {
    TraverseHeader header;
    uvec2 nodes[];
} traverse_out;
layout(set = 0, binding = 1, std430) readonly buffer View { TerrainView v; } view;
layout(set = 0, binding = 2, r8ui) uniform readonly uimage2D lod_map;
layout(set = 0, binding = 3) uniform utexture2DArray patch_min_max;
#ifdef CONE_CULL
layout(set = 0, binding = 4) uniform texture2DArray patch_cones;
#endif
#ifdef HOLE_CULL
layout(set = 0, binding = 5) uniform utexture2DArray patch_holes;
#endif
layout(set = 0, binding = 6) uniform sampler nearest;

layout(push_constant, std430) uniform CullPush {
    uint stages;
    uint capacity;  // entries of each output list
    uint depth_w;   // cull_occluded: the depth target's size (the pyramid's source)
    uint depth_h;
} pc;

bool box_outside_frustum(vec3 lo, vec3 hi) {
    for (uint i = 0u; i < 5u; ++i) {
        vec4 p = view.v.frustum[i];
        // The corner farthest along the inward normal.
        vec3 far_corner = mix(lo, hi, greaterThanEqual(p.xyz, vec3(0.0)));
        if (dot(p.xyz, far_corner) + p.w < 0.0) {
            return true;
        }
    }
    return false;
}

#ifdef CONE_CULL
// Every triangle faces away iff every normal n in the cone has
// dot(n, corner - camera) > 0 for every point of the box; the set of
// such view vectors is a convex cone, so testing the 8 corners suffices:
// dot(axis, d) > sin(half-angle) * |d| for each corner vector d.
bool cone_faces_away(vec4 cone, vec3 lo, vec3 hi) {
    if (cone.w >= 1.0) {
        return false;
    }
    for (uint c = 0u; c < 8u; ++c) {
        vec3 d = vec3((c & 1u) != 0u ? hi.x : lo.x, (c & 2u) != 0u ? hi.y : lo.y, (c & 4u) != 0u ? hi.z : lo.z);
        if (!(dot(cone.xyz, d) > cone.w * length(d))) {
            return false;
        }
    }
    return true;
}
#endif

// LOD delta toward a neighbour sector: how many LODs coarser it is, 0 for
// finer, equal, unlisted or outside sectors, at most MAX_LOD_DELTA.
uint edge_delta(ivec2 sector, uint lod) {
    if (any(lessThan(sector, ivec2(0))) || sector.x >= int(view.v.lod_map_w) || sector.y >= int(view.v.lod_map_h)) {
        return 0u;
    }
    uint n = imageLoad(lod_map, sector).r;
    if (n == NO_LOD || n <= lod) {
        return 0u;
    }
    return min(n - lod, MAX_LOD_DELTA);
}

// One patch after the frustum, cone and hole stages.
struct PatchCull {
    vec3 lo;          // camera-relative box, padded
    vec3 hi;
    bool frustum;     // survived each stage so far
    bool cone;
    bool hole;
    bool holey;       // some holes: drawn by terrain_holes
    uvec2 record;     // the patch-list entry
    uint slot;
};

PatchCull cull_patch(uint t) {
    // Spec constants read into variables: expressions of spec constants
    // alone become OpSpecConstantOp, which naga cannot parse.
    uint per_side = PATCHES_PER_SIDE, quads = PATCH_QUADS;
    PatchCull c;
    uvec2 entry = traverse_out.nodes[gl_WorkGroupID.x];
    uint n = entry.x, slot = entry.y;
    c.slot = slot;
    uint lod = node_lod(n);
    ivec2 node = ivec2(node_x(n), node_y(n));
    ivec2 pxy = ivec2(t % per_side, t / per_side);
    int node_samples = int(per_side * quads);

    // Camera-relative box from exact LOD-0 sample indices.
    ivec2 s0 = (node * node_samples + pxy * int(quads)) << lod;
    ivec2 s1 = s0 + (int(quads) << lod);
    uvec2 mm = texelFetch(usampler2DArray(patch_min_max, nearest), ivec3(pxy, int(slot)), 0).xy;
    vec3 lo = vec3(view_rel_xy(s0, view.v.camera_sample, view.v.camera_frac, view.v.spacing_m),
                   view.v.height_lo + float(mm.x) * view.v.height_scale - view.v.camera_z);
    vec3 hi = vec3(view_rel_xy(s1, view.v.camera_sample, view.v.camera_frac, view.v.spacing_m),
                   view.v.height_lo + float(mm.y) * view.v.height_scale - view.v.camera_z);
    // Rounding of the box (f32, relative to the camera) must never shrink it.
    vec3 pad = 1e-4 * (abs(lo) + abs(hi)) + 1e-3;
    c.lo = lo - pad;
    c.hi = hi + pad;

    // Edge LOD deltas from the neighbouring sectors (only border patches
    // can have a neighbour of another node), looked up at the middle of the
    // patch edge, in units of 1/(2 * PATCHES_PER_SIDE) sector so patches
    // smaller than a sector (LOD < 3) find the right row or column.
    int halves = 2 * int(per_side);
    ivec2 sector0 = node << lod;
    ivec2 sector1 = (node + 1) << lod;
    ivec2 mid = (sector0 * halves + ((2 * pxy + 1) << lod)) / halves;
    int row = mid.y, col = mid.x;
    uint dw = pxy.x == 0 ? edge_delta(ivec2(sector0.x - 1, row), lod) : 0u;
    uint de = pxy.x == int(per_side) - 1 ? edge_delta(ivec2(sector1.x, row), lod) : 0u;
    uint ds = pxy.y == 0 ? edge_delta(ivec2(col, sector0.y - 1), lod) : 0u;
    uint dn = pxy.y == int(per_side) - 1 ? edge_delta(ivec2(col, sector1.y), lod) : 0u;
    uint b = PATCH_DELTA_BITS;
    uint deltas = (dw << (b * EDGE_WEST)) | (de << (b * EDGE_EAST)) | (ds << (b * EDGE_SOUTH)) | (dn << (b * EDGE_NORTH));

    bool keep = (pc.stages & CULL_STAGE_FRUSTUM) == 0u || !box_outside_frustum(c.lo, c.hi);
    c.frustum = keep;
    // Stitched edges move vertices onto the coarser grid, making triangles
    // the baked cone does not bound: only unstitched patches are cone-tested.
#ifdef CONE_CULL
    if (keep && (pc.stages & CULL_STAGE_CONE) != 0u && deltas == 0u) {
        vec4 cone = texelFetch(sampler2DArray(patch_cones, nearest), ivec3(pxy, int(slot)), 0);
        keep = !cone_faces_away(cone, c.lo, c.hi);
    }
#endif
    c.cone = keep;
    c.holey = false;
#ifdef HOLE_CULL
    uint holes = texelFetch(usampler2DArray(patch_holes, nearest), ivec3(pxy, int(slot)), 0).r;
    if (keep && (pc.stages & CULL_STAGE_HOLE) != 0u) {
        keep = holes != PATCH_HOLE_ALL;
    }
    c.holey = holes != PATCH_HOLE_NONE;
#endif
    c.hole = keep;
    c.record = uvec2(n, pack_patch(slot, uint(pxy.y) * per_side + uint(pxy.x), deltas));
    return c;
}

#endif
