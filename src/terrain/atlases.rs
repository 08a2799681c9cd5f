//! The payload atlases' kinds (one texture array per payload kind, a node
//! slot is a layer): their formats, sizes, names and upload layout.

use crate::gpu::vk;
use crate::world::{
    BakedNode, PayloadFormat, TexelKind, ATLAS_SIDE, CONE_BLOCKS_PER_NODE_SIDE, PATCHES_PER_NODE_SIDE, SPLAT_RES,
};

pub(super) struct AtlasKind {
    pub(super) name: &'static str,
    pub(super) format: vk::Format,
    pub(super) side: u32,
    /// Bytes of one layer; `None` for the normal and albedo layers, whose
    /// size depends on the payload format.
    layer_bytes: Option<u32>,
}

const fn plain(name: &'static str, format: vk::Format, side: u32, texel_bytes: u32) -> AtlasKind {
    AtlasKind { name, format, side, layer_bytes: Some(side * side * texel_bytes) }
}

const fn texels(name: &'static str) -> AtlasKind {
    AtlasKind { name, format: vk::Format::UNDEFINED, side: ATLAS_SIDE as u32, layer_bytes: None }
}

/// Atlas formats, in the order of `payload_bytes`; the `ATLAS_*` indices
/// name them.
pub(super) const ATLASES: [AtlasKind; 10] = [
    plain("atlas_height", vk::Format::R16_UNORM, ATLAS_SIDE as u32, 2),
    texels("atlas_normal"),
    texels("atlas_albedo"),
    plain("atlas_splat", vk::Format::R8_UINT, SPLAT_RES as u32, 1),
    plain("atlas_patch_min_max", vk::Format::R16G16_UINT, PATCHES_PER_NODE_SIDE, 4),
    plain("atlas_patch_cones", vk::Format::R32G32B32A32_SFLOAT, CONE_BLOCKS_PER_NODE_SIDE, 16),
    plain("atlas_patch_holes", vk::Format::R8_UINT, PATCHES_PER_NODE_SIDE, 1),
    plain("atlas_patch_errors", vk::Format::R32G32_SFLOAT, PATCHES_PER_NODE_SIDE, 8),
    plain("atlas_control", vk::Format::R16_UINT, SPLAT_RES as u32, 2),
    // The heights' layout: a LOD-0 node's vertices below its samples read
    // their parents one sample past the node.
    plain("atlas_vertex_bounds", vk::Format::R32_UINT, ATLAS_SIDE as u32, 4),
];

/// Vulkan format and layer bytes of atlas `i` for payloads in `format`.
pub(super) fn atlas_format(i: usize, format: PayloadFormat) -> (vk::Format, u64) {
    let a = &ATLASES[i];
    if let Some(bytes) = a.layer_bytes {
        return (a.format, u64::from(bytes));
    }
    let kind = if i == ATLAS_NORMAL { TexelKind::Normal } else { TexelKind::Albedo };
    let vk_format = match (format, kind) {
        (PayloadFormat::Rgba8, _) => vk::Format::R8G8B8A8_UNORM,
        (PayloadFormat::Bc, TexelKind::Normal) => vk::Format::BC3_UNORM_BLOCK,
        // RGBA: BC1's 1-bit alpha carries the holes.
        (PayloadFormat::Bc, TexelKind::Albedo) => vk::Format::BC1_RGBA_UNORM_BLOCK,
    };
    (vk_format, format.layer_bytes(kind) as u64)
}

/// Index of each atlas in `GpuQuadtree::atlases`.
pub const ATLAS_HEIGHT: usize = 0;
pub const ATLAS_NORMAL: usize = 1;
pub const ATLAS_ALBEDO: usize = 2;
pub const ATLAS_SPLAT: usize = 3;
pub const ATLAS_PATCH_MIN_MAX: usize = 4;
pub const ATLAS_PATCH_CONES: usize = 5;
pub const ATLAS_PATCH_HOLES: usize = 6;
pub const ATLAS_PATCH_ERRORS: usize = 7;
/// A control-map world's control words (the control-map flavour only).
pub const ATLAS_CONTROL: usize = 8;
/// The per-triangle rule's vertex numbers (that rule's renderers only).
pub const ATLAS_VERTEX_BOUNDS: usize = 9;

/// Which payload atlases live on the GPU: one bit per `ATLAS_*` index. An
/// effect that is off keeps none of the atlases only it reads (no image, no
/// upload bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AtlasSet(u16);

impl AtlasSet {
    /// Every payload kind a world's nodes carry: all but the control words,
    /// which only a control-map bake makes (a renderer in control-map mode
    /// adds them), and the vertex numbers, which only the per-triangle rule
    /// attaches.
    pub const ALL: AtlasSet = AtlasSet(((1 << ATLAS_COUNT) - 1) & !(1 << ATLAS_CONTROL) & !(1 << ATLAS_VERTEX_BOUNDS));
    /// What drawing needs in any case: heights, albedo, patch bounds and
    /// errors (the per-patch LOD selection).
    pub const CORE: AtlasSet =
        AtlasSet((1 << ATLAS_HEIGHT) | (1 << ATLAS_ALBEDO) | (1 << ATLAS_PATCH_MIN_MAX) | (1 << ATLAS_PATCH_ERRORS));

    pub fn with(self, atlas: usize) -> AtlasSet {
        assert!(atlas < ATLAS_COUNT);
        AtlasSet(self.0 | (1 << atlas))
    }

    pub fn contains(self, atlas: usize) -> bool {
        atlas < ATLAS_COUNT && self.0 & (1 << atlas) != 0
    }
}

impl Default for AtlasSet {
    fn default() -> Self {
        AtlasSet::ALL
    }
}

/// Number of payload kinds (atlases).
pub const ATLAS_COUNT: usize = ATLASES.len();

/// Debug name of atlas `i` (`ATLAS_*`).
pub fn atlas_name(i: usize) -> &'static str {
    ATLASES[i].name
}

pub(super) fn payload_bytes(n: &BakedNode) -> [&[u8]; ATLAS_COUNT] {
    [
        bytemuck::cast_slice(&n.heights),
        &n.normals,
        &n.albedo,
        &n.splat,
        bytemuck::cast_slice(&n.patch_min_max),
        bytemuck::cast_slice(&n.patch_cones),
        &n.patch_holes,
        bytemuck::cast_slice(&n.patch_errors),
        bytemuck::cast_slice(&n.control),
        bytemuck::cast_slice(&n.vertex_bounds),
    ]
}

/// Copy offsets must be multiples of the texel or block size (16 for
/// RGBA32F and BC3).
const UPLOAD_ALIGN: u64 = 16;

pub(super) fn aligned_size(i: usize, format: PayloadFormat) -> u64 {
    atlas_format(i, format).1.next_multiple_of(UPLOAD_ALIGN)
}

pub(super) fn node_upload_bytes(set: AtlasSet, format: PayloadFormat) -> u64 {
    (0..ATLAS_COUNT).filter(|i| set.contains(*i)).map(|i| aligned_size(i, format)).sum()
}

/// Resting layout of the atlases.
pub const ATLAS_LAYOUT: vk::ImageLayout = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
