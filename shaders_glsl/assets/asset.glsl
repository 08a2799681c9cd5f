// The example asset pass (effect assets, effects/assets): mesh vertices
// and placed instances, read by index (no vertex input state).
#ifndef VISTA_ASSET_GLSL
#define VISTA_ASSET_GLSL

struct AssetVertex {
    vec4 position;  // xyz: metres in the mesh's frame (z up, 0 at the ground)
    vec4 normal;    // xyz: unit
};

struct AssetInstance {
    vec4 place;   // x, y: where it stands (world m); z: yaw (radians); w: scale
    vec4 albedo;  // rgb: its own colour (linear)
};

#endif
