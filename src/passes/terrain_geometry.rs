//! `terrain_geometry`: every visible patch without holes in ONE instanced
//! indexed-indirect draw of an 8x8-quad grid (the draw args are the patch
//! list's header). The vertex shader stitches LOD seams; patches with holes
//! are drawn by `terrain_holes`, whose vertex shader alone tests holes.
//! The fragment shader writes what the G-buffer tile passes shade from:
//! the classification bits and two octahedral normals; the pipeline writes
//! the terrain stencil bit. Depth is reversed-Z D32_SFLOAT_S8_UINT
//! (cleared to 0, GREATER passes).

use crate::error::Result;
use crate::gpu::{
    depth_layout, has_stencil, vk, Binding, Buffer, BufferDesc, ColorTarget, Context, DepthTarget,
    GraphicsPipelineDesc, Image, MemoryLocation, Pipeline, Recorder, Resource, Sampler, SamplerDesc, ShaderInfo,
    StencilDesc,
};
use crate::render::gbuffer::{GBuffer, CLASSIFICATION_FORMAT, GEOMETRY_NORMALS_FORMAT, PATCH_INFO_FORMAT};
use crate::shaders::{terrain_geometry_frag as fs, terrain_geometry_vert as vs};
use crate::terrain::gpu_quadtree::{GpuQuadtree, ATLAS_HEIGHT, ATLAS_LAYOUT, ATLAS_NORMAL};
use crate::terrain::patch_grid::diamond_indices;
use crate::world::{PATCHES_PER_NODE_SIDE, PATCH_QUADS};

/// Colour target format of the lit output (gamma-encoded by the shader).
pub const COLOR_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;
/// The default depth format: reversed-Z, infinite far plane, with a
/// stencil aspect for the engine's terrain bit ([`DepthOptions`]).
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT_S8_UINT;

/// The default depth target's layout on entry to and exit from a frame
/// (`DepthOptions::layout` for another format).
pub const DEPTH_LAYOUT: vk::ImageLayout = vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL;

/// The depth test of the passes that shade terrain pixels only
/// (`gbuffer_tiles`, `lighting_resolve`): their fragments lie at depth 0,
/// the far plane the target is cleared to, so LESS passes exactly where the
/// geometry pass wrote terrain (reversed-Z: every finite distance is above
/// 0). Needs no stencil, so any depth format of [`DepthOptions`] works.
pub const TERRAIN_ONLY: vk::CompareOp = vk::CompareOp::LESS;

/// The engine's depth target: its format and the stencil bit vista sets
/// where there is terrain (`RendererOptions::depth`). vista clears the
/// depth each frame; where it writes a stencil bit it clears the stencil
/// too, and otherwise leaves the stencil aspect as it was.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DepthOptions {
    /// `D32_SFLOAT_S8_UINT` (the default) or `D32_SFLOAT`.
    pub format: vk::Format,
    /// The stencil bit (0-7) set on terrain pixels; `None`: the stencil is
    /// not touched (and must be `None` for a format without stencil).
    pub terrain_stencil_bit: Option<u32>,
}

impl Default for DepthOptions {
    fn default() -> Self {
        DepthOptions { format: DEPTH_FORMAT, terrain_stencil_bit: Some(0) }
    }
}

impl DepthOptions {
    /// The formats vista draws reversed-Z depth into (32-bit float: a
    /// 24-bit integer depth would lose the far field's precision).
    pub const FORMATS: [vk::Format; 2] = [vk::Format::D32_SFLOAT_S8_UINT, vk::Format::D32_SFLOAT];

    /// Refuses a format vista cannot use or a bit the format cannot hold.
    pub fn check(&self) -> std::result::Result<(), String> {
        if !Self::FORMATS.contains(&self.format) {
            return Err(format!(
                "depth format {:?} is not one vista draws into (D32_SFLOAT_S8_UINT or D32_SFLOAT)",
                self.format
            ));
        }
        match self.terrain_stencil_bit {
            Some(b) if !has_stencil(self.format) => {
                Err(format!("terrain stencil bit {b} asked for, but depth format {:?} has no stencil", self.format))
            }
            Some(b) if b > 7 => Err(format!("terrain stencil bit {b} is not a bit of an 8-bit stencil (0-7)")),
            _ => Ok(()),
        }
    }

    /// The layout the target is in on entry to and exit from a frame.
    pub fn layout(&self) -> vk::ImageLayout {
        depth_layout(self.format, false)
    }

    /// The stencil mask vista writes (0: none).
    pub fn stencil_mask(&self) -> u32 {
        self.terrain_stencil_bit.map_or(0, |b| 1 << b)
    }
}

/// The patch's index list: the diamond pattern (every odd/odd vertex the
/// centre of 8 triangles), triangles reordered for the post-transform
/// vertex cache by meshoptimizer (which keeps each triangle's corners and
/// winding, so the topology is unchanged).
pub fn patch_indices() -> Vec<u32> {
    let idx = diamond_indices(PATCH_QUADS);
    let vertices = ((PATCH_QUADS + 1) * (PATCH_QUADS + 1)) as usize;
    meshopt::optimize_vertex_cache(&idx, vertices)
}

/// Host twin of `TerrainDrawPush` (terrain_vertex.glsl), both draws'.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TerrainDrawPush {
    /// A quiet NaN's bits (`terrain_holes` makes hole vertices of them).
    pub nan_bits: u32,
    /// 1 in occlusion culling's phase 2 (the debug views show it).
    pub phase: u32,
    pub pad: [u32; 2],
}

/// Bits of a quiet NaN, passed as data so no compiler folds it.
pub const QUIET_NAN_BITS: u32 = 0x7FC0_0000;

impl TerrainDrawPush {
    pub fn new(late: bool) -> Self {
        TerrainDrawPush { nan_bits: QUIET_NAN_BITS, phase: u32::from(late), pad: [0; 2] }
    }
}

/// The colour and depth images a frame renders into, and the clear colour.
/// Layouts on entry and exit: COLOR_ATTACHMENT_OPTIMAL and [`DEPTH_LAYOUT`].
pub struct RenderTargets<'a> {
    pub color: &'a Image,
    pub depth: &'a Image,
    pub clear: [f32; 4],
}

/// The terrain pipeline of pass `name` with vertex shader `vertex`.
pub(crate) fn terrain_pipeline(
    ctx: &Context,
    name: &str,
    vertex: &'static ShaderInfo,
    depth: DepthOptions,
) -> Result<Pipeline> {
    let spec = [(vs::SPEC_PATCHES_PER_SIDE, PATCHES_PER_NODE_SIDE), (vs::SPEC_PATCH_QUADS, PATCH_QUADS)];
    geometry_pipeline(ctx, name, (vertex, &fs::SHADER), &spec, depth)
}

/// A pipeline of the geometry pass (the terrain's and the meshes drawn
/// beside it): its three targets, reversed-Z depth written, the terrain
/// stencil bit where the engine asked for one, back faces culled.
pub(crate) fn geometry_pipeline(
    ctx: &Context,
    name: &str,
    (vertex, fragment): (&'static ShaderInfo, &'static ShaderInfo),
    specialization: crate::gpu::pipeline::Specialization,
    depth: DepthOptions,
) -> Result<Pipeline> {
    let desc = GraphicsPipelineDesc {
        name,
        vertex,
        fragment,
        specialization,
        color_formats: &[CLASSIFICATION_FORMAT, GEOMETRY_NORMALS_FORMAT, PATCH_INFO_FORMAT],
        depth_format: Some(depth.format),
        depth_compare: vk::CompareOp::GREATER,
        depth_write: true,
        stencil: depth.terrain_stencil_bit.map(|_| StencilDesc {
            compare: vk::CompareOp::ALWAYS,
            reference: depth.stencil_mask(),
            compare_mask: 0,
            write_mask: depth.stencil_mask(),
        }),
        cull_mode: vk::CullModeFlags::BACK,
        topology: vk::PrimitiveTopology::TRIANGLE_LIST,
        blend: false,
    };
    Pipeline::graphics(ctx, &desc)
}

pub struct TerrainGeometry {
    pipeline: Pipeline,
    indices: Buffer,
    nearest: Sampler,
    linear: Sampler,
    index_count: u32,
    depth: DepthOptions,
}

impl TerrainGeometry {
    pub const NAME: &'static str = vs::PASS;

    pub fn new(ctx: &Context, depth: DepthOptions) -> Result<Self> {
        let pipeline = terrain_pipeline(ctx, Self::NAME, &vs::SHADER, depth)?;
        let idx = patch_indices();
        let indices = Buffer::new(
            ctx,
            &BufferDesc {
                name: "terrain_patch_indices",
                size: (idx.len() * 4) as u64,
                usage: vk::BufferUsageFlags::INDEX_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuOnly,
            },
        )?;
        ctx.upload(&indices, bytemuck::cast_slice(&idx))?;
        let sampler = |name, filter| {
            Sampler::new(ctx, &SamplerDesc { name, filter, address_mode: vk::SamplerAddressMode::CLAMP_TO_EDGE })
        };
        Ok(TerrainGeometry {
            pipeline,
            indices,
            nearest: sampler("terrain_geometry_nearest", vk::Filter::NEAREST)?,
            linear: sampler("terrain_geometry_linear", vk::Filter::LINEAR)?,
            index_count: idx.len() as u32,
            depth,
        })
    }

    /// The depth target it draws into.
    pub fn depth(&self) -> DepthOptions {
        self.depth
    }

    /// Indices of one patch instance.
    pub fn index_count(&self) -> u32 {
        self.index_count
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// The patch index buffer, shared with `terrain_holes`.
    pub fn indices(&self) -> &Buffer {
        &self.indices
    }

    /// Binds `pipeline` (this pass's or `terrain_holes`') with the patch
    /// list `list`; `extra` adds the bindings only that pipeline has.
    pub(crate) fn bind(
        &self,
        rec: &mut Recorder,
        pipeline: &Pipeline,
        view: &Buffer,
        list: &Buffer,
        tree: &GpuQuadtree,
        extra: &[(Binding, Resource)],
    ) {
        rec.bind_pipeline(pipeline);
        let mut bindings = vec![
            (vs::VIEW, Resource::Buffer(view)),
            (vs::PATCH_LIST, Resource::Buffer(list)),
            (vs::HEIGHT_ATLAS, Resource::Image(tree.required_atlas(ATLAS_HEIGHT), ATLAS_LAYOUT)),
            (fs::NORMAL_ATLAS, Resource::Image(tree.required_atlas(ATLAS_NORMAL), ATLAS_LAYOUT)),
            (vs::NEAREST, Resource::Sampler(self.nearest.raw())),
            (fs::LINEAR_CLAMP, Resource::Sampler(self.linear.raw())),
        ];
        bindings.extend(extra.iter().map(|(b, r)| (*b, *r)));
        rec.push_descriptors(pipeline, &bindings);
    }

    /// Draws patch list `list` (phase 1's, after clearing the targets, or
    /// phase 2's over them: `clear` is false only there).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder,
        targets: &RenderTargets,
        gbuffer: &GBuffer,
        view: &Buffer,
        list: &Buffer,
        tree: &GpuQuadtree,
        clear: bool,
    ) {
        begin_geometry(rec, targets, gbuffer, self.depth, clear);
        self.bind(rec, &self.pipeline, view, list, tree, &[]);
        rec.push_constants(&self.pipeline, &TerrainDrawPush::new(!clear));
        rec.draw_indexed_indirect(&self.indices, list, 0);
        rec.end_rendering();
    }
}

/// Opens the geometry pass's rendering scope: classification (cleared to
/// 0 = no terrain), geometry normals, patch info, depth (cleared to far)
/// and, where vista writes a bit of it, stencil (cleared to 0).
pub(crate) fn begin_geometry(
    rec: &mut Recorder,
    targets: &RenderTargets,
    gbuffer: &GBuffer,
    depth: DepthOptions,
    clear: bool,
) {
    let (class, normals, info) = (&gbuffer.classification, &gbuffer.geometry_normals, &gbuffer.patch_info);
    if clear {
        for target in [class, normals, info] {
            rec.discard_to(target, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
        }
    } else if info.layout() != vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL {
        rec.transition(info, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
    }
    debug_assert_eq!(depth_layout(DEPTH_FORMAT, false), DEPTH_LAYOUT);
    assert_eq!(targets.depth.format, depth.format, "the depth target is not in the renderer's depth format");
    rec.begin_rendering(
        &[
            ColorTarget { image: class, clear: clear.then_some([0.0; 4]) },
            ColorTarget { image: normals, clear: clear.then_some([0.0; 4]) },
            ColorTarget { image: info, clear: clear.then_some([0.0; 4]) },
        ],
        Some(DepthTarget {
            image: targets.depth,
            clear: clear.then_some(0.0),
            clear_stencil: depth.terrain_stencil_bit.is_some(),
            read_only: false,
        }),
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeSet;

    /// A triangle up to rotation (same winding).
    fn canonical(t: &[u32]) -> [u32; 3] {
        let r = (0..3).min_by_key(|&i| t[i]).unwrap();
        [t[r], t[(r + 1) % 3], t[(r + 2) % 3]]
    }

    #[test]
    fn optimized_indices_keep_the_diamond_topology() {
        let plain: BTreeSet<[u32; 3]> = diamond_indices(PATCH_QUADS).chunks(3).map(canonical).collect();
        let opt = patch_indices();
        let reordered: BTreeSet<[u32; 3]> = opt.chunks(3).map(canonical).collect();
        assert_eq!(opt.len(), (PATCH_QUADS * PATCH_QUADS * 6) as usize);
        assert_eq!(plain, reordered, "same triangles with the same winding");
        assert_ne!(opt, diamond_indices(PATCH_QUADS), "the optimizer reordered something");
    }

    #[test]
    fn optimized_order_reuses_the_vertex_cache_better() {
        let vertices = ((PATCH_QUADS + 1) * (PATCH_QUADS + 1)) as usize;
        // A 16-entry FIFO cache, a typical post-transform cache model.
        let acmr = |idx: &[u32]| meshopt::analyze_vertex_cache(idx, vertices, 16, 0, 0).acmr;
        let (plain, opt) = (acmr(&diamond_indices(PATCH_QUADS)), acmr(&patch_indices()));
        assert!(opt < plain, "ACMR {opt} not below the row-order {plain}");
    }
}
