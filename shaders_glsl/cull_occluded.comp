#version 460
#extension GL_GOOGLE_include_directive : require
// variants: CONE_CULL HOLE_CULL
// Phase 2 of two-phase occlusion culling (niagara; Haar and Aaltonen): the
// same nodes, selection and stages as cull_patches, then every survivor is
// tested against the depth pyramid of what phase 1 drew. Survivors phase 1
// did not draw (not visible last frame) that the pyramid leaves visible are
// listed for the second draw; every patch's visibility bit is rewritten
// for the next frame's phase 1.
layout(local_size_x = 256) in;
#include "patch_cull.glsl"

layout(set = 0, binding = 9, std430) buffer Visibility { uint words[]; } visibility;
layout(set = 0, binding = 10) uniform texture2D hiz;
#include "hiz_test.glsl"

shared uint s_in;
shared uint s_visible[VISIBILITY_WORDS_PER_SLOT];
shared uint s_tested;
shared uint s_listed;

void main() {
    uint t = gl_LocalInvocationID.x;
    if (t < VISIBILITY_WORDS_PER_SLOT) {
        s_visible[t] = 0u;
    }
    if (t == 0u) {
        s_in = 0u;
        s_tested = 0u;
        s_listed = 0u;
    }
    barrier();
    // Counted in instances, as cull_patches counts them.
    PatchCull c = cull_patch(t);
    atomicAdd(s_in, c.units);
    uint bit = 1u << (t & 31u);
    // Read before the barrier below; the words are rewritten after it.
    // (cull_patches draws patches that stitch beyond their corners whatever the bit.)
    bool drawn_in_phase1 = c.hole && (c.beyond || (visibility.words[c.slot * VISIBILITY_WORDS_PER_SLOT + (t >> 5u)] & bit) != 0u);
    bool visible = false;
    if (c.hole) {
        uint level;
        visible = c.beyond || hiz_box_visible(c.lo, c.hi, view.v.view_proj, uvec2(pc.depth_w, pc.depth_h), level);
    }
    if (visible) {
        atomicOr(s_visible[t >> 5u], bit);
    }
    if (c.hole && !drawn_in_phase1) {
        atomicAdd(s_tested, kept_units(c, true));
        if (visible) {
            atomicAdd(s_listed, kept_units(c, true));
            emit_patch(c);
        }
    }
    barrier();
    if (t < VISIBILITY_WORDS_PER_SLOT) {
        visibility.words[c.slot * VISIBILITY_WORDS_PER_SLOT + t] = s_visible[t];
    }
    if (t == 0u) {
        atomicAdd(patch_list.header.patches_in, s_in);
        atomicAdd(patch_list.header.after_hole, s_tested);
        atomicAdd(patch_list.header.after_occlusion, s_listed);
    }
}
