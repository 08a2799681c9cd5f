// Octahedral unit-vector codes, 8 bits per component. `precise` keeps
// compilers from fusing or reordering the arithmetic, so a CPU twin doing
// the same steps in f32 can give identical codes (the stability issue's
// case 3 compares them).
#ifndef VISTA_OCTAHEDRAL_GLSL
#define VISTA_OCTAHEDRAL_GLSL
#include "constants.glsl"

float oct_sign(float v) {
    return v >= 0.0 ? 1.0 : -1.0;
}

// Unit vector -> [0, 1]^2.
vec2 oct_encode(vec3 n) {
    precise float l1 = abs(n.x) + abs(n.y) + abs(n.z);
    precise vec2 p = n.xy / l1;
    if (n.z < 0.0) {
        precise vec2 folded = (1.0 - abs(p.yx)) * vec2(oct_sign(p.x), oct_sign(p.y));
        p = folded;
    }
    precise vec2 e = p * 0.5 + 0.5;
    return e;
}

// Codes 0..=254, so the square's centre (code 127) and edges are exact:
// +z and the axis directions decode exactly. With 255 steps the centre fell
// between two codes and a flat plane decoded 0.3 degrees tilted, which at
// grazing incidence moved the reconstructed derivatives by whole mips.
const float OCT_CODE_MAX = float(OCT_CODE_LAST);

// Unit vector -> two 8-bit codes (round to nearest, ties up).
uvec2 oct_encode8(vec3 n) {
    precise vec2 scaled = oct_encode(n) * OCT_CODE_MAX + 0.5;
    return uvec2(clamp(floor(scaled), vec2(0.0), vec2(OCT_CODE_MAX)));
}

vec3 oct_decode(vec2 e) {
    vec2 f = e * 2.0 - 1.0;
    vec3 n = vec3(f, 1.0 - abs(f.x) - abs(f.y));
    float t = max(-n.z, 0.0);
    n.xy += vec2(n.x >= 0.0 ? -t : t, n.y >= 0.0 ? -t : t);
    return normalize(n);
}

vec3 oct_decode8(uvec2 code) {
    return oct_decode(vec2(code) / OCT_CODE_MAX);
}

// Two 8-bit codes packed in a word's low 16 bits (x low), as the cliff
// meshes' and the probes' vertices and grass's ground normal carry them.
vec3 oct_decode_packed(uint code) {
    return oct_decode8(uvec2(code & 0xFFu, (code >> 8u) & 0xFFu));
}

#endif
