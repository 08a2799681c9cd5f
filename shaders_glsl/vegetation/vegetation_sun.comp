#version 460
// `vista vegetate --sun gpu`: the generator's sun share of each listed cell
// of its grid (world/vegetation/sun.rs's `lit` and `lit_share`, in f32):
// over the day's sun positions, the share in which the cell faces the sun
// and a march towards it finds no ground above the ray, bilinear between
// cell centres, steps of half a cell growing by an eighth, to the reach or
// until the ray clears the highest cell or leaves the grid.
layout(local_size_x = 64) in;

layout(set = 0, binding = 0, std430) readonly buffer SunField { float z[]; } field;
layout(set = 0, binding = 1, std430) readonly buffer SunPath { vec4 dir[]; } path;
layout(set = 0, binding = 2, std430) readonly buffer SunCells { uint cell[]; } cells;
layout(set = 0, binding = 3, std430) buffer SunShares { float share[]; } shares;

// grid: cells across, cells up, listed cells, sun samples; march: cell
// side (m), reach (m), the highest cell (m), unused.
layout(push_constant, std430) uniform VegetationSunPush {
    uvec4 grid;
    vec4 march;
} pc;

// Height of cell (i, j), indices clamped to the grid.
float at(int i, int j) {
    i = clamp(i, 0, int(pc.grid.x) - 1);
    j = clamp(j, 0, int(pc.grid.y) - 1);
    return field.z[uint(j) * pc.grid.x + uint(i)];
}

float bilinear(float x, float y) {
    float u = x / pc.march.x - 0.5, v = y / pc.march.x - 0.5;
    float fi = floor(u), fj = floor(v);
    float fu = u - fi, fv = v - fj;
    int i = int(fi), j = int(fj);
    float lo = at(i, j) * (1.0 - fu) + at(i + 1, j) * fu;
    float hi = at(i, j + 1) * (1.0 - fu) + at(i + 1, j + 1) * fu;
    return lo * (1.0 - fv) + hi * fv;
}

// Central differences, one-sided at the grid's edge.
vec3 cell_normal(int i, int j) {
    int nx = int(pc.grid.x), ny = int(pc.grid.y);
    float sx = max(float(min(i + 1, nx - 1) - max(i - 1, 0)), 1.0);
    float sy = max(float(min(j + 1, ny - 1) - max(j - 1, 0)), 1.0);
    float dx = (at(i + 1, j) - at(i - 1, j)) / (sx * pc.march.x);
    float dy = (at(i, j + 1) - at(i, j - 1)) / (sy * pc.march.x);
    return normalize(vec3(-dx, -dy, 1.0));
}

bool lit(int i, int j, vec3 sun) {
    if (dot(cell_normal(i, j), sun) <= 0.0) {
        return false;
    }
    float c = pc.march.x;
    float flat_len = length(sun.xy);
    if (flat_len < 1e-9) {
        return true;
    }
    vec3 d = sun / flat_len;
    vec2 p0 = (vec2(i, j) + 0.5) * c;
    // A little above the ground: a plane facing the sun never shadows itself.
    float z0 = at(i, j) + 1e-3 * c;
    vec2 extent = vec2(pc.grid.xy) * c;
    float t = 0.5 * c;
    while (t <= pc.march.y) {
        vec2 p = p0 + d.xy * t;
        float ray = z0 + d.z * t;
        if (ray > pc.march.z || any(lessThan(p, vec2(0.0))) || any(greaterThan(p, extent))) {
            return true;
        }
        if (bilinear(p.x, p.y) > ray) {
            return false;
        }
        t += max(0.5 * c, t * 0.125);
    }
    return true;
}

void main() {
    uint n = gl_GlobalInvocationID.x;
    if (n >= pc.grid.z) {
        return;
    }
    uint k = cells.cell[n];
    int i = int(k % pc.grid.x), j = int(k / pc.grid.x);
    uint seen = 0u;
    for (uint s = 0u; s < pc.grid.w; ++s) {
        if (lit(i, j, path.dir[s].xyz)) {
            seen += 1u;
        }
    }
    shares.share[n] = pc.grid.w == 0u ? 0.0 : float(seen) / float(pc.grid.w);
}
