// Conservative occlusion test of a camera-relative box against the depth
// pyramid of hiz_build. The includer declares `texture2D hiz` and
// `sampler nearest`. Integer texel arithmetic throughout, so the CPU twin
// (src/reference/occlusion.rs) makes the same choices bit for bit.
//
// Pyramid: level 0 is the depth target's size rounded DOWN to powers of
// two; its texel i covers pixels [i*W/w0, ceil((i+1)*W/w0)), so pixel p lies
// in texel p*w0/W. Each texel holds the farthest depth it covers (reversed-Z:
// the minimum).
#ifndef VISTA_HIZ_TEST_GLSL
#define VISTA_HIZ_TEST_GLSL

uvec2 hiz_size0(uvec2 depth_size) {
    return uvec2(1u << uint(findMSB(depth_size.x)), 1u << uint(findMSB(depth_size.y)));
}

uint hiz_mip_count(uvec2 size0) {
    return uint(findMSB(max(size0.x, size0.y))) + 1u;
}

// True unless every point of the box lies behind the pyramid; `level` is
// the mip read (the smallest at which the box spans at most 2x2 texels:
// choosing it from floor(log2(size)) lets a box straddle 3 texels).
bool hiz_box_visible(vec3 lo, vec3 hi, mat4 view_proj, uvec2 depth_size, out uint level) {
    level = 0u;
    vec2 uv_lo = vec2(3.0e38), uv_hi = vec2(-3.0e38);
    float z_nearest = 0.0;
    for (uint c = 0u; c < 8u; ++c) {
        vec3 p = vec3((c & 1u) != 0u ? hi.x : lo.x, (c & 2u) != 0u ? hi.y : lo.y, (c & 4u) != 0u ? hi.z : lo.z);
        vec4 clip = view_proj * vec4(p, 1.0);
        // Reversed-Z with an infinite far plane: z = near and w = view
        // depth, so a corner before the near plane has z >= w. A box
        // crossing it has no usable projection: visible.
        if (!(clip.w > 0.0) || clip.z >= clip.w) {
            return true;
        }
        vec3 ndc = clip.xyz / clip.w;
        vec2 uv = ndc.xy * 0.5 + 0.5;
        uv_lo = min(uv_lo, uv);
        uv_hi = max(uv_hi, uv);
        z_nearest = max(z_nearest, ndc.z);
    }
    if (any(greaterThan(uv_lo, vec2(1.0))) || any(lessThan(uv_hi, vec2(0.0)))) {
        return false;  // covers no pixel
    }
    // Every pixel whose centre the box can cover (a superset: whole pixels).
    vec2 dsz = vec2(depth_size);
    uvec2 px0 = uvec2(clamp(floor(uv_lo * dsz), vec2(0.0), dsz - 1.0));
    uvec2 px1 = uvec2(clamp(floor(uv_hi * dsz), vec2(0.0), dsz - 1.0));
    uvec2 size0 = hiz_size0(depth_size);
    uvec2 t0 = (px0 * size0) / depth_size;
    uvec2 t1 = (px1 * size0) / depth_size;
    uint mips = hiz_mip_count(size0);
    uint l = 0u;
    while (l + 1u < mips && ((t1.x >> l) - (t0.x >> l) > 1u || (t1.y >> l) - (t0.y >> l) > 1u)) {
        l++;
    }
    level = l;
    float farthest = 1.0;
    for (uint y = t0.y >> l; y <= (t1.y >> l); ++y) {
        for (uint x = t0.x >> l; x <= (t1.x >> l); ++x) {
            farthest = min(farthest, texelFetch(sampler2D(hiz, nearest), ivec2(x, y), int(l)).r);
        }
    }
    return z_nearest >= farthest;
}

#endif
