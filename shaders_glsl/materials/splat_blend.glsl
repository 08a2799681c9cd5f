// The splat material blend (seed 000): four splat texels around a point,
// each a material sampled from the detail textures, blended bilinearly
// with height weighting. Shared by gbuffer_tiles (the splat flavour, with
// screen derivatives) and vt_pages (the virtual texture's pages, with a
// texel's footprint as derivatives), so both make the same material.
// The includer binds detail_albedo, detail_normal, detail_height and
// detail_sampler, and for the blend itself (VISTA_SPLAT_ATLAS defined)
// splat_atlas, materials and nearest, after terrain_sample.glsl.
#ifndef VISTA_SPLAT_BLEND_GLSL
#define VISTA_SPLAT_BLEND_GLSL

struct Texel {
    vec3 albedo;
    vec2 tangent;  // detail normal xy on its plane, world-aligned
    float roughness;
    float height;
};

// The detail textures of layers `layers` (albedo | normal << 8 | height <<
// 16) at texture coordinates `uv` with derivatives `gx`, `gy`; `rot` turns
// the texture's axes into the plane's.
Texel sample_layers(uint layers, vec2 uv, vec2 gx, vec2 gy, mat2 rot) {
    vec3 a = vec3(uv, float(layers & 0xFFu));
    vec3 n = vec3(uv, float((layers >> 8u) & 0xFFu));
    vec3 h = vec3(uv, float((layers >> 16u) & 0xFFu));
    Texel t;
    t.albedo = textureGrad(sampler2DArray(detail_albedo, detail_sampler), a, gx, gy).rgb;
    vec4 nr = textureGrad(sampler2DArray(detail_normal, detail_sampler), n, gx, gy);
    // Back from texture axes to the plane's axes.
    t.tangent = transpose(rot) * (nr.xy * 2.0 - 1.0);
    t.roughness = nr.a;
    t.height = textureGrad(sampler2DArray(detail_height, detail_sampler), h, gx, gy).r;
    return t;
}

#ifdef VISTA_SPLAT_ATLAS
// Height-weighted blending: how far (in height units) below the highest
// layer a texel still shows.
const float HEIGHT_BLEND = 0.6;
const float BLEND_DEPTH = 0.2;

// The four splat texels around `xy` and their bilinear weights.
void splat_texels(vec2 xy, out uint ids[4], out vec4 weights) {
    ivec3 base;
    bool found = vista_map_texels(xy, base, weights);
    for (int k = 0; k < 4; ++k) {
        ivec3 at = base + ivec3(k & 1, k >> 1, 0);
        ids[k] = found ? texelFetch(usampler2DArray(VISTA_SPLAT_ATLAS, nearest), at, 0).r : 0u;
    }
}

// Material `id` on a plane with coordinates `plane` (m) and their screen
// derivatives, at tiling scale `scale` (1 = the material's own).
Texel sample_material(uint id, vec2 plane, vec2 dx, vec2 dy, float scale) {
    uint layers = materials.m[id].layers;
    float k = scale / materials.m[id].tiling_m;
    vec2 cs = vec2(materials.m[id].cos_rot, materials.m[id].sin_rot);
    mat2 rot = mat2(cs.x, cs.y, -cs.y, cs.x);
    return sample_layers(layers, rot * plane * k, rot * dx * k, rot * dy * k, rot);
}

struct SplatBlend {
    vec3 albedo;
    vec2 tangent;   // detail normal xy, added to the geometric normal's
    float roughness;
    uint dominant;  // the material with the largest weight
};

// Four materials on the ground plane at `xy`, height-weighted; `dx`, `dy`
// are the footprint's derivatives on that plane.
SplatBlend splat_blend(vec2 xy, vec2 dx, vec2 dy) {
    uint ids[4];
    vec4 bil;
    splat_texels(xy, ids, bil);
    Texel t[4];
    float a[4];
    float top = -1e9;
    for (int k = 0; k < 4; ++k) {
        t[k] = sample_material(ids[k], xy, dx, dy, 1.0);
        a[k] = bil[k] + t[k].height * HEIGHT_BLEND;
        top = max(top, a[k]);
    }
    SplatBlend b = SplatBlend(vec3(0.0), vec2(0.0), 0.0, ids[0]);
    float sum = 0.0, best = -1.0;
    for (int k = 0; k < 4; ++k) {
        float w = max(a[k] - top + BLEND_DEPTH, 0.0) * step(1e-6, bil[k]);
        if (w > best) {
            best = w;
            b.dominant = ids[k];
        }
        b.albedo += w * t[k].albedo;
        b.tangent += w * t[k].tangent;
        b.roughness += w * t[k].roughness;
        sum += w;
    }
    sum = max(sum, 1e-6);
    b.albedo /= sum;
    b.roughness /= sum;
    b.tangent /= sum;
    return b;
}
#endif

#endif
