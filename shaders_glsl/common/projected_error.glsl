// The largest projected length (px) of a vertical error anywhere in a
// camera-relative box: shared by the per-patch selection (lod_select.glsl)
// and the per-triangle rule (emit_triangles.comp). The includer declares
// the frame's view as `view` (a buffer of one TerrainView `v`) first.
#ifndef VISTA_PROJECTED_ERROR_GLSL
#define VISTA_PROJECTED_ERROR_GLSL

// Two upper bounds of the projected length (px) of a vertical segment of
// `err` metres anywhere in the camera-relative box [lo, hi] inside the
// frustum; projected_px takes the smaller.
//
// The traversal's (traverse_common.glsl): a segment of length e at p
// projects to at most e f |p| / z(p)^2 pixels (the largest singular value
// of the perspective Jacobian; z is the depth along the forward axis): at
// most e f k / d, d the box's distance and k = |v|^2 / z(v)^2 at its worst
// corner v (the angle is quasi-convex), never above the frustum's widest.
float jacobian_px(float err, vec3 lo, vec3 hi) {
    vec3 fwd = view.v.lod_forward.xyz;
    float widest = view.v.lod_params.y;
    vec3 o = max(max(lo, -hi), vec3(0.0));
    float d = max(length(o), 1e-3);
    float k = 1.0;
    for (uint c = 0u; c < 8u; ++c) {
        vec3 v = vec3((c & 1u) != 0u ? hi.x : lo.x, (c & 2u) != 0u ? hi.y : lo.y, (c & 4u) != 0u ? hi.z : lo.z);
        float dt = dot(v, fwd);
        k = dt <= 0.0 ? widest : max(k, dot(v, v) / (dt * dt));
    }
    return err * view.v.lod_forward.w * min(k, widest) / d;
}

// The vertical direction's own: moving a point at depth z and screen
// tangents s by e along the world's up axis u moves its image by
// e f |u_xy - s u_z| / z pixels (u in camera axes: right, up, forward),
// which is 0 looking straight down at the image centre where the Jacobian
// bound says e f / z. Over the box: the smallest depth of its corners (the
// near plane where a corner is closer) and the largest |u_xy - s u_z| over
// the rectangle of its corners' tangents within the frustum (convex in s:
// a rectangle corner is the worst).
float vertical_px(float err, vec3 lo, vec3 hi) {
    vec3 fwd = view.v.lod_forward.xyz, right = view.v.lod_right.xyz, up = view.v.lod_up.xyz;
    vec2 tan_half = vec2(view.v.lod_right.w, view.v.lod_up.w);
    float near = view.v.camera_world.w;
    float zmin = 1e30;
    vec2 smin = vec2(1e30), smax = vec2(-1e30);
    bool straddles = false;
    for (uint c = 0u; c < 8u; ++c) {
        vec3 v = vec3((c & 1u) != 0u ? hi.x : lo.x, (c & 2u) != 0u ? hi.y : lo.y, (c & 4u) != 0u ? hi.z : lo.z);
        float z = dot(v, fwd);
        zmin = min(zmin, z);
        if (z <= near) {
            straddles = true;
        } else {
            vec2 s = vec2(dot(v, right), dot(v, up)) / z;
            smin = min(smin, s);
            smax = max(smax, s);
        }
    }
    // A box reaching the near plane: any tangent in the frustum, at the near plane.
    smin = straddles ? -tan_half : clamp(smin, -tan_half, tan_half);
    smax = straddles ? tan_half : clamp(smax, -tan_half, tan_half);
    zmin = max(zmin, near);
    vec3 u = vec3(right.z, up.z, fwd.z);
    float g = 0.0;
    for (uint c = 0u; c < 4u; ++c) {
        vec2 s = vec2((c & 1u) != 0u ? smax.x : smin.x, (c & 2u) != 0u ? smax.y : smin.y);
        g = max(g, length(u.xy - s * u.z));
    }
    return err * view.v.lod_forward.w * g / zmin;
}

// The largest projected vertical error (px) of `err` metres anywhere in the
// camera-relative box [lo, hi] inside the frustum: the smaller of two upper
// bounds, so never above the traversal's (a node it keeps meets the target
// here too).
float projected_px(float err, vec3 lo, vec3 hi) {
    return min(jacobian_px(err, lo, hi), vertical_px(err, lo, hi));
}

#endif
