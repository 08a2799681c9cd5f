#version 460
#extension GL_GOOGLE_include_directive : require
// variants: LIGHTING SHADOWS ATMOSPHERE HDR_OUTPUT
// The lit output of the tools and tests (an engine lights the G-buffer
// itself): sun plus sky ambient on the G-buffer's albedo and normal
// (variant LIGHTING, the `lighting` effect; without it, unlit albedo).
// Writes linear HDR radiance and the display image: exposed and through the
// scene's tonemapper (scene/tonemap.rs; the unlit albedo view is clipped).
// With SHADOWS (the `shadows` effect), the sun term is scaled by how much
// of the sun the pixel sees: its height against the bilinear threshold of
// the finest resident node's shadow texture (sun_shadow.glsl), at a
// silhouette pixel the one of the surface in front (silhouette.glsl).
// With ATMOSPHERE (the `atmosphere` effect), the terrain is seen through
// the height fog of atmosphere.glsl and the background is its sky; without
// it the pass is depth-tested to terrain pixels and the background keeps the clear colour.
// SHADOWS and ATMOSPHERE need LIGHTING. Output `lit` writes the display
// image and vista's own HDR image; HDR_OUTPUT (output `hdr`) writes only
// the linear radiance, into the engine's float target. A pixel vista drew
// nothing into (the engine's own, under a loaded depth) is left as is.
#include "terrain_view.glsl"
#include "octahedral.glsl"
#include "srgb.glsl"

// Stephen Hill's fit of the ACES RRT + sRGB ODT (scene/tonemap.rs): into
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


layout(set = 0, binding = 0, std430) readonly buffer View { TerrainView v; } view;
layout(set = 0, binding = 1) uniform texture2D gb_albedo;
layout(set = 0, binding = 2) uniform texture2D gb_normal;
layout(set = 0, binding = 3) uniform sampler nearest;
// x material id, y the flavour bits shaded or GBUFFER_GRASS/ASSET: 0 where
// vista drew nothing.
layout(set = 0, binding = 8) uniform utexture2D gb_material;
// 1: the display target is sRGB (the hardware encodes on store).
layout(constant_id = 0) const uint DISPLAY_SRGB_TARGET = 0u;
// 1: the atmosphere's sky fills the background (output `hdr` may leave it).
layout(constant_id = 1) const uint SKY = 1u;

layout(set = 0, binding = 4) uniform texture2D depth_target;
#if defined(SHADOWS) || defined(ATMOSPHERE)
#define NEEDS_POSITION
#include "reconstruct.glsl"
#define VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"
#undef VISTA_TERRAIN_DECLARE_ONLY
// shadow: x the penumbra's height per metre of occluder distance, y the
// shadow texture's side; fog, haze, zenith: atmosphere.glsl's parameters.
layout(push_constant, std430) uniform LightingPush {
    VistaTerrain terrain;
    vec4 shadow;
    vec4 fog;
    vec4 haze;
    vec4 zenith;
} pc;
#endif

#ifdef SHADOWS
#include "shadows/sun_shadow.glsl"
layout(set = 0, binding = 5, std430) readonly buffer SectorData { uint words[]; } sector_data;
layout(set = 0, binding = 6) uniform texture2DArray height_atlas;
layout(set = 0, binding = 7) uniform texture2DArray shadow_atlas;

#define VISTA_SECTOR_WORD(i) sector_data.words[i]
#define VISTA_HEIGHT_ATLAS height_atlas
#define VISTA_NORMAL_ATLAS height_atlas
#define VISTA_ATLAS_SAMPLER nearest
#define VISTA_NO_MATERIAL_QUERY
#define VISTA_TERRAIN pc.terrain
#include "terrain_sample.glsl"

#define VISTA_SILHOUETTE_DEPTH(q) texelFetch(sampler2D(depth_target, nearest), q, 0).r
#include "silhouette.glsl"

vec2 shadow_texel(ivec2 t, uint slot) {
    return texelFetch(sampler2DArray(shadow_atlas, nearest), ivec3(t, int(slot)), 0).rg;
}

// How much of the sun the ground under `p` (world metres) sees: 1 where no
// resident node covers it. The ground, not the pixel's drawn height: the
// threshold is relative to the finest resident ground, from which a
// coarser patch drawn there strays by up to its LOD error.
float sun_seen(vec3 p) {
    VistaNodeHit hit = vista_find_node(p.xy);
    if (!hit.found) {
        return 1.0;
    }
    int last = int(pc.shadow.y) - 1;
    vec2 f = hit.local * (float(last) / 128.0);
    ivec2 i0 = min(ivec2(floor(f)), ivec2(last - 1));
    vec2 w = f - vec2(i0);
    vec2 a = mix(shadow_texel(i0, hit.slot), shadow_texel(i0 + ivec2(1, 0), hit.slot), w.x);
    vec2 b = mix(shadow_texel(i0 + ivec2(0, 1), hit.slot), shadow_texel(i0 + ivec2(1, 1), hit.slot), w.x);
    vec2 s = mix(a, b, w.y);
    return sun_visibility(0.0, s.x, s.y, pc.shadow.x);
}
#endif

#ifdef ATMOSPHERE
#include "atmosphere/atmosphere.glsl"
#endif

#ifdef HDR_OUTPUT
layout(location = 0) out vec4 hdr;
#else
layout(location = 0) out vec4 display;
layout(location = 1) out vec4 hdr;

// The display encoding of linear radiance `lit`.
vec3 display_encoded(vec3 lit) {
#ifdef LIGHTING
    vec3 exposed = lit * view.v.image.x;
    if (view.v.image.y == 1.0) {
        return srgb_encode(aces_fitted(exposed));
    }
    return pow(clamp(exposed, 0.0, 1.0), vec3(1.0 / 2.2));
#else
    return pow(clamp(lit, 0.0, 1.0), vec3(1.0 / 2.2));
#endif
}
#endif

// Writes the linear radiance and (output `lit`) its display encoding.
void emit(vec3 lit) {
    hdr = vec4(lit, 1.0);
#ifndef HDR_OUTPUT
    vec3 encoded = display_encoded(lit);
    // A variable, not a constant expression: naga reads no SpecConstantOp.
    uint srgb_target = DISPLAY_SRGB_TARGET;
    display = vec4(srgb_target != 0u ? srgb_decode(encoded) : encoded, 1.0);
#endif
}

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    float depth = texelFetch(sampler2D(depth_target, nearest), px, 0).r;
    // The pass's depth test is NOT_EQUAL: a fragment at the stored depth
    // fails it and leaves the pixel as it is (naga reads no discard, which
    // glslang makes a demote). So vista's pixels pass at depth 0, the
    // background (stored 0) passes at 1 where the atmosphere draws the sky,
    // and the engine's own pixels under its loaded depth, which vista did
    // not draw into, fail at their own depth.
    bool vista_drew = texelFetch(usampler2D(gb_material, nearest), px, 0).y != 0u;
    bool sky = false;
#ifdef ATMOSPHERE
    // A variable, not a constant expression: naga reads no SpecConstantOp.
    uint sky_on = SKY;
    sky = depth == 0.0 && sky_on != 0u;
#endif
    gl_FragDepth = sky ? 1.0 : (vista_drew ? 0.0 : depth);
    if (!sky && !vista_drew) {
        return;
    }
#ifdef ATMOSPHERE
    vec3 view_dir = normalize(eye_ray(view.v.inv_view_proj, gl_FragCoord.xy, view.v.viewport));
    vec3 scatter = fog_inscatter(pc.fog, pc.haze.rgb, view_dir, view.v.sun_dir.xyz, view.v.sun_color.rgb,
                                 view.v.sky_color.rgb);
    // Reversed-Z: the background keeps the clear depth 0.
    if (sky) {
        float t = fog_sky_transmittance(pc.fog, pc.zenith.w, view.v.camera_world.xyz, view_dir);
        emit(pc.zenith.rgb * t + scatter * (1.0 - t));
        return;
    }
#endif
    // The albedo target is sRGB: texelFetch returns linear values.
    vec3 albedo = texelFetch(sampler2D(gb_albedo, nearest), px, 0).rgb;
    // The "lighting only" view: a uniform albedo.
    if (view.v.shade_flags.w != 0u) {
        albedo = vec3(uintBitsToFloat(view.v.shade_flags.w));
    }
#ifdef NEEDS_POSITION
    vec3 rel = reconstruct_position(view.v.inv_view_proj, gl_FragCoord.xy, view.v.viewport, depth);
#endif
#ifdef LIGHTING
    vec3 n = oct_decode(texelFetch(sampler2D(gb_normal, nearest), px, 0).xy);
    float sun = max(dot(n, view.v.sun_dir.xyz), 0.0);
#ifdef SHADOWS
    // A silhouette pixel's position lies past the horizon, often in the
    // crest's own shadow: the sun it sees is the surface's in front. Where
    // the pixel turns from the sun neither matters.
    if (sun > 0.0) {
        ivec2 front[3];
        ivec2 source = silhouette_sources(px, depth, front) > 0 ? front[0] : px;
        vec3 shadow_at = source == px ? rel
            : reconstruct_position(view.v.inv_view_proj, vec2(source) + 0.5, view.v.viewport, VISTA_SILHOUETTE_DEPTH(source));
        sun *= sun_seen(view.v.camera_world.xyz + shadow_at);
    }
#endif
    vec3 light = view.v.sun_color.rgb * sun
               + view.v.sky_color.rgb * (0.5 + 0.5 * n.z);
    vec3 lit = albedo * light;
#else
    vec3 lit = albedo;
#endif
#ifdef ATMOSPHERE
    float t = exp(-fog_optical_depth(pc.fog, view.v.camera_world.xyz, view.v.camera_world.xyz + rel));
    lit = lit * t + scatter * (1.0 - t);
#endif
    emit(lit);
}
