// emit_triangles' borders: what the nodes across a drawn node's border
// hold, read from the LOD map (its includer's globals and bindings come
// first; emit_triangles.comp only). No loop in what a decision calls:
// lavapipe runs every loop of the decision on every triangle (its
// branches are masks) and ends an invocation's loops after 65535
// iterations in all (emit_triangles.comp's walk says why that matters).
#ifndef VISTA_EMIT_TRIANGLES_BORDERS_GLSL
#define VISTA_EMIT_TRIANGLES_BORDERS_GLSL

// The LODs of the sectors across the node's four borders (west, east,
// south, north; each from the sector before the border's first to the one
// past its last, so the corners' diagonal sectors too), read from the LOD
// map once a workgroup: a decision reads up to 7 of them, and an image
// load (on lavapipe, masked on every decision) costs more than a shared one.
const uint ACROSS_MAX = (1u << (MAX_NODE_LODS - 1u)) + 2u;
shared uint s_across[4u * ACROSS_MAX];

// Sectors across one border: the node's side in sectors and two more.
uint across_count() {
    return (1u << g_lod) + 2u;
}

// Border `side`'s sector `i` (0: the one before its first).
ivec2 across_sector(uint side, uint i) {
    int n = 1 << int(g_lod);
    ivec2 o = g_node * n;
    int k = int(i) - 1;
    if (side < 2u) {
        return ivec2(side == 0u ? o.x - 1 : o.x + n, o.y + k);
    }
    return ivec2(o.x + k, side == 2u ? o.y - 1 : o.y + n);
}

// Fills s_across (the workgroup's invocations, then a barrier).
void fill_across(uint t) {
    uint count = across_count();
    for (uint e = t; e < 4u * count; e += gl_WorkGroupSize.x) {
        uint side = e / count;
        s_across[side * ACROSS_MAX + e % count] = lod_at(across_sector(side, e % count));
    }
}

// The LOD of the listed node covering sector q (or NO_LOD), q one of the
// sectors across the node's borders.
uint lod_across(ivec2 q) {
    int n = 1 << int(g_lod);
    ivec2 r = q - g_node * n;
    uint side = r.x < 0 ? 0u : (r.x >= n ? 1u : (r.y < 0 ? 2u : 3u));
    int i = clamp((side < 2u ? r.y : r.x) + 1, 0, n + 1);
    return s_across[side * ACROSS_MAX + uint(i)];
}

// Whether the listed node covering sector q (if any) holds sample s: its
// grid has a point there.
bool sector_holds(ivec2 q, ivec2 s) {
    uint l = lod_across(q);
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
// node's corner strictly inside it, across. The nodes across tile the
// border with aligned squares, and the segment is aligned to its length:
// the node across its first sector covers all of it, unless it is shorter
// (its far corner is then inside), so that one sector decides (no loop
// over the segment's sectors: lavapipe ran it on every decision, a fifth
// of the pass).
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
    int len = sample_of(max(u, w))[along] - s0[along];
    int side = g_side;
    ivec2 q = s0 / side;
    q[1 - along] += out_step;
    uint l = lod_across(q);
    return l != NO_LOD && (side << l) < len;
}

#endif
