#version 460
#extension GL_GOOGLE_include_directive : require
// variants: HIZ
// Trees and bushes (effect vegetation): one thread per cluster (a cell of
// the instances' grid) tests its box, by the farthest draw distance of its
// types, the frustum and (HIZ) the pyramid; culled, its instances are never
// visited (counted as skipped). The workgroup then takes the instances of
// its clusters that may show, all its threads over each in turn. An instance is culled by its type's draw distance, by the frustum and (HIZ,
// effect occlusion, on this frame) by the depth pyramid, each test on the
// box around its bounding sphere (conservative: a culled instance covers
// no pixel); the rest go to the draw of their mesh kind at the LOD their
// distance picks (LOD 0 within lod0_m, 1 within lod1_m, 2 beyond: the
// crossed quads). The draws' first instances (set by the host) mark each
// draw's region of the visible list.
#include "constants.glsl"
#include "terrain_view.glsl"
#include "vegetation.glsl"

#define CULL_GROUP 64
layout(local_size_x = CULL_GROUP) in;

layout(set = 0, binding = 0, std430) readonly buffer View { TerrainView v; } view;
layout(set = 0, binding = 1, std430) readonly buffer VegInstances { VegetationInstance i[]; } instances;
layout(set = 0, binding = 2, std430) readonly buffer VegTypes { VegetationType t[]; } types;
layout(set = 0, binding = 3, std430) buffer VegHeader { VegetationHeader h; } header;
layout(set = 0, binding = 4, std430) buffer VegVisible { uint i[]; } visible;
layout(set = 0, binding = 7, std430) readonly buffer VegClusters { VegetationCluster c[]; } clusters;
#ifdef HIZ
layout(set = 0, binding = 5) uniform texture2D hiz;
layout(set = 0, binding = 6) uniform sampler nearest;
#include "hiz_test.glsl"
#endif

layout(push_constant, std430) uniform VegetationCullPush {
    uint count;        // clusters
    uint flags;        // VEG_FLAG_*
    float lod0_m;      // LOD 0 within this distance of the camera
    float lod1_m;      // LOD 1 within this one
    uvec2 depth_size;  // the depth target the pyramid was built from
    uint pad0;
    uint pad1;
} pc;

#include "frustum_box.glsl"

// Why a box around the camera-relative `lo`..`hi` cannot show: 0 it may,
// else the VEG_FLAG_* of the test that culls it.
uint box_culled(vec3 lo, vec3 hi, float draw_m) {
    // The box's nearest point: no farther than any sphere inside it.
    if ((pc.flags & VEG_FLAG_DISTANCE) != 0u && length(max(max(lo, -hi), vec3(0.0))) > draw_m) {
        return VEG_FLAG_DISTANCE;
    }
    if ((pc.flags & VEG_FLAG_FRUSTUM) != 0u && box_outside_frustum(lo, hi)) {
        return VEG_FLAG_FRUSTUM;
    }
#ifdef HIZ
    uint level;
    if ((pc.flags & VEG_FLAG_HIZ) != 0u && !hiz_box_visible(lo, hi, view.v.view_proj, pc.depth_size, level)) {
        return VEG_FLAG_HIZ;
    }
#endif
    return 0u;
}

void cull_instance(uint i) {
    atomicAdd(header.h.considered, 1u);
    // Member by member: a whole-struct load is OpCopyLogical, which naga cannot parse.
    uint ty = instances.i[i].type_id;
    float h = types.t[ty].height_m * instances.i[i].scale;
    // The sphere about the mesh's middle holds the crown (0.3 h across at
    // most) and the trunk's foot (0.05 h below the ground).
    vec3 foot = vec3(instances.i[i].x, instances.i[i].y, instances.i[i].z);
    vec3 centre = foot + vec3(0.0, 0.0, 0.45 * h) - view.v.camera_world.xyz;
    float r = 0.56 * h;
    float d = length(centre);
    if ((pc.flags & VEG_FLAG_DISTANCE) != 0u && d - r > types.t[ty].draw_m) {
        atomicAdd(header.h.culled_distance, 1u);
        return;
    }
    vec3 lo = centre - vec3(r), hi = centre + vec3(r);
    if ((pc.flags & VEG_FLAG_FRUSTUM) != 0u && box_outside_frustum(lo, hi)) {
        atomicAdd(header.h.culled_frustum, 1u);
        return;
    }
#ifdef HIZ
    uint level;
    if ((pc.flags & VEG_FLAG_HIZ) != 0u && !hiz_box_visible(lo, hi, view.v.view_proj, pc.depth_size, level)) {
        atomicAdd(header.h.culled_hiz, 1u);
        return;
    }
#endif
    uint lod = d < pc.lod0_m ? 0u : (d < pc.lod1_m ? 1u : 2u);
    uint draw = (types.t[ty].kind * VEG_LODS + lod) * 5u;
    uint slot = header.h.draws[draw + 4u] + atomicAdd(header.h.draws[draw + 1u], 1u);
    visible.i[slot] = i;
}

// This group's clusters that may show, and the counts of those culled.
shared uint group_visible[CULL_GROUP];
shared uint group_shown;
shared uint group_culled;
shared uint group_skipped;

void main() {
    if (gl_LocalInvocationIndex == 0u) {
        group_shown = 0u;
        group_culled = 0u;
        group_skipped = 0u;
    }
    barrier();
    uint k = gl_GlobalInvocationID.x;
    if (k < pc.count) {
        vec3 cam = view.v.camera_world.xyz;
        if (box_culled(clusters.c[k].lo.xyz - cam, clusters.c[k].hi.xyz - cam, clusters.c[k].lo.w) != 0u) {
            atomicAdd(group_culled, 1u);
            atomicAdd(group_skipped, clusters.c[k].count);
        } else {
            group_visible[atomicAdd(group_shown, 1u)] = k;
        }
    }
    barrier();
    if (gl_LocalInvocationIndex == 0u && group_culled > 0u) {
        atomicAdd(header.h.clusters_culled, group_culled);
        atomicAdd(header.h.skipped, group_skipped);
    }
    // The whole group takes the instances of each cluster that may show.
    for (uint v = 0u; v < group_shown; ++v) {
        uint c = group_visible[v];
        uint first = clusters.c[c].first;
        uint end = first + clusters.c[c].count;
        for (uint i = first + gl_LocalInvocationIndex; i < end; i += gl_WorkGroupSize.x) {
            cull_instance(i);
        }
    }
}
