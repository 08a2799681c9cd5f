#version 460
#extension GL_GOOGLE_include_directive : require
// variants: OCCLUSION LATE
// The per-triangle rule on the GPU (src/world/vertex_bounds.rs; its CPU
// twin is src/reference/bintree_cut.rs): one workgroup per drawn node
// (indirect, from traverse): each of its EMIT_GROUP_SIZE invocations
// decides the depths above EMIT_THREAD_DEPTH on its own path, to its 4
// triangles there, then the invocations share out the subtrees the cut
// reaches (listed) and walk each down to the grid's cells; the triangles
// left go to one index list (terrain_triangles draws it). Few invocations
// per node matter on lavapipe, where the body of every branch and loop
// runs for each 8 of them, masked or not: 256 invocations, each walking
// its own subtree, made the pass 2.4 times as slow (docs/accuracy.md).
// Points are in lattice units (2^-REFINE_LEVELS grid steps): a LOD-0 node
// continues the bisection below its samples, on the Catmull-Rom surface,
// with numbers each vertex takes from its parents (emit_triangles_fine.glsl):
// its cell halves the cut reaches are appended to the fine list, and
// emit_fine walks them (only the workgroups with such cells pay for it).
//
// A triangle is split at the midpoint m of its hypotenuse when
// - m is active: its saturated error, projected from its box (its level's
//   width across, its reach up and down, within the world's height range),
//   is over the target, and a node across the border (m on it) holds m in
//   its grid (else the triangle stays whole and m counts as clamped); or
// - an edge of it on the node's border holds a corner of a finer node
//   across (forced: that node draws the corner as a vertex).
// Both nodes of a border decide a vertex they share from the same bits in
// the same arithmetic, so the list is a conforming cut: no T-junction and
// no stitching. A subtree whose box is outside the frustum is dropped,
// and one inside a patch of holes only; then each triangle left whole on
// the grid that faces away (EMIT_CULL_FACING) or lies outside the frustum
// by its own vertices (emit_unless_hidden).
//
// Occlusion (two phases, as cull_patches and cull_occluded do for
// patches; one visibility bit per subtree and slot): with
// OCCLUSION this is phase 1, which emits the triangles above the
// subtrees' depth and the subtrees visible when last tested; with LATE
// too it is phase 2, after hiz_build reduced phase 1's depth: every
// subtree the cut reaches is tested against the pyramid (its split
// vertex's box holds every triangle under it), those visible that phase 1
// did not emit are emitted into phase 2's list, and every bit is rewritten
// for the next frame. Phase 1 leaves which depth-7 triangles its cut
// reached (a bit each), so phase 2 does not decide the depths above again.
// Phase 2 is a phase of occlusion (the LATE-only variant is its twin).
#if defined(LATE) && !defined(OCCLUSION)
#define OCCLUSION
#endif

#include "emit_triangles_core.glsl"

layout(local_size_x = EMIT_GROUP_SIZE) in;

#include "emit_triangles_borders.glsl"

layout(set = 0, binding = 0, std430) readonly buffer TraverseOutput {
    TraverseHeader header;
    uvec2 nodes[];
} traverse_out;
#ifdef OCCLUSION
layout(set = 0, binding = 10, std430) buffer Visibility { uint words[]; } visibility;
// Phase 1's s_reached, a bit each (VISIBILITY_WORDS_PER_SLOT words a slot).
layout(set = 0, binding = 12, std430) buffer Reached { uint words[]; } reached;
#endif
#ifdef LATE
layout(set = 0, binding = 11) uniform texture2D hiz;
// Each patch's sample height range (encoded), the bake's.
layout(set = 0, binding = 15) uniform utexture2DArray patch_min_max;
#endif

#ifdef LATE
#include "hiz_test.glsl"
#endif

// What to do with triangle t; `px`: its split vertex's projected error
// when it stays whole.
uint decide(Tri t, out float px) {
    px = 0.0;
    ivec2 sum = t.b + t.c;
    // The finest triangles: a LOD-0 node's lattice, a coarser node's grid.
    int finest = g_lod == 0u ? 1 : 2 * UNITS - 1;
    if (((sum.x | sum.y) & finest) != 0) {
        return CELL;
    }
    ivec2 ml = sum / 2;
    if (((ml.x | ml.y) & (UNITS - 1)) != 0) {
        return g_refine == 0u ? CELL : FINE;
    }
    if ((pc.cull & EMIT_CULL_HOLES) != 0u && all_holes(t)) {
        return HOLES;
    }
    // On the grid, and so are t's corners.
    ivec2 m = ml / UNITS;
    vec3 lo, hi;
    px = vertex_px(m, lo, hi);
    // A hole's box is the height range: it still bounds the subtree.
    if ((pc.cull & EMIT_CULL_FRUSTUM) != 0u && box_outside_frustum(lo, hi)) {
        return CULLED;
    }
    ivec2 a = t.apex / UNITS, b = t.b / UNITS, c = t.c / UNITS;
    if (corner_across(a, b) || corner_across(b, c) || corner_across(c, a)) {
        g_forced += 1u;
        return SPLIT;
    }
    if (px <= view.v.lod_params.x) {
        return LEAF;
    }
    bool border = m.x == 0 || m.y == 0 || m.x == g_side || m.y == g_side;
    if (border && !held_across(m)) {
        g_clamped += 1u;
        return LEAF;
    }
    return SPLIT;
}

// The triangles at EMIT_THREAD_DEPTH (the subtrees) the cut reaches, a
// bit each (phase 1 decides them; phase 2 reads phase 1's).
shared uint s_reached[VISIBILITY_WORDS_PER_SLOT];

// The subtrees this phase walks (or, in phase 2, tests first), listed; an
// invocation takes every EMIT_GROUP_SIZE-th. lavapipe runs the body of
// every loop at least once for each 8 invocations, masked, the walk's
// too: a quarter of the invocations, each walking several subtrees,
// pay a quarter of that for the subtrees the cut does not reach.
shared uint s_list[2u << EMIT_THREAD_DEPTH];
shared uint s_count;

// Cell halves below the subtree an invocation walks (its depth to the
// grid's cells), and their marks: a bit each, FINE_WORDS words an
// invocation (only its own).
// (The cells are 2 x EMIT_THREAD_DEPTH below the node's halves: NODE_QUADS is
// 1 << EMIT_THREAD_DEPTH; the invocations' triangles EMIT_THREAD_DEPTH.)
const uint CELL_DEPTH = EMIT_THREAD_DEPTH;
const uint FINE_WORDS = (1u << CELL_DEPTH) / 32u;
shared uint s_fine[EMIT_GROUP_SIZE * FINE_WORDS];

// The triangles `walk` leaves whole under the subtree an invocation
// walks (down to the grid's cells, CELL_DEPTH + 1 levels), a bit each in
// preorder, LEAF_WORDS words an invocation: emitted after the walk, each
// tested first (emit_unless_hidden), so neither the test nor the list's
// atomic is in the walk's loop (lavapipe runs its whole body on every
// decision).
const uint LEAF_WORDS = (2u << CELL_DEPTH) / 32u;
shared uint s_leaves[EMIT_GROUP_SIZE * LEAF_WORDS];

// Moves (w, bits) on to the first word from w of ARR[BASE .., WORDS of
// them] holding a set bit (bits 0 past the last). Loops over a bit set
// step bit by bit, not word by word: lavapipe runs a loop's body at least
// once, masked, so a word loop ran the step's whole body once a word even
// for invocations with nothing to do.
#define SKIP_EMPTY_WORDS(ARR, BASE, WORDS, w, bits) \
    while (bits == 0u && w + 1u < (WORDS)) { \
        w += 1u; \
        bits = ARR[(BASE) + w]; \
    }

// Depth-first over `root`'s subtree down to the grid's cells, the first
// half before the second as a stack would; the grid's cell halves are
// marked in s_fine. Every loop an invocation runs counts towards one
// lavapipe limit (65535 iterations in all, after which its loops end),
// and lavapipe runs every loop in a loop's body on every pass, masked: so
// the decisions hold no loop, and the steps a few iterations each (a
// LOD-0 subtree refined to the finest lattice decides 4095 triangles).
void walk(Tri root) {
    uint depth = 0u;
    uint path = 0u;
    Tri t = root;
    while (true) {
        float px;
        uint what = decide(t, px);
        if (what == SPLIT) {
            t = half_of(t, 0u);
            depth += 1u;
            path <<= 1u;
            continue;
        }
        uint me = gl_LocalInvocationID.x;
        if (what == FINE || what == CELL) {
            s_fine[me * FINE_WORDS + (path >> 5u)] |= 1u << (path & 31u);
        }
        if (what == LEAF || what == CELL) {
            uint i = preorder(depth, path, CELL_DEPTH);
            s_leaves[me * LEAF_WORDS + (i >> 5u)] |= 1u << (i & 31u);
            g_bound_px = max(g_bound_px, px);
        } else if (what == CULLED || what == HOLES) {
            count_dropped(what);
        }
        if (!next_triangle(t, depth, path)) {
            break;
        }
    }
}

// The cell halves `walk` marked under subtree t, appended to
// the fine list with one atomic (and the dispatch's workgroups counted
// as they fill); past its capacity a cell half is drawn whole, its node's
// error counted in the bound.
void queue_cells(uint t) {
    uint base = gl_LocalInvocationID.x * FINE_WORDS;
    uint n = 0u;
    for (uint w = 0u; w < FINE_WORDS; ++w) {
        n += uint(bitCount(s_fine[base + w]));
    }
    if (n == 0u) {
        return;
    }
    uint first = atomicAdd(fine.header.count, n);
    uint end = min(first + n, pc.fine_capacity);
    if (end > first) {
        uint groups = (end + FINE_GROUP_SIZE - 1u) / FINE_GROUP_SIZE - (first + FINE_GROUP_SIZE - 1u) / FINE_GROUP_SIZE;
        if (groups != 0u) {
            atomicAdd(fine.header.groups_x, groups);
        }
    }
    uint i = first;
    uint w = 0u;
    uint bits = s_fine[base];
    while (true) {
        SKIP_EMPTY_WORDS(s_fine, base, FINE_WORDS, w, bits)
        if (bits == 0u) {
            break;
        }
        uint index = (t << CELL_DEPTH) | (32u * w + uint(findLSB(bits)));
        bits &= bits - 1u;
        if (i < pc.fine_capacity) {
            fine.cells[i] = fine_cell(g_slot, index);
        } else {
            Tri c = triangle_at(2u * EMIT_THREAD_DEPTH, index);
            emit(c);
            g_unrefined += 1u;
            g_grid_px = max(g_grid_px, cell_px(c));
        }
        i += 1u;
    }
}

// The triangles `walk` left whole under root, in its order, those hidden
// on their own not.
void emit_leaves(Tri root) {
    uint base = gl_LocalInvocationID.x * LEAF_WORDS;
    uint w = 0u;
    uint bits = s_leaves[base];
    while (true) {
        SKIP_EMPTY_WORDS(s_leaves, base, LEAF_WORDS, w, bits)
        if (bits == 0u) {
            break;
        }
        Tri c = preorder_triangle(root, 32u * w + uint(findLSB(bits)), CELL_DEPTH);
        bits &= bits - 1u;
        emit_unless_hidden(c);
    }
}

// The grid's cell halves `walk` drew whole under root where the node is
// not refined below them: each adds the node's own error over its column
// to the grid's bound. Not in the walk: lavapipe
// runs the whole body of its loop on every pass, masked, and this
// projection was a sixth of the pass there. (emit_leaves draws them in
// the walk's order: drawn after the others, the rule's draw was slower on
// Mont Blanc.)
void bound_cells(Tri root) {
    uint base = gl_LocalInvocationID.x * FINE_WORDS;
    uint w = 0u;
    uint bits = s_fine[base];
    while (true) {
        SKIP_EMPTY_WORDS(s_fine, base, FINE_WORDS, w, bits)
        if (bits == 0u) {
            break;
        }
        Tri c = below(root, CELL_DEPTH, 32u * w + uint(findLSB(bits)));
        bits &= bits - 1u;
        g_grid_px = max(g_grid_px, cell_px(c));
    }
}

// Walks subtree t (a triangle at EMIT_THREAD_DEPTH) down to the grid's
// cells, then bounds or queues the cell halves it reaches (queued: a
// LOD-0 node refined below its samples).
void walk_subtree(uint t) {
    Tri root = triangle_at(EMIT_THREAD_DEPTH, t);
    uint me = gl_LocalInvocationID.x;
    for (uint w = 0u; w < FINE_WORDS; ++w) {
        s_fine[me * FINE_WORDS + w] = 0u;
    }
    for (uint w = 0u; w < LEAF_WORDS; ++w) {
        s_leaves[me * LEAF_WORDS + w] = 0u;
    }
    walk(root);
    emit_leaves(root);
    if (g_lod == 0u && g_refine != 0u) {
        queue_cells(t);
    } else {
        bound_cells(root);
    }
}

// Each invocation's own triangle is at LANE_DEPTH, the 4 subtrees under it
// at EMIT_THREAD_DEPTH (4 l .. 4 l + 3 for invocation l).
const uint LANE_DEPTH = EMIT_THREAD_DEPTH - 2u;

// Which of invocation l's 4 subtrees the cut reaches (bit j: 4 l + j).
// l decides the triangles on its path from the node's half to its own
// triangle, in parallel with the others (the 8 lanes of a lavapipe SIMD
// group share the depths above the last 3, so those decisions cost one),
// then its own triangle's two halves. A triangle above its own that the
// cut leaves whole is emitted and counted by its first descendant's
// invocation only (l's bits below its depth all 0). The triangle left
// whole on the path is finished after the loop: in it, its test would run
// (masked) on every depth.
uint path_reached(uint l) {
    Tri tri = triangle_at(0u, l >> LANE_DEPTH);
    uint what = SPLIT;
    float px = 0.0;
    bool owner = false;
    for (uint d = 0u; d <= LANE_DEPTH && what == SPLIT; ++d) {
        owner = (l & ((1u << (LANE_DEPTH - d)) - 1u)) == 0u;
        uint forced = g_forced, clamped = g_clamped;
        what = decide(tri, px);
        if (!owner) {
            g_forced = forced;
            g_clamped = clamped;
        }
        if (what == SPLIT && d < LANE_DEPTH) {
            tri = half_of(tri, (l >> (LANE_DEPTH - 1u - d)) & 1u);
        }
    }
    if (what != SPLIT) {
        if (owner) {
            finish(tri, what, px);
        }
        return 0u;
    }
    uint reached = 0u;
    for (uint h = 0u; h < 2u; ++h) {
        Tri part = half_of(tri, h);
        what = decide(part, px);
        if (what == SPLIT) {
            reached |= 3u << (2u * h);
        } else {
            finish(part, what, px);
        }
    }
    return reached;
}

// Invocation l's 4 bits of a per-subtree bit set (they share a word).
uint own_bits(uint word, uint l) {
    return (word >> (4u * (l & 7u))) & 15u;
}

// Appends the subtrees of invocation l's set bits (bit j: 4 l + j) to
// s_list.
void list_subtrees(uint bits, uint l) {
    if (bits == 0u) {
        return;
    }
    uint i = atomicAdd(s_count, uint(bitCount(bits)));
    while (bits != 0u) {
        s_list[i] = 4u * l + uint(findLSB(bits));
        bits &= bits - 1u;
        i += 1u;
    }
}

#ifdef OCCLUSION
// This workgroup's slot's visibility bits, rewritten by phase 2.
shared uint s_visible[VISIBILITY_WORDS_PER_SLOT];

// The slot's visibility word of subtrees 32 w .. 32 w + 31 when last tested.
uint was_visible(uint w) {
    return visibility.words[g_slot * VISIBILITY_WORDS_PER_SLOT + w];
}
#endif
#ifdef LATE
// Camera-relative position across (m) of grid point p (lattice units).
vec2 rel_xy_of(ivec2 p) {
    return view_rel_xy(sample_of(p / UNITS), view.v.camera_sample, view.v.camera_frac, view.v.spacing_m);
}

// The camera-relative height range (m) of the samples of the patches
// under r (a triangle at EMIT_THREAD_DEPTH spans a patch or two), padded
// like the patches' boxes.
vec2 patches_z(Tri r) {
    uint quads = PATCH_QUADS;  // read first: naga cannot parse a converted spec constant
    int patch_l = int(quads) * UNITS;
    ivec2 p0 = min(min(r.apex, r.b), r.c) / patch_l, p1 = (max(max(r.apex, r.b), r.c) - 1) / patch_l;
    uvec2 m = uvec2(0xffffu, 0u);
    for (int y = p0.y; y <= p1.y; ++y) {
        for (int x = p0.x; x <= p1.x; ++x) {
            uvec2 t = texelFetch(usampler2DArray(patch_min_max, nearest), ivec3(x, y, int(g_slot)), 0).xy;
            m = uvec2(min(m.x, t.x), max(m.y, t.y));
        }
    }
    vec2 z = view.v.height_lo + vec2(m) * view.v.height_scale - view.v.camera_z;
    return z + vec2(-1.0, 1.0) * (1e-4 * abs(z) + 1e-3);
}

// Whether any of the subtree under r may show past the pyramid. Its box:
// across, r's own (its split vertex's box spans the diamond, both sides);
// up and down, the vertex's reach, cut to r's patches' sample range where
// no cell below the samples is drawn (Catmull-Rom overshoots them). A
// hole under the vertex: its box bounds nothing, so it counts as visible.
// Padded like the patches' boxes.
bool subtree_visible(Tri r) {
    vec3 lo, hi;
    if (vertex_px((r.b + r.c) / (2 * UNITS), lo, hi) >= HUGE_PX) {
        return true;
    }
    vec2 a = rel_xy_of(r.apex), b = rel_xy_of(r.b), c = rel_xy_of(r.c);
    vec2 lo_xy = min(min(a, b), c), hi_xy = max(max(a, b), c);
    vec2 pad = 1e-4 * (abs(lo_xy) + abs(hi_xy)) + 1e-3;
    lo.xy = lo_xy - pad;
    hi.xy = hi_xy + pad;
    if (g_lod != 0u || g_refine == 0u) {
        vec2 z = patches_z(r);
        lo.z = max(lo.z, z.x);
        hi.z = min(hi.z, z.y);
    }
    uint level;
    return hiz_box_visible(lo, hi, view.v.view_proj, uvec2(pc.depth_w, pc.depth_h), level);
}

// Phase 2: tests the subtrees phase 1 reached (listed) against the
// pyramid into s_visible, then lists those visible that phase 1 did not
// walk (not visible when last tested).
void list_newly_visible(uint l) {
    for (uint k = l; k < s_count; k += EMIT_GROUP_SIZE) {
        uint t = s_list[k];
        if (subtree_visible(triangle_at(EMIT_THREAD_DEPTH, t))) {
            atomicOr(s_visible[t >> 5u], 1u << (t & 31u));
        }
    }
    barrier();
    if (l == 0u) {
        s_count = 0u;
    }
    barrier();
    list_subtrees(own_bits(s_visible[l >> 3u] & ~was_visible(l >> 3u), l), l);
}
#endif

void main() {
    uvec2 entry = traverse_out.nodes[gl_WorkGroupID.x];
    uint n = entry.x;
    enter_node(n, entry.y);
    uint l = gl_LocalInvocationID.x;
    fill_across(l);
    if (l < VISIBILITY_WORDS_PER_SLOT) {
#ifdef LATE
        s_reached[l] = reached.words[g_slot * VISIBILITY_WORDS_PER_SLOT + l];
        s_visible[l] = 0u;
#else
        s_reached[l] = 0u;
#endif
    }
    if (l == 0u) {
        s_count = 0u;
    }
    barrier();
#ifdef LATE
    list_subtrees(own_bits(s_reached[l >> 3u], l), l);
    barrier();
    list_newly_visible(l);
#else
    if (l == 0u) {
        slot_nodes.nodes[g_slot] = n;
    }
    uint mine = path_reached(l);
    if (mine != 0u) {
        atomicOr(s_reached[l >> 3u], mine << (4u * (l & 7u)));
    }
    barrier();
#ifdef OCCLUSION
    // Phase 1 walks the subtrees visible when last tested.
    if (l < VISIBILITY_WORDS_PER_SLOT) {
        reached.words[g_slot * VISIBILITY_WORDS_PER_SLOT + l] = s_reached[l];
    }
    mine &= own_bits(was_visible(l >> 3u), l);
#endif
    list_subtrees(mine, l);
#endif
    barrier();
    for (uint k = l; k < s_count; k += EMIT_GROUP_SIZE) {
        walk_subtree(s_list[k]);
    }
#ifdef LATE
    if (l < VISIBILITY_WORDS_PER_SLOT) {
        visibility.words[g_slot * VISIBILITY_WORDS_PER_SLOT + l] = s_visible[l];
    }
#endif
    flush();
}
