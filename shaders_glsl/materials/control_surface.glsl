// The control-map flavour (REDengine 3, seed 004), included by
// gbuffer_tiles.frag under CONTROL_MAP after its declarations (view,
// control, control_atlas, the detail textures, vista_find_node, Texel,
// Surface, project, perturb, sample_layers).
//
// Each control word names a background texture (tri-planar, the tightened
// blend: planes whose weight abs(n) - tighten is not positive are not
// sampled) and an overlay texture (planar, from above), a UV scale and a
// slope threshold. Per pixel, seed 004's steps:
//  1. background and overlay normals combined with the vertex normal;
//  2. the background normal flattened towards up on flat ground by the
//     background's slope damp (artificial materials ~0, natural ~1);
//  3. its slope (angle / 90 degrees) against the threshold: a linear step
//     over the overlay's sharpness (blend width) gives the background's
//     share t;
//  4. the normals combined through their derivatives, weighted by the
//     background's normal damp;
//  5. colour, normal and roughness lerped by t.
// The four control texels around the pixel are blended bilinearly (each
// distinct word evaluated once: painted regions are uniform).
#ifndef VISTA_CONTROL_SURFACE_GLSL
#define VISTA_CONTROL_SURFACE_GLSL

// The slope measure's unit: a vertical face is 1 (a right angle).
const float HALF_PI = 1.5707963268;

uint control_field(uint word, uint shift, uint mask) {
    return (word >> shift) & mask;
}

// Texture `tex` of the control table on a plane, at UV scale `scale`.
Texel sample_control(uint tex, vec2 plane, vec2 dx, vec2 dy, float scale) {
    float k = scale / control.t[tex].tiling_m;
    return sample_layers(control.t[tex].layers, plane * k, dx * k, dy * k, mat2(1.0));
}

// The four control texels around `xy` and their bilinear weights (as the
// splat map's: one texel per two samples).
void control_texels(vec2 xy, out uint words[4], out vec4 weights) {
    ivec3 base;
    bool found = vista_map_texels(xy, base, weights);
    for (int k = 0; k < 4; ++k) {
        ivec3 at = base + ivec3(k & 1, k >> 1, 0);
        words[k] = found ? texelFetch(usampler2DArray(control_atlas, nearest), at, 0).r : 0u;
    }
}

// The tri-planar weights of the background at vertex normal `nv`,
// tightened and normalised (what the classification counted).
vec3 control_plane_weights(vec3 nv) {
    vec3 w = max(abs(nv) - vec3(view.v.control.x), vec3(0.0));
    float sum = w.x + w.y + w.z;
    // A tighten factor above 1/sqrt(3) may leave no plane: the dominant one.
    if (sum <= 0.0) {
        vec3 a = abs(nv);
        w = a.x >= a.y && a.x >= a.z ? vec3(1.0, 0.0, 0.0) : (a.y >= a.z ? vec3(0.0, 1.0, 0.0) : vec3(0.0, 0.0, 1.0));
        sum = 1.0;
    }
    return w / sum;
}

// Seed 004's CombineNormalsDerivatives: the surface slopes (n.xy / n.z) of
// two normals added with weights `w`, back to a normal.
vec3 combine_derivatives(vec3 a, vec3 b, vec2 w) {
    vec2 da = a.xy / max(a.z, 0.05), db = b.xy / max(b.z, 0.05);
    return normalize(vec3(w.x * da + w.y * db, 1.0));
}

// One control word's surface (the steps above). `nv`: vertex normal (the
// plane weights and the damp); `ng`: the geometric normal shading uses.
// `dominant`: the texture with the larger share.
Surface control_word_surface(uint word, vec3 world, vec3 nv, vec3 ng, vec3 ddx, vec3 ddy, out uint dominant) {
    uint overlay = control_field(word, CONTROL_OVERLAY_SHIFT, CONTROL_TEXTURE_MASK);
    uint background = control_field(word, CONTROL_BACKGROUND_SHIFT, CONTROL_TEXTURE_MASK);
    float scale = control.uv_scales[control_field(word, CONTROL_UV_SCALE_SHIFT, CONTROL_CODE_MASK)];
    uint threshold_code = control_field(word, CONTROL_THRESHOLD_SHIFT, CONTROL_CODE_MASK);
    float threshold = threshold_code == 0u ? control.t[background].threshold : control.thresholds[threshold_code];

    // 1. Background: tri-planar over the planes with weight.
    vec3 w = control_plane_weights(nv);
    vec3 v_albedo = vec3(0.0), v_normal = vec3(0.0);
    float v_rough = 0.0;
    for (int p = 0; p < 3; ++p) {
        if (w[p] <= 0.0) {
            continue;
        }
        Texel t = sample_control(background, project(world, p), project(ddx, p), project(ddy, p), scale);
        v_albedo += w[p] * t.albedo;
        v_normal += w[p] * perturb(ng, t.tangent, p);
        v_rough += w[p] * t.roughness;
    }
    vec3 vertical = normalize(v_normal);
    // ... overlay: planar, from above.
    Texel o = sample_control(overlay, world.xy, ddx.xy, ddy.xy, scale);
    vec3 horizontal = normalize(perturb(ng, o.tangent, 2));

    // 2. Slope-based damp of the background normal.
    vec3 flattened = mix(vertical, vec3(0.0, 0.0, 1.0), clamp(nv.z, 0.0, 1.0));
    vec3 biased = normalize(mix(vertical, flattened, control.t[background].slope_damp));
    // 3. The background's share from its slope.
    float slope = acos(clamp(biased.z, -1.0, 1.0)) / HALF_PI;
    float t = clamp((slope - threshold) / max(control.t[overlay].sharpness, 1e-3), 0.0, 1.0);
    // 4. Normals through their derivatives.
    float nd = control.t[background].normal_damp;
    vec3 full = combine_derivatives(vertical, horizontal, vec2(1.0 - nd, nd));
    // 5. The lerps.
    dominant = t < 0.5 ? overlay : background;
    return Surface(mix(o.albedo, v_albedo, t), normalize(mix(full, vertical, t)), mix(o.roughness, v_rough, t));
}

// The control-map flavour at a pixel: the four control texels' surfaces
// blended bilinearly, each distinct word once. `dominant`: the texture
// index of the heaviest word's dominant texture (the G-buffer's material).
Surface control_surface(vec3 world, vec3 nv, vec3 ng, vec3 ddx, vec3 ddy, out uint dominant) {
    uint words[4];
    vec4 bil;
    control_texels(world.xy, words, bil);
    Surface s = Surface(vec3(0.0), vec3(0.0), 0.0);
    float best = -1.0;
    dominant = 0u;
    for (int k = 0; k < 4; ++k) {
        // The weight of every texel holding this word; counted at its first.
        float wk = 0.0;
        bool first = true;
        for (int j = 0; j < 4; ++j) {
            if (words[j] == words[k]) {
                wk += bil[j];
                first = first && j >= k;
            }
        }
        if (!first || wk <= 0.0) {
            continue;
        }
        uint d;
        Surface c = control_word_surface(words[k], world, nv, ng, ddx, ddy, d);
        s.albedo += wk * c.albedo;
        s.normal += wk * c.normal;
        s.roughness += wk * c.roughness;
        if (wk > best) {
            best = wk;
            dominant = d;
        }
    }
    s.normal = normalize(s.normal);
    return s;
}

#endif
