// Camera-relative position and its screen-space derivatives from depth.
//
// Derivatives: the eye rays through the pixel's right and lower neighbours
// (left or upper where those miss) are intersected with the plane of the
// triangle normal through the pixel's position. Near grazing incidence a
// ray is almost parallel to the plane and the intersection runs off to
// infinity; the guard bounds |cos(incidence)| from below by GRAZING_COS, so
// a derivative never exceeds the pixel's distance times
// (1 + 1 / GRAZING_COS): finite, and the mip chosen from it saturates at
// the last mip instead of overflowing. tests/derivatives.rs holds it to
// exact plane intersections from 0 to 89.9 degrees.
#ifndef VISTA_RECONSTRUCT_GLSL
#define VISTA_RECONSTRUCT_GLSL

// cos(89.99 degrees): the steepest incidence resolved exactly.
const float GRAZING_COS = 1.745e-4;

// Unnormalised eye ray through a pixel position (pixels, top-left origin).
vec3 eye_ray(mat4 inv_view_proj, vec2 pixel, vec4 viewport) {
    vec2 ndc = pixel * viewport.zw * 2.0 - 1.0;
    // Reversed-Z with an infinite far plane: clip depth 0 is the point at
    // infinity along the ray, whose xyz is the direction.
    vec4 h = inv_view_proj * vec4(ndc, 0.0, 1.0);
    return h.xyz;
}

vec3 reconstruct_position(mat4 inv_view_proj, vec2 pixel, vec4 viewport, float depth) {
    vec2 ndc = pixel * viewport.zw * 2.0 - 1.0;
    vec4 h = inv_view_proj * vec4(ndc, depth, 1.0);
    return h.xyz / h.w;
}

// Position where the eye ray through `pixel` meets the plane (p, n), the
// incidence guarded as above; `hit` is false where the ray runs within the
// guard of parallel to the plane or meets it behind the eye (the point
// returned is then finite but not on the ray's visible part).
vec3 ray_plane(mat4 inv_view_proj, vec2 pixel, vec4 viewport, vec3 p, vec3 n, out bool hit) {
    vec3 d = eye_ray(inv_view_proj, pixel, viewport);
    float len = length(d);
    float cosi = dot(d, n) / len;
    bool parallel = abs(cosi) < GRAZING_COS;
    float guarded = parallel ? (cosi < 0.0 ? -GRAZING_COS : GRAZING_COS) : cosi;
    float t = dot(p, n) / (guarded * len);
    hit = !parallel && t > 0.0;
    return d * t;
}

// The step to the neighbour `offset` pixels away: forward where its ray
// meets the plane, else backward (a pixel at the plane's horizon, or a
// camera rolled so +x or +y leads up), else the guarded forward step.
vec3 neighbour_step(mat4 inv_view_proj, vec2 pixel, vec2 offset, vec4 viewport, vec3 p, vec3 n) {
    bool hit;
    vec3 forward = ray_plane(inv_view_proj, pixel + offset, viewport, p, n, hit);
    if (hit) {
        return forward - p;
    }
    vec3 backward = ray_plane(inv_view_proj, pixel - offset, viewport, p, n, hit);
    return hit ? p - backward : forward - p;
}

void position_derivatives(mat4 inv_view_proj, vec2 pixel, vec4 viewport, vec3 p, vec3 n, out vec3 ddx, out vec3 ddy) {
    ddx = neighbour_step(inv_view_proj, pixel, vec2(1.0, 0.0), viewport, p, n);
    ddy = neighbour_step(inv_view_proj, pixel, vec2(0.0, 1.0), viewport, p, n);
}

#endif
