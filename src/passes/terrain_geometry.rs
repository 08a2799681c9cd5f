//! `terrain_geometry`: every visible patch without holes in ONE instanced
//! indexed-indirect draw of an 8x8-quad grid (the draw args are the patch
//! list's header). The vertex shader stitches LOD seams; patches with holes
//! are drawn by `terrain_holes`, whose vertex shader alone tests holes.
//! The fragment shader writes what the G-buffer tile passes shade from:
//! the classification bits and two octahedral normals; the pipeline writes
//! the terrain stencil bit. Depth is reversed-Z D32_SFLOAT_S8_UINT
//! (cleared to 0, or the engine's kept: `DepthOptions::load`; GREATER passes).

use crate::error::Result;
use crate::gpu::{
    depth_layout, vk, Binding, Buffer, BufferDesc, ColorTarget, Context, DepthTarget, GraphicsPipelineDesc,
    MemoryLocation, Pipeline, Recorder, Resource, Sampler, SamplerDesc, ShaderInfo, StencilDesc,
};
use crate::shaders::{terrain_geometry_frag as fs, terrain_geometry_vert as vs};
use crate::targets::gbuffer::{GBuffer, CLASSIFICATION_FORMAT, GEOMETRY_NORMALS_FORMAT, PATCH_INFO_FORMAT};
use crate::terrain::gpu_quadtree::{GpuQuadtree, ATLAS_HEIGHT, ATLAS_LAYOUT, ATLAS_NORMAL};
use crate::terrain::patch_grid::diamond_indices;
use crate::world::{PATCHES_PER_NODE_SIDE, PATCH_QUADS};

pub use crate::targets::{DepthOptions, RenderTargets, COLOR_FORMAT, DEPTH_FORMAT, DEPTH_LAYOUT, TERRAIN_ONLY};

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

/// The terrain pipeline of pass `name` with vertex shader `vertex`
/// (`sink`: its fragments pushed behind in the sunk cells, terrain_sink.rs).
pub(crate) fn terrain_pipeline(
    ctx: &Context,
    name: &str,
    vertex: &'static ShaderInfo,
    depth: DepthOptions,
    sink: bool,
) -> Result<Pipeline> {
    let spec = [(vs::SPEC_PATCHES_PER_SIDE, PATCHES_PER_NODE_SIDE), (vs::SPEC_PATCH_QUADS, PATCH_QUADS)];
    let fragment = fs::variant(if sink { fs::VARIANT_SINK } else { 0 });
    geometry_pipeline(ctx, name, (vertex, fragment), &spec, depth)
}

/// Indices of one patch instance.
pub const PATCH_INDEX_COUNT: u32 = PATCH_QUADS * PATCH_QUADS * 6;

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
    /// Built with the SINK variant: draws want the sink bound.
    sink: bool,
}

impl TerrainGeometry {
    pub const NAME: &'static str = vs::PASS;

    pub fn new(ctx: &Context, depth: DepthOptions, sink: bool) -> Result<Self> {
        let pipeline = terrain_pipeline(ctx, Self::NAME, &vs::SHADER, depth, sink)?;
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
            sink,
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
    /// list `list` and the sink where built with it; `extra` adds the
    /// bindings only that pipeline has.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn bind(
        &self,
        rec: &mut Recorder,
        pipeline: &Pipeline,
        view: &Buffer,
        list: &Buffer,
        tree: &GpuQuadtree,
        sink: Option<&Buffer>,
        extra: &[(Binding, Resource)],
    ) {
        assert_eq!(sink.is_some(), self.sink, "the terrain's sink is bound exactly to its SINK variant");
        rec.bind_pipeline(pipeline);
        let mut bindings = vec![
            (vs::VIEW, Resource::Buffer(view)),
            (vs::PATCH_LIST, Resource::Buffer(list)),
            (vs::HEIGHT_ATLAS, Resource::Image(tree.required_atlas(ATLAS_HEIGHT), ATLAS_LAYOUT)),
            (fs::NORMAL_ATLAS, Resource::Image(tree.required_atlas(ATLAS_NORMAL), ATLAS_LAYOUT)),
            (vs::NEAREST, Resource::Sampler(self.nearest.raw())),
            (fs::LINEAR_CLAMP, Resource::Sampler(self.linear.raw())),
        ];
        bindings.extend(sink.map(|s| (fs::SINK, Resource::Buffer(s))));
        bindings.extend(extra.iter().map(|(b, r)| (*b, *r)));
        rec.push_descriptors(pipeline, &bindings);
    }

    /// Draws patch list `list` (phase 1's, after clearing the targets, or
    /// phase 2's over them: `clear` is false only there), with the sink
    /// where built with it.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder,
        targets: &RenderTargets,
        gbuffer: &GBuffer,
        view: &Buffer,
        list: &Buffer,
        tree: &GpuQuadtree,
        sink: Option<&Buffer>,
        clear: bool,
    ) {
        begin_geometry(rec, targets, gbuffer, self.depth, clear);
        self.bind(rec, &self.pipeline, view, list, tree, sink, &[]);
        rec.push_constants(&self.pipeline, &TerrainDrawPush::new(!clear));
        rec.draw_indexed_indirect(&self.indices, list, 0);
        rec.end_rendering();
    }
}

/// Opens the geometry pass's rendering scope: classification (cleared to
/// 0 = no terrain), geometry normals, patch info, depth (cleared to far
/// unless the engine's is loaded) and, where vista writes a bit of it and
/// clears the depth, stencil (cleared to 0).
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
            // The engine's depth (and stencil) kept: its occluders hide terrain.
            clear: (clear && !depth.load).then_some(0.0),
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
        assert_eq!(opt.len(), PATCH_INDEX_COUNT as usize);
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
