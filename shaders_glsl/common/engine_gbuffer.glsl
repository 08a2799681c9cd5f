// Output `gbuffer`: the terrain's surface written straight into the
// engine's G-buffer (targets/gbuffer_layout.rs). Four outputs, one per
// attachment the layout may have (a pipeline with fewer attachments gives
// the rest no format and no image: their writes are discarded); each
// channel is picked by a specialization constant, so a layout compiles
// into the passes' pipelines and costs no branch per pixel after the
// driver folds the constants. Includers: gbuffer_tiles, grass_draw,
// asset_draw (variant ENGINE_GBUFFER).
#ifndef VISTA_ENGINE_GBUFFER_GLSL
#define VISTA_ENGINE_GBUFFER_GLSL
#include "constants.glsl"
#include "octahedral.glsl"
#include "srgb.glsl"

layout(constant_id = 16) const uint GB_CHANNELS0 = 0u;
layout(constant_id = 17) const uint GB_CHANNELS1 = 0u;
layout(constant_id = 18) const uint GB_CHANNELS2 = 0u;
layout(constant_id = 19) const uint GB_CHANNELS3 = 0u;
layout(constant_id = 20) const uint GB_FLAGS = 0u;

layout(location = 0) out vec4 engine_gb0;
layout(location = 1) out vec4 engine_gb1;
layout(location = 2) out vec4 engine_gb2;
layout(location = 3) out vec4 engine_gb3;

// One attachment's texel: `channels` its nibble codes, `flags` its byte.
vec4 gb_attachment(uint channels, uint flags, vec3 base, vec3 normal, float roughness, uint material) {
    vec3 b = (flags & GB_FLAG_SRGB_ENCODE) != 0u ? srgb_encode(clamp(base, 0.0, 1.0)) : base;
    vec3 n = (flags & GB_FLAG_SIGNED) != 0u ? normal : normal * 0.5 + 0.5;
    vec4 texel = vec4(0.0);
    for (uint k = 0u; k < 4u; ++k) {
        uint code = (channels >> (4u * k)) & 15u;
        float v = 0.0;
        switch (code) {
            case GB_CHANNEL_ONE: v = 1.0; break;
            case GB_CHANNEL_BASE_R: v = b.r; break;
            case GB_CHANNEL_BASE_G: v = b.g; break;
            case GB_CHANNEL_BASE_B: v = b.b; break;
            case GB_CHANNEL_NORMAL_X: v = n.x; break;
            case GB_CHANNEL_NORMAL_Y: v = n.y; break;
            case GB_CHANNEL_NORMAL_Z: v = n.z; break;
            case GB_CHANNEL_ROUGHNESS: v = roughness; break;
            case GB_CHANNEL_MATERIAL: v = float(material) / 255.0; break;
            default: break;
        }
        texel[k] = v;
    }
    return texel;
}

// Writes the surface: linear base colour, unit world normal (z up),
// roughness, splat palette id.
void write_engine_gbuffer(vec3 base, vec3 normal, float roughness, uint material) {
    // Variables, not constant expressions: naga reads no SpecConstantOp.
    uint flags = GB_FLAGS;
    uint c0 = GB_CHANNELS0;
    uint c1 = GB_CHANNELS1;
    uint c2 = GB_CHANNELS2;
    uint c3 = GB_CHANNELS3;
    // The octahedral map's coordinates in [-1, 1] (z unused).
    vec3 stored = (flags & GB_FLAG_OCTAHEDRAL) != 0u ? vec3(oct_encode(normal) * 2.0 - 1.0, 0.0) : normal;
    engine_gb0 = gb_attachment(c0, flags, base, stored, roughness, material);
    engine_gb1 = gb_attachment(c1, flags >> 8u, base, stored, roughness, material);
    engine_gb2 = gb_attachment(c2, flags >> 16u, base, stored, roughness, material);
    engine_gb3 = gb_attachment(c3, (flags >> 24u) & 0x7Fu, base, stored, roughness, material);
}

#endif
