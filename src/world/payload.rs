//! The baked payload of one quadtree node and its byte serialisation.

use super::layout::{NodeId, CONE_BLOCKS_PER_NODE, NODE_SAMPLES, PATCHES_PER_NODE, SPLAT_RES};
use super::texels::{texel_index, PayloadFormat, TexelKind, ATLAS_TEXELS};

/// Splat material ids (index into the renderer's 256-entry palette).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Material {
    Grass = 0,
    Rock = 1,
    Snow = 2,
    Scree = 3,
    /// Beach and sea floor.
    Sand = 4,
}

/// Patch hole summary: no sample of the patch is a hole.
pub const PATCH_HOLE_NONE: u8 = crate::shaders::consts::PATCH_HOLE_NONE as u8;
/// Some samples of the patch are holes: its vertices test the hole mask.
pub const PATCH_HOLE_SOME: u8 = crate::shaders::consts::PATCH_HOLE_SOME as u8;
/// Every sample is a hole: the cull pass removes the patch.
pub const PATCH_HOLE_ALL: u8 = crate::shaders::consts::PATCH_HOLE_ALL as u8;

/// Everything the GPU needs for one node. Grids are row-major with row 0 at
/// the node's south edge (index `j * side + i`, x east, y north); patch
/// arrays are indexed `py * 8 + px`.
#[derive(Clone, Debug, PartialEq)]
pub struct BakedNode {
    pub id: NodeId,
    /// 132x132 R16_UNORM heights over the world height range, laid out as
    /// the normal and albedo layers: texel (t, u) holds sample (t - 2, u - 2)
    /// ([`texel_index`]), so the vertex shader's Catmull-Rom refinement
    /// below the samples reads its 4x4 taps inside the node's own layer.
    pub heights: Vec<u16>,
    /// How `normals` and `albedo` are stored (`world::texels`).
    pub format: PayloadFormat,
    /// 132x132 normal layer (samples -2..=129): x, y of the unit normal as
    /// `n * 127.5 + 127.5` in alpha and green (z is positive and implied),
    /// red = smoothness, blue = specular occlusion (255 = none).
    pub normals: Vec<u8>,
    /// 132x132 albedo layer; alpha 255 solid, 0 hole.
    pub albedo: Vec<u8>,
    /// 65x65 material ids ([`Material`]), texel (i, j) at sample (2i, 2j).
    pub splat: Vec<u8>,
    /// A control-map world's 65x65 control words (`super::control_map`),
    /// laid out as `splat`; empty in other worlds.
    pub control: Vec<u16>,
    /// 16x16 (min, max) R16 heights of each patch: the finest surface's
    /// range over the patch's area ([`super::ErrorTree`]), which holds the
    /// node's own samples, every finer level's and the refinement's; until
    /// errors are attached, the range of the patch's own 9x9 samples.
    pub patch_min_max: Vec<[u16; 2]>,
    /// 8x8 normal cones, one per 2x2 patches: axis xyz + sin(half-angle);
    /// axis 0 and sin 1 mean "never cull" (half-angle of 90 degrees or more).
    pub patch_cones: Vec<[f32; 4]>,
    /// 16x16 hole summary per patch ([`PATCH_HOLE_NONE`], [`PATCH_HOLE_SOME`],
    /// [`PATCH_HOLE_ALL`]): the cull pass drops all-hole patches outright.
    pub patch_holes: Vec<u8>,
    /// The union of the patch ranges.
    pub min_height: u16,
    pub max_height: u16,
    /// Largest patch error (metres): this node's surface against the finest
    /// surface vista can draw ([`super::ErrorTree`]); infinite until
    /// attached, so a node without errors is always refined.
    pub max_error_m: f32,
    /// 16x16 [error drawn at this node's level, error drawn 2x refined below
    /// the samples (LOD 0 only)], metres; infinite until attached.
    pub patch_errors: Vec<[f32; 2]>,
    /// The largest LOD-0 representation error under the node (LOD 0's
    /// triangles against the finest surface), metres.
    pub repr_error_m: f32,
    /// The per-triangle rule's numbers of the node's 129x129 grid points
    /// and the points past them, in the heights' 132x132 atlas layout
    /// (`world::vertex_bounds`): f16 error | f16 reach << 16. Attached after
    /// the load by a renderer that draws with the rule (the world's bounds
    /// are computed whole); empty otherwise, and never in the cache file.
    pub vertex_bounds: Vec<u32>,
}

const SAMPLES: usize = NODE_SAMPLES * NODE_SAMPLES;
const HEIGHT_TEXELS: usize = ATLAS_TEXELS;
const SPLATS: usize = SPLAT_RES * SPLAT_RES;

impl BakedNode {
    /// Its errors are not known yet: never attached, or a root attached
    /// pending numbers by a tree making roots on demand
    /// ([`super::ErrorTree::with_roots_on_demand`]). Such a node is not
    /// written to a cache folder.
    pub fn errors_pending(&self) -> bool {
        self.max_error_m.is_infinite()
    }

    /// Size of [`Self::to_bytes`]' output; payloads of one format, with or
    /// without control words, are fixed-size.
    pub fn serialized_bytes(format: PayloadFormat, control: bool) -> usize {
        10 + 2 * 2
            + 4
            + HEIGHT_TEXELS * 2
            + format.layer_bytes(TexelKind::Normal)
            + format.layer_bytes(TexelKind::Albedo)
            + SPLATS
            + 1
            + if control { SPLATS * 2 } else { 0 }
            + PATCHES_PER_NODE * (1 + 4 + 8)
            + CONE_BLOCKS_PER_NODE * 16
            + 4
    }

    /// R16 height of node sample (i, j), i and j in -2..=129.
    pub fn height(&self, i: isize, j: isize) -> u16 {
        self.heights[texel_index(i, j)]
    }

    /// The 129x129 heights of the node's own samples, row 0 south.
    pub fn sample_heights(&self) -> Vec<u16> {
        (0..SAMPLES).map(|k| self.height((k % NODE_SAMPLES) as isize, (k / NODE_SAMPLES) as isize)).collect()
    }

    /// The normal layer as RGBA8 texels, decoded as the GPU does.
    pub fn normal_texels(&self) -> Vec<[u8; 4]> {
        self.format.decode(TexelKind::Normal, &self.normals)
    }

    /// The albedo layer as RGBA8 texels, decoded as the GPU does.
    pub fn albedo_texels(&self) -> Vec<[u8; 4]> {
        self.format.decode(TexelKind::Albedo, &self.albedo)
    }

    /// 129x129 hole flags of the node's samples (row 0 south), from the
    /// albedo alpha the vertex shader tests.
    pub fn hole_mask(&self) -> Vec<bool> {
        let a = self.albedo_texels();
        (0..SAMPLES)
            .map(|k| a[texel_index((k % NODE_SAMPLES) as isize, (k / NODE_SAMPLES) as isize)][3] < 128)
            .collect()
    }

    /// Little-endian serialisation, independent of the host.
    pub fn to_bytes(&self) -> Vec<u8> {
        assert!(self.control.is_empty() || self.control.len() == SPLATS, "control words: 0 or 65x65");
        let control = !self.control.is_empty();
        let mut out = Vec::with_capacity(Self::serialized_bytes(self.format, control));
        out.push(self.id.lod);
        out.push(self.format.tag());
        out.extend_from_slice(&self.id.x.to_le_bytes());
        out.extend_from_slice(&self.id.y.to_le_bytes());
        out.extend_from_slice(&self.min_height.to_le_bytes());
        out.extend_from_slice(&self.max_height.to_le_bytes());
        out.extend_from_slice(&self.max_error_m.to_le_bytes());
        out.extend_from_slice(&self.patch_holes);
        self.heights.iter().for_each(|v| out.extend_from_slice(&v.to_le_bytes()));
        out.extend_from_slice(&self.normals);
        out.extend_from_slice(&self.albedo);
        out.extend_from_slice(&self.splat);
        out.push(u8::from(control));
        self.control.iter().for_each(|v| out.extend_from_slice(&v.to_le_bytes()));
        for mm in &self.patch_min_max {
            mm.iter().for_each(|v| out.extend_from_slice(&v.to_le_bytes()));
        }
        for c in &self.patch_cones {
            c.iter().for_each(|v| out.extend_from_slice(&v.to_le_bytes()));
        }
        for e in &self.patch_errors {
            e.iter().for_each(|v| out.extend_from_slice(&v.to_le_bytes()));
        }
        out.extend_from_slice(&self.repr_error_m.to_le_bytes());
        debug_assert_eq!(out.len(), Self::serialized_bytes(self.format, control));
        out
    }

    /// Inverse of [`Self::to_bytes`]; `None` when the format tag or the
    /// length is wrong.
    pub fn from_bytes(bytes: &[u8]) -> Option<Self> {
        let format = PayloadFormat::from_tag(*bytes.get(1)?)?;
        let control = match bytes.len() {
            n if n == Self::serialized_bytes(format, false) => false,
            n if n == Self::serialized_bytes(format, true) => true,
            _ => return None,
        };
        let mut r = Reader { bytes, pos: 0 };
        let lod = r.take::<2>()[0];
        let x = u32::from_le_bytes(r.take());
        let y = u32::from_le_bytes(r.take());
        let min_height = u16::from_le_bytes(r.take());
        let max_height = u16::from_le_bytes(r.take());
        let max_error_m = f32::from_le_bytes(r.take());
        let patch_holes = (0..PATCHES_PER_NODE).map(|_| r.take::<1>()[0]).collect();
        let heights = (0..HEIGHT_TEXELS).map(|_| u16::from_le_bytes(r.take())).collect();
        let normals = r.slice(format.layer_bytes(TexelKind::Normal)).to_vec();
        let albedo = r.slice(format.layer_bytes(TexelKind::Albedo)).to_vec();
        let splat = (0..SPLATS).map(|_| r.take::<1>()[0]).collect();
        if r.take::<1>()[0] != u8::from(control) {
            return None;
        }
        let control = (0..if control { SPLATS } else { 0 }).map(|_| u16::from_le_bytes(r.take())).collect();
        let patch_min_max =
            (0..PATCHES_PER_NODE).map(|_| [u16::from_le_bytes(r.take()), u16::from_le_bytes(r.take())]).collect();
        let patch_cones =
            (0..CONE_BLOCKS_PER_NODE).map(|_| [0; 4].map(|_: i32| f32::from_le_bytes(r.take()))).collect();
        let patch_errors = (0..PATCHES_PER_NODE).map(|_| [0; 2].map(|_: i32| f32::from_le_bytes(r.take()))).collect();
        let repr_error_m = f32::from_le_bytes(r.take());
        Some(BakedNode {
            id: NodeId::new(lod, x, y),
            heights,
            format,
            normals,
            albedo,
            splat,
            control,
            patch_min_max,
            patch_cones,
            patch_holes,
            min_height,
            max_height,
            max_error_m,
            patch_errors,
            repr_error_m,
            vertex_bounds: Vec::new(),
        })
    }
}

/// Fixed-size reads over a slice whose total length was checked up front.
struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> [u8; N] {
        let mut a = [0u8; N];
        a.copy_from_slice(&self.bytes[self.pos..self.pos + N]);
        self.pos += N;
        a
    }

    fn slice(&mut self, n: usize) -> &[u8] {
        let s = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        s
    }
}
