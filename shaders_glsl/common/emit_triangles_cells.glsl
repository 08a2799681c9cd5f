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

// Levels below a grid cell half to the finest lattice's triangles.
const uint FINE_LEVELS = 2u * REFINE_LEVELS;

// The 4 x 4 samples around the cell a walk below the samples is in, its
// Catmull-Rom taps (refined_height's): every point of the cell's lattice
// takes its height from these, fetched once a cell half.
float g_taps[16];
// The cell's south-west sample (node-local).
ivec2 g_tap_cell;

void find_taps(ivec2 cell) {
    g_tap_cell = cell;
    cell_taps(g_slot, cell, g_taps);
}

// Node-local lattice point p of the taps' cell (its edges included) where
// terrain_triangles puts it, camera-relative (m): on the Catmull-Rom
// surface, weighed as refined_height weighs it (a sample itself on the grid).
vec3 fine_point(ivec2 p) {
    vec2 t = vec2(p - g_tap_cell * UNITS) / float(UNITS);
    float h = weigh_taps(g_taps, catmull_rom(t.x), catmull_rom(t.y));
    vec2 xy = view_rel_xy_fine(g_origin_l + p, REFINE_LEVELS, view.v.camera_sample, view.v.camera_frac, view.v.spacing_m);
    return vec3(xy, view.v.height_lo + h * view.v.height_range - view.v.camera_z);
}

// Depth-first over a LOD-0 cell half's levels below the samples; the
// triangles it leaves whole are marked (a bit each in preorder) and
// emitted after the loop, each tested on its own first (hidden).
void walk_fine(Tri root) {
    uint depth = 0u;
    uint path = 0u;
    uint leaves = 0u;
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
        if (what == CULLED) {
            count_dropped(what);
        } else {
            leaves |= 1u << preorder(depth, path, FINE_LEVELS);
            g_bound_px = max(g_bound_px, px);
        }
        if (!next_triangle(t, depth, path)) {
            break;
        }
    }
    bool test = tests_triangles();
    while (leaves != 0u) {
        Tri c = preorder_triangle(root, uint(findLSB(leaves)), FINE_LEVELS);
        leaves &= leaves - 1u;
        if (!test || !hidden(fine_point(c.apex), fine_point(c.b), fine_point(c.c))) {
            emit(c);
        }
    }
}

// Walks LOD-0 cell half t below the samples, its cell's 3 x 3 centres
// and 4 x 4 taps found first.
void walk_cell(Tri t) {
    ivec2 corner = min(min(t.apex, t.b), t.c);
    find_centres(corner);
    if (tests_triangles()) {
        find_taps(corner / UNITS);
    }
    walk_fine(t);
}

#endif
