#version 460
#extension GL_GOOGLE_include_directive : require
// The per-triangle rule's draw's fragments (common/terrain_fragment.glsl).
// variants: SINK
#include "terrain_fragment.glsl"
