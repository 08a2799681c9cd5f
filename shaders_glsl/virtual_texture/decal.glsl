// One decal as effects/virtual_texture/decal_gpu.rs uploads it (DecalGpu),
// shared by vt_pages (blended into pages), grass_pigment and grass_place
// (grass takes a decal's colour and does not grow under it).
#ifndef VISTA_DECAL_GLSL
#define VISTA_DECAL_GLSL

struct Decal {
    vec2 origin;     // quad: centre (m)
    vec2 axis_u;     // quad: u, v = 0.5 + dot(p - origin, axis)
    vec2 axis_v;
    uint kind;       // DECAL_KIND_QUAD / DECAL_KIND_ROAD
    uint layer;
    float opacity;
    float roughness; // < 0: the material's is kept
    uint first_point;
    uint point_count;
    float half_width;
    float repeat_m;
};

#endif
