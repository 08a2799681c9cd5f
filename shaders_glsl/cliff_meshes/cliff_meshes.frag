#version 460
#extension GL_GOOGLE_include_directive : require
// A cliff mesh in the geometry pass (geometry_outputs.glsl): its steep
// normal classifies it into the cliff flavours, so gbuffer_tiles shades it
// with the same tri-planar cliff materials as the height field's cliffs.
#include "geometry_outputs.glsl"

void main() {
    write_geometry();
}
