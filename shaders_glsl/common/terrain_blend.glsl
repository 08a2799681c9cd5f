// Assets grounded in the terrain (seed 000: "we want rocks, trees and grass
// to blend with, and be grounded in, the terrain"): an asset's vertex near
// the ground takes the terrain's normal and colour at its position, so a
// rock's foot continues the ground's shading instead of cutting a line
// into it. This is the include an engine's own asset shaders use
// (asset_draw.vert is the example):
//
//   #define VISTA_SECTOR_WORD(i)  sector_data.words[i]   (terrain_sample.glsl's
//   #define VISTA_HEIGHT_ATLAS ... VISTA_TERRAIN          macros, see there)
//   #define VISTA_NO_MATERIAL_QUERY                       (unless a splat atlas is bound)
//   #define VISTA_ALBEDO_ATLAS    albedo_atlas
//   #define VISTA_LINEAR_SAMPLER  linear_clamp
//   #include "terrain_sample.glsl"
//   #include "terrain_blend.glsl"
//   ...
//   VistaBlend b = vista_blend_to_terrain(world_pos, normal, albedo, 0.6);
//   // b.normal, b.albedo: what the vertex passes on; b.weight: how much
//   // of the terrain it took (1 on the ground, 0 from 0.6 m above it).
//
// Per vertex, so the blend is as fine as the asset's mesh near the ground.
// Where no terrain is found (outside the world or nothing resident) the
// vertex keeps its own.
#ifndef VISTA_TERRAIN_BLEND_GLSL
#define VISTA_TERRAIN_BLEND_GLSL

struct VistaBlend {
    vec3 normal;   // unit
    vec3 albedo;   // linear RGB
    float weight;  // the terrain's share, 0..1
};

// `world_pos` in world metres (z up), `normal` unit; the blend fades out
// smoothly over `blend_height_m` above the ground (below it: full).
VistaBlend vista_blend_to_terrain(vec3 world_pos, vec3 normal, vec3 albedo, float blend_height_m) {
    float ground;
    vec3 n;
    vec3 colour;
    if (!vista_terrain_height(world_pos.xy, ground) || !vista_terrain_normal(world_pos.xy, n)
        || !vista_terrain_albedo(world_pos.xy, colour)) {
        return VistaBlend(normal, albedo, 0.0);
    }
    float w = 1.0 - smoothstep(0.0, max(blend_height_m, 1e-6), world_pos.z - ground);
    vec3 blended = mix(normal, n, w);
    float l = length(blended);
    // Opposite normals cancel: keep the terrain's where they do.
    return VistaBlend(l > 1e-4 ? blended / l : n, mix(albedo, colour, w), w);
}

#endif
