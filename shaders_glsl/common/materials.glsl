// One entry of the 256-entry splat material table (render/materials.rs
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

#endif
