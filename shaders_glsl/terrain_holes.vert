#version 460
#extension GL_GOOGLE_include_directive : require
// Patches with some holes (the hole list of cull_patches): hole vertices
// become NaN. Shaded by terrain_geometry.frag. See terrain_vertex.glsl.
#define TERRAIN_HOLES 1
#include "terrain_vertex.glsl"
