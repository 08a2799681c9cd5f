// Random numbers for stochastic shading that stay put under camera motion:
// "Hashed Alpha Testing" (Wyman and McGuire, 2017). The hash input is the
// world position quantised at a scale tied to the pixel footprint, taken at
// the two neighbouring powers of two and interpolated, so the noise neither
// swims (world-space anchoring) nor aliases (about one cell per pixel at any
// distance). The interpolation makes the value non-uniform; their CDF
// correction restores a uniform [0, 1) value, which is what lets the average
// over many seeds converge to the fully blended shading.
#ifndef VISTA_HASHED_NOISE_GLSL
#define VISTA_HASHED_NOISE_GLSL

// PCG-based 3D integer hash (Jarzynski and Olano, "Hash Functions for GPU
// Rendering", 2020), one lane kept.
uint pcg3d_x(uvec3 v) {
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v ^= v >> 16u;
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    return v.x;
}

float hash_cell(vec3 cell, uint seed) {
    uvec3 u = uvec3(ivec3(cell)) + uvec3(seed * 0x9E3779B9u, seed * 0x85EBCA6Bu, seed * 0xC2B2AE35u);
    return float(pcg3d_x(u) >> 8u) * (1.0 / 16777216.0);
}

// Uniform [0, 1) value for world point `p` whose footprint is `max_deriv`
// metres per pixel; `g` scales the cell size (1 = a cell per pixel);
// `stream` gives independent values at the same point.
float hashed_uniform(vec3 p, float max_deriv, float g, uint seed, uint stream) {
    float pix_scale = 1.0 / max(g * max_deriv, 1e-6);
    float l = log2(pix_scale);
    vec2 scales = vec2(exp2(floor(l)), exp2(ceil(l)));
    uint s = seed * 2u + stream * 0x68E31DA4u;
    float lo = hash_cell(floor(scales.x * p), s);
    float hi = hash_cell(floor(scales.y * p), s);
    float blend = fract(l);
    float x = mix(lo, hi, blend);
    float a = min(blend, 1.0 - blend);
    if (a < 1e-4) {
        return x;
    }
    float lo_case = x * x / (2.0 * a * (1.0 - a));
    float mid_case = (x - 0.5 * a) / (1.0 - a);
    float hi_case = 1.0 - (1.0 - x) * (1.0 - x) / (2.0 * a * (1.0 - a));
    float u = x < 1.0 - a ? (x < a ? lo_case : mid_case) : hi_case;
    return clamp(u, 0.0, 0.99999994);
}

#endif
