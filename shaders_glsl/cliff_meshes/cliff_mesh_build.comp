#version 460
#extension GL_GOOGLE_include_directive : require
// Procedural cliff meshes (effect cliff_meshes), built near the camera
// from the terrain the frame has resident: one thread per cell of the
// world grid within the radius. A cell is listed when any of its vertices
// is steeper than the threshold (slope from the bilinear height's central
// differences); its (CLIFF_CELL_QUADS + 1)^2 vertices are the height
// field pushed out along that normal by amplitude x ramp(slope) x noise,
// with their own normals from the displaced surface's central differences.
// Vertices depend only on their world position, so neighbouring cells
// share theirs bit for bit, and where the ramp is 0 a vertex lies on the
// height field: the mesh is watertight to it. The cells are those within
// the reach of a centre that snaps to a step of the radius, so the build
// holds while the camera stays in its step; rebuilt when it leaves it or
// the resident terrain changes. Each meshed (drawn) cell's bit in the
// terrain's sink (terrain_sink.glsl) pushes the height field there behind
// its mesh.
#include "constants.glsl"
#include "octahedral.glsl"
#include "hashed_noise.glsl"
#include "cliff_mesh.glsl"
#include "terrain_sink.glsl"

layout(local_size_x = 64) in;

layout(set = 0, binding = 1, std430) readonly buffer SectorData { uint words[]; } sector_data;
layout(set = 0, binding = 2) uniform texture2DArray height_atlas;
layout(set = 0, binding = 3) uniform sampler nearest;
layout(set = 0, binding = 4, std430) buffer CliffHeaderBlock { CliffHeader h; } header;
layout(set = 0, binding = 5, std430) buffer CliffVertices { CliffVertex v[]; } vertices;
// Its header and zeroed bits written by the host before the dispatch.
layout(set = 0, binding = 6, std430) buffer Sink { TerrainSinkHeader h; uint bits[]; } sink;

#define VISTA_SECTOR_WORD(i) sector_data.words[i]
#define VISTA_HEIGHT_ATLAS height_atlas
#define VISTA_NORMAL_ATLAS height_atlas
#define VISTA_ATLAS_SAMPLER nearest
#define VISTA_NO_MATERIAL_QUERY
#define VISTA_TERRAIN pc.terrain
#define VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"

layout(push_constant, std430) uniform CliffBuildPush {
    VistaTerrain terrain;
    ivec2 cell0;        // the square's first cell
    uint side;          // cells a side
    uint capacity;      // cells the vertex buffer holds
    float cell_m;
    float reach_m;      // cells whose centre lies this close to `centre`
    float cos_start;    // normal z where the push starts (the threshold)
    float cos_full;     // normal z where it is full
    float amplitude_m;
    float step_m;       // central differences' half step
    uint seed;
    uint pad;
    vec2 centre;        // world m
} pc;

#undef VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"

float height_at(vec2 p) {
    float h;
    vista_terrain_height(p, h);
    return h;
}

// The height field's normal at p from central differences.
vec3 ground_normal(vec2 p) {
    float e = pc.step_m;
    float dx = height_at(p + vec2(e, 0.0)) - height_at(p - vec2(e, 0.0));
    float dy = height_at(p + vec2(0.0, e)) - height_at(p - vec2(0.0, e));
    return normalize(vec3(-dx, -dy, 2.0 * e));
}

// 0 under the threshold slope, 1 past threshold + band.
float cliff_ramp(float nz) {
    return clamp((pc.cos_start - nz) / max(pc.cos_start - pc.cos_full, 1e-6), 0.0, 1.0);
}

// Smooth value noise in 0..1: two octaves of a bilinear lattice hash.
float lattice(vec2 p, float scale, uint seed) {
    vec2 q = p / scale;
    vec2 i = floor(q);
    vec2 f = q - i;
    f = f * f * (3.0 - 2.0 * f);
    float a = hash_cell(vec3(i, 0.0), seed), b = hash_cell(vec3(i + vec2(1.0, 0.0), 0.0), seed);
    float c = hash_cell(vec3(i + vec2(0.0, 1.0), 0.0), seed), d = hash_cell(vec3(i + vec2(1.0), 0.0), seed);
    return mix(mix(a, b, f.x), mix(c, d, f.x), f.y);
}

vec3 cliff_point(vec2 p) {
    vec3 n = ground_normal(p);
    float push = pc.amplitude_m * cliff_ramp(n.z) * (0.35 + 0.65 * lattice(p, 3.0, pc.seed) * 0.7 + 0.3 * lattice(p, 1.1, pc.seed + 1u));
    return vec3(p, height_at(p)) + n * push;
}

void main() {
    uint idx = gl_GlobalInvocationID.x;
    if (idx >= pc.side * pc.side) {
        return;
    }
    ivec2 cell = pc.cell0 + ivec2(idx % pc.side, idx / pc.side);
    vec2 origin = vec2(cell) * pc.cell_m;
    vec2 centre = origin + 0.5 * pc.cell_m;
    if (distance(centre, pc.centre) >= pc.reach_m) {
        return;
    }
    atomicAdd(header.h.tested, 1u);
    const uint SIDE = CLIFF_CELL_QUADS + 1u;
    float q = pc.cell_m / float(CLIFF_CELL_QUADS);
    // Vertices from integer lattice indices times one spacing: a vertex two
    // cells share is the same product in both, so the same bits for any
    // cell_m (cell * cell_m + k * q rounds differently on each side).
    ivec2 lattice0 = cell * int(CLIFF_CELL_QUADS);
    bool steep = false;
    for (uint k = 0u; k < SIDE * SIDE && !steep; ++k) {
        steep = cliff_ramp(ground_normal(vec2(lattice0 + ivec2(k % SIDE, k / SIDE)) * q).z) > 0.0;
    }
    if (!steep) {
        return;
    }
    uint slot = atomicAdd(header.h.instance_count, 1u);
    if (slot >= pc.capacity) {
        atomicAdd(header.h.overflow, 1u);
        atomicMin(header.h.instance_count, pc.capacity);
        return;
    }
    atomicOr(sink.bits[idx >> 5u], 1u << (idx & 31u));
    float e = 0.5 * q;
    for (uint k = 0u; k < SIDE * SIDE; ++k) {
        vec2 p = vec2(lattice0 + ivec2(k % SIDE, k / SIDE)) * q;
        vec3 tx = cliff_point(p + vec2(e, 0.0)) - cliff_point(p - vec2(e, 0.0));
        vec3 ty = cliff_point(p + vec2(0.0, e)) - cliff_point(p - vec2(0.0, e));
        vec3 n = normalize(cross(tx, ty));
        uvec2 code = oct_encode8(n);
        vertices.v[slot * SIDE * SIDE + k].p = vec4(cliff_point(p), uintBitsToFloat(code.x | (code.y << 8u)));
    }
}
