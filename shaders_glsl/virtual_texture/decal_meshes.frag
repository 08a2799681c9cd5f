#version 460
#extension GL_GOOGLE_include_directive : require
// A displacement decal's mesh in the geometry pass: what terrain_geometry
// writes for terrain (geometry_outputs.glsl), so gbuffer_tiles shades it
// as terrain, from the pages the decal was blended into.
#include "geometry_outputs.glsl"

void main() {
    write_geometry();
}
