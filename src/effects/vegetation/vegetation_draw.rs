//! `vegetation_draw` (effect `vegetation`): the instances `vegetation_cull`
//! kept, into the G-buffer after `gbuffer_tiles`, depth-tested and
//! depth-writing, six indexed indirect draws (tree and bush, three LODs),
//! both faces (the far billboards are seen from either side); near the
//! ground the vertices blend into the terrain's normal and colour.

use crate::error::Result;
use crate::gpu::{vk, Buffer, Context, Pipeline, Recorder, Resource, Sampler};
use crate::passes::cull_patches::nearest_sampler;
use crate::passes::gbuffer_tiles::GbufferTiles;
use crate::passes::terrain_geometry::RenderTargets;
use crate::passes::terrain_query::VistaTerrain;
use crate::shaders::{structs, vegetation_draw_frag as fs, vegetation_draw_vert as vs};
use crate::targets::gbuffer::GBuffer;
use crate::targets::GbufferLayout;
use crate::terrain::gpu_quadtree::{GpuQuadtree, ATLAS_ALBEDO, ATLAS_HEIGHT, ATLAS_LAYOUT, ATLAS_NORMAL};

/// Host twin of `VegetationDrawPush`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VegetationDrawPush {
    pub terrain: VistaTerrain,
    pub blend_height_m: f32,
    pub pad: [u32; 3],
}

const _: () = assert!(std::mem::size_of::<VegetationDrawPush>() == structs::VEGETATION_DRAW_PUSH);

/// What the draws read.
pub struct DrawBuffers<'a> {
    pub view: &'a Buffer,
    pub vertices: &'a Buffer,
    pub instances: &'a Buffer,
    pub types: &'a Buffer,
    pub visible: &'a Buffer,
    /// The draws' arguments (the header's first words).
    pub header: &'a Buffer,
    /// Per draw, in the header's order: its mesh's indices.
    pub indices: &'a [(Buffer, u32)],
    pub sector_data: &'a Buffer,
}

pub struct VegetationDraw {
    pipeline: Pipeline,
    nearest: Sampler,
    linear: Sampler,
}

impl VegetationDraw {
    pub const NAME: &'static str = vs::PASS;

    /// `layout`: the engine's G-buffer (output `gbuffer`), else vista's.
    pub fn new(ctx: &Context, depth_format: vk::Format, layout: Option<&GbufferLayout>) -> Result<Self> {
        let fragment = fs::variant(if layout.is_some() { fs::VARIANT_ENGINE_GBUFFER } else { 0 });
        Ok(VegetationDraw {
            pipeline: GbufferTiles::overlay_pipeline(
                ctx,
                Self::NAME,
                (&vs::SHADER, fragment),
                depth_format,
                vk::CullModeFlags::NONE,
                layout,
            )?,
            nearest: nearest_sampler(ctx, "vegetation_draw_nearest")?,
            linear: crate::passes::cull_patches::linear_clamp_sampler(ctx, "vegetation_draw_linear")?,
        })
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// Records the six draws; the depth target read-only on entry and exit
    /// (as gbuffer_tiles leaves it, lighting_resolve wants it).
    pub fn record(
        &self,
        rec: &mut Recorder,
        targets: &RenderTargets,
        gbuffer: &GBuffer,
        b: &DrawBuffers,
        tree: &GpuQuadtree,
        push: VegetationDrawPush,
    ) {
        GbufferTiles::begin_overlay(rec, targets, gbuffer);
        rec.bind_pipeline(&self.pipeline);
        let bindings = [
            (vs::VIEW, Resource::Buffer(b.view)),
            (vs::VERTICES, Resource::Buffer(b.vertices)),
            (vs::INSTANCES, Resource::Buffer(b.instances)),
            (vs::TYPES, Resource::Buffer(b.types)),
            (vs::VISIBLE, Resource::Buffer(b.visible)),
            (vs::SECTOR_DATA, Resource::Buffer(b.sector_data)),
            (vs::HEIGHT_ATLAS, Resource::Image(tree.required_atlas(ATLAS_HEIGHT), ATLAS_LAYOUT)),
            (vs::NORMAL_ATLAS, Resource::Image(tree.required_atlas(ATLAS_NORMAL), ATLAS_LAYOUT)),
            (vs::ALBEDO_ATLAS, Resource::Image(tree.required_atlas(ATLAS_ALBEDO), ATLAS_LAYOUT)),
            (vs::NEAREST, Resource::Sampler(self.nearest.raw())),
            (vs::LINEAR_CLAMP, Resource::Sampler(self.linear.raw())),
        ];
        rec.push_descriptors(&self.pipeline, &bindings);
        rec.push_constants(&self.pipeline, &push);
        let stride = std::mem::size_of::<vk::DrawIndexedIndirectCommand>() as u64;
        for (d, (indices, _)) in b.indices.iter().enumerate() {
            rec.draw_indexed_indirect(indices, b.header, d as u64 * stride);
        }
        GbufferTiles::end_overlay(rec, targets);
    }
}
