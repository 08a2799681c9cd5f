// emit_triangles' borders: what the nodes across a drawn node's border
// hold, read from the LOD map (its includer's globals and bindings come
// first). No loop in what a decision calls: lavapipe runs every loop of
// the decision on every triangle (its branches are masks) and ends an
// invocation's loops after 65535 iterations in all (emit_triangles.comp's
// walk says why that matters).
#ifndef VISTA_EMIT_TRIANGLES_BORDERS_GLSL
#define VISTA_EMIT_TRIANGLES_BORDERS_GLSL

// The LOD of the listed node covering sector q, or NO_LOD.
uint lod_at(ivec2 q) {
    if (any(lessThan(q, ivec2(0))) || q.x >= int(view.v.lod_map_w) || q.y >= int(view.v.lod_map_h)) {
        return NO_LOD;
    }
    return imageLoad(lod_map, q).r;
}

// Whether the listed node covering sector q (if any) holds sample s: its
// grid has a point there.
bool sector_holds(ivec2 q, ivec2 s) {
    uint l = lod_at(q);
    return l == NO_LOD || ((s.x | s.y) & ((1 << l) - 1)) == 0;
}

// Whether every node across the border line through sample s (the line's
// axis `along`; `out_step` -1 or 0 picks the sector across) holds s.
bool held_on_line(ivec2 s, int along, int out_step) {
    int side = g_side;
    ivec2 q = s / side;
    q[1 - along] += out_step;
    // A point on a sector boundary touches the sectors on both sides.
    ivec2 before = q;
    before[along] -= 1;
    return sector_holds(q, s) && (s[along] % side != 0 || sector_holds(before, s));
}

bool held_across(ivec2 p) {
    ivec2 s = sample_of(p);
    bool ok = true;
    if (p.x == 0 || p.x == g_side) {
        ok = held_on_line(s, 1, p.x == 0 ? -1 : 0);
    }
    if (p.y == 0 || p.y == g_side) {
        ok = ok && held_on_line(s, 0, p.y == 0 ? -1 : 0);
    }
    return ok;
}

// Whether the grid segment u-w lies on the node's border with a finer
// node's corner strictly inside it, across.
bool corner_across(ivec2 u, ivec2 w) {
    int along;
    int out_step;
    if (u.x == w.x && (u.x == 0 || u.x == g_side)) {
        along = 1;
        out_step = u.x == 0 ? -1 : 0;
    } else if (u.y == w.y && (u.y == 0 || u.y == g_side)) {
        along = 0;
        out_step = u.y == 0 ? -1 : 0;
    } else {
        return false;
    }
    ivec2 s0 = sample_of(min(u, w));
    ivec2 s1 = sample_of(max(u, w));
    int len = s1[along] - s0[along];
    int side = g_side;
    ivec2 q = s0 / side;
    q[1 - along] += out_step;
    for (int k = s0[along] / side; k < (s1[along] + side - 1) / side; ++k) {
        ivec2 at = q;
        at[along] = k;
        uint l = lod_at(at);
        if (l != NO_LOD && (side << l) < len) {
            return true;
        }
    }
    return false;
}

#endif
