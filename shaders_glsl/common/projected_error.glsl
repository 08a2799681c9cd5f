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
//
// The corners are written out, not looped over: lavapipe ends every loop of
// an invocation once they have run 65535 iterations in all, and
// emit_triangles projects thousands of vertices an invocation.
void jacobian_corner(vec3 v, vec3 fwd, float widest, inout float k) {
    float dt = dot(v, fwd);
    k = dt <= 0.0 ? widest : max(k, dot(v, v) / (dt * dt));
}

float jacobian_px(float err, vec3 lo, vec3 hi) {
    vec3 fwd = view.v.lod_forward.xyz;
    float widest = view.v.lod_params.y;
    vec3 o = max(max(lo, -hi), vec3(0.0));
    float d = max(length(o), 1e-3);
    float k = 1.0;
    jacobian_corner(vec3(lo.x, lo.y, lo.z), fwd, widest, k);
    jacobian_corner(vec3(hi.x, lo.y, lo.z), fwd, widest, k);
    jacobian_corner(vec3(lo.x, hi.y, lo.z), fwd, widest, k);
    jacobian_corner(vec3(hi.x, hi.y, lo.z), fwd, widest, k);
    jacobian_corner(vec3(lo.x, lo.y, hi.z), fwd, widest, k);
    jacobian_corner(vec3(hi.x, lo.y, hi.z), fwd, widest, k);
    jacobian_corner(vec3(lo.x, hi.y, hi.z), fwd, widest, k);
    jacobian_corner(vec3(hi.x, hi.y, hi.z), fwd, widest, k);
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
// A corner's depth and screen tangents (the near plane where it is closer).
struct Tangents {
    float zmin;
    vec2 smin;
    vec2 smax;
    bool straddles;
};

void vertical_corner(vec3 v, inout Tangents t) {
    vec3 fwd = view.v.lod_forward.xyz, right = view.v.lod_right.xyz, up = view.v.lod_up.xyz;
    float z = dot(v, fwd);
    t.zmin = min(t.zmin, z);
    if (z <= view.v.camera_world.w) {
        t.straddles = true;
    } else {
        vec2 s = vec2(dot(v, right), dot(v, up)) / z;
        t.smin = min(t.smin, s);
        t.smax = max(t.smax, s);
    }
}

float vertical_px(float err, vec3 lo, vec3 hi) {
    vec3 fwd = view.v.lod_forward.xyz, right = view.v.lod_right.xyz, up = view.v.lod_up.xyz;
    vec2 tan_half = vec2(view.v.lod_right.w, view.v.lod_up.w);
    float near = view.v.camera_world.w;
    Tangents t = Tangents(1e30, vec2(1e30), vec2(-1e30), false);
    vertical_corner(vec3(lo.x, lo.y, lo.z), t);
    vertical_corner(vec3(hi.x, lo.y, lo.z), t);
    vertical_corner(vec3(lo.x, hi.y, lo.z), t);
    vertical_corner(vec3(hi.x, hi.y, lo.z), t);
    vertical_corner(vec3(lo.x, lo.y, hi.z), t);
    vertical_corner(vec3(hi.x, lo.y, hi.z), t);
    vertical_corner(vec3(lo.x, hi.y, hi.z), t);
    vertical_corner(vec3(hi.x, hi.y, hi.z), t);
    // A box reaching the near plane: any tangent in the frustum, at the near plane.
    vec2 smin = t.straddles ? -tan_half : clamp(t.smin, -tan_half, tan_half);
    vec2 smax = t.straddles ? tan_half : clamp(t.smax, -tan_half, tan_half);
    float zmin = max(t.zmin, near);
    vec3 u = vec3(right.z, up.z, fwd.z);
    float g = max(max(length(u.xy - smin * u.z), length(u.xy - vec2(smax.x, smin.y) * u.z)),
                  max(length(u.xy - vec2(smin.x, smax.y) * u.z), length(u.xy - smax * u.z)));
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
