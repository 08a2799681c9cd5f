#version 460
#extension GL_GOOGLE_include_directive : require
// variants: LIGHTING
// The lit output of the tools and tests (an engine lights the G-buffer
// itself): sun plus sky ambient on the G-buffer's albedo and normal
// (variant LIGHTING, the `lighting` effect; without it, unlit albedo).
// Writes linear HDR radiance and the display image (clipped to [0, 1] and
// gamma-encoded). Stencil-tested: the background keeps the clear colour.
#include "terrain_view.glsl"
#include "octahedral.glsl"

layout(set = 0, binding = 0, std430) readonly buffer View { TerrainView v; } view;
layout(set = 0, binding = 1) uniform texture2D gb_albedo;
layout(set = 0, binding = 2) uniform texture2D gb_normal;
layout(set = 0, binding = 3) uniform sampler nearest;

layout(location = 0) out vec4 display;
layout(location = 1) out vec4 hdr;

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    // The albedo target is sRGB: texelFetch returns linear values.
    vec3 albedo = texelFetch(sampler2D(gb_albedo, nearest), px, 0).rgb;
    // The "lighting only" view: a uniform albedo.
    if (view.v.shade_flags.w != 0u) {
        albedo = vec3(uintBitsToFloat(view.v.shade_flags.w));
    }
#ifdef LIGHTING
    vec3 n = oct_decode(texelFetch(sampler2D(gb_normal, nearest), px, 0).xy);
    vec3 light = view.v.sun_color.rgb * max(dot(n, view.v.sun_dir.xyz), 0.0)
               + view.v.sky_color.rgb * (0.5 + 0.5 * n.z);
    vec3 lit = albedo * light;
#else
    vec3 lit = albedo;
#endif
    hdr = vec4(lit, 1.0);
    display = vec4(pow(clamp(lit, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
}
