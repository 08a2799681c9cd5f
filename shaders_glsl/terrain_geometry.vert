#version 460
#extension GL_GOOGLE_include_directive : require
// Patches without holes (most of them): no hole test. See terrain_vertex.glsl.
#include "terrain_vertex.glsl"
