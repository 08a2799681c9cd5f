#version 460
#extension GL_GOOGLE_include_directive : require
// Grass (effect grass): ONE instanced indirect draw of every tuft
// grass_place kept (instance = tuft), GRASS_BLADES bent blades each, made
// from the vertex index: a blade is a quad from its root to 0.55 of its
// height and a tip triangle, as wide as WIDTH_PER_M of its height, leaning
// towards its facing by the tuft's lean. The tuft's colour is the pigment
// map's (the ground's albedo under it) times its material's tint.
#include "constants.glsl"
#include "terrain_view.glsl"
#include "octahedral.glsl"
#include "grass.glsl"

layout(set = 0, binding = 0, std430) readonly buffer View { TerrainView v; } view;
layout(set = 0, binding = 1, std430) readonly buffer Instances { GrassInstance i[]; } instances;
layout(set = 0, binding = 2, std430) readonly buffer Rules { GrassRule r[]; } rules;
layout(set = 0, binding = 3) uniform texture2D pigment;
layout(set = 0, binding = 4) uniform sampler linear_clamp;

layout(push_constant, std430) uniform GrassDrawPush {
    vec2 pigment_origin_m;  // the pigment map's south-west corner (world m)
    float pigment_size_m;   // its side
    float width_per_m;      // a blade's root width per metre of its height
} pc;

layout(location = 0) out vec3 colour;
layout(location = 1) out float along;  // 0 at the root, 1 at the tip
layout(location = 2) out vec3 normal;  // world, unnormalised
layout(location = 3) flat out uint material;

// The blade's corners: 0, 1 the root (left, right), 2, 3 the middle, 4 the tip.
const uint CORNER[9] = uint[9](0u, 1u, 2u, 2u, 1u, 3u, 2u, 3u, 4u);

void main() {
    uint tuft = uint(gl_InstanceIndex);
    uint blade = uint(gl_VertexIndex) / GRASS_BLADE_VERTICES;
    uint corner = CORNER[uint(gl_VertexIndex) % GRASS_BLADE_VERTICES];
    vec4 pos = instances.i[tuft].position;
    uint packed = instances.i[tuft].packed;
    uint code = instances.i[tuft].normal;
    float turn = (float((packed >> 8u) & 0xFFu) / 256.0 + float(blade) / float(GRASS_BLADES)) * 6.2831853;
    vec2 facing = vec2(cos(turn), sin(turn));
    vec2 across = vec2(-facing.y, facing.x);
    float lean = 0.15 + 0.35 * float(packed >> 16u) / 255.0;
    float t = corner < 2u ? 0.0 : (corner < 4u ? 0.55 : 1.0);
    float side = corner == 4u ? 0.0 : ((corner & 1u) == 0u ? -0.5 : 0.5);
    float h = pos.w * (1.0 - 0.15 * float(blade));
    float w = h * pc.width_per_m * (1.0 - 0.6 * t);
    vec3 offset = vec3(across * side * w + facing * (lean * h * t * t), h * t);
    vec3 rel = vec3(pos.xy - view.v.camera_world.xy, pos.z - view.v.camera_world.z) + offset;
    gl_Position = view.v.view_proj * vec4(rel, 1.0);

    vec2 uv = (pos.xy - pc.pigment_origin_m) / pc.pigment_size_m;
    vec4 p = textureLod(sampler2D(pigment, linear_clamp), uv, 0.0);
    material = packed & 0xFFu;
    colour = p.rgb * p.rgb * rules.r[material].tint.rgb;
    along = t;
    // Lit as the ground it stands on, the tips turned a little to their facing.
    vec3 ground = oct_decode_packed(code);
    normal = ground + vec3(facing * (0.5 * t), 0.0);
}
