// Whether a camera-relative box lies wholly outside the frame's frustum
// (patch culling and the per-triangle rule). The includer declares the
// frame's view as `view` (a buffer of one TerrainView `v`) first.
#ifndef VISTA_FRUSTUM_BOX_GLSL
#define VISTA_FRUSTUM_BOX_GLSL

bool box_outside_frustum(vec3 lo, vec3 hi) {
    for (uint i = 0u; i < 5u; ++i) {
        vec4 p = view.v.frustum[i];
        // The corner farthest along the inward normal.
        vec3 far_corner = mix(lo, hi, greaterThanEqual(p.xyz, vec3(0.0)));
        if (dot(p.xyz, far_corner) + p.w < 0.0) {
            return true;
        }
    }
    return false;
}

#endif
