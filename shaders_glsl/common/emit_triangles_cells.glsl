// The walk below a LOD-0 node's samples (emit_triangles_core.glsl's
// globals, walk steps and numbers come first): a cell half emit_triangles
// queued, walked down to the finest lattice by one emit_fine invocation,
// so the grid's walk holds none of these decisions (lavapipe runs every
// branch of a loop's body, masked, in every workgroup).
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

// Walks LOD-0 cell half t below the samples, its cell's 3 x 3 centres
// found first.
void walk_cell(Tri t) {
    find_centres(min(min(t.apex, t.b), t.c));
    walk_fine(t);
}

#endif
