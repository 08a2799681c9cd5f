#version 460
#extension GL_GOOGLE_include_directive : require
// variants: OCCLUSION LATE
// The per-triangle rule on the GPU (src/world/vertex_bounds.rs; its CPU
// twin is src/reference/bintree_cut.rs): one workgroup per drawn node
// (indirect, from traverse), each of its 256 invocations walking one
// subtree of the node's bintree from depth EMIT_THREAD_DEPTH down to the
// grid's cells (the depths above are decided first, by one invocation);
// the triangles left go to one index list (terrain_triangles draws it).
// Points are in lattice units (2^-REFINE_LEVELS grid steps): a LOD-0 node
// continues the bisection below its samples, on the Catmull-Rom surface,
// with numbers each vertex takes from its parents (emit_triangles_fine.glsl).
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
// no stitching. A subtree whose box is outside the frustum is dropped.
//
// Occlusion (two phases, as cull_patches and cull_occluded do for
// patches; one visibility bit per invocation's subtree and slot): with
// OCCLUSION this is phase 1, which emits the triangles above the
// invocations' depth and the subtrees visible when last tested; with LATE
// too it is phase 2, after hiz_build reduced phase 1's depth: every
// subtree the cut reaches is tested against the pyramid (its split
// vertex's box holds every triangle under it), those visible that phase 1
// did not emit are emitted into phase 2's list, and every bit is rewritten
// for the next frame. Phase 1 leaves which depth-7 triangles its cut
// reached (a bit each), so phase 2 does not decide the depths above again.
layout(local_size_x = 256) in;

// Phase 2 is a phase of occlusion (the LATE-only variant is its twin).
#if defined(LATE) && !defined(OCCLUSION)
#define OCCLUSION
#endif

#include "node_list.glsl"
#include "terrain_view.glsl"
#include "atlas_texels.glsl"
#include "triangle_list.glsl"

// Quads per node side (world NODE_QUADS): 1 << EMIT_THREAD_DEPTH.
layout(constant_id = 0) const uint NODE_SIDE = 128u;

layout(set = 0, binding = 0, std430) readonly buffer TraverseOutput {
    TraverseHeader header;
    uvec2 nodes[];
} traverse_out;
layout(set = 0, binding = 1, std430) readonly buffer View { TerrainView v; } view;
layout(set = 0, binding = 2, r8ui) uniform readonly uimage2D lod_map;
layout(set = 0, binding = 3) uniform texture2DArray height_atlas;
layout(set = 0, binding = 4) uniform utexture2DArray vertex_bounds;
layout(set = 0, binding = 5) uniform sampler nearest;
layout(set = 0, binding = 6, std430) readonly buffer NodeDescs { uvec2 descs[]; } node_descs;
layout(set = 0, binding = 7, std430) readonly buffer NodeErrors { float errors[]; } node_errors;
layout(set = 0, binding = 8, std430) buffer Triangles {
    TriangleListHeader header;
    uint indices[];
} tris;
layout(set = 0, binding = 9, std430) buffer SlotNodes { uint nodes[]; } slot_nodes;
#ifdef OCCLUSION
layout(set = 0, binding = 10, std430) buffer Visibility { uint words[]; } visibility;
// Phase 1's s_reached, a bit each (VISIBILITY_WORDS_PER_SLOT words a slot).
layout(set = 0, binding = 12, std430) buffer Reached { uint words[]; } reached;
#endif
#ifdef LATE
layout(set = 0, binding = 11) uniform texture2D hiz;
#endif

layout(push_constant, std430) uniform EmitPush {
    uint capacity;  // triangles the list holds
    uint frustum;   // 1: subtrees outside the frustum are dropped (CullStages::frustum)
    uint depth_w;   // LATE: the depth target's size (the pyramid's level 0 is made from it)
    uint depth_h;
} pc;

#include "projected_error.glsl"
#include "frustum_box.glsl"
#ifdef LATE
#include "hiz_test.glsl"
#endif

const uint LEAF = 0u;
const uint SPLIT = 1u;
const uint CULLED = 2u;
// A leaf whose hypotenuse has no midpoint in the grid (a cell's half), or
// below a LOD-0 node's samples in the finest lattice.
const uint CELL = 3u;
// A LOD-0 node's cell half: the levels below its samples are walked after
// the grid's (walk_cells), so the walks' loops each hold one kind of
// decision (lavapipe runs every branch of a loop's body, masked).
const uint FINE = 4u;

struct Tri {
    ivec2 apex;
    ivec2 b;
    ivec2 c;
};

uint g_slot;
uint g_lod;
ivec2 g_node;
int g_side;
// This invocation's counts and largest errors, added to the header once at
// the end instead of a global atomic each per triangle; only the
// triangle's index slot is taken per triangle.
uint g_written = 0u;
uint g_forced = 0u;
uint g_clamped = 0u;
uint g_culled = 0u;
float g_bound_px = 0.0;
float g_grid_px = 0.0;
// Lattice units a grid step, the node's side in them, and (LOD 0) its
// south-west corner on the world's lattice.
const int UNITS = 1 << int(REFINE_LEVELS);
int g_side_l;
ivec2 g_origin_l;
// Levels below LOD 0 the frame refines to (LodOptions::refine_levels, 0 to
// REFINE_LEVELS; 0: a LOD-0 node's cells are drawn whole).
uint g_refine;

ivec2 sample_of(ivec2 p) {
    return (g_node * g_side + p) << int(g_lod);
}

// An infinite error's projection (a hole under the vertex): a literal
// infinity would be folded into an invalid constant.
const float HUGE_PX = 3.0e38;

// Half the width (m) of the box of the vertex at world lattice point g
// (world/vertex_rule.rs box_half_width; never the origin, a corner of
// every level).
float half_width_lattice_m(ivec2 g) {
    int t = min(findLSB(g.x | g.y), 28);
    bool centre = ((g.x >> t) & 1) == 1 && ((g.y >> t) & 1) == 1;
    int r = centre ? 3 * (1 << t) - 1 : (2 << t) - 1;
    return float(r) * view.v.spacing_m / float(UNITS);
}

// A vertex's numbers as the rule reads them: its saturated error (m; 0:
// it splits nothing; infinite: a hole under it) and its camera-relative box.
struct Numbers {
    float e;
    vec3 lo;
    vec3 hi;
};

// Grid point p's numbers (p one past the grid: a neighbour's sample, the
// layer's margin). A hole under it bounds nothing: its box is the world's
// height range.
Numbers grid_numbers(ivec2 p) {
    ivec3 at = ivec3(atlas_texel(p), int(g_slot));
    vec2 n = unpackHalf2x16(texelFetch(usampler2DArray(vertex_bounds, nearest), at, 0).r);
    ivec2 s = sample_of(p);
    float h = texelFetch(sampler2DArray(height_atlas, nearest), at, 0).r;
    float z = view.v.height_lo + h * view.v.height_range;
    float top = view.v.height_lo + view.v.height_range;
    float reach = isinf(n.x) ? view.v.height_range : n.y;
    float r = half_width_lattice_m(s * UNITS);
    vec2 xy = view_rel_xy(s, view.v.camera_sample, view.v.camera_frac, view.v.spacing_m);
    Numbers o;
    o.e = n.x;
    o.lo = vec3(xy - r, clamp(z - reach, view.v.height_lo, top) - view.v.camera_z);
    o.hi = vec3(xy + r, clamp(z + reach, view.v.height_lo, top) - view.v.camera_z);
    return o;
}

// Numbers' projected error (px; HUGE_PX: a hole under the vertex).
float numbers_px(Numbers n) {
    if (isinf(n.e)) {
        return HUGE_PX;
    }
    return n.e > 0.0 ? projected_px(n.e, n.lo, n.hi) : 0.0;
}

// Projected error (px) of grid point p's numbers, and its box.
float vertex_px(ivec2 p, out vec3 lo, out vec3 hi) {
    Numbers n = grid_numbers(p);
    lo = n.lo;
    hi = n.hi;
    return numbers_px(n);
}

#include "emit_triangles_borders.glsl"

#include "emit_triangles_fine.glsl"

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
    // On the grid, and so are t's corners.
    ivec2 m = ml / UNITS;
    vec3 lo, hi;
    px = vertex_px(m, lo, hi);
    if (pc.frustum != 0u && px < HUGE_PX && box_outside_frustum(lo, hi)) {
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

void emit(Tri t) {
    uint i = atomicAdd(tris.header.triangles, 1u);
    if (i >= pc.capacity) {
        atomicAdd(tris.header.overflow, 1u);
        return;
    }
    ivec2 u = t.b - t.apex, w = t.c - t.apex;
    // Counter-clockwise seen from above (the front faces).
    bool ccw = u.x * w.y - u.y * w.x > 0;
    tris.indices[3u * i] = triangle_vertex(g_slot, t.apex);
    tris.indices[3u * i + 1u] = triangle_vertex(g_slot, ccw ? t.b : t.c);
    tris.indices[3u * i + 2u] = triangle_vertex(g_slot, ccw ? t.c : t.b);
    g_written += 1u;
}

// Its two halves, each with the split vertex as its right angle.
Tri half_of(Tri t, uint which) {
    ivec2 m = (t.b + t.c) / 2;
    return which == 0u ? Tri(m, t.apex, t.b) : Tri(m, t.c, t.apex);
}

// The largest projected error (px) of the node's own error over cell
// triangle t's column (its square across, the node's height range up):
// what a cell of a coarser node's grid may be off by (a LOD-0 node's
// finest triangles lie on the finest surface).
float cell_px(Tri t) {
    uvec2 d = node_descs.descs[g_slot];
    int bias = bitfieldExtract(int(d.y), int(DESC_BIAS_SHIFT), int(DESC_BIAS_BITS));
    float err = ldexp(node_errors.errors[g_slot], bias);
    ivec2 lo = min(min(t.apex, t.b), t.c) / UNITS, hi = max(max(t.apex, t.b), t.c) / UNITS;
    vec2 xy0 = view_rel_xy(sample_of(lo), view.v.camera_sample, view.v.camera_frac, view.v.spacing_m);
    vec2 xy1 = view_rel_xy(sample_of(hi), view.v.camera_sample, view.v.camera_frac, view.v.spacing_m);
    float z0 = view.v.height_lo + float(bitfieldExtract(d.x, 0, int(HALF_BITS))) * view.v.height_scale;
    float z1 = view.v.height_lo + float(d.x >> HALF_BITS) * view.v.height_scale;
    return projected_px(err, vec3(xy0, z0 - view.v.camera_z), vec3(xy1, z1 - view.v.camera_z));
}

// Emits t as the rule leaves it (a leaf, culled, or split further).
void finish(Tri t, uint what, float px) {
    if (what == CULLED) {
        g_culled += 1u;
        return;
    }
    emit(t);
    if (what == CELL && (g_lod != 0u || g_refine == 0u)) {
        g_grid_px = max(g_grid_px, cell_px(t));
    } else {
        g_bound_px = max(g_bound_px, px);
    }
}

// Adds this invocation's counts and errors to the header (errors >= 0:
// their bits order as the values do).
void flush() {
    if (g_written != 0u) {
        atomicAdd(tris.header.index_count, 3u * g_written);
    }
    if ((g_forced | g_clamped | g_culled) != 0u) {
        atomicAdd(tris.header.forced, g_forced);
        atomicAdd(tris.header.clamped, g_clamped);
        atomicAdd(tris.header.culled, g_culled);
    }
    if (g_bound_px > 0.0) {
        atomicMax(tris.header.bound_bits, floatBitsToUint(g_bound_px));
    }
    if (g_grid_px > 0.0) {
        atomicMax(tris.header.grid_bound_bits, floatBitsToUint(g_grid_px));
    }
}

// Marks of the triangles at EMIT_THREAD_DEPTH the cut reaches (1: reached,
// the invocation of its index walks it).
shared uint s_reached[2u << EMIT_THREAD_DEPTH];

// The triangle half_of(p, which) was cut from: p's hypotenuse ends are
// the half's legs' far ends, mirrored through its right angle.
Tri parent_of(Tri t, uint which) {
    return which == 0u ? Tri(t.b, t.c, 2 * t.apex - t.c) : Tri(t.c, 2 * t.apex - t.b, t.b);
}

// A depth-first walk's step after a triangle is done: up past the second
// halves, then across to the next second half; false when the walk is done.
// The way down is kept as bits (the halves taken, the last lowest) and the
// one triangle moves down, up or across: no per-invocation array (on
// lavapipe every push and pop to one costs a gather or scatter).
bool next_triangle(inout Tri t, inout uint depth, inout uint path) {
    while (depth > 0u && (path & 1u) == 1u) {
        t = parent_of(t, 1u);
        depth -= 1u;
        path >>= 1u;
    }
    if (depth == 0u) {
        return false;
    }
    t = half_of(parent_of(t, 0u), 1u);
    path += 1u;
    return true;
}

// Cell halves below an invocation's triangle (its own subtree's depth to
// the grid's cells), and their marks: a bit each, FINE_WORDS words an
// invocation (only its own).
// (The cells are 2 x EMIT_THREAD_DEPTH below the node's halves: NODE_QUADS is
// 1 << EMIT_THREAD_DEPTH; the invocations' triangles EMIT_THREAD_DEPTH.)
const uint CELL_DEPTH = EMIT_THREAD_DEPTH;
const uint FINE_WORDS = (1u << CELL_DEPTH) / 32u;
shared uint s_fine[256u * FINE_WORDS];

// Depth-first over `root`'s subtree down to the grid's cells, the first
// half before the second as a stack would. Every loop an invocation runs
// counts towards one lavapipe limit (65535 iterations in all, after which
// its loops end), and lavapipe runs every loop in a loop's body on every
// pass, masked: so the decisions hold no loop, and the steps a few
// iterations each (a LOD-0 subtree refined to the finest lattice decides
// 4095 triangles). A triangle `limit` depths below the root is not decided
// here but marked in s_reached at `mark` (its index above the path's
// bits); NO_LIMIT: every triangle is decided, and the LOD-0 cell halves
// marked in s_fine.
const uint NO_LIMIT = 0xffffffffu;
void walk(Tri root, uint limit, uint mark) {
    uint depth = 0u;
    uint path = 0u;
    Tri t = root;
    while (true) {
        if (depth == limit) {
            s_reached[mark | path] = 1u;
        } else {
            float px;
            uint what = decide(t, px);
            if (what == SPLIT) {
                t = half_of(t, 0u);
                depth += 1u;
                path <<= 1u;
                continue;
            }
            if (what == FINE) {
                s_fine[gl_LocalInvocationID.x * FINE_WORDS + (path >> 5u)] |= 1u << (path & 31u);
            } else {
                finish(t, what, px);
            }
        }
        if (!next_triangle(t, depth, path)) {
            break;
        }
    }
}

#include "emit_triangles_cells.glsl"

// Walks an invocation's own subtree, the grid's levels then the ones below.
void walk_subtree(Tri root) {
    for (uint w = 0u; w < FINE_WORDS; ++w) {
        s_fine[gl_LocalInvocationID.x * FINE_WORDS + w] = 0u;
    }
    walk(root, NO_LIMIT, 0u);
    walk_cells(root);
}

// Triangle i (0 .. 2 << depth) of the node's bintree at `depth`: bit
// `depth` of i picks the square's half, the lower bits the halves below.
Tri triangle_at(uint depth, uint i) {
    ivec2 sw = ivec2(0), se = ivec2(g_side_l, 0), nw = ivec2(0, g_side_l), ne = ivec2(g_side_l);
    bool slash = ((g_node.x + g_node.y) & 1) == 0;
    bool first = (i >> depth) == 0u;
    Tri t = slash ? (first ? Tri(se, sw, ne) : Tri(nw, ne, sw)) : (first ? Tri(sw, se, nw) : Tri(ne, nw, se));
    for (uint d = 0u; d < depth; ++d) {
        t = half_of(t, (i >> (depth - 1u - d)) & 1u);
    }
    return t;
}

#ifdef OCCLUSION
// This workgroup's slot's visibility bits, rewritten by phase 2.
shared uint s_visible[VISIBILITY_WORDS_PER_SLOT];

// Whether invocation t's subtree was visible when last tested.
bool was_visible(uint t) {
    return (visibility.words[g_slot * VISIBILITY_WORDS_PER_SLOT + (t >> 5u)] & (1u << (t & 31u))) != 0u;
}
#endif

#ifdef LATE
// Whether any of the subtree under r may show past the pyramid: the box of
// its split vertex holds every triangle under it (a hole under it: its
// box bounds nothing, so it counts as visible).
bool subtree_visible(Tri r) {
    vec3 lo, hi;
    if (vertex_px((r.b + r.c) / (2 * UNITS), lo, hi) >= HUGE_PX) {
        return true;
    }
    uint level;
    return hiz_box_visible(lo, hi, view.v.view_proj, uvec2(pc.depth_w, pc.depth_h), level);
}
#endif

// Walks invocation t's subtree where this phase draws it (all of it
// without occlusion), and in phase 2 notes whether it is visible.
void own_subtree(uint t) {
    Tri root = triangle_at(EMIT_THREAD_DEPTH, t);
#if defined(LATE)
    bool now = subtree_visible(root);
    if (now) {
        atomicOr(s_visible[t >> 5u], 1u << (t & 31u));
    }
    if (now && !was_visible(t)) {
        walk_subtree(root);
    }
#elif defined(OCCLUSION)
    if (was_visible(t)) {
        walk_subtree(root);
    }
#else
    walk_subtree(root);
#endif
}

void main() {
    uvec2 entry = traverse_out.nodes[gl_WorkGroupID.x];
    uint n = entry.x;
    g_slot = entry.y;
    g_lod = node_lod(n);
    g_node = ivec2(node_x(n), node_y(n));
    uint side_u = NODE_SIDE;  // read first: naga cannot parse a converted spec constant
    g_side = int(side_u);
    g_side_l = g_side * UNITS;
    g_refine = min(uint(view.v.lod_params.z), REFINE_LEVELS);
    g_origin_l = g_node * g_side_l;
    uint t = gl_LocalInvocationID.x;
#ifndef LATE
    if (t == 0u) {
        slot_nodes.nodes[g_slot] = n;
    }
#endif
#ifdef LATE
    if (t < VISIBILITY_WORDS_PER_SLOT) {
        s_visible[t] = 0u;
    }
    s_reached[t] = (reached.words[g_slot * VISIBILITY_WORDS_PER_SLOT + (t >> 5u)] >> (t & 31u)) & 1u;
#else
    // The depths above the threads' own, by one invocation: on lavapipe a
    // workgroup barrier costs more than these few hundred decisions, so
    // there is one barrier, not two a depth.
    if (t == 0u) {
        for (uint i = 0u; i < (2u << EMIT_THREAD_DEPTH); ++i) {
            s_reached[i] = 0u;
        }
        for (uint r = 0u; r < 2u; ++r) {
            walk(triangle_at(0u, r), EMIT_THREAD_DEPTH, r << EMIT_THREAD_DEPTH);
        }
    }
#endif
    barrier();
#if defined(OCCLUSION) && !defined(LATE)
    if (t < VISIBILITY_WORDS_PER_SLOT) {
        uint w = 0u;
        for (uint i = 0u; i < 32u; ++i) {
            w |= s_reached[32u * t + i] << i;
        }
        reached.words[g_slot * VISIBILITY_WORDS_PER_SLOT + t] = w;
    }
#endif
    // Each invocation walks the subtree of its own triangle, if the cut reaches it.
    if (s_reached[t] == 1u) {
        own_subtree(t);
    }
#ifdef LATE
    barrier();
    if (t < VISIBILITY_WORDS_PER_SLOT) {
        visibility.words[g_slot * VISIBILITY_WORDS_PER_SLOT + t] = s_visible[t];
    }
#endif
    flush();
}
