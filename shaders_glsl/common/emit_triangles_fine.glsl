// emit_triangles' bisection below a LOD-0 node's samples (its includer's
// globals, bindings and grid_numbers come first). The sample lattice's
// numbers are saturated over the levels below it, so a vertex below the
// samples takes the smaller error of its two parents (the right angles of
// its diamond) and the meet of their boxes with its own: never below its
// own saturated error, never above either parent's, its box inside both.
// The rule then splits it only where both parents are split (a conforming
// cut), and each triangle left whole is within its split vertex's number
// (a strict bound). Every step is a function of the vertex's world
// position, the samples and the LOD map (one sample past the node: the
// layer's margin), so the nodes on both sides of a border decide a vertex
// on it alike.
//
// A point no node across holds (a coarser node across: never below its
// grid) is blocked: drawn unsplit, and as a parent its error is 0, so
// nothing under it is split either.
#ifndef VISTA_EMIT_TRIANGLES_FINE_GLSL
#define VISTA_EMIT_TRIANGLES_FINE_GLSL

// Whether the listed node covering sector q (if any) lacks world lattice
// point g: coarser than LOD 0 (which holds every point) and g off its grid.
bool sector_lacks(ivec2 q, ivec2 g) {
    uint l = lod_at(q);
    return l != NO_LOD && l != 0u && ((g.x | g.y) & ((UNITS << l) - 1)) != 0;
}

// Whether a sector whose closed square holds node-local lattice point v
// (a LOD-0 node's, or its margin's) draws a coarser grid without it. No
// loop (held_on_line says why).
bool blocked(ivec2 v) {
    if (all(greaterThan(v, ivec2(0))) && all(lessThan(v, ivec2(g_side_l)))) {
        return false;  // inside this LOD-0 node: it holds every point
    }
    ivec2 g = g_origin_l + v;
    ivec2 q = ivec2(floor(vec2(g) / float(g_side_l)));
    bvec2 on_line = equal(g - q * g_side_l, ivec2(0));
    return sector_lacks(q, g) || (on_line.x && sector_lacks(q - ivec2(1, 0), g))
        || (on_line.y && sector_lacks(q - ivec2(0, 1), g)) || (all(on_line) && sector_lacks(q - ivec2(1), g));
}

// The right angles of the diamond node-local lattice point v (below the
// samples) halves (world/bintree.rs `diamond`).
void parents_of(ivec2 v, out ivec2 a, out ivec2 b) {
    ivec2 g = g_origin_l + v;
    int t = findLSB(g.x | g.y);
    int d = 1 << t;
    ivec2 o;
    if (((g.x >> t) & 1) == 1 && ((g.y >> t) & 1) == 1) {
        ivec2 q = (g - d) >> (t + 1);
        o = ((q.x + q.y) & 1) == 0 ? ivec2(d, -d) : ivec2(d, d);
    } else {
        o = ((g.x >> t) & 1) == 1 ? ivec2(0, d) : ivec2(d, 0);
    }
    a = v + o;
    b = v - o;
}

// v's numbers from its parents' a and b.
Numbers from_parents(Numbers a, Numbers b, ivec2 v) {
    ivec2 g = g_origin_l + v;
    float r = half_width_lattice_m(g);
    vec2 xy = view_rel_xy_fine(g, REFINE_LEVELS, view.v.camera_sample, view.v.camera_frac, view.v.spacing_m);
    Numbers n;
    n.e = min(a.e, b.e);
    n.lo = max(a.lo, b.lo);
    n.hi = min(a.hi, b.hi);
    n.lo.xy = max(n.lo.xy, xy - r);
    n.hi.xy = min(n.hi.xy, xy + r);
    return n;
}

Numbers as_parent(Numbers n, ivec2 v) {
    if (blocked(v)) {
        n.e = 0.0;
    }
    return n;
}

// The four bisections below the samples (REFINE_LEVELS 2: the pass's
// host side asserts it), coarsest first: quad centres
// (parents: samples), quad edges (parents: centres), then the same a level
// down. A level's parents are the level before's.
Numbers centre_1(ivec2 v) {
    ivec2 a, b;
    parents_of(v, a, b);
    return from_parents(as_parent(grid_numbers(a / UNITS), a), as_parent(grid_numbers(b / UNITS), b), v);
}

// The quad centres of the 3 x 3 cells around the cell a walk below the
// samples is in: every vertex under a cell half takes its numbers from
// these, so they are found once a cell half (walk_cell), not once a
// vertex.
Numbers g_centres[9];
// The first one's point (node-local lattice).
ivec2 g_first_centre;

// Finds the centres around the cell whose south-west corner is `cell`.
void find_centres(ivec2 cell) {
    g_first_centre = cell - ivec2(UNITS / 2);
    for (int k = 0; k < 9; ++k) {
        g_centres[k] = centre_1(g_first_centre + ivec2(k % 3, k / 3) * UNITS);
    }
}

Numbers centre_near(ivec2 v) {
    ivec2 k = (v - g_first_centre) / UNITS;
    return g_centres[3 * k.y + k.x];
}

Numbers edge_1(ivec2 v) {
    ivec2 a, b;
    parents_of(v, a, b);
    return from_parents(as_parent(centre_near(a), a), as_parent(centre_near(b), b), v);
}

Numbers centre_0(ivec2 v) {
    ivec2 a, b;
    parents_of(v, a, b);
    return from_parents(as_parent(edge_1(a), a), as_parent(edge_1(b), b), v);
}

Numbers edge_0(ivec2 v) {
    ivec2 a, b;
    parents_of(v, a, b);
    return from_parents(as_parent(centre_0(a), a), as_parent(centre_0(b), b), v);
}

// Numbers of node-local lattice point v, below the samples.
Numbers fine_numbers(ivec2 v) {
    ivec2 g = g_origin_l + v;
    int t = findLSB(g.x | g.y);
    bool centre = ((g.x >> t) & 1) == 1 && ((g.y >> t) & 1) == 1;
    if (t == 1) {
        return centre ? centre_near(v) : edge_1(v);
    }
    return centre ? centre_0(v) : edge_0(v);
}

// What to do with a triangle split at m, below a LOD-0 node's samples.
uint decide_fine(ivec2 m, out float px) {
    Numbers n = fine_numbers(m);
    px = numbers_px(n);
    if ((pc.cull & EMIT_CULL_FRUSTUM) != 0u && box_outside_frustum(n.lo, n.hi)) {
        return CULLED;
    }
    if (px <= view.v.lod_params.x) {
        return LEAF;
    }
    if (blocked(m)) {
        g_clamped += 1u;
        return LEAF;
    }
    return SPLIT;
}

#endif
