#version 460
#extension GL_GOOGLE_include_directive : require
// variants: LIGHTING
// The lit output of the tools and tests (an engine lights the G-buffer
// itself): sun plus sky ambient on the G-buffer's albedo and normal
// (variant LIGHTING, the `lighting` effect; without it, unlit albedo).
// Writes linear HDR radiance and the display image: exposed and through the
// scene's tonemapper (render/tonemap.rs; the unlit albedo view is clipped).
// Stencil-tested: the background keeps the clear colour.
#include "terrain_view.glsl"
#include "octahedral.glsl"

// Stephen Hill's fit of the ACES RRT + sRGB ODT (render/tonemap.rs): into
// the RRT's input space (sRGB to AP1 with the RRT's saturation), a rational
// fit per channel, back to linear sRGB. The published rows fill the
// matrices' columns, so `v * m` (a row vector) is the published `m v`.
vec3 aces_fitted(vec3 c) {
    const mat3 to_rrt = mat3(0.59719, 0.35458, 0.04823,
                             0.07600, 0.90834, 0.01566,
                             0.02840, 0.13383, 0.83777);
    const mat3 from_odt = mat3(1.60475, -0.53108, -0.07367,
                               -0.10208, 1.10813, -0.00605,
                               -0.00327, -0.07276, 1.07602);
    vec3 v = c * to_rrt;
    vec3 fit = (v * (v + 0.0245786) - 0.000090537) / (v * (0.983729 * v + 0.4329510) + 0.238081);
    return clamp(fit * from_odt, 0.0, 1.0);
}

vec3 srgb_encode(vec3 c) {
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}

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
#ifdef LIGHTING
    vec3 exposed = lit * view.v.image.x;
    if (view.v.image.y == 1.0) {
        display = vec4(srgb_encode(aces_fitted(exposed)), 1.0);
        return;
    }
    display = vec4(pow(clamp(exposed, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
#else
    display = vec4(pow(clamp(lit, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
#endif
}
