#version 460
// Exclusive prefix sum of up to 256 * ITEMS_PER_THREAD u32 in ONE workgroup,
// through shared memory: the building block of the single-dispatch quadtree
// traversal (its lists live in shared memory the same way).
layout(local_size_x = 256) in;

// Items each thread scans serially before the shared-memory pass; a
// specialization constant so the capacity can change without recompiling.
layout(constant_id = 0) const uint ITEMS_PER_THREAD = 4;

layout(set = 0, binding = 0, std430) readonly buffer Input { uint values[]; } input_values;
layout(set = 0, binding = 1, std430) buffer Output { uint sums[]; } output_sums;
layout(push_constant, std430) uniform PrefixSumPush { uint count; } pc;

// Two halves: Hillis-Steele ping-pong, so no step reads what it overwrites.
shared uint partial[2][256];

void main() {
    uint t = gl_LocalInvocationID.x;
    uint base = t * ITEMS_PER_THREAD;
    uint local_sum = 0;
    for (uint i = 0; i < ITEMS_PER_THREAD; ++i) {
        uint idx = base + i;
        local_sum += idx < pc.count ? input_values.values[idx] : 0u;
    }
    uint src = 0;
    partial[src][t] = local_sum;
    barrier();
    for (uint offset = 1; offset < 256u; offset <<= 1) {
        uint v = partial[src][t];
        if (t >= offset) {
            v += partial[src][t - offset];
        }
        partial[1 - src][t] = v;
        src = 1 - src;
        barrier();
    }
    // Inclusive scan of the thread totals minus our own total = exclusive base.
    uint running = partial[src][t] - local_sum;
    for (uint i = 0; i < ITEMS_PER_THREAD; ++i) {
        uint idx = base + i;
        if (idx < pc.count) {
            output_sums.sums[idx] = running;
            running += input_values.values[idx];
        }
    }
}
