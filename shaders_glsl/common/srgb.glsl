// The sRGB transfer function (IEC 61966-2-1) and its inverse, for values
// in [0, 1]: lighting_resolve's display encoding, and engine_gbuffer's
// base colour in a UNORM attachment.
#ifndef VISTA_SRGB_GLSL
#define VISTA_SRGB_GLSL

vec3 srgb_encode(vec3 c) {
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}

vec3 srgb_decode(vec3 c) {
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), greaterThan(c, vec3(0.04045)));
}

#endif
