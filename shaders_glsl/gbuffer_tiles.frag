#version 460
#extension GL_GOOGLE_include_directive : require
// variants: MATERIALS CONTROL_MAP VIRTUAL_TEXTURE ENGINE_GBUFFER
// Shades the tiles of one variant into the G-buffer. The variant's flavour
// bits are a specialization constant, so each pipeline contains only the
// flavours its tiles need; per pixel, the flavours are weighted by the
// shared rule (shade_rules.glsl) restricted to the pixel's own
// classification bits, so a tiled variant and the all-flavour pipeline give
// the same pixel. Position and derivatives come from depth and the
// triangle normal (reconstruct.glsl); materials from the splat map of the
// finest resident node (terrain_sample.glsl); a silhouette pixel takes its
// geometric normal from the surface in front of the edge (silhouette.glsl).
// Without MATERIALS (no splat or cliffs effect) only the far atlas flavour
// exists and no material resource is bound or built. CONTROL_MAP: the
// control-map flavour (seed 004, control_surface.glsl) instead of splat,
// with its own atlas and texture table over the same detail textures.
// ENGINE_GBUFFER (output `gbuffer`): the surface goes into the engine's
// own G-buffer layout (engine_gbuffer.glsl) instead of vista's. A pixel
// the geometry pass did not classify (the engine's own, under a loaded
// depth) is left as the engine wrote it.
#include "terrain_view.glsl"
#include "octahedral.glsl"
#include "atlas_texels.glsl"
#include "shade_rules.glsl"
#include "reconstruct.glsl"
#include "hashed_noise.glsl"
#include "materials/materials.glsl"
#include "tile_lists.glsl"

layout(constant_id = 0) const uint VARIANT_BITS = 0u;
// 1: evaluate every flavour of the variant at every pixel, weighted by its
// share even where that is 0 (the "one shader doing everything" baseline of
// `vista bench shade`); 0: skip the flavours a pixel does not need.
layout(constant_id = 1) const uint EVERY_FLAVOUR = 0u;

layout(set = 0, binding = 0, std430) readonly buffer View { TerrainView v; } view;
layout(set = 0, binding = 2) uniform texture2D depth_target;
layout(set = 0, binding = 3) uniform utexture2D classification;
layout(set = 0, binding = 4) uniform utexture2D normals;
layout(set = 0, binding = 5, std430) readonly buffer SectorData { uint words[]; } sector_data;
layout(set = 0, binding = 6) uniform texture2DArray albedo_atlas;
layout(set = 0, binding = 7) uniform texture2DArray normal_atlas;
#ifdef MATERIALS
layout(set = 0, binding = 8) uniform utexture2DArray splat_atlas;
layout(set = 0, binding = 9, std430) readonly buffer Materials { TerrainMaterial m[]; } materials;
#define VISTA_SPLAT_ATLAS splat_atlas
#else
#define VISTA_NO_MATERIAL_QUERY
#endif
#if defined(MATERIALS) || defined(CONTROL_MAP)
#define DETAIL_TEXTURES 1
layout(set = 0, binding = 10) uniform texture2DArray detail_albedo;
layout(set = 0, binding = 11) uniform texture2DArray detail_normal;
layout(set = 0, binding = 12) uniform texture2DArray detail_height;
layout(set = 0, binding = 15) uniform sampler detail_sampler;
#endif
#ifdef CONTROL_MAP
layout(set = 0, binding = 17) uniform utexture2DArray control_atlas;
layout(set = 0, binding = 18, std430) readonly buffer ControlTable {
    float uv_scales[8];   // by UV scale code (0: 1, the textures' own)
    float thresholds[8];  // by slope threshold code (0: unused, the background's own)
    ControlTexture t[CONTROL_TEXTURES];
} control;
#endif
#ifdef VIRTUAL_TEXTURE
layout(set = 0, binding = 19, std430) readonly buffer VtState { uint words[]; } vt_state;
layout(set = 0, binding = 20) uniform texture2D vt_albedo;
layout(set = 0, binding = 21) uniform texture2D vt_detail;
#define VISTA_VT_WORD(i) vt_state.words[i]
#include "virtual_texture/virtual_texture.glsl"
#endif
layout(set = 0, binding = 13) uniform sampler nearest;
layout(set = 0, binding = 14) uniform sampler linear_clamp;
layout(set = 0, binding = 16) uniform texture2DArray height_atlas;

#define VISTA_SILHOUETTE_DEPTH(q) texelFetch(sampler2D(depth_target, nearest), q, 0).r
#define VISTA_SILHOUETTE_NORMAL(q) oct_decode8(texelFetch(usampler2D(normals, nearest), q, 0).xy)
#include "silhouette.glsl"

#define VISTA_SECTOR_WORD(i) sector_data.words[i]
#define VISTA_HEIGHT_ATLAS height_atlas
#define VISTA_NORMAL_ATLAS normal_atlas
#define VISTA_ATLAS_SAMPLER nearest
#define VISTA_TERRAIN pc.terrain
#define VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"

layout(push_constant, std430) uniform TileDrawPush { TilePush p; VistaTerrain terrain; } pc;

#undef VISTA_TERRAIN_DECLARE_ONLY
#include "terrain_sample.glsl"

#ifdef ENGINE_GBUFFER
#include "engine_gbuffer.glsl"
#else
layout(location = 0) out vec4 gb_albedo;    // rgb albedo (sRGB target)
layout(location = 1) out vec4 gb_normal;    // xy octahedral shading normal, z roughness
layout(location = 2) out uvec2 gb_material; // x material id, y flavour bits shaded
#endif


struct Surface {
    vec3 albedo;
    vec3 normal;   // world space
    float roughness;
};


#ifdef DETAIL_TEXTURES
#include "materials/splat_blend.glsl"

// Plane coordinates of tri-planar projection `p` (0: x axis, 1: y, 2: z).
vec2 project(vec3 v, int p) {
    return p == 0 ? v.yz : (p == 1 ? v.xz : v.xy);
}

// The detail normal of projection `p` applied to the geometric normal.
vec3 perturb(vec3 ng, vec2 tangent, int p) {
    if (p == 0) {
        return vec3(ng.x, ng.y + tangent.x, ng.z + tangent.y);
    } else if (p == 1) {
        return vec3(ng.x + tangent.x, ng.y, ng.z + tangent.y);
    }
    return vec3(ng.xy + tangent, ng.z);
}

#endif

Surface far_atlas(vec3 world, vec3 ng) {
    VistaNodeHit hit = vista_find_node(world.xy);
    if (!hit.found) {
        return Surface(vec3(0.3), ng, 0.8);
    }
    vec3 uvw = vec3(atlas_texel_uv(hit.local), float(hit.slot));
    vec3 albedo = texture(sampler2DArray(albedo_atlas, linear_clamp), uvw).rgb;
    float smoothness = atlas_smoothness(texture(sampler2DArray(normal_atlas, linear_clamp), uvw));
    return Surface(albedo, ng, 1.0 - smoothness);
}

#ifdef MATERIALS
// Full splat (splat_blend.glsl) around the geometric normal.
Surface splat_surface(vec3 world, vec3 ng, vec3 ddx, vec3 ddy, out uint dominant) {
    SplatBlend b = splat_blend(world.xy, ddx.xy, ddy.xy);
    dominant = b.dominant;
    return Surface(b.albedo, normalize(vec3(ng.xy + b.tangent, ng.z)), b.roughness);
}

// Index picked by uniform `u` in proportion to `w` (which sums to 1).
int pick(vec4 w, float u) {
    float c = 0.0;
    for (int k = 0; k < 3; ++k) {
        c += w[k];
        if (u < c) {
            return k;
        }
    }
    return 3;
}

// Tri-planar cliff shading. Near: every projection, one material picked
// stochastically (3 material samples). Far: one material and one projection
// picked stochastically, at two tiling scales blended by distance (2
// samples). Not stochastic: every material and projection blended (the
// reference the stochastic paths converge to over hash seeds).
Surface cliff_surface(vec3 world, vec3 ng, vec3 ddx, vec3 ddy, bool far_cliff, float depth_m, inout uint dominant) {
    uint ids[4];
    vec4 bil;
    splat_texels(world.xy, ids, bil);
    vec3 tw = pow(abs(ng), vec3(4.0));
    tw /= (tw.x + tw.y + tw.z);
    bool stochastic = view.v.shade_flags.z != 0u;
    float footprint = max(length(ddx), length(ddy));
    float u_material = hashed_uniform(world, footprint, view.v.shade_slope.w, view.v.shade_flags.y, 0u);
    float u_projection = hashed_uniform(world, footprint, view.v.shade_slope.w, view.v.shade_flags.y, 1u);
    float coarse = far_cliff ? ramp(depth_m, view.v.shade_bands.z, view.v.shade_bands.z * view.v.shade_slope.z) : 0.0;
    int picked = pick(bil, u_material);
    dominant = ids[picked];
    int kp = pick(vec4(tw, 0.0), u_projection);
    Surface s = Surface(vec3(0.0), vec3(0.0), 0.0);
    for (int k = 0; k < 4; ++k) {
        float wm = stochastic ? (k == picked ? 1.0 : 0.0) : bil[k];
        if (wm <= 0.0) {
            continue;
        }
        for (int p = 0; p < 3; ++p) {
            float wp = (stochastic && far_cliff) ? (p == kp ? 1.0 : 0.0) : tw[p];
            if (wp <= 0.0) {
                continue;
            }
            vec2 plane = project(world, p), dx = project(ddx, p), dy = project(ddy, p);
            for (int scale = 0; scale < 2; ++scale) {
                float ws = scale == 0 ? 1.0 - coarse : coarse;
                if (ws <= 0.0) {
                    continue;
                }
                Texel t = sample_material(ids[k], plane, dx, dy, scale == 0 ? 1.0 : 1.0 / view.v.shade_slope.z);
                float w = wm * wp * ws;
                s.albedo += w * t.albedo;
                s.normal += w * perturb(ng, t.tangent, p);
                s.roughness += w * t.roughness;
            }
        }
    }
    s.normal = normalize(s.normal);
    return s;
}

#endif

#ifdef CONTROL_MAP
#include "materials/control_surface.glsl"
#endif

#ifdef VIRTUAL_TEXTURE
// Bilinear by hand around `c` (texels, relative to `corner`): the weights
// come from the page's own coordinates, so a page filters to the same
// value in whichever tile it was cached (which tile depends on when its
// request came back; the sampler's weights would follow the cache's
// absolute coordinates and differ in the last bit from tile to tile).
vec4 vt_bilinear(texture2D t, ivec2 corner, vec2 c) {
    vec2 f = floor(c);
    vec2 w = c - f;
    ivec2 i = corner + ivec2(f);
    vec4 a = mix(texelFetch(sampler2D(t, nearest), i, 0), texelFetch(sampler2D(t, nearest), i + ivec2(1, 0), 0), w.x);
    vec4 b = mix(texelFetch(sampler2D(t, nearest), i + ivec2(0, 1), 0),
                 texelFetch(sampler2D(t, nearest), i + ivec2(1, 1), 0), w.x);
    return mix(a, b, w.y);
}

// The cached page texels at `xy` of `level`, or of the nearest coarser
// level resident (false: none is, not even level 0).
bool vt_fetch(VtSub s, vec2 xy, uint level, out vec4 albedo, out vec4 detail) {
    uvec2 corner;
    vec2 local;
    uint found;
    if (!vt_find_tile(s, xy, level, corner, local, found)) {
        return false;
    }
    // Texel centres at half-integers, as the sampler's.
    albedo = vt_bilinear(vt_albedo, ivec2(corner), local - 0.5);
    detail = vt_bilinear(vt_detail, ivec2(corner), local - 0.5);
    // The material id is not filtered: the nearest texel's.
    detail.z = texelFetch(sampler2D(vt_detail, nearest), ivec2(corner) + ivec2(floor(local)), 0).z;
    return true;
}

// The virtual texture's material (the splat blend cached in pages),
// trilinear between the two levels the footprint falls between; `served`
// is false where no page covers the point (the caller falls back to the
// far atlas, seed 001's low-resolution callback).
Surface vt_surface(vec3 world, vec3 ng, vec3 ddx, vec3 ddy, out uint material, out bool served) {
    material = 0u;
    served = false;
    VtSub s = vt_sub_texture(world.xy);
    if (!s.valid) {
        return Surface(vec3(0.0), ng, 1.0);
    }
    float level = clamp(vt_level(max(length(ddx.xy), length(ddy.xy)), s.region_m), 0.0, float(s.k));
    uint fine = uint(ceil(level));
    uint coarse = uint(floor(level));
    vec4 a0, d0, a1, d1;
    if (!vt_fetch(s, world.xy, fine, a0, d0)) {
        return Surface(vec3(0.0), ng, 1.0);
    }
    served = true;
    float t = float(fine) - level;
    if (coarse != fine && t > 0.0 && vt_fetch(s, world.xy, coarse, a1, d1)) {
        a0 = mix(a0, a1, t);
        d0.xy = mix(d0.xy, d1.xy, t);
    }
    material = uint(d0.z * 255.0 + 0.5);
    vec2 tangent = (d0.xy - 0.5) * 4.0;
    return Surface(a0.rgb * a0.rgb, normalize(vec3(ng.xy + tangent, ng.z)), a0.a);
}
#endif

void main() {
    uint variant = VARIANT_BITS;
    // A variable, not a constant expression: naga reads no SpecConstantOp.
    uint every_bits = EVERY_FLAVOUR;
    bool every = every_bits != 0u;
    ivec2 px = ivec2(gl_FragCoord.xy);
    float depth = texelFetch(sampler2D(depth_target, nearest), px, 0).r;
    uint classified = texelFetch(usampler2D(classification, nearest), px, 0).r;
    // Not terrain: the engine's own pixel under its loaded depth, left as
    // it is by failing the depth test (1 is not LESS than any depth; naga
    // reads no discard, which glslang makes a demote).
    gl_FragDepth = classified == 0u ? 1.0 : 0.0;
    if (classified == 0u) {
        return;
    }
    uint bits = classified & variant;
    uvec4 codes = texelFetch(usampler2D(normals, nearest), px, 0);
    vec3 ng = oct_decode8(codes.xy);
    vec3 nt = oct_decode8(codes.zw);
    vec2 pixel = gl_FragCoord.xy;
    vec3 p = reconstruct_position(view.v.inv_view_proj, pixel, view.v.viewport, depth);
    vec3 ddx, ddy;
    position_derivatives(view.v.inv_view_proj, pixel, view.v.viewport, p, nt, ddx, ddy);
    vec3 world = view.v.camera_world.xyz + p;
    float depth_m = view.v.camera_world.w / max(depth, 1e-30);

    float splat_share;
    vec4 shares = flavour_shares(depth_m, ng.z, view.v.shade_bands, view.v.shade_slope, view.v.shade_flags.x, splat_share);
    // Only the pixel's own flavours (its tile's variant contains them).
    shares *= vec4(0.0, (bits & FLAVOUR_FAR_ATLAS) != 0u ? 1.0 : 0.0, (bits & FLAVOUR_NEAR_CLIFF) != 0u ? 1.0 : 0.0,
                   (bits & FLAVOUR_FAR_CLIFF) != 0u ? 1.0 : 0.0);
    splat_share *= (bits & (FLAVOUR_SPLAT | FLAVOUR_CONTROL_MAP | FLAVOUR_VIRTUAL_TEXTURE)) != 0u ? 1.0 : 0.0;
    float total = shares.y + shares.z + shares.w + splat_share;
    if (total <= 0.0) {
        // Rounding left the pixel with none of its flavours' shares: the
        // cheapest one it has, in full.
        shares.y = 1.0;
        total = 1.0;
    }
    shares /= total;
    splat_share /= total;
    // The baked normal as classified (the tri-planar planes follow it).
    vec3 nv = ng;
    // After the shares, which follow the geometry pass's classification.
    ng = silhouette_normal(px, depth, ng, normalize(-p));

    Surface s = Surface(vec3(0.0), vec3(0.0), 0.0);
    uint material = 0u;
    if ((variant & FLAVOUR_FAR_ATLAS) != 0u && (every || shares.y > 0.0)) {
        Surface f = far_atlas(world, ng);
        s.albedo += shares.y * f.albedo;
        s.normal += shares.y * f.normal;
        s.roughness += shares.y * f.roughness;
    }
#ifdef VIRTUAL_TEXTURE
    if ((variant & FLAVOUR_VIRTUAL_TEXTURE) != 0u && (every || splat_share > 0.0)) {
        uint m;
        bool served;
        Surface f = vt_surface(world, ng, ddx, ddy, m, served);
        if (!served) {
            f = far_atlas(world, ng);
        }
        material = splat_share > 0.0 ? m : material;
        s.albedo += splat_share * f.albedo;
        s.normal += splat_share * f.normal;
        s.roughness += splat_share * f.roughness;
    }
#endif
#ifdef MATERIALS
    if ((variant & FLAVOUR_SPLAT) != 0u && (every || splat_share > 0.0)) {
        uint m;
        Surface f = splat_surface(world, ng, ddx, ddy, m);
        material = splat_share > 0.0 ? m : material;
        s.albedo += splat_share * f.albedo;
        s.normal += splat_share * f.normal;
        s.roughness += splat_share * f.roughness;
    }
    if ((variant & FLAVOUR_NEAR_CLIFF) != 0u && (every || shares.z > 0.0)) {
        uint m = material;
        Surface f = cliff_surface(world, ng, ddx, ddy, false, depth_m, m);
        material = shares.z > 0.0 ? m : material;
        s.albedo += shares.z * f.albedo;
        s.normal += shares.z * f.normal;
        s.roughness += shares.z * f.roughness;
    }
    if ((variant & FLAVOUR_FAR_CLIFF) != 0u && (every || shares.w > 0.0)) {
        uint m = material;
        Surface f = cliff_surface(world, ng, ddx, ddy, true, depth_m, m);
        material = shares.w > 0.0 ? m : material;
        s.albedo += shares.w * f.albedo;
        s.normal += shares.w * f.normal;
        s.roughness += shares.w * f.roughness;
    }
#endif
#ifdef CONTROL_MAP
    if ((variant & FLAVOUR_CONTROL_MAP) != 0u && (every || splat_share > 0.0)) {
        uint m;
        Surface f = control_surface(world, nv, ng, ddx, ddy, m);
        material = splat_share > 0.0 ? m : material;
        s.albedo += splat_share * f.albedo;
        s.normal += splat_share * f.normal;
        s.roughness += splat_share * f.roughness;
    }
#endif
    vec3 n = normalize(s.normal);
#ifdef ENGINE_GBUFFER
    write_engine_gbuffer(s.albedo, n, s.roughness, material);
#else
    gb_albedo = vec4(s.albedo, 1.0);
    gb_normal = vec4(oct_encode(n), s.roughness, 1.0);
    gb_material = uvec2(material, bits);
#endif
}
