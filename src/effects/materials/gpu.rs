//! The splat material resources on the GPU (effects `splat` and `cliffs`):
//! the 256-entry material table and the detail texture arrays, made once
//! at start-up from the scene's material set (or the defaults).

use crate::effects::materials::detail_textures::{DetailImages, DetailTextures};
use crate::effects::materials::{material_set, ControlGpu, MaterialGpu, MaterialSet};
use crate::effects::{Effects, MaterialsMode};
use crate::error::Result;
use crate::gpu::{vk, Buffer, BufferDesc, Context, MemoryLocation};
use crate::passes::gbuffer_tiles::MaterialBindings;
use crate::shaders::{consts, structs};

/// Detail texture side (texels); every layer has a full mip chain.
pub const DETAIL_SIZE: u32 = 256;

const _: () = assert!(std::mem::size_of::<MaterialGpu>() == structs::TERRAIN_MATERIAL);

pub struct MaterialResources {
    pub set: MaterialSet,
    pub table: Buffer,
    /// The control-map flavour's table (`[materials] mode = "control_map"`).
    pub control: Option<Buffer>,
    pub textures: DetailTextures,
}

const _: () = assert!(std::mem::size_of::<ControlGpu>() == structs::CONTROL_TEXTURE);

impl MaterialResources {
    pub fn new(ctx: &Context, fx: &Effects) -> Result<Self> {
        let set = material_set(fx)?;
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
        let control = match fx.materials {
            MaterialsMode::ControlMap => Some(control_table(ctx, &set)?),
            MaterialsMode::Splat => None,
        };
        Ok(MaterialResources { set, table, control, textures })
    }

    pub fn bindings(&self) -> MaterialBindings<'_> {
        MaterialBindings {
            table: &self.table,
            control: self.control.as_ref(),
            albedo: &self.textures.albedo,
            normal: &self.textures.normal,
            height: &self.textures.height,
            virtual_texture: None,
        }
    }

    pub fn memory_bytes(&self) -> u64 {
        self.table.memory_bytes() + self.control.as_ref().map_or(0, Buffer::memory_bytes) + self.textures.memory_bytes()
    }
}

/// The control table's buffer: the code values, then every texture.
fn control_table(ctx: &Context, set: &MaterialSet) -> Result<Buffer> {
    let (head, entries) = set.control_gpu();
    assert_eq!(entries.len(), consts::CONTROL_TEXTURES as usize);
    let mut bytes = bytemuck::bytes_of(&head).to_vec();
    bytes.extend_from_slice(bytemuck::cast_slice(&entries));
    let buffer = Buffer::new(
        ctx,
        &BufferDesc {
            name: "control_table",
            size: bytes.len() as u64,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            location: MemoryLocation::GpuOnly,
        },
    )?;
    ctx.upload(&buffer, &bytes)?;
    Ok(buffer)
}
