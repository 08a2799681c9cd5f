#version 460
#extension GL_GOOGLE_include_directive : require
// variants: CONE_CULL HOLE_CULL OCCLUSION
// Far Cry 5's patch culling: one workgroup per listed node (indirect, from
// traverse), one thread per patch (16x16), each drawing what select_patches
// chose for it (an ancestor's patch, its own, or its sub-patches below LOD
// 0; common/patch_cull.glsl). Stages: frustum, backface (variant
// CONE_CULL), holes (variant HOLE_CULL: all-hole patches removed,
// partly-holed ones sent to the hole list drawn by terrain_holes). Built
// stages can still be switched off per frame. With OCCLUSION this is phase
// 1 of two-phase occlusion culling: only the survivors that were visible
// last frame are listed; cull_occluded tests the rest against the depth
// pyramid of what phase 1 drew.
layout(local_size_x = 256) in;
#include "patch_cull.glsl"

#ifdef OCCLUSION
// One bit per patch and slot: visible when cull_occluded last ran.
layout(set = 0, binding = 9, std430) readonly buffer Visibility { uint words[]; } visibility;
#endif

shared uint s_in;
shared uint s_frustum;
shared uint s_cone;
shared uint s_hole;

void main() {
    uint t = gl_LocalInvocationID.x;
    if (t == 0u) {
        s_in = 0u;
        s_frustum = 0u;
        s_cone = 0u;
        s_hole = 0u;
    }
    barrier();
    // Counted in instances (a refined patch is 4^r of them): with every
    // stage off, drawn == patches_in.
    PatchCull c = cull_patch(t);
    atomicAdd(s_in, c.units);
    atomicAdd(s_frustum, kept_units(c, c.frustum));
    atomicAdd(s_cone, kept_units(c, c.cone));
    atomicAdd(s_hole, kept_units(c, c.hole));
    bool keep = c.hole;
#ifdef OCCLUSION
    uint word = visibility.words[c.slot * VISIBILITY_WORDS_PER_SLOT + (t >> 5u)];
    if ((pc.stages & CULL_STAGE_OCCLUSION) != 0u) {
        keep = keep && (c.beyond || (word & (1u << (t & 31u))) != 0u);
    }
#endif
    if (keep) {
        emit_patch(c);
    }
    barrier();
    if (t == 0u) {
        atomicAdd(patch_list.header.patches_in, s_in);
        atomicAdd(patch_list.header.after_frustum, s_frustum);
        atomicAdd(patch_list.header.after_cone, s_cone);
        atomicAdd(patch_list.header.after_hole, s_hole);
    }
}
