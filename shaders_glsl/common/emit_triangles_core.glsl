// What emit_triangles and emit_fine share (the per-triangle rule's cut;
// emit_triangles.comp says how it stays conforming): the bindings both
// read and write, a triangle and its steps, the vertices' numbers, the
// decisions below a LOD-0 node's samples, and what a triangle left whole
// adds to the list and its counters. Its includer declares the workgroup.
#ifndef VISTA_EMIT_TRIANGLES_CORE_GLSL
#define VISTA_EMIT_TRIANGLES_CORE_GLSL

#include "node_list.glsl"
#include "terrain_view.glsl"
#include "atlas_texels.glsl"
#include "triangle_list.glsl"
#include "fine_cells.glsl"

// Quads per node side (world NODE_QUADS): 1 << EMIT_THREAD_DEPTH.
layout(constant_id = 0) const uint NODE_SIDE = 128u;
// Quads per patch side (world PATCH_QUADS): the squares patch_holes flags.
layout(constant_id = 1) const uint PATCH_QUADS = 8u;

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
// The LOD-0 cell halves whose levels below the samples emit_fine walks
// (emit_triangles appends them).
layout(set = 0, binding = 13, std430) buffer FineCells {
    FineCellsHeader header;
    uint cells[];
} fine;

// Per patch of a node, whether its samples are all, some or no holes
// (PATCH_HOLE_*): a subtree inside an all-hole patch draws nothing.
layout(set = 0, binding = 14) uniform utexture2DArray patch_holes;

layout(push_constant, std430) uniform EmitPush {
    uint capacity;  // triangles the list holds
    uint cull;      // EMIT_CULL_* bits: the frustum, holes, facing (CullStages::frustum, ::hole, ::cone)
    uint depth_w;   // LATE: the depth target's size (the pyramid's level 0 is made from it)
    uint depth_h;
    uint fine_capacity;  // cell halves the fine list holds (MAX_FINE_CELLS; less in tests)
} pc;

#include "projected_error.glsl"
#include "frustum_box.glsl"
#include "refined_surface.glsl"

const uint LEAF = 0u;
const uint SPLIT = 1u;
const uint CULLED = 2u;
// A leaf whose hypotenuse has no midpoint in the grid (a cell's half), or
// below a LOD-0 node's samples in the finest lattice.
const uint CELL = 3u;
// A LOD-0 node's cell half: the levels below its samples are walked by
// emit_fine, so emit_triangles' walk holds none of those decisions
// (lavapipe runs every branch of a loop's body, masked).
const uint FINE = 4u;
// Inside a patch whose samples are all holes: every vertex under it is NaN.
const uint HOLES = 5u;

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
uint g_holes = 0u;
uint g_facing = 0u;
uint g_outside = 0u;
// LOD-0 cell halves drawn whole: the fine list was full (emit_triangles).
uint g_unrefined = 0u;
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

// The LOD of the listed node covering sector q, or NO_LOD.
uint lod_at(ivec2 q) {
    if (any(lessThan(q, ivec2(0))) || q.x >= int(view.v.lod_map_w) || q.y >= int(view.v.lod_map_h)) {
        return NO_LOD;
    }
    return imageLoad(lod_map, q).r;
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

// Whether t is the half of a patch's square and the patch's samples are all
// holes (a vertex below the samples takes its nearest sample's flag,
// inside the patch too): nothing under t is drawn. Only that level looks:
// a finer triangle lies in the patch its ancestor there was tested in,
// and a coarser one spans several (the cost is one fetch per patch the
// cut reaches, not one per decision).
bool all_holes(Tri t) {
    ivec2 lo = min(min(t.apex, t.b), t.c), hi = max(max(t.apex, t.b), t.c);
    uint quads = PATCH_QUADS;
    int patch_l = int(quads) * UNITS;
    if (any(notEqual(hi - lo, ivec2(patch_l)))) {
        return false;
    }
    return texelFetch(usampler2DArray(patch_holes, nearest), ivec3(lo / patch_l, int(g_slot)), 0).r == PATCH_HOLE_ALL;
}

#include "emit_triangles_fine.glsl"

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

// Grid point p's place as terrain_triangles puts it (camera-relative m;
// p in lattice units, on the grid).
vec3 grid_point(ivec2 p) {
    ivec2 g = p / UNITS;
    float h = texelFetch(sampler2DArray(height_atlas, nearest), ivec3(atlas_texel(g), int(g_slot)), 0).r;
    vec2 xy = view_rel_xy(sample_of(g), view.v.camera_sample, view.v.camera_frac, view.v.spacing_m);
    return vec3(xy, view.v.height_lo + h * view.v.height_range - view.v.camera_z);
}

// Whether all of a, b and c lie outside plane p by more than float error.
bool outside_plane(vec4 p, vec3 a, vec3 b, vec3 c) {
    float pad = 1e-3 + 1e-5 * (length(a) + length(b) + length(c));
    return max(max(dot(p.xyz, a), dot(p.xyz, b)), dot(p.xyz, c)) + p.w < -pad;
}

// Whether triangle a, b, c (camera-relative, placed as terrain_triangles
// places its vertices) is hidden on its own, counted: it faces away from
// the camera (EMIT_CULL_FACING: by more than half a degree, so no rounding
// in the rasteriser's own test turns it) or lies outside a frustum plane
// (EMIT_CULL_FRUSTUM; its subtree's box, tested first, spans its
// vertices' whole reach).
bool hidden(vec3 a, vec3 b, vec3 c) {
    // The plane's normal up (a height field's front faces look up).
    vec3 n = cross(b - a, c - a);
    n = n.z < 0.0 ? -n : n;
    if ((pc.cull & EMIT_CULL_FACING) != 0u && dot(n, a) > 1e-2 * length(n) * length(a)) {
        g_facing += 1u;
        return true;
    }
    if ((pc.cull & EMIT_CULL_FRUSTUM) != 0u
        && (outside_plane(view.v.frustum[0], a, b, c) || outside_plane(view.v.frustum[1], a, b, c)
            || outside_plane(view.v.frustum[2], a, b, c) || outside_plane(view.v.frustum[3], a, b, c)
            || outside_plane(view.v.frustum[4], a, b, c))) {
        g_outside += 1u;
        return true;
    }
    return false;
}

// Whether the frame tests triangles on their own (hidden).
bool tests_triangles() {
    return (pc.cull & (EMIT_CULL_FACING | EMIT_CULL_FRUSTUM)) != 0u;
}

// Emits triangle t of the node's grid unless it is hidden on its own. A
// triangle with a vertex below the samples is emitted as it is: walk_fine
// tests those, with the heights of its cell's taps.
void emit_unless_hidden(Tri t) {
    ivec2 any_bits = t.apex | t.b | t.c;
    if (!tests_triangles() || ((any_bits.x | any_bits.y) & (UNITS - 1)) != 0
        || !hidden(grid_point(t.apex), grid_point(t.b), grid_point(t.c))) {
        emit(t);
    }
}

// Counts a subtree the rule drops (CULLED or HOLES).
void count_dropped(uint what) {
    if (what == CULLED) {
        g_culled += 1u;
    } else {
        g_holes += 1u;
    }
}

// Emits grid triangle t as the rule leaves it (a leaf, or dropped).
void finish(Tri t, uint what, float px) {
    if (what == CULLED || what == HOLES) {
        count_dropped(what);
        return;
    }
    emit_unless_hidden(t);
    g_bound_px = max(g_bound_px, px);
}

// Adds this invocation's counts and errors to the header (errors >= 0:
// their bits order as the values do).
void flush() {
    if (g_written != 0u) {
        atomicAdd(tris.header.index_count, 3u * g_written);
    }
    if ((g_forced | g_clamped | g_culled | g_unrefined | g_holes) != 0u) {
        atomicAdd(tris.header.forced, g_forced);
        atomicAdd(tris.header.clamped, g_clamped);
        atomicAdd(tris.header.culled, g_culled);
        atomicAdd(tris.header.unrefined, g_unrefined);
        atomicAdd(tris.header.holes, g_holes);
    }
    if ((g_facing | g_outside) != 0u) {
        atomicAdd(tris.header.facing_away, g_facing);
        atomicAdd(tris.header.outside, g_outside);
    }
    if (g_bound_px > 0.0) {
        atomicMax(tris.header.bound_bits, floatBitsToUint(g_bound_px));
    }
    if (g_grid_px > 0.0) {
        atomicMax(tris.header.grid_bound_bits, floatBitsToUint(g_grid_px));
    }
}

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

// The triangle `depth` levels below t along `path` (its bits the halves
// taken, the first highest).
Tri below(Tri t, uint depth, uint path) {
    for (uint d = 0u; d < depth; ++d) {
        t = half_of(t, (path >> (depth - 1u - d)) & 1u);
    }
    return t;
}

// Triangle i (0 .. 2 << depth) of the node's bintree at `depth`: bit
// `depth` of i picks the square's half, the lower bits the halves below.
Tri triangle_at(uint depth, uint i) {
    ivec2 sw = ivec2(0), se = ivec2(g_side_l, 0), nw = ivec2(0, g_side_l), ne = ivec2(g_side_l);
    bool slash = ((g_node.x + g_node.y) & 1) == 0;
    bool first = (i >> depth) == 0u;
    Tri t = slash ? (first ? Tri(se, sw, ne) : Tri(nw, ne, sw)) : (first ? Tri(sw, se, nw) : Tri(ne, nw, se));
    return below(t, depth, i);
}

// A triangle's preorder index in a subtree `levels` deep (its root at 0,
// its leaves at `levels`): `depth` below the root along `path` (the
// halves taken, the first highest); a second half at depth d skips the
// 2^(levels + 1 - d) - 1 triangles of the first. (Walks mark the
// triangles they leave whole by it and emit them after the loop: lavapipe
// runs a loop's whole body on every pass, masked, so a test in it would
// run on every decision.)
uint preorder(uint depth, uint path, uint levels) {
    return depth + (path << (levels + 1u - depth)) - uint(bitCount(path));
}

// The triangle at preorder index i under root (a subtree `levels` deep).
Tri preorder_triangle(Tri root, uint i, uint levels) {
    Tri t = root;
    for (uint d = 0u; d < levels && i != 0u; ++d) {
        i -= 1u;
        // Triangles under each half of a triangle at depth d.
        uint under = (1u << (levels - d)) - 1u;
        uint second = i >= under ? 1u : 0u;
        i -= second * under;
        t = half_of(t, second);
    }
    return t;
}

// Points this invocation at the drawn node n in `slot`.
void enter_node(uint n, uint slot) {
    g_slot = slot;
    g_lod = node_lod(n);
    g_node = ivec2(node_x(n), node_y(n));
    uint side_u = NODE_SIDE;  // read first: naga cannot parse a converted spec constant
    g_side = int(side_u);
    g_side_l = g_side * UNITS;
    g_refine = min(uint(view.v.lod_params.z), REFINE_LEVELS);
    g_origin_l = g_node * g_side_l;
}

#include "emit_triangles_cells.glsl"

#endif
