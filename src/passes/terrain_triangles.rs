//! `terrain_triangles`: the per-triangle rule's draw, ONE indexed-indirect
//! draw of the list `emit_triangles` wrote (the list's header is the draw's
//! args; its indices are vertex codes the vertex shader decodes into a
//! node's grid point). Same targets, depth and fragment stage as
//! `terrain_geometry` (common/terrain_fragment.glsl); holes are tested per
//! vertex, so there is no separate hole draw.

use crate::error::Result;
use crate::gpu::{vk, Context, Pipeline, Recorder, Resource, Sampler, SamplerDesc};
use crate::passes::emit_triangles::EmitTriangles;
use crate::passes::terrain_geometry::{begin_geometry, geometry_pipeline, DepthOptions, RenderTargets, QUIET_NAN_BITS};
use crate::shaders::{terrain_triangles_frag as fs, terrain_triangles_vert as vs};
use crate::targets::gbuffer::GBuffer;
use crate::terrain::gpu_quadtree::{GpuQuadtree, ATLAS_ALBEDO, ATLAS_HEIGHT, ATLAS_LAYOUT, ATLAS_NORMAL};
use crate::world::NODE_QUADS;

/// Host twin of `TrianglesPush` (terrain_triangles.vert).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TrianglesPush {
    /// A quiet NaN's bits (hole vertices are made of them).
    pub nan_bits: u32,
    pub pad: [u32; 3],
}

pub struct TerrainTriangles {
    pipeline: Pipeline,
    nearest: Sampler,
    linear: Sampler,
    depth: DepthOptions,
    /// Built with the SINK variant (terrain_sink.rs): draws want it bound.
    sink: bool,
}

impl TerrainTriangles {
    pub const NAME: &'static str = vs::PASS;

    pub fn new(ctx: &Context, depth: DepthOptions, sink: bool) -> Result<Self> {
        let spec = [(vs::SPEC_NODE_SIDE, NODE_QUADS)];
        let fragment = fs::variant(if sink { fs::VARIANT_SINK } else { 0 });
        let pipeline = geometry_pipeline(ctx, Self::NAME, (&vs::SHADER, fragment), &spec, depth)?;
        let sampler = |name, filter| {
            Sampler::new(ctx, &SamplerDesc { name, filter, address_mode: vk::SamplerAddressMode::CLAMP_TO_EDGE })
        };
        Ok(TerrainTriangles {
            pipeline,
            nearest: sampler("terrain_triangles_nearest", vk::Filter::NEAREST)?,
            linear: sampler("terrain_triangles_linear", vk::Filter::LINEAR)?,
            depth,
            sink,
        })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// Draws the list `emit` wrote, after clearing the targets, with the
    /// sink where built with it; `late`: occlusion's phase 2, the second
    /// list, over what phase 1 drew.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder,
        targets: &RenderTargets,
        gbuffer: &GBuffer,
        view: &crate::gpu::Buffer,
        emit: &EmitTriangles,
        late: bool,
        tree: &GpuQuadtree,
        sink: Option<&crate::gpu::Buffer>,
    ) {
        assert_eq!(sink.is_some(), self.sink, "the terrain's sink is bound exactly to its SINK variant");
        let list = match late {
            true => emit.late_list().expect("phase 2 is built with occlusion"),
            false => emit.list(),
        };
        begin_geometry(rec, targets, gbuffer, self.depth, !late);
        rec.bind_pipeline(&self.pipeline);
        let mut bindings = vec![
            (vs::VIEW, Resource::Buffer(view)),
            (vs::SLOT_NODES, Resource::Buffer(emit.slot_nodes())),
            (vs::HEIGHT_ATLAS, Resource::Image(tree.required_atlas(ATLAS_HEIGHT), ATLAS_LAYOUT)),
            (vs::ALBEDO_ATLAS, Resource::Image(tree.required_atlas(ATLAS_ALBEDO), ATLAS_LAYOUT)),
            (vs::NEAREST, Resource::Sampler(self.nearest.raw())),
            (fs::NORMAL_ATLAS, Resource::Image(tree.required_atlas(ATLAS_NORMAL), ATLAS_LAYOUT)),
            (fs::LINEAR_CLAMP, Resource::Sampler(self.linear.raw())),
        ];
        bindings.extend(sink.map(|s| (fs::SINK, Resource::Buffer(s))));
        rec.push_descriptors(&self.pipeline, &bindings);
        rec.push_constants(&self.pipeline, &TrianglesPush { nan_bits: QUIET_NAN_BITS, pad: [0; 3] });
        rec.draw_indexed_indirect(list, list, 0);
        rec.end_rendering();
    }
}
