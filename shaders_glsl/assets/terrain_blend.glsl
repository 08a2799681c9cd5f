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
// The terrain's colour is its baked albedo (vista_terrain_albedo, the far
// atlas's) unless the includer defines VISTA_BLEND_COLOUR(p) (a vec3 at
// world point p) first: asset_draw.vert's MATERIALS variant gives the
// splat blend, the colour the near ground is shaded with.
//
// Per vertex, so the blend is as fine as the asset's mesh near the ground.
// Where no terrain is found (outside the world or nothing resident) the
// vertex keeps its own.
#ifndef VISTA_TERRAIN_BLEND_GLSL
#define VISTA_TERRAIN_BLEND_GLSL

#ifndef VISTA_BLEND_COLOUR
vec3 vista_blend_atlas_colour(vec2 p) {
    vec3 c;
    vista_terrain_albedo(p, c);
    return c;
}
#define VISTA_BLEND_COLOUR(p) vista_blend_atlas_colour(p)
#endif

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
    if (!vista_terrain_height(world_pos.xy, ground) || !vista_terrain_normal(world_pos.xy, n)) {
        return VistaBlend(normal, albedo, 0.0);
    }
    vec3 colour = VISTA_BLEND_COLOUR(world_pos.xy);
    float w = 1.0 - smoothstep(0.0, max(blend_height_m, 1e-6), world_pos.z - ground);
    vec3 blended = mix(normal, n, w);
    float l = length(blended);
    // Opposite normals cancel: keep the terrain's where they do.
    return VistaBlend(l > 1e-4 ? blended / l : n, mix(albedo, colour, w), w);
}

#endif
