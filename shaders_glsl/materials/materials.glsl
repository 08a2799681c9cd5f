// One entry of the 256-entry splat material table (effects/materials
// MaterialGpu): which layer of each detail texture array it samples, and
// how its texture lies on the ground.
#ifndef VISTA_MATERIALS_GLSL
#define VISTA_MATERIALS_GLSL

struct TerrainMaterial {
    uint layers;     // albedo | normal << 8 | height << 16
    float tiling_m;  // metres per texture repeat
    float cos_rot;   // rotation of the texture on its plane
    float sin_rot;
};

// One of the 32 control-map textures (effects/materials ControlGpu):
// its layers and tiling, and seed 004's per-texture parameters.
struct ControlTexture {
    uint layers;        // albedo | normal << 8 | height << 16
    float tiling_m;     // metres per texture repeat
    float threshold;    // as background: its own slope threshold (control code 0)
    float sharpness;    // as overlay: the slope span of its blend into the background
    float slope_damp;   // as background: how much flat ground flattens its normal for the slope test
    float normal_damp;  // as background: how much of the overlay's normal the combination keeps
    float pad0;
    float pad1;
};

#endif
