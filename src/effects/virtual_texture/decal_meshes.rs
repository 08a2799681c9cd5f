//! `decal_meshes` (effect `decals`, with a displacement decal): every
//! displacement decal's mesh (effects/virtual_texture/decal_mesh.rs) in ONE
//! indexed draw after the terrain draws, into the geometry pass's targets
//! (classification, normal codes, depth and the terrain stencil bit), so
//! the tile passes shade it as terrain: from the virtual texture pages the
//! decal was blended into.

use crate::effects::virtual_texture::decal_mesh::DecalMeshes;
use crate::error::Result;
use crate::gpu::{vk, Buffer, Context, Pipeline, Recorder, Resource, Sampler};
use crate::passes::cull_patches::nearest_sampler;
use crate::passes::terrain_geometry::{begin_geometry, geometry_pipeline, DepthOptions, RenderTargets};
use crate::passes::terrain_query::VistaTerrain;
use crate::shaders::{decal_meshes_frag as fs, decal_meshes_vert as vs, structs};
use crate::targets::gbuffer::GBuffer;
use crate::terrain::gpu_quadtree::{GpuQuadtree, ATLAS_HEIGHT, ATLAS_LAYOUT, ATLAS_NORMAL};

const _: () = assert!(std::mem::size_of::<VistaTerrain>() == structs::DECAL_MESH_PUSH);
const _: () = assert!(
    std::mem::size_of::<crate::effects::virtual_texture::decal_mesh::DecalMeshVertex>() == structs::DECAL_MESH_VERTEX
);

pub struct DecalMeshPass {
    pipeline: Pipeline,
    vertices: Buffer,
    indices: Buffer,
    index_count: u32,
    nearest: Sampler,
    depth: DepthOptions,
    /// Displacement decals drawn and their triangles.
    pub meshes: u32,
    pub triangles: u64,
}

impl DecalMeshPass {
    pub const NAME: &'static str = vs::PASS;

    pub fn new(ctx: &Context, meshes: &DecalMeshes, depth: DepthOptions) -> Result<Self> {
        let (vertices, indices) = upload(ctx, meshes)?;
        Ok(DecalMeshPass {
            pipeline: geometry_pipeline(ctx, Self::NAME, (&vs::SHADER, &fs::SHADER), &[], depth)?,
            vertices,
            indices,
            index_count: meshes.indices.len() as u32,
            nearest: nearest_sampler(ctx, "decal_meshes_nearest")?,
            depth,
            meshes: meshes.meshes,
            triangles: meshes.triangles(),
        })
    }

    /// New meshes (a decal edit): the old buffers are retired until the
    /// frames drawing them completed.
    pub fn replace(&mut self, ctx: &Context, meshes: &DecalMeshes) -> Result<()> {
        (self.vertices, self.indices) = upload(ctx, meshes)?;
        self.index_count = meshes.indices.len() as u32;
        (self.meshes, self.triangles) = (meshes.meshes, meshes.triangles());
        Ok(())
    }

    /// No displacement decal is left to draw (an edit removed them).
    pub fn is_empty(&self) -> bool {
        self.index_count == 0
    }

    pub fn pipeline_label(&self) -> &str {
        &self.pipeline.label
    }

    /// Draws over the terrain's geometry pass (its targets loaded).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder,
        targets: &RenderTargets,
        gbuffer: &GBuffer,
        view: &Buffer,
        terrain: VistaTerrain,
        sector_data: &Buffer,
        tree: &GpuQuadtree,
    ) {
        begin_geometry(rec, targets, gbuffer, self.depth, false);
        rec.bind_pipeline(&self.pipeline);
        rec.push_descriptors(
            &self.pipeline,
            &[
                (vs::VIEW, Resource::Buffer(view)),
                (vs::VERTICES, Resource::Buffer(&self.vertices)),
                (vs::SECTOR_DATA, Resource::Buffer(sector_data)),
                (vs::HEIGHT_ATLAS, Resource::Image(tree.required_atlas(ATLAS_HEIGHT), ATLAS_LAYOUT)),
                (vs::NORMAL_ATLAS, Resource::Image(tree.required_atlas(ATLAS_NORMAL), ATLAS_LAYOUT)),
                (vs::NEAREST, Resource::Sampler(self.nearest.raw())),
            ],
        );
        rec.push_constants(&self.pipeline, &terrain);
        rec.draw_indexed(&self.indices, self.index_count, 1);
        rec.end_rendering();
    }

    pub fn memory(&self) -> Vec<(String, u64)> {
        [&self.vertices, &self.indices].iter().map(|b| (b.name.clone(), b.memory_bytes())).collect()
    }
}

/// The vertex and index buffers of `meshes` (4-byte placeholders when empty).
fn upload(ctx: &Context, meshes: &DecalMeshes) -> Result<(Buffer, Buffer)> {
    let buffer = |name, bytes: &[u8], usage| Buffer::with_data(ctx, name, bytes, usage);
    let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
    Ok((
        buffer("decal_mesh_vertices", bytemuck::cast_slice(&meshes.vertices), storage)?,
        buffer("decal_mesh_indices", bytemuck::cast_slice(&meshes.indices), vk::BufferUsageFlags::INDEX_BUFFER)?,
    ))
}
