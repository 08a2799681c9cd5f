//! The decals' GPU objects (effect `decals`): the texture array (one layer
//! per decal texture, with mips, uploaded once), the decal and road point
//! lists (uploaded in the frame after an edit) and the per-page decal index
//! list of each frame's page jobs. Destroyed in field order through the
//! context's deferred destruction.

use super::decals::{DecalGpu, DecalSet};
use crate::error::{Error, Result};
use crate::gpu::{vk, Buffer, BufferDesc, Context, Image, ImageDesc, MemoryLocation, Recorder, Sampler, SamplerDesc};
use crate::shaders::consts::{DECAL_MAX, DECAL_MAX_PER_PAGE, DECAL_MAX_POINTS, DECAL_TEXELS, VT_MAX_JOBS};
use crate::shaders::structs;

const _: () = assert!(std::mem::size_of::<DecalGpu>() == structs::DECAL);

/// Largest `vkCmdUpdateBuffer`.
const UPDATE_MAX: usize = 65536;

pub struct DecalResources {
    pub textures: Image,
    pub list: Buffer,
    pub points: Buffer,
    /// Per frame: the decal indices of each page job, in order.
    pub job_decals: Buffer,
    pub clamp: Sampler,
    pub repeat: Sampler,
}

fn storage(ctx: &Context, name: &str, size: u64) -> Result<Buffer> {
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
    Buffer::new(ctx, &BufferDesc { name, size, usage, location: MemoryLocation::GpuOnly })
}

impl DecalResources {
    /// Uploads every texture of `set` (one submission) and makes the lists.
    pub fn new(ctx: &Context, set: &DecalSet) -> Result<DecalResources> {
        set.check()?;
        // At least 2: `Image` views a single layer as 2D, the shader samples
        // an array.
        let layers = set.textures.len().max(2) as u32;
        let mips = DECAL_TEXELS.ilog2() + 1;
        let textures = Image::new(
            ctx,
            &ImageDesc {
                name: "decal_textures",
                format: vk::Format::R8G8B8A8_SRGB,
                extent: [DECAL_TEXELS; 2],
                mip_levels: mips,
                array_layers: layers,
                usage: vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
            },
        )?;
        let chains: Vec<Vec<Vec<u8>>> = set.textures.iter().map(|t| t.mips()).collect();
        let total: usize = chains.iter().flatten().map(Vec::len).sum::<usize>().max(4);
        let mut staging = Buffer::new(
            ctx,
            &BufferDesc {
                name: "decal_staging",
                size: total as u64,
                usage: vk::BufferUsageFlags::TRANSFER_SRC,
                location: MemoryLocation::CpuToGpu,
            },
        )?;
        let mapped = staging
            .mapped_mut()
            .ok_or_else(|| Error::Unsupported("the decal staging buffer is not host-visible".into()))?;
        // (mip, layer, offset); every mip's bytes are a multiple of 4.
        let mut copies = Vec::new();
        let mut at = 0;
        for (layer, chain) in chains.iter().enumerate() {
            for (mip, bytes) in chain.iter().enumerate() {
                mapped[at..at + bytes.len()].copy_from_slice(bytes);
                copies.push((mip as u32, layer as u32, at as u64));
                at += bytes.len();
            }
        }
        ctx.submit_and_wait(|rec| {
            rec.discard_to(&textures, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
            for &(mip, layer, offset) in &copies {
                rec.copy_buffer_to_image(&staging, offset, &textures, mip, layer);
            }
            rec.transition(&textures, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
            Ok(())
        })?;
        let sampler = |name, address_mode| {
            Sampler::mipmapped(ctx, &SamplerDesc { name, filter: vk::Filter::LINEAR, address_mode })
        };
        Ok(DecalResources {
            textures,
            list: storage(ctx, "decal_list", u64::from(DECAL_MAX) * structs::DECAL as u64)?,
            points: storage(ctx, "decal_points", u64::from(DECAL_MAX_POINTS) * 16)?,
            job_decals: storage(ctx, "decal_job_lists", u64::from(VT_MAX_JOBS * DECAL_MAX_PER_PAGE) * 4)?,
            clamp: sampler("decal_clamp", vk::SamplerAddressMode::CLAMP_TO_EDGE)?,
            repeat: sampler("decal_repeat", vk::SamplerAddressMode::REPEAT)?,
        })
    }

    /// Uploads the decal and point `lists` where given, and the frame's
    /// job decal indices (before `vt_pages`' barrier).
    pub fn record_upload(
        &self,
        rec: &mut Recorder,
        lists: Option<&(Vec<DecalGpu>, Vec<[f32; 4]>)>,
        job_decals: &[u32],
    ) {
        if let Some((list, points)) = lists {
            for (buf, bytes) in [(&self.list, bytemuck::cast_slice(list)), (&self.points, bytemuck::cast_slice(points))]
            {
                for (i, chunk) in bytes.chunks(UPDATE_MAX).enumerate() {
                    rec.update_buffer(buf, (i * UPDATE_MAX) as u64, chunk);
                }
            }
        }
        for (i, chunk) in bytemuck::cast_slice(job_decals).chunks(UPDATE_MAX).enumerate() {
            rec.update_buffer(&self.job_decals, (i * UPDATE_MAX) as u64, chunk);
        }
    }

    /// (name, bytes) of every GPU object.
    pub fn memory(&self) -> Vec<(String, u64)> {
        let mut v: Vec<(String, u64)> =
            [&self.list, &self.points, &self.job_decals].iter().map(|b| (b.name.clone(), b.memory_bytes())).collect();
        v.push((self.textures.name.clone(), self.textures.memory_bytes()));
        v
    }
}
