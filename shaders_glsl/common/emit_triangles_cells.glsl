// emit_triangles' walk below a LOD-0 node's samples (its includer's
// globals, walk steps and decisions come first): the cell halves `walk`
// marked, each walked down to the finest lattice in a loop of its own, so
// the grid's walk holds none of these decisions (lavapipe runs every
// branch of a loop's body, masked).
#ifndef VISTA_EMIT_TRIANGLES_CELLS_GLSL
#define VISTA_EMIT_TRIANGLES_CELLS_GLSL

// What to do with triangle t below a LOD-0 node's samples.
uint decide_below(Tri t, out float px) {
    px = 0.0;
    ivec2 sum = t.b + t.c;
    if (((sum.x | sum.y) & 1) != 0) {
        return CELL;
    }
    ivec2 m = sum / 2;
    // Past the levels the frame refines to: drawn whole, its error counted.
    if (findLSB((g_origin_l.x + m.x) | (g_origin_l.y + m.y)) < int(REFINE_LEVELS - g_refine)) {
        px = numbers_px(fine_numbers(m));
        return LEAF;
    }
    return decide_fine(m, px);
}

// Depth-first over a LOD-0 cell half's levels below the samples.
void walk_fine(Tri root) {
    uint depth = 0u;
    uint path = 0u;
    Tri t = root;
    while (true) {
        float px;
        uint what = decide_below(t, px);
        if (what == SPLIT) {
            t = half_of(t, 0u);
            depth += 1u;
            path <<= 1u;
            continue;
        }
        finish(t, what, px);
        if (!next_triangle(t, depth, path)) {
            break;
        }
    }
}

// The cell halves `walk` marked under `root`, each walked below the
// samples: one loop over the marks of all words (on lavapipe a loop's body
// runs once even when no invocation enters it, so one loop, not a loop a
// word).
void walk_cells(Tri root) {
    uint base = gl_LocalInvocationID.x * FINE_WORDS;
    uint w = 0u;
    uint bits = s_fine[base];
    while (true) {
        while (bits == 0u && w + 1u < FINE_WORDS) {
            w += 1u;
            bits = s_fine[base + w];
        }
        if (bits == 0u) {
            break;
        }
        uint p = 32u * w + uint(findLSB(bits));
        bits &= bits - 1u;
        Tri t = root;
        for (uint d = 0u; d < CELL_DEPTH; ++d) {
            t = half_of(t, (p >> (CELL_DEPTH - 1u - d)) & 1u);
        }
        find_centres(min(min(t.apex, t.b), t.c));
        walk_fine(t);
    }
}


#endif
