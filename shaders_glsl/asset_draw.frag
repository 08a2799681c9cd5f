#version 460
#extension GL_GOOGLE_include_directive : require
// The example assets into the G-buffer: the blended albedo and normal, a
// rough surface, the material target marked GBUFFER_ASSET.
#include "constants.glsl"
#include "octahedral.glsl"

layout(location = 0) in vec3 albedo;
layout(location = 1) in vec3 normal;
layout(location = 0) out vec4 gb_albedo;
layout(location = 1) out vec4 gb_normal;
layout(location = 2) out uvec2 gb_material;

void main() {
    gb_albedo = vec4(albedo, 1.0);
    gb_normal = vec4(oct_encode(normalize(normal)), 0.8, 1.0);
    gb_material = uvec2(0u, GBUFFER_ASSET);
}
