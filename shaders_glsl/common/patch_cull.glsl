// Patch culling shared by cull_patches (phase 1) and cull_occluded (phase
// 2): one workgroup per listed node, one thread per patch (16x16). Each
// thread draws what select_patches decided for its patch (lod_select.glsl):
// nothing, when another patch of its block draws their common ancestor;
// the ancestor's patch; its own; or its 4 or 16 sub-patches below LOD 0.
// Both phases run the same frustum / cone / hole stages on the same inputs,
// so they agree on which patches survive them; only the occlusion decision
// differs (last frame's visibility bit, or the depth pyramid).
#ifndef VISTA_PATCH_CULL_GLSL
#define VISTA_PATCH_CULL_GLSL

#include "lod_select.glsl"
#include "patch_list.glsl"

#ifdef CONE_CULL
layout(set = 0, binding = 4) uniform texture2DArray patch_cones;
#endif
#ifdef HOLE_CULL
layout(set = 0, binding = 5) uniform utexture2DArray patch_holes;
// Patches with some holes: drawn by terrain_holes (header: its draw args).
layout(set = 0, binding = 8, std430) buffer HolePatchList {
    PatchListHeader header;
    uvec4 patches[];
} hole_list;
#endif
layout(set = 0, binding = 7, std430) buffer PatchList {
    PatchListHeader header;
    uvec4 patches[];
} patch_list;

layout(push_constant, std430) uniform CullPush {
    uint stages;
    uint capacity;  // entries of each output list
    uint depth_w;   // cull_occluded: the depth target's size (the pyramid's source)
    uint depth_h;
} pc;

#include "frustum_box.glsl"

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

// LOD deltas (EDGE_* order, PATCH_DELTA_BITS each) of a square of `size` LOD-0
// samples at `o` drawn at `level`, from the drawn levels just across the
// middle of each edge (a coarser neighbour covers the whole edge). A delta
// past MAX_LOD_DELTA (select_patches prevents it) is clamped and counted.
uint edge_deltas(ivec2 o, int size, int level, inout uint overflow) {
    int h = size / 2;
    ivec2 across[4] = ivec2[4](ivec2(o.x - 1, o.y + h), ivec2(o.x + size, o.y + h), ivec2(o.x + h, o.y - 1), ivec2(o.x + h, o.y + size));
    uint deltas = 0u;
    for (uint e = 0u; e < 4u; ++e) {
        int l = level_at(across[e], true);
        if (l != int(NO_LEVEL) && l > level) {
            int d = l - level;
            if (d > int(MAX_LOD_DELTA)) {
                overflow += 1u;
                d = int(MAX_LOD_DELTA);
            }
            deltas |= uint(d) << (PATCH_DELTA_BITS * e);
        }
    }
    return deltas;
}

// Whether an edge snaps past the patch's corners (a delta above
// log2(quads)): then the patch's triangles fill part of its neighbour's
// ground, which the neighbour alone does not cover, so culling it by its
// own box could open a crack there. Such patches (only where node LODs
// differ by 4) skip the frustum, cone and occlusion tests.
bool stitches_beyond(uint deltas) {
    uint within = uint(findMSB(PATCH_QUADS));
    for (uint e = 0u; e < 4u; ++e) {
        if (bitfieldExtract(deltas, int(PATCH_DELTA_BITS * e), int(PATCH_DELTA_BITS)) > within) {
            return true;
        }
    }
    return false;
}

// One listed patch after selection and the frustum, cone and hole stages.
struct PatchCull {
    bool drawn;       // this thread draws for its block (select_patches)
    bool beyond;      // some edge snaps past its corners (stitches_beyond): never frustum-, cone- or occlusion-culled
    vec3 lo;          // camera-relative box of what it draws, padded
    vec3 hi;
    bool frustum;     // survived each stage so far
    bool cone;
    bool hole;
    bool holey;       // some holes: drawn by terrain_holes
    uvec4 record;     // the patch-list entry (z: no refinement yet)
    uint slot;        // the listed node's slot (visibility bits)
    uint refine;      // levels below LOD 0 (4^refine sub-patches)
    uint subs;        // bit per sub-patch (bit 0 alone when not refined) the frustum keeps
    uint units;       // instances it stands for before culling: 4^refine when drawn, else 0
    ivec2 origin;     // LOD-0 sample of the drawn patch's corner
    int level;        // drawn level (-refine below LOD 0)
    float error;      // error of the drawn level (m)
    uint overflow;    // edges clamped to MAX_LOD_DELTA
};

// Bits of the sub-patches of a refined patch whose boxes (their own xy,
// the patch's height range) the frustum does not exclude.
uint sub_patches_in_frustum(PatchCull c) {
    uint quads = PATCH_QUADS;
    uint subs = 1u << c.refine;
    int size = int(quads >> c.refine);
    uint mask = 0u;
    for (uint s = 0u; s < subs * subs; ++s) {
        ivec2 o = c.origin + ivec2(s % subs, s / subs) * size;
        vec3 lo = c.lo, hi = c.hi;
        lo.xy = view_rel_xy(o, view.v.camera_sample, view.v.camera_frac, view.v.spacing_m) - vec2(1e-3);
        hi.xy = view_rel_xy(o + size, view.v.camera_sample, view.v.camera_frac, view.v.spacing_m) + vec2(1e-3);
        if (!box_outside_frustum(lo, hi)) {
            mask |= 1u << s;
        }
    }
    return mask;
}

// Bits of the sub-patches of a refined patch that stitch beyond their
// corners (stitches_beyond).
uint sub_patches_beyond(PatchCull c) {
    uint subs = 1u << c.refine;
    int size = int(PATCH_QUADS >> c.refine);
    uint mask = 0u;
    for (uint s = 0u; s < subs * subs; ++s) {
        uint overflow = 0u;
        if (stitches_beyond(edge_deltas(c.origin + ivec2(s % subs, s / subs) * size, size, c.level, overflow))) {
            mask |= 1u << s;
        }
    }
    return mask;
}

PatchCull cull_patch(uint t) {
    uint per_side = PATCHES_PER_SIDE, quads = PATCH_QUADS;
    PatchCull c;
    uvec2 entry = traverse_out.nodes[gl_WorkGroupID.x];
    uint n = entry.x;
    c.slot = entry.y;
    uint lod = node_lod(n);
    ivec2 node = ivec2(node_x(n), node_y(n));
    ivec2 pxy = ivec2(t % per_side, t / per_side);
    int i = select_index(c.slot, t);
    int coarse = select_levels.levels[2 * i];
    uint a = uint(coarse) - lod;
    c.drawn = ((pxy.x | pxy.y) & ((1 << a) - 1)) == 0;
    ivec2 cell = node, dpxy = pxy;
    uint dslot = c.slot;
    c.refine = 0u;
    if (a > 0u) {
        ancestor_patch(node, pxy, a, cell, dpxy);
        dslot = node_slot(uint(coarse), cell);
    } else if (lod == 0u) {
        c.refine = uint(-select_levels.levels[2 * i + 1]);
    }
    uint dlod = uint(coarse);
    c.level = c.refine > 0u ? -int(c.refine) : coarse;
    patch_box(dlod, cell, dpxy, dslot, c.lo, c.hi);
    vec2 e = patch_error(dslot, dpxy);
    c.error = c.refine == 0u ? e.x : c.refine == 1u ? e.y : 0.0;
    c.origin = (cell * int(per_side * quads) + dpxy * int(quads)) << dlod;
    c.overflow = 0u;
    uint deltas = 0u;
    if (c.refine == 0u) {
        deltas = edge_deltas(c.origin, int(quads) << dlod, c.level, c.overflow);
    }
    c.units = c.drawn ? 1u << (2u * c.refine) : 0u;
    c.subs = c.units == 0u ? 0u : (1u << c.units) - 1u;
    uint beyond = c.subs == 0u ? 0u : c.refine > 0u ? sub_patches_beyond(c) : stitches_beyond(deltas) ? 1u : 0u;
    c.beyond = beyond != 0u;
    if (c.subs != 0u && (pc.stages & CULL_STAGE_FRUSTUM) != 0u) {
        uint in_view = box_outside_frustum(c.lo, c.hi) ? 0u : c.refine == 0u ? c.subs : sub_patches_in_frustum(c);
        c.subs = in_view | beyond;
    }
    bool keep = c.subs != 0u;
    c.frustum = keep;
    // The baked cone holds every stitched variant of the patch's triangles
    // (src/world/cones.rs), not the Catmull-Rom triangles of sub-patches:
    // refined patches are not cone-tested, nor are patches whose triangles
    // leave their box (stitches_beyond).
#ifdef CONE_CULL
    if (keep && (pc.stages & CULL_STAGE_CONE) != 0u && c.refine == 0u && !c.beyond) {
        ivec2 block = dpxy / int(CONE_BLOCK_PATCHES);
        vec4 cone = texelFetch(sampler2DArray(patch_cones, nearest), ivec3(block, int(dslot)), 0);
        keep = !cone_faces_away(cone, c.lo, c.hi);
    }
#endif
    c.cone = keep;
    c.holey = false;
#ifdef HOLE_CULL
    // Holes switched off this frame: every patch is solid.
    uint holes = (pc.stages & CULL_HOLES_OFF) != 0u
        ? PATCH_HOLE_NONE
        : texelFetch(usampler2DArray(patch_holes, nearest), ivec3(dpxy, int(dslot)), 0).r;
    if (keep && (pc.stages & CULL_STAGE_HOLE) != 0u) {
        keep = holes != PATCH_HOLE_ALL;
    }
    c.holey = holes != PATCH_HOLE_NONE;
#endif
    c.hole = keep;
    uint index = uint(dpxy.y) * per_side + uint(dpxy.x);
    c.record = uvec4(pack_node(dlod, uint(cell.x), uint(cell.y)), pack_patch(dslot, index, deltas), 0u, 0u);
    return c;
}

void append(bool holey, uvec4 record) {
#ifdef HOLE_CULL
    if (holey) {
        uint i = atomicAdd(hole_list.header.instance_count, 1u);
        if (i < pc.capacity) {
            hole_list.patches[i] = record;
        }
        return;
    }
#endif
    uint i = atomicAdd(patch_list.header.instance_count, 1u);
    if (i < pc.capacity) {
        patch_list.patches[i] = record;
    }
}

// Instances a stage keeps when the patch survives it.
uint kept_units(PatchCull c, bool survived) {
    return survived ? bitCount(c.subs) : 0u;
}

// Lists what a surviving patch draws: itself, or its sub-patches the
// frustum keeps, and raises the frame's error bound to its projected error.
void emit_patch(PatchCull c) {
    atomicMax(patch_list.header.bound_bits, floatBitsToUint(projected_px(c.error, c.lo, c.hi)));
    if (c.overflow > 0u) {
        atomicAdd(patch_list.header.seam_overflow, c.overflow);
    }
    if (c.refine == 0u) {
        append(c.holey, c.record);
        return;
    }
    uint quads = PATCH_QUADS;
    uint subs = 1u << c.refine;
    int size = int(quads >> c.refine);
    for (uint s = 0u; s < subs * subs; ++s) {
        if ((c.subs & (1u << s)) == 0u) {
            continue;
        }
        ivec2 o = c.origin + ivec2(s % subs, s / subs) * size;
        uint overflow = 0u;
        uint deltas = edge_deltas(o, size, c.level, overflow);
        uvec4 r = c.record;
        r.y = (r.y & ~(0xFFFFu << PATCH_DELTA_SHIFT)) | (deltas << PATCH_DELTA_SHIFT);
        r.z = pack_refine(c.refine, s);
        append(c.holey, r);
    }
}

#endif
