// Silhouette pixels: shade them from the surface in front of the edge.
//
// At a ridge's silhouette the drawn LOD surface is hit beyond the exact
// surface's horizon: near grazing incidence its vertical error of up to a
// pixel becomes metres along the ray, so the pixel's position lands on the
// crest's far side, whose normal faces away from the eye (and often from
// the sun). Point-sampled, such pixels make a dotted dark line that the
// exact surface does not have: what the eye sees in that pixel is the front
// face up to the horizon. So a pixel on the near side of a depth edge (a
// 4-neighbour SILHOUETTE_FAR times farther, or background) takes
// - as its geometric normal, the average of its own and those of its
//   neighbours one step away from the edge on the same surface (within
//   SILHOUETTE_SAME), each weighted by the area the eye sees of it
//   (n . to_eye, 0 when facing away), then turned to face the eye by at
//   least SILHOUETTE_FACING (a visible surface faces the eye);
// - its sun shadow from the first of those neighbours' positions.
// The ratios and the facing were chosen by tests/silhouettes.rs, which
// counts the dots against the exact surface.
//
// The including shader defines VISTA_SILHOUETTE_DEPTH(ivec2) (the depth
// target's texel, reversed-Z: 0 is background), and for
// silhouette_normal VISTA_SILHOUETTE_NORMAL(ivec2) (the geometric normal
// the geometry pass wrote), and has `view` bound.
#ifndef VISTA_SILHOUETTE_GLSL
#define VISTA_SILHOUETTE_GLSL

// Linear depth ratios (linear depth is proportional to 1 / depth). A few
// percent: ridges kilometres away overlap ones only 3-7 % farther; on a
// smooth surface both sides of a pixel differ by nearly the same ratio, so
// "farther one way, the same the other" holds only at a step.
const float SILHOUETTE_FAR = 1.03;
const float SILHOUETTE_SAME = 1.03;
const float SILHOUETTE_FACING = 0.3;

bool silhouette_inside(ivec2 q) {
    return all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(view.v.viewport.xy)));
}

// -1 where `px` is not on the near side of a depth edge; else how many
// pixels (0-3) to shade it from, in `src`: its neighbours one step away
// from the edge (diagonally where two sides are farther, and along each
// axis) that lie on its surface, the diagonal first.
int silhouette_sources(ivec2 px, float depth, out ivec2 src[3]) {
    src = ivec2[3](px, px, px);
    if (depth <= 0.0) {
        return -1;
    }
    const ivec2 steps[4] = ivec2[4](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1));
    ivec2 towards_far = ivec2(0);
    bool edge = false;
    for (int k = 0; k < 4; ++k) {
        ivec2 q = px + steps[k];
        // Farther: its linear depth is SILHOUETTE_FAR times ours or more.
        if (silhouette_inside(q) && VISTA_SILHOUETTE_DEPTH(q) * SILHOUETTE_FAR <= depth) {
            towards_far += steps[k];
            edge = true;
        }
    }
    if (!edge) {
        return -1;
    }
    ivec2 away = -sign(towards_far);
    ivec2 dirs[3] = ivec2[3](away, ivec2(away.x, 0), ivec2(0, away.y));
    int count = 0;
    for (int d = 0; d < 3; ++d) {
        ivec2 q = px + dirs[d];
        if (dirs[d] == ivec2(0) || (d > 0 && dirs[d] == away) || !silhouette_inside(q)) {
            continue;
        }
        float dq = VISTA_SILHOUETTE_DEPTH(q);
        if (dq > 0.0 && dq * SILHOUETTE_SAME >= depth && depth * SILHOUETTE_SAME >= dq) {
            src[count] = q;
            ++count;
        }
    }
    return count;
}

// `n` turned towards the unit eye direction `to_eye` until n . to_eye is
// at least `facing` (unchanged where it already is).
vec3 face_eye(vec3 n, vec3 to_eye, float facing) {
    float f = dot(n, to_eye);
    return f >= facing ? n : normalize(n + to_eye * (facing - f));
}

#ifdef VISTA_SILHOUETTE_NORMAL
// The geometric normal to shade `px` with (`own`: its own; `to_eye`: unit).
vec3 silhouette_normal(ivec2 px, float depth, vec3 own, vec3 to_eye) {
    ivec2 front[3];
    int fronts = silhouette_sources(px, depth, front);
    if (fronts < 0) {
        return own;
    }
    vec3 sum = own * max(dot(own, to_eye), 0.0);
    for (int k = 0; k < fronts; ++k) {
        vec3 n = VISTA_SILHOUETTE_NORMAL(front[k]);
        sum += n * max(dot(n, to_eye), 0.0);
    }
    return face_eye(dot(sum, sum) > 0.0 ? normalize(sum) : own, to_eye, SILHOUETTE_FACING);
}
#endif

#endif
