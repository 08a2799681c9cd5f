// A decal's colour and coverage at a world point (effect decals). The
// includer declares, after decal.glsl: `decals` (Decal d[]),
// `decal_points` (vec4 p[]), `decal_textures` (a texture2DArray) and the
// samplers `decal_clamp` and `decal_repeat`.
#ifndef VISTA_DECAL_SHAPES_GLSL
#define VISTA_DECAL_SHAPES_GLSL

// Coverage ramps over one texel at a shape's edge (edge_m: metres inside).
float edge_alpha(float edge_m, float texel_m) {
    return clamp(edge_m / texel_m + 0.5, 0.0, 1.0);
}

// A road at xy: the nearest segment gives the distance across (signed, to
// its left) and along; the road's two ends are square, its bends round.
vec4 decal_road(uint di, vec2 xy, float texel_m) {
    uint first = decals.d[di].first_point;
    uint n = decals.d[di].point_count;
    float half_width = decals.d[di].half_width;
    float best = 1e30;
    vec4 r = vec4(0.0, 0.0, -1e30, 0.0);
    for (uint i = 0u; i + 1u < n; ++i) {
        vec4 a = decal_points.p[first + i];
        vec4 b = decal_points.p[first + i + 1u];
        vec2 ab = b.xy - a.xy;
        float len = length(ab);
        vec2 dir = ab / len;
        float t = dot(xy - a.xy, dir);
        float across = dir.x * (xy.y - a.y) - dir.y * (xy.x - a.x);
        float dist = length(xy - (a.xy + dir * clamp(t, 0.0, len)));
        if (dist < best) {
            best = dist;
            bool start = i == 0u && t < 0.0;
            bool end = i + 2u == n && t > len;
            float edge = half_width - ((start || end) ? abs(across) : dist);
            if (start) {
                edge = min(edge, t);
            } else if (end) {
                edge = min(edge, len - t);
            }
            r = vec4(0.5 + across / (2.0 * half_width), (a.z + clamp(t, 0.0, len)) / decals.d[di].repeat_m, edge, 0.0);
        }
    }
    return r;
}


// Decal `di` at xy: its texture's colour, alpha = coverage (texture alpha
// x the one-texel soft edge; 0 outside), the texture filtered over a
// footprint of texel_m.
vec4 decal_colour(uint di, vec2 xy, float texel_m) {
    float layer = float(decals.d[di].layer);
    vec4 c = vec4(0.0);
    if (decals.d[di].kind == DECAL_KIND_QUAD) {
        vec2 au = decals.d[di].axis_u;
        vec2 av = decals.d[di].axis_v;
        vec2 q = xy - decals.d[di].origin;
        vec2 uv = vec2(dot(q, au), dot(q, av));
        vec2 inside_m = (0.5 - abs(uv)) / vec2(length(au), length(av));
        float a = edge_alpha(min(inside_m.x, inside_m.y), texel_m);
        if (a > 0.0) {
            c = textureGrad(sampler2DArray(decal_textures, decal_clamp), vec3(uv + 0.5, layer),
                            vec2(au.x, av.x) * texel_m, vec2(au.y, av.y) * texel_m);
            c.a *= a;
        }
    } else {
        vec4 r = decal_road(di, xy, texel_m);
        float half_width = decals.d[di].half_width;
        float a = edge_alpha(r.z, texel_m);
        if (a > 0.0) {
            c = textureGrad(sampler2DArray(decal_textures, decal_repeat), vec3(r.xy, layer),
                            vec2(texel_m / (2.0 * half_width), 0.0), vec2(0.0, texel_m / decals.d[di].repeat_m));
            c.a *= a;
        }
    }
    return c;
}

#endif
