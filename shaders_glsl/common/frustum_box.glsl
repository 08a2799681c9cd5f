// Whether a camera-relative box lies wholly outside the frame's frustum
// (patch culling and the per-triangle rule). The includer declares the
// frame's view as `view` (a buffer of one TerrainView `v`) first.
#ifndef VISTA_FRUSTUM_BOX_GLSL
#define VISTA_FRUSTUM_BOX_GLSL

// The planes are written out, not looped over (projected_error.glsl says
// why).
bool box_outside_plane(vec4 p, vec3 lo, vec3 hi) {
    // The corner farthest along the inward normal.
    vec3 far_corner = mix(lo, hi, greaterThanEqual(p.xyz, vec3(0.0)));
    return dot(p.xyz, far_corner) + p.w < 0.0;
}

bool box_outside_frustum(vec3 lo, vec3 hi) {
    return box_outside_plane(view.v.frustum[0], lo, hi) || box_outside_plane(view.v.frustum[1], lo, hi)
        || box_outside_plane(view.v.frustum[2], lo, hi) || box_outside_plane(view.v.frustum[3], lo, hi)
        || box_outside_plane(view.v.frustum[4], lo, hi);
}

#endif
