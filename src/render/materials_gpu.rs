//! The splat material resources on the GPU (effects `splat` and `cliffs`):
//! the 256-entry material table and the detail texture arrays, made once
//! at start-up from the scene's material set (or the defaults).

use crate::error::Result;
use crate::gpu::{vk, Buffer, BufferDesc, Context, MemoryLocation};
use crate::passes::gbuffer_tiles::MaterialBindings;
use crate::render::detail_textures::{DetailImages, DetailTextures};
use crate::render::effects::Effects;
use crate::render::materials::{MaterialGpu, MaterialSet};
use crate::shaders::{consts, structs};

/// Detail texture side (texels); every layer has a full mip chain.
pub const DETAIL_SIZE: u32 = 256;

const _: () = assert!(std::mem::size_of::<MaterialGpu>() == structs::TERRAIN_MATERIAL);

pub struct MaterialResources {
    pub set: MaterialSet,
    pub table: Buffer,
    pub textures: DetailTextures,
}

impl MaterialResources {
    pub fn new(ctx: &Context, fx: &Effects) -> Result<Self> {
        let set = match &fx.splat_materials {
            Some(path) => MaterialSet::from_file(path)?,
            None => MaterialSet::default(),
        };
        let images = DetailImages::build(&set, DETAIL_SIZE)?;
        let textures = DetailTextures::new(ctx, &images)?;
        let gpu = set.gpu_table();
        assert_eq!(gpu.len(), consts::MATERIAL_COUNT as usize);
        let table = Buffer::new(
            ctx,
            &BufferDesc {
                name: "material_table",
                size: std::mem::size_of_val(gpu.as_slice()) as u64,
                usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuOnly,
            },
        )?;
        ctx.upload(&table, bytemuck::cast_slice(&gpu))?;
        Ok(MaterialResources { set, table, textures })
    }

    pub fn bindings(&self) -> MaterialBindings<'_> {
        MaterialBindings {
            table: &self.table,
            albedo: &self.textures.albedo,
            normal: &self.textures.normal,
            height: &self.textures.height,
        }
    }

    pub fn memory_bytes(&self) -> u64 {
        self.table.memory_bytes() + self.textures.memory_bytes()
    }
}
