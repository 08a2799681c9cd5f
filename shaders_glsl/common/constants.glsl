// Every constant shared by host and shader code: the single source. build.rs
// parses this file (one `#define NAME VALUE` per line, VALUE an unsigned
// literal with a `u` suffix) and exports each as `vista::shaders::consts::NAME`
// (u32); host code uses those, never a copy. Any other line here is an error.
#ifndef VISTA_CONSTANTS_GLSL
#define VISTA_CONSTANTS_GLSL

// Node texture (R16_UINT, one mip per LOD): a slot, or one of these.
#define NODE_EMPTY 0xFFFFu
#define NODE_INVALID 0xFFFEu
// Slot 0 is never allocated: sector data uses 0 for "no node".
#define FIRST_SLOT 1u
// Slots are 11-bit in sector data, node descriptions and patch records:
// every slot is an atlas layer, and 2048 layers is what Vulkan guarantees
// (maxImageArrayLayers; lavapipe and NVIDIA allow no more).
#define SLOT_BITS 11u
#define MAX_SLOTS 2047u
// Node description word 1: slot | lod << 11 | bias (4 bits, signed) << 15 | holes << 19.
#define DESC_LOD_SHIFT 11u
#define DESC_BIAS_SHIFT 15u
#define DESC_BIAS_BITS 4u
#define DESC_HOLES_SHIFT 19u
// Node description word 0 and the node texture hold 16-bit values.
#define HALF_BITS 16u
// Packed node reference: lod (4 bits) << 28 | y (14 bits) << 14 | x (14 bits).
#define NODE_REF_LOD_SHIFT 28u
#define NODE_REF_Y_SHIFT 14u
#define NODE_REF_COORD_MASK 0x3FFFu
// Levels of the per-LOD arrays (lod_counts, traverse_level's level args).
#define MAX_LEVELS 16u
// Node texture mips the quadtree_update pass can write (world MAX_LOD_COUNT).
#define MAX_NODE_LODS 10u
// Normal and albedo atlas layers: texel t holds node sample t - ATLAS_BORDER
// (samples -2..129), so bilinear filtering anywhere in a node reads only
// its own layer and the side is a whole number of 4x4 BC blocks.
#define ATLAS_TEXTURE_SIDE 132u
#define ATLAS_BORDER 2u
// Up to this many cameras refine one node list (two keep the traversal's
// push constants, with each camera's forward axis, within 128 bytes).
#define MAX_CAMERAS 2u
// Entries of each shared-memory list of traverse.comp: every entry is a
// distinct resident node, so the slot budget (<= MAX_SLOTS) bounds it.
#define SHARED_LIST_CAPACITY 2048u
// `current_lod` of traverse_level's finalize dispatch.
#define LEVEL_FINALIZE 0xFFu
// Sector data holds the slot of every LOD (up to MAX_NODE_LODS), 2 per
// u32 word at SLOT_BITS each: ceil(MAX_NODE_LODS / 2) words per sector.
#define SECTOR_LODS_PER_WORD 2u
#define SECTOR_DATA_WORDS 5u
// quadtree_update targets beside a node-texture mip.
#define UPDATE_TARGET_DESC 0xFFu
#define UPDATE_TARGET_ERROR 0xFEu
// LOD map value where no listed node covers a sector.
#define NO_LOD 0xFFu
// cull_patches stage switches.
#define CULL_STAGE_FRUSTUM 1u
#define CULL_STAGE_CONE 2u
#define CULL_STAGE_HOLE 4u
#define CULL_STAGE_OCCLUSION 8u
// Not a stage: holes switched off for the frame (FrameSwitches::holes).
#define CULL_HOLES_OFF 16u
// Patch hole summary (one texel per patch).
#define PATCH_HOLE_NONE 0u
#define PATCH_HOLE_SOME 1u
#define PATCH_HOLE_ALL 2u
// Patch record word 1: slot | patch index (8 bits) << 11 | 4 LOD deltas (3 bits each) << 19.
#define PATCH_INDEX_SHIFT 11u
#define PATCH_INDEX_MASK 0xFFu
#define PATCH_DELTA_SHIFT 19u
#define PATCH_DELTA_BITS 3u
// Largest stitched LOD delta. Above log2(PATCH_QUADS) = 3 an edge snaps to
// vertices beyond the patch's corners (terrain_vertex.glsl), so such a
// patch covers part of its neighbour's ground and is never frustum- or
// occlusion-culled (patch_cull.glsl).
#define MAX_LOD_DELTA 4u
// Per-patch LOD selection (select_patches): a listed node's patch may be
// drawn from an ancestor up to this many levels coarser (its patch covers
// 2^a x 2^a of the node's patches; 4 would be the whole node).
#define MAX_COARSEN 3u
// Refinement below LOD 0: 2x and 4x denser vertices on the Catmull-Rom
// surface of the samples, as 4 or 16 sub-patches of the same 8x8 grid.
#define REFINE_LEVELS 2u
// Patch record word 2: refinement level (2 bits) | sub-patch index << 2.
#define PATCH_REFINE_MASK 3u
#define PATCH_SUB_SHIFT 2u
// LOD-0 patches refined per frame at most (the patch lists are sized for
// them); beyond, a patch is drawn at LOD 0 and counted.
#define MAX_REFINED_PATCHES 8192u
// When more LOD-0 patches ask to be refined than the budget allows, the
// ones refined are chosen by priority, not by which workgroup came first
// (select_patches, phases 2 and 3): REFINE_BUCKETS buckets of the patch's
// projected error over the target, REFINE_BUCKETS_PER_OCTAVE to a doubling;
// whole buckets are kept or refused, so the set is the same on any device.
#define REFINE_BUCKETS 256u
#define REFINE_BUCKETS_PER_OCTAVE 16u
// The per-triangle rule (emit_triangles): a vertex of the emitted index
// list is its point, x and y in lattice units of its node (2^-REFINE_LEVELS
// grid steps, 0..NODE_QUADS << REFINE_LEVELS: a LOD-0 node refines below
// its samples), and its slot: the low TRIANGLE_LOW_BITS of x, then of y,
// then the high TRIANGLE_HIGH_BITS of x, then of y, then the slot; the
// lowest byte is then XORed with the top byte of the bits above it times
// TRIANGLE_MIX_MUL (triangle_list.glsl). lavapipe's vertex cache is 256
// entries indexed by an index's lowest byte: with the slot there every
// vertex of a node took one entry, and with only x's and y's low bits
// every grid point of a cut coarser than 4 samples did (their low bits are
// 0), so almost no vertex was shaded once.
#define TRIANGLE_LOW_BITS 4u
#define TRIANGLE_HIGH_BITS 6u
#define TRIANGLE_SLOT_SHIFT 20u
#define TRIANGLE_MIX_MUL 0x9E3779B1u
// emit_triangles' culling stages (EmitPush.cull bits).
#define EMIT_CULL_FRUSTUM 1u
#define EMIT_CULL_HOLES 2u
// A drawn triangle on the node's grid facing away from the camera (effect
// cone_cull: each triangle's own plane, exact, where patches test a cone).
#define EMIT_CULL_FACING 4u
// The depth of the subtrees emit_triangles walks, each in one go: 2 <<
// depth = 256 of them a node, 4 under each of its invocations' own
// triangles (EMIT_GROUP_SIZE below).
#define EMIT_THREAD_DEPTH 7u
// emit_triangles' invocations: each decides the triangles above on its way
// to its own 4 triangles at EMIT_THREAD_DEPTH (2 << EMIT_THREAD_DEPTH of
// them in all), then walks some of those the cut reaches.
#define EMIT_GROUP_SIZE 64u
// LOD-0 cell halves a phase's fine list holds (4 MiB), each walked below
// the samples by one emit_fine invocation; beyond, emit_triangles draws a
// cell half whole and counts it (its node's error then bounds it).
#define MAX_FINE_CELLS 1048576u
#define FINE_GROUP_SIZE 64u
// Counters before the per-slot levels in the selection buffer.
#define SELECT_HEADER_WORDS 4u
// A region no listed node covers (outside the world, or no root yet).
#define NO_LEVEL 0x7FFFu
// Edge order of the patch deltas.
#define EDGE_WEST 0u
#define EDGE_EAST 1u
#define EDGE_SOUTH 2u
#define EDGE_NORTH 3u
// Backface culling: one normal cone per 2 x 2 patches, holding all four's
// triangles (a node's GPU payload stays within 70 KB).
#define CONE_BLOCK_PATCHES 2u
// Occlusion: visibility bits per slot (one bit per patch, 256 patches).
#define VISIBILITY_WORDS_PER_SLOT 8u
// G-buffer tile shading: one bit per shading flavour a pixel needs (the
// classification target); a tile's OR of them is its shader variant.
#define FLAVOUR_VIRTUAL_TEXTURE 1u
#define FLAVOUR_FAR_ATLAS 2u
#define FLAVOUR_NEAR_CLIFF 4u
#define FLAVOUR_FAR_CLIFF 8u
#define FLAVOUR_SPLAT 16u
#define FLAVOUR_CONTROL_MAP 32u
#define FLAVOUR_VARIANTS 64u
// Flavour bits (log2 of FLAVOUR_VARIANTS).
#define FLAVOUR_BITS 6u
// The flavour bits of a classification (the rest say more about the pixel).
#define FLAVOUR_MASK 63u
// A control-map pixel's tri-planar background samples 2 or more planes
// (bit 6), 3 planes (bit 7): a tile's OR gives its largest plane count.
#define CLASS_PLANES_2 64u
#define CLASS_PLANES_3 128u
// Control-map words (seed 004; world/control_map.rs): bits 0-4 overlay
// texture, 5-9 background texture, 10-12 UV scale code, 13-15 slope
// threshold code (0: the background texture's own; 1-7: a table value).
#define CONTROL_OVERLAY_SHIFT 0u
#define CONTROL_BACKGROUND_SHIFT 5u
#define CONTROL_UV_SCALE_SHIFT 10u
#define CONTROL_THRESHOLD_SHIFT 13u
#define CONTROL_TEXTURE_MASK 31u
#define CONTROL_CODE_MASK 7u
#define CONTROL_TEXTURES 32u
// Screen tiles of classify_tiles (pixels per side).
#define TILE_SIZE 8u
// The geometry pass's patch info (R8_UINT, for the debug views): bits 0-3
// the node's LOD, 4-5 the levels refined below LOD 0, 6 drawn in
// occlusion culling's phase 2, 7 within a pixel of the patch grid's edge.
#define PATCH_INFO_LOD_MASK 15u
#define PATCH_INFO_REFINE_SHIFT 4u
#define PATCH_INFO_PHASE_SHIFT 6u
#define PATCH_INFO_EDGE_SHIFT 7u
// The debug views (debug_view.frag's modes).
#define DEBUG_VIEW_LOD 0u
#define DEBUG_VIEW_CLASSIFICATION 1u
#define DEBUG_VIEW_EDGES 2u
#define DEBUG_VIEW_PHASE 3u
// Entries of the splat material table.
#define MATERIAL_COUNT 256u
// Splat map texels per node side (65x65: one per two height samples).
#define SPLAT_TEXELS 65u
// The largest octahedral normal code (octahedral.glsl): 255 codes per axis.
#define OCT_CODE_LAST 254u
// Sun shadows (effects/shadows): node shadow jobs one sun_shadows
// dispatch takes (the update budget plus a frame's uploads); the largest
// shadow texture side per node.
#define SUN_SHADOW_MAX_JOBS 80u
#define SUN_SHADOW_MAX_SIDE 257u

// Adaptive virtual texture (effect virtual_texture, effects/virtual_texture):
// physical tiles of VT_TILE_TEXELS texels a side plus VT_TILE_BORDER on
// each side; a region's sub-texture has levels 0..K (2^L pages a side at
// level L), K at most VT_MAX_LEVEL.
#define VT_TILE_TEXELS 128u
#define VT_TILE_BORDER 4u
#define VT_MAX_LEVEL 7u
#define VT_NONE 0xFFFFFFFFu
// The state buffer: VT_STATE_HEADER words (regions x, regions y,
// indirection side, cache tiles per row, region metres as float bits,
// cache texels x, y, window side W in regions), a sub-texture word per
// window slot (W x W; region (x, y) in slot x mod W + (y mod W) W), the
// region each slot holds per slot, then the indirection's mips (a
// physical tile index per texel, or VT_NONE).
#define VT_STATE_HEADER 8u
// Sub-texture word: mip-0 x | y << 11 | K << 22 (VT_NONE: no sub-texture).
#define VT_SUB_Y_SHIFT 11u
#define VT_SUB_COORD_MASK 0x7FFu
#define VT_SUB_K_SHIFT 22u
// Page request: word 0 the region, word 1 level | x << 4 | y << 12.
#define VT_REQ_X_SHIFT 4u
#define VT_REQ_Y_SHIFT 12u
#define VT_REQ_LEVEL_MASK 15u
#define VT_REQ_COORD_MASK 0xFFu
// Feedback: one sample per VT_FEEDBACK_STRIDE^2 pixels, its place in the
// block jittered over VT_FEEDBACK_STRIDE^2 frames (seed 000: 1/8 size).
#define VT_FEEDBACK_STRIDE 8u
// Requests one frame can list (more are counted, not listed).
#define VT_REQUEST_CAPACITY 16384u
// Pages vt_pages renders in one frame at most, and state writes vt_update applies.
#define VT_MAX_JOBS 256u
#define VT_MAX_WRITES 8192u

// Decals in the virtual texture's pages (effect decals,
// effects/virtual_texture/decals.rs): at most DECAL_MAX decals with
// DECAL_MAX_POINTS road points in all, DECAL_MAX_TEXTURES textures of
// DECAL_TEXELS a side (one layer each, with mips), and DECAL_MAX_PER_PAGE
// decals blended into one page.
#define DECAL_MAX 256u
#define DECAL_MAX_POINTS 4096u
#define DECAL_MAX_TEXTURES 32u
#define DECAL_TEXELS 256u
#define DECAL_MAX_PER_PAGE 32u
// A page job's decal word: its first index in the job decal list | count << 16.
#define DECAL_COUNT_SHIFT 16u
#define DECAL_KIND_QUAD 0u
#define DECAL_KIND_ROAD 1u
// A displacement decal's mesh: this many quads a side over its quad.
#define DECAL_MESH_QUADS 64u

// Grass (effect grass, effects/grass.rs): one possible tuft per world cell
// in a square of at most GRASS_MAX_SIDE cells a side around the camera,
// GRASS_BLADES blades of GRASS_BLADE_VERTICES vertices each (a triangle
// list), coloured from a pigment map of GRASS_PIGMENT_TEXELS a side. The
// rule table has one entry per material id (GRASS_RULES).
#define GRASS_MAX_SIDE 512u
#define GRASS_BLADES 3u
#define GRASS_BLADE_VERTICES 9u
#define GRASS_PIGMENT_TEXELS 256u
#define GRASS_RULES 256u
// grass_place's flags: holes cut (FrameSwitches::holes), frustum culling,
// Hi-Z culling (the HIZ variant).
#define GRASS_FLAG_HOLES 1u
#define GRASS_FLAG_FRUSTUM 2u
#define GRASS_FLAG_HIZ 4u
// Trees and bushes (effect vegetation, effects/vegetation): VEG_KINDS mesh
// kinds (tree, bush) of VEG_LODS levels each (the last two crossed quads),
// one indexed indirect draw each; at most VEG_TYPES types. vegetation_cull's
// flags: distance, frustum and Hi-Z culling (the HIZ variant).
#define VEG_KINDS 2u
#define VEG_LODS 3u
#define VEG_TYPES 16u
#define VEG_FLAG_DISTANCE 1u
#define VEG_FLAG_FRUSTUM 2u
#define VEG_FLAG_HIZ 4u
// Procedural cliff meshes (effect cliff_meshes): quads a side of one cell's patch.
#define CLIFF_CELL_QUADS 4u

// The G-buffer material target's y on a grass pixel and on an asset's
// (above the flavour bits).
#define GBUFFER_GRASS 128u
#define GBUFFER_ASSET 64u

// Output `gbuffer` (targets/gbuffer_layout.rs, engine_gbuffer.glsl): what
// a channel of the engine's attachment holds (a nibble per channel, r
// lowest, in one specialization constant per attachment).
#define GB_CHANNEL_ZERO 0u
#define GB_CHANNEL_ONE 1u
#define GB_CHANNEL_BASE_R 2u
#define GB_CHANNEL_BASE_G 3u
#define GB_CHANNEL_BASE_B 4u
#define GB_CHANNEL_NORMAL_X 5u
#define GB_CHANNEL_NORMAL_Y 6u
#define GB_CHANNEL_NORMAL_Z 7u
#define GB_CHANNEL_ROUGHNESS 8u
#define GB_CHANNEL_MATERIAL 9u
// Output `gbuffer`'s flags: a byte per attachment (normal stored signed;
// base colour sRGB-encoded by the shader), and the octahedral normal.
#define GB_FLAG_SIGNED 1u
#define GB_FLAG_SRGB_ENCODE 2u
#define GB_FLAG_OCTAHEDRAL 0x80000000u

#endif
