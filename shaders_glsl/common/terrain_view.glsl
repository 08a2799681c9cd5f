// The per-frame view every terrain pass reads (scene/view.rs TerrainViewGpu).
// Positions on the GPU are relative to the camera: a vertex's LOD-0 sample
// index (an exact integer) minus the camera's anchor sample, times the
// spacing, minus the camera's offset inside that sample cell. Both sides of
// a LOD seam compute the same integers, so shared edges are bit-identical,
// and a camera far from the origin loses no precision.
#ifndef VISTA_TERRAIN_VIEW_GLSL
#define VISTA_TERRAIN_VIEW_GLSL

struct TerrainView {
    mat4 view_proj;         // camera-relative metres -> clip (reversed-Z, infinite far)
    vec4 frustum[5];        // camera-relative planes, xyz inward normal, w offset (left, right, top, bottom, near)
    vec4 sun_dir;           // xyz: unit vector toward the sun (world); w: unused
    vec4 sun_color;         // rgb: sun radiance on a surface facing it (linear)
    vec4 sky_color;         // rgb: sky ambient on an upward surface (linear)
    ivec2 camera_sample;    // LOD-0 sample index of the camera's anchor
    vec2 camera_frac;       // camera xy minus the anchor's position (m)
    float camera_z;         // camera height (m)
    float spacing_m;        // LOD-0 sample spacing
    float height_lo;        // world height range low end (m)
    float height_scale;     // metres per R16 step: (hi - lo) / 65535
    float height_range;     // hi - lo (m), for UNORM samples
    uint lod_map_w;         // LOD map extent (sectors, padded)
    uint lod_map_h;
    uint pad;
    // G-buffer tile shading (scene/shading.rs).
    mat4 inv_view_proj;     // clip -> camera-relative metres
    vec4 viewport;          // width, height, 1 / width, 1 / height (pixels)
    vec4 camera_world;      // xyz: camera position in world metres (lookups and texture tiling only); w: near plane (m)
    vec4 shade_bands;       // view depth (m): far atlas from x to y; far cliff from z to w
    vec4 shade_slope;       // x: normal z where cliff shading starts, y: where it is full;
                            // z: far cliff's second tiling scale; w: hash scale (Wyman-McGuire g)
    uvec4 shade_flags;      // x: flavours the scene can produce; y: hash seed; z: 1 = stochastic cliffs; w: clay albedo bits (0: G-buffer albedo)
    // Per-patch LOD selection (lod_select.glsl).
    vec4 lod_forward;       // xyz: the camera's forward axis (world); w: pixels per unit of tan (viewport_h / (2 tan(fov_y / 2)))
    vec4 lod_params;        // x: target error (px); y: 1 / cos^2 of the frustum's widest angle to the forward axis;
                            // z: refinement levels below LOD 0 allowed; w: 1 = no stitching (tests only)
    vec4 lod_right;         // xyz: the camera's right axis (world); w: tan of the frustum's half width
    vec4 lod_up;            // xyz: the camera's up axis (world); w: tan of the frustum's half height
    // The display image (scene/tonemap.rs).
    vec4 image;             // x: exposure scale (2^EV); y: tonemapper (Tonemap::gpu_id: 0 clip, 1 ACES fitted); zw: unused
    // The control-map flavour (scene/shading.rs).
    vec4 control;           // x: tri-planar tighten factor (a plane counts where abs(n) exceeds it); yzw: unused
};

// LOD-0 sample index -> camera-relative metres (x, y). Takes fields, not
// the struct: a by-value copy out of a block is OpCopyLogical, which naga
// cannot parse.
vec2 view_rel_xy(ivec2 sample_index, ivec2 camera_sample, vec2 camera_frac, float spacing_m) {
    precise vec2 d = vec2(sample_index - camera_sample) * spacing_m;
    precise vec2 r = d - camera_frac;
    return r;
}

// The same for an index in units of 2^-r LOD-0 samples (refinement level
// r): spacing / 2^r is exact, and equal points give equal bits whatever r
// names them (the integer differences scale by the same power of two).
vec2 view_rel_xy_fine(ivec2 fine_index, uint r, ivec2 camera_sample, vec2 camera_frac, float spacing_m) {
    precise vec2 d = vec2(fine_index - (camera_sample << int(r))) * (spacing_m / float(1u << r));
    precise vec2 rel = d - camera_frac;
    return rel;
}

#endif
