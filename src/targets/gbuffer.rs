//! The renderer's own screen-sized targets: the classification and
//! geometry-normal targets the geometry pass writes (every output), and,
//! where vista lights the frame itself (outputs `lit`, `hdr`), its own
//! G-buffer the tile passes write and (output `lit`) the HDR lit image.
//! With output `gbuffer` the tile passes write the engine's images and
//! none of those is made. Made for the first view size seen and remade
//! (the old ones deferred-destroyed) when it changes.

use crate::error::Result;
use crate::gpu::{vk, Context, Image, ImageDesc};
use crate::targets::Output;

/// One bit per flavour the pixel needs (0 = no terrain).
pub const CLASSIFICATION_FORMAT: vk::Format = vk::Format::R8_UINT;
/// The patch info of the debug views (PATCH_INFO_* bits: LOD, refinement,
/// phase, grid edge).
pub const PATCH_INFO_FORMAT: vk::Format = vk::Format::R8_UINT;
/// Two octahedral normals as 8-bit codes: geometric (baked), triangle.
pub const GEOMETRY_NORMALS_FORMAT: vk::Format = vk::Format::R8G8B8A8_UINT;
/// rgb albedo.
pub const ALBEDO_FORMAT: vk::Format = vk::Format::R8G8B8A8_SRGB;
/// xy octahedral shading normal, z roughness.
pub const NORMAL_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;
/// x material id, y the flavour bits shaded (debug).
pub const MATERIAL_FORMAT: vk::Format = vk::Format::R8G8_UINT;
/// Linear lit radiance.
pub const HDR_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;

pub struct GBuffer {
    pub classification: Image,
    pub geometry_normals: Image,
    pub patch_info: Image,
    /// Outputs `lit` and `hdr`: the G-buffer vista lights.
    own: Option<OwnGbuffer>,
}

/// The G-buffer vista lights itself (outputs `lit`, `hdr`).
pub struct OwnGbuffer {
    pub albedo: Image,
    pub normal: Image,
    pub material: Image,
    /// Output `lit`: the linear radiance beside the display image.
    pub hdr: Option<Image>,
}

impl GBuffer {
    pub fn new(ctx: &Context, size: [u32; 2], output: &Output) -> Result<GBuffer> {
        let attach = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED;
        let image = |name, format| {
            Image::new(
                ctx,
                &ImageDesc {
                    name,
                    format,
                    extent: size,
                    mip_levels: 1,
                    array_layers: 1,
                    // Read back by tools and tests.
                    usage: attach | vk::ImageUsageFlags::TRANSFER_SRC,
                },
            )
        };
        let own = match output {
            Output::Gbuffer(_) => None,
            Output::Lit { .. } | Output::Hdr { .. } => Some(OwnGbuffer {
                albedo: image("gbuffer_albedo", ALBEDO_FORMAT)?,
                normal: image("gbuffer_normal", NORMAL_FORMAT)?,
                material: image("gbuffer_material", MATERIAL_FORMAT)?,
                hdr: match output {
                    Output::Lit { .. } => Some(image("lit_hdr", HDR_FORMAT)?),
                    _ => None,
                },
            }),
        };
        Ok(GBuffer {
            classification: image("classification", CLASSIFICATION_FORMAT)?,
            geometry_normals: image("geometry_normals", GEOMETRY_NORMALS_FORMAT)?,
            patch_info: image("patch_info", PATCH_INFO_FORMAT)?,
            own,
        })
    }

    pub fn size(&self) -> [u32; 2] {
        self.classification.extent
    }

    /// vista's own G-buffer (outputs `lit`, `hdr`).
    pub fn own(&self) -> Option<&OwnGbuffer> {
        self.own.as_ref()
    }

    pub fn images(&self) -> Vec<&Image> {
        let mut out = vec![&self.classification, &self.geometry_normals, &self.patch_info];
        if let Some(o) = &self.own {
            out.extend([&o.albedo, &o.normal, &o.material]);
            out.extend(o.hdr.as_ref());
        }
        out
    }

    pub fn memory_bytes(&self) -> u64 {
        self.images().iter().map(|i| i.memory_bytes()).sum()
    }
}

/// The G-buffer and lit image of the last frame, read back (tools, tests).
/// What the output does not make is empty: `hdr` outside output `lit`,
/// `albedo`, `normal` and `material` with output `gbuffer`.
pub struct GBufferCapture {
    pub size: [u32; 2],
    /// Linear lit radiance, RGBA.
    pub hdr: Vec<[f32; 4]>,
    pub classification: Vec<u8>,
    /// Two octahedral codes each: geometric normal, triangle normal.
    pub geometry_normals: Vec<[u8; 4]>,
    /// PATCH_INFO_* bits.
    pub patch_info: Vec<u8>,
    /// sRGB-encoded albedo.
    pub albedo: Vec<[u8; 4]>,
    pub normal: Vec<[u8; 4]>,
    /// Material id, flavour bits shaded.
    pub material: Vec<[u8; 2]>,
}

impl GBuffer {
    /// Reads every target back (waits for the GPU).
    pub fn capture(&self, ctx: &Context) -> Result<GBufferCapture> {
        let rgba8 =
            |img: &Image| -> Result<Vec<[u8; 4]>> { Ok(bytemuck::pod_collect_to_vec(&ctx.read_image(img, 0, 0, 4)?)) };
        let mut capture = GBufferCapture {
            size: self.size(),
            hdr: Vec::new(),
            classification: ctx.read_image(&self.classification, 0, 0, 1)?,
            geometry_normals: rgba8(&self.geometry_normals)?,
            patch_info: ctx.read_image(&self.patch_info, 0, 0, 1)?,
            albedo: Vec::new(),
            normal: Vec::new(),
            material: Vec::new(),
        };
        let Some(own) = &self.own else { return Ok(capture) };
        capture.albedo = rgba8(&own.albedo)?;
        capture.normal = rgba8(&own.normal)?;
        capture.material = bytemuck::pod_collect_to_vec(&ctx.read_image(&own.material, 0, 0, 2)?);
        if let Some(hdr) = &own.hdr {
            let halves: Vec<u16> = bytemuck::pod_collect_to_vec(&ctx.read_image(hdr, 0, 0, 8)?);
            capture.hdr =
                halves.chunks_exact(4).map(|c| [0, 1, 2, 3].map(|i| half::f16::from_bits(c[i]).to_f32())).collect();
        }
        Ok(capture)
    }
}

/// The classification's colour of each flavour bit (bit 0 first): virtual
/// texture violet, far atlas blue, near cliff red, far cliff orange, splat
/// green, control map pink (`debug_view` shows the same).
pub fn classification_palette() -> [[u8; 3]; FLAVOUR_COUNT] {
    use crate::shaders::consts::*;
    let colour = |bit: u32| match bit {
        FLAVOUR_VIRTUAL_TEXTURE => [200, 60, 255],
        FLAVOUR_FAR_ATLAS => [60, 100, 255],
        FLAVOUR_NEAR_CLIFF => [255, 50, 40],
        FLAVOUR_FAR_CLIFF => [255, 190, 30],
        FLAVOUR_SPLAT => [60, 220, 60],
        FLAVOUR_CONTROL_MAP => [255, 110, 200],
        _ => unreachable!("flavour bit {bit}"),
    };
    std::array::from_fn(|b| colour(1 << b))
}

/// Flavour bits of a classification (the plane bits above them are not
/// flavours).
pub const FLAVOUR_COUNT: usize = crate::shaders::consts::FLAVOUR_BITS as usize;

/// Debug colour of a classification value: the mean of its flavours'
/// colours ([`classification_palette`]); black where no terrain.
pub fn classification_colour(bits: u8) -> [u8; 3] {
    let palette = classification_palette();
    let on: Vec<[u8; 3]> = (0..FLAVOUR_COUNT).filter(|b| bits & (1 << b) != 0).map(|b| palette[b]).collect();
    if on.is_empty() {
        return [0, 0, 0];
    }
    let n = on.len() as f32;
    [0, 1, 2].map(|i| (on.iter().map(|c| f32::from(c[i])).sum::<f32>() / n).round() as u8)
}
