#version 460
#extension GL_GOOGLE_include_directive : require
// variants: ENGINE_GBUFFER
// Grass into the G-buffer (effect grass): albedo darkened towards the root
// (the tuft's own occlusion), the ground's normal bent to the blade's
// facing, a rough surface, and the material target marked GBUFFER_GRASS
// with the ground's material id. lighting_resolve lights it as terrain.
#include "constants.glsl"
#include "octahedral.glsl"

layout(location = 0) in vec3 colour;
layout(location = 1) in float along;
layout(location = 2) in vec3 normal;
layout(location = 3) flat in uint material;
#ifdef ENGINE_GBUFFER
// Output `gbuffer`: the engine's layout (engine_gbuffer.glsl).
#include "engine_gbuffer.glsl"
#else
layout(location = 0) out vec4 gb_albedo;
layout(location = 1) out vec4 gb_normal;
layout(location = 2) out uvec2 gb_material;
#endif

void main() {
    vec3 albedo = colour * mix(0.55, 1.1, along);
    vec3 n = normalize(normal);
    const float roughness = 0.85;
#ifdef ENGINE_GBUFFER
    write_engine_gbuffer(albedo, n, roughness, material);
#else
    gb_albedo = vec4(albedo, 1.0);
    gb_normal = vec4(oct_encode(n), roughness, 1.0);
    gb_material = uvec2(material, GBUFFER_GRASS);
#endif
}
