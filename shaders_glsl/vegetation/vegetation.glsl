// Trees and bushes (effect vegetation, effects/vegetation): `vista
// vegetate`'s instances, their types, the meshes (unit height), and the
// header of the six indexed indirect draws and the culling counters.
#ifndef VISTA_VEGETATION_GLSL
#define VISTA_VEGETATION_GLSL

// One instance as `vista vegetate` writes it (instances.bin, 32 bytes).
struct VegetationInstance {
    float x;        // world metres from the south-west corner
    float y;
    float z;        // the ground there (the height source's)
    float yaw;      // radians
    float scale;    // times the type's height
    uint type_id;   // index into the types
    uint tint;      // RGBA8 (linear): the crown's
    uint cell;      // the generator's cell
};

struct VegetationType {
    vec4 crown;       // rgb: the crown's colour (linear)
    float height_m;   // a scale-1 instance's height
    uint kind;        // 0 tree, 1 bush: the mesh
    float draw_m;     // drawn within this distance of the camera
    float pad;
};

// A cell of the instances' grid (effects/vegetation/clusters.rs): the box
// around its instances' bounding spheres, the farthest draw distance of
// their types, and where they lie in the sorted list.
struct VegetationCluster {
    vec4 lo;       // xyz: the box's low corner (world m); w: the farthest draw distance
    vec4 hi;       // xyz: its high corner
    uint first;
    uint count;
    uint pad0;
    uint pad1;
};

struct VegetationVertex {
    vec4 position;  // xyz: the mesh at unit height (z up, 0 at the ground)
    vec4 normal;    // xyz: unit; w: 0 trunk, 1 crown
};

// VEG_KINDS x VEG_LODS VkDrawIndexedIndirectCommands (kind-major), then
// the counters.
struct VegetationHeader {
    uint draws[30];   // 5 words each: index count, instance count, first index, vertex offset, first instance
    uint considered;        // instances tested one by one
    uint culled_distance;
    uint culled_frustum;
    uint culled_hiz;
    uint clusters_culled;   // clusters culled whole (distance, frustum or pyramid)
    uint skipped;           // their instances, never visited
    uint pad0;
    uint pad1;
};

#endif
