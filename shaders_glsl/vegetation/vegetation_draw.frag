#version 460
#extension GL_GOOGLE_include_directive : require
// variants: ENGINE_GBUFFER
// Trees and bushes into the G-buffer: the blended albedo and normal, a
// rough surface, the material target marked GBUFFER_ASSET (lit as the
// assets are). Both faces: the far LOD's crossed quads are seen from either
// side, their normal turned towards the viewer.
#include "constants.glsl"
#include "octahedral.glsl"

layout(location = 0) in vec3 albedo;
layout(location = 1) in vec3 normal;
#ifdef ENGINE_GBUFFER
#include "engine_gbuffer.glsl"
#else
layout(location = 0) out vec4 gb_albedo;
layout(location = 1) out vec4 gb_normal;
layout(location = 2) out uvec2 gb_material;
#endif

void main() {
    vec3 n = normalize(normal);
    n = gl_FrontFacing ? n : vec3(-n.xy, n.z);
    const float roughness = 0.9;
#ifdef ENGINE_GBUFFER
    write_engine_gbuffer(albedo, n, roughness, 0u);
#else
    gb_albedo = vec4(albedo, 1.0);
    gb_normal = vec4(oct_encode(n), roughness, 1.0);
    gb_material = uvec2(0u, GBUFFER_ASSET);
#endif
}
