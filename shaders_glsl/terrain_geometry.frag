#version 460
#extension GL_GOOGLE_include_directive : require
// variants: LIGHTING
// Until the G-buffer tile passes exist: the node's baked albedo, lit by sun
// and sky ambient from the baked normal (variant LIGHTING, the `lighting`
// effect), or unlit albedo without it (no normal atlas is bound or kept).
#include "terrain_view.glsl"

layout(set = 0, binding = 0, std430) readonly buffer View { TerrainView v; } view;
layout(set = 0, binding = 3) uniform texture2DArray albedo_atlas;
#ifdef LIGHTING
layout(set = 0, binding = 5) uniform texture2DArray normal_atlas;
#endif
layout(set = 0, binding = 6) uniform sampler linear_clamp;

layout(location = 0) in vec2 atlas_uv;
layout(location = 1) flat in uint atlas_layer;
layout(location = 0) out vec4 color;

void main() {
    vec3 uvw = vec3(atlas_uv, float(atlas_layer));
    vec3 albedo = texture(sampler2DArray(albedo_atlas, linear_clamp), uvw).rgb;
#ifdef LIGHTING
    // Baked as n * 127.5 + 127.5 in 8 bits: UNORM u = n / 2 + 1 / 2.
    vec2 nxy = texture(sampler2DArray(normal_atlas, linear_clamp), uvw).xy * 2.0 - 1.0;
    vec3 nrm = normalize(vec3(nxy, sqrt(max(1.0 - dot(nxy, nxy), 0.0))));
    vec3 light = view.v.sun_color.rgb * max(dot(nrm, view.v.sun_dir.xyz), 0.0)
               + view.v.sky_color.rgb * (0.5 + 0.5 * nrm.z);
    vec3 lit = albedo * light;
#else
    vec3 lit = albedo;
#endif
    // Display encoding: the target is UNORM, written gamma-encoded.
    color = vec4(pow(clamp(lit, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
}
