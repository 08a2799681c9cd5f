// Terrain sun shadows after REDengine 3 (seed 004): per resident node, a
// texture whose texel holds the height below which a point there is in the
// sun's shadow, relative to the ground there (positive: the ground is in
// shadow), and how far towards the sun the occluder that sets it lies.
// sun_shadows.comp makes it by marching towards the sun through the height
// data; lighting_resolve shades the ground under each pixel by it. The occluder's
// distance sizes the penumbra: the sun is a disc, so the heights from where
// its top edge to where its bottom edge is hidden span distance x the
// disc's spread in slope (`penumbra`, effects/shadows). The CPU twin
// of both is src/reference/sun_shadow.rs.
#ifndef VISTA_SUN_SHADOW_GLSL
#define VISTA_SUN_SHADOW_GLSL

// Stored where no terrain can occlude (nothing found, or the ray leaves the
// world's height range at once); any height is above it.
const float SUN_SHADOW_NONE = -1.0e30;

// March distance of step i of n (i = 0..n-1): quadratic from `first` to
// `last`, so steps start at the sample spacing, where small relief next to
// the point matters, and widen to 2 (last - first) / n at the far end. (A
// geometric series widens too fast: at a low sun it steps over whole hills
// a few hundred metres away.)
float sun_shadow_step(uint i, uint n, float first, float last) {
    if (n <= 1u) {
        return last;
    }
    float f = float(i) / float(n - 1u);
    return first + (last - first) * f * f;
}

// Where the shadow texel of texel coordinate `t` (0..side-1) lies inside its
// node, in node samples (0..128).
vec2 sun_shadow_texel_local(vec2 t, uint side) {
    return t * (128.0 / float(side - 1u));
}

// How much of the sun a point at height `z` sees given the threshold `h` set
// by an occluder `dist` metres away (both heights relative to the same
// ground): a ramp `dist * penumbra` metres wide centred on the threshold (a
// hard step where that is 0).
float sun_visibility(float z, float h, float dist, float penumbra) {
    float width = dist * penumbra;
    if (width <= 0.0) {
        return z >= h ? 1.0 : 0.0;
    }
    return clamp(0.5 + (z - h) / width, 0.0, 1.0);
}

#endif
