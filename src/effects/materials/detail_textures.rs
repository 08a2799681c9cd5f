//! Detail textures of the splat materials: one layer per texture set of a
//! [`MaterialSet`] in three 2D arrays (albedo, normal + roughness, height),
//! generated procedurally or loaded from PNGs on the CPU ([`DetailImages`])
//! and uploaded once ([`DetailTextures`]).
//!
//! Texel formats, tightly packed, all layers of a mip concatenated:
//! - albedo RGBA8, sRGB-encoded colour, a = 255;
//! - normal RGBA8: a tangent-space unit normal as `n * 127.5 + 127.5`, x
//!   along +u (columns), y along +v (rows, as Vulkan samples them), z out of
//!   the surface; a = roughness 0..255;
//! - height R8, 0..255, for height-weighted blending between materials.
//!
//! Procedural textures are functions on the unit torus (noise lattices with
//! whole periods), so they tile exactly and look the same at every size;
//! normals come from wrapped finite differences of the same height field.

use crate::effects::materials::{MaterialSet, ProceduralKind, TextureSource, MAX_TEXTURE_SETS};
use crate::error::{Error, Result};
use crate::gpu::{vk, Buffer, BufferDesc, Context, Image, ImageDesc, MemoryLocation};
use image::imageops::FilterType;
use rayon::prelude::*;
use std::f32::consts::TAU;
use std::path::Path;

/// Smallest and largest layer side.
pub const MIN_SIZE: u32 = 16;
pub const MAX_SIZE: u32 = 2048;
/// Roughness of a normal map without an alpha channel.
pub const DEFAULT_ROUGHNESS: u8 = 200;

/// Every layer and mip of the three arrays, ready to upload.
#[derive(Debug, Clone, PartialEq)]
pub struct DetailImages {
    /// Side of mip 0.
    pub size: u32,
    /// Full chain down to 1x1 from `build`; an upload takes any prefix.
    pub mips: u32,
    pub layers: u32,
    /// Per mip, layer-major (see the module docs for the formats).
    pub albedo: Vec<Vec<u8>>,
    pub normal: Vec<Vec<u8>>,
    pub height: Vec<Vec<u8>>,
}

/// One mip of one layer.
struct Layer {
    albedo: Vec<u8>,
    normal: Vec<u8>,
    height: Vec<u8>,
}

impl DetailImages {
    /// Generates or loads every texture set of `set` at `size` (a power of
    /// two in 16..=2048), with mips.
    pub fn build(set: &MaterialSet, size: u32) -> Result<DetailImages> {
        if !size.is_power_of_two() || !(MIN_SIZE..=MAX_SIZE).contains(&size) {
            return Err(Error::BadInput(format!(
                "detail texture size {size} must be a power of two in {MIN_SIZE}..={MAX_SIZE}"
            )));
        }
        if set.textures.is_empty() || set.textures.len() > MAX_TEXTURE_SETS {
            return Err(Error::BadInput(format!(
                "{} texture sets: a material set needs 1..={MAX_TEXTURE_SETS}",
                set.textures.len()
            )));
        }
        let mips = size.ilog2() + 1;
        let chains: Vec<Vec<Layer>> = set
            .textures
            .par_iter()
            .map(|t| {
                let base = match &t.source {
                    TextureSource::Procedural(kind) => procedural(*kind, size),
                    TextureSource::Files { albedo, normal, height } => load_files(albedo, normal, height, size)?,
                };
                let mut chain = vec![base];
                for m in 1..mips {
                    chain.push(downsample(&chain[m as usize - 1], (size >> (m - 1)) as usize));
                }
                Ok(chain)
            })
            .collect::<Result<_>>()?;
        let gather = |f: fn(&Layer) -> &Vec<u8>| -> Vec<Vec<u8>> {
            (0..mips as usize).map(|m| chains.iter().flat_map(|c| f(&c[m]).iter().copied()).collect()).collect()
        };
        Ok(DetailImages {
            size,
            mips,
            layers: set.textures.len() as u32,
            albedo: gather(|l| &l.albedo),
            normal: gather(|l| &l.normal),
            height: gather(|l| &l.height),
        })
    }

    /// Layer `layer`'s mean albedo, linear (as the far atlas stores it: a
    /// UNORM layer the shader reads as linear colour), and mean roughness:
    /// its last mip's texel (the chain averages down to 1x1, in linear).
    pub fn mean(&self, layer: u32) -> ([u8; 3], u8) {
        let last = self.mips as usize - 1;
        let (a, n) = (&self.albedo[last], &self.normal[last]);
        let i = layer as usize * self.layer_bytes(last as u32, 4);
        let linear = |v: u8| (srgb_to_linear_lut()[v as usize] * 255.0).round() as u8;
        ([linear(a[i]), linear(a[i + 1]), linear(a[i + 2])], n[i + 3])
    }

    /// Side of `mip`.
    pub fn mip_size(&self, mip: u32) -> u32 {
        (self.size >> mip).max(1)
    }

    /// Bytes of one layer of `mip` at `texel_bytes` per texel.
    pub fn layer_bytes(&self, mip: u32, texel_bytes: usize) -> usize {
        let s = self.mip_size(mip) as usize;
        s * s * texel_bytes
    }

    /// Whether the vectors have the shape the fields claim (they are
    /// public, so an upload checks rather than trusts them).
    fn check(&self) -> Result<()> {
        let bad = |what: String| Error::BadInput(format!("detail images: {what}"));
        if !self.size.is_power_of_two() || self.mips == 0 || self.mips > self.size.ilog2() + 1 || self.layers == 0 {
            return Err(bad(format!("size {}, {} mips, {} layers", self.size, self.mips, self.layers)));
        }
        for (name, data, texel) in
            [("albedo", &self.albedo, 4), ("normal", &self.normal, 4), ("height", &self.height, 1)]
        {
            if data.len() != self.mips as usize {
                return Err(bad(format!("{name} has {} mips, not {}", data.len(), self.mips)));
            }
            for (m, d) in data.iter().enumerate() {
                let want = self.layer_bytes(m as u32, texel) * self.layers as usize;
                if d.len() != want {
                    return Err(bad(format!("{name} mip {m} has {} bytes, not {want}", d.len())));
                }
            }
        }
        Ok(())
    }
}

/// The three detail texture arrays on the GPU, sampled by the splat shading.
pub struct DetailTextures {
    pub albedo: Image,
    pub normal: Image,
    pub height: Image,
}

impl DetailTextures {
    /// Creates the arrays and uploads every mip and layer through one
    /// staging buffer in one submission.
    pub fn new(ctx: &Context, images: &DetailImages) -> Result<DetailTextures> {
        Self::with_usage(ctx, images, vk::ImageUsageFlags::empty())
    }

    /// `new` with extra image usage (tests read the arrays back).
    pub(crate) fn with_usage(
        ctx: &Context,
        images: &DetailImages,
        extra: vk::ImageUsageFlags,
    ) -> Result<DetailTextures> {
        images.check()?;
        let kinds: [(&str, vk::Format, usize, &Vec<Vec<u8>>); 3] = [
            ("detail_albedo", vk::Format::R8G8B8A8_SRGB, 4, &images.albedo),
            ("detail_normal", vk::Format::R8G8B8A8_UNORM, 4, &images.normal),
            ("detail_height", vk::Format::R8_UNORM, 1, &images.height),
        ];
        // (image, mip, layer, staging offset, bytes). Offsets stay 16-byte
        // aligned: a multiple of every texel size, and of the optimal copy
        // offset alignment of common devices.
        let mut copies = Vec::new();
        let mut total = 0u64;
        for (i, &(_, _, texel, data)) in kinds.iter().enumerate() {
            for mip in 0..images.mips {
                let n = images.layer_bytes(mip, texel);
                for layer in 0..images.layers {
                    let start = layer as usize * n;
                    copies.push((i, mip, layer, total, &data[mip as usize][start..start + n]));
                    total = (total + n as u64).next_multiple_of(16);
                }
            }
        }
        let mut staging = Buffer::new(
            ctx,
            &BufferDesc {
                name: "detail_staging",
                size: total,
                usage: vk::BufferUsageFlags::TRANSFER_SRC,
                location: MemoryLocation::CpuToGpu,
            },
        )?;
        let mapped = staging
            .mapped_mut()
            .ok_or_else(|| Error::Unsupported("the detail texture staging buffer is not host-visible".into()))?;
        for (_, _, _, offset, bytes) in &copies {
            mapped[*offset as usize..*offset as usize + bytes.len()].copy_from_slice(bytes);
        }
        let image = |(name, format, _, _): (&str, vk::Format, usize, &Vec<Vec<u8>>)| {
            Image::new(
                ctx,
                &ImageDesc {
                    name,
                    format,
                    extent: [images.size; 2],
                    mip_levels: images.mips,
                    array_layers: images.layers,
                    usage: vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST | extra,
                },
            )
        };
        let out = DetailTextures { albedo: image(kinds[0])?, normal: image(kinds[1])?, height: image(kinds[2])? };
        ctx.submit_and_wait(|rec| {
            let imgs = [&out.albedo, &out.normal, &out.height];
            for img in imgs {
                rec.discard_to(img, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
            }
            for (i, mip, layer, offset, _) in &copies {
                rec.copy_buffer_to_image(&staging, *offset, imgs[*i], *mip, *layer);
            }
            for img in imgs {
                rec.transition(img, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
            }
            Ok(())
        })?;
        Ok(out)
    }

    /// Device memory of the three arrays.
    pub fn memory_bytes(&self) -> u64 {
        self.albedo.memory_bytes() + self.normal.memory_bytes() + self.height.memory_bytes()
    }
}

// ---- files ----

fn load_files(albedo: &Path, normal: &Path, height: &Path, size: u32) -> Result<Layer> {
    let a = decode(albedo, "albedo")?;
    let n = decode(normal, "normal")?;
    let h = decode(height, "height")?;
    let fit = |img: image::DynamicImage| {
        if img.width() == size {
            img
        } else {
            img.resize_exact(size, size, FilterType::Triangle)
        }
    };
    let mut a = fit(a).into_rgba8().into_raw();
    a.chunks_exact_mut(4).for_each(|t| t[3] = 255);
    let has_alpha = n.color().has_alpha();
    let mut n = fit(n).into_rgba8().into_raw();
    for t in n.chunks_exact_mut(4) {
        let roughness = if has_alpha { t[3] } else { DEFAULT_ROUGHNESS };
        let v = normalize(decode_normal(t));
        t.copy_from_slice(&encode_normal(v, roughness));
    }
    let h = fit(h).into_luma8().into_raw();
    Ok(Layer { albedo: a, normal: n, height: h })
}

fn decode(path: &Path, what: &str) -> Result<image::DynamicImage> {
    let fail = |why: String| {
        let why = why.lines().map(str::trim).collect::<Vec<_>>().join("; ");
        Error::Scene(format!("{what} texture {}: {why}", path.display()))
    };
    let img = crate::world::require_regular_file(path)
        .and_then(|()| image::ImageReader::open(path))
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| fail(format!("cannot read it: {e}")))?
        .decode()
        .map_err(|e| fail(format!("cannot decode it: {e}")))?;
    if img.width() != img.height() {
        return Err(fail(format!("is {}x{}, must be square", img.width(), img.height())));
    }
    Ok(img)
}

// ---- mips ----

/// Halves a layer of side `size` (2x2 boxes: sides are powers of two):
/// albedo averaged in linear light, normals renormalised.
fn downsample(src: &Layer, size: usize) -> Layer {
    let half = size / 2;
    let lut = srgb_to_linear_lut();
    let texels = |x: usize, y: usize| {
        [(2 * y) * size + 2 * x, (2 * y) * size + 2 * x + 1, (2 * y + 1) * size + 2 * x, (2 * y + 1) * size + 2 * x + 1]
    };
    let mut albedo = vec![0u8; half * half * 4];
    let mut normal = vec![0u8; half * half * 4];
    let mut height = vec![0u8; half * half];
    albedo
        .par_chunks_mut(half * 4)
        .zip(normal.par_chunks_mut(half * 4))
        .zip(height.par_chunks_mut(half))
        .enumerate()
        .for_each(|(y, ((a_row, n_row), h_row))| {
            for x in 0..half {
                let q = texels(x, y);
                let mut rgb = [0f32; 3];
                let mut n = [0f32; 3];
                let (mut rough, mut h) = (0u32, 0u32);
                for i in q {
                    for c in 0..3 {
                        rgb[c] += lut[src.albedo[4 * i + c] as usize];
                    }
                    let d = decode_normal(&src.normal[4 * i..4 * i + 4]);
                    n = [n[0] + d[0], n[1] + d[1], n[2] + d[2]];
                    rough += src.normal[4 * i + 3] as u32;
                    h += src.height[i] as u32;
                }
                a_row[4 * x..4 * x + 4].copy_from_slice(&[
                    linear_to_srgb8(rgb[0] / 4.0),
                    linear_to_srgb8(rgb[1] / 4.0),
                    linear_to_srgb8(rgb[2] / 4.0),
                    255,
                ]);
                n_row[4 * x..4 * x + 4].copy_from_slice(&encode_normal(normalize(n), ((rough + 2) / 4) as u8));
                h_row[x] = ((h + 2) / 4) as u8;
            }
        });
    Layer { albedo, normal, height }
}

fn srgb_to_linear_lut() -> &'static [f32; 256] {
    static LUT: std::sync::OnceLock<[f32; 256]> = std::sync::OnceLock::new();
    LUT.get_or_init(|| {
        std::array::from_fn(|i| {
            let c = i as f32 / 255.0;
            if c <= 0.04045 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            }
        })
    })
}

fn linear_to_srgb8(x: f32) -> u8 {
    let x = x.clamp(0.0, 1.0);
    let c = if x <= 0.003_130_8 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 };
    (c * 255.0).round() as u8
}

fn decode_normal(t: &[u8]) -> [f32; 3] {
    [t[0] as f32 / 127.5 - 1.0, t[1] as f32 / 127.5 - 1.0, t[2] as f32 / 127.5 - 1.0]
}

fn encode_normal(n: [f32; 3], roughness: u8) -> [u8; 4] {
    let e = |c: f32| (c * 127.5 + 127.5).round().clamp(0.0, 255.0) as u8;
    [e(n[0]), e(n[1]), e(n[2]), roughness]
}

/// Unit length; a zero vector (opposite normals averaged) becomes +z.
fn normalize(n: [f32; 3]) -> [f32; 3] {
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if len > 1e-6 {
        [n[0] / len, n[1] / len, n[2] / len]
    } else {
        [0.0, 0.0, 1.0]
    }
}

// ---- procedural ----

/// What a kind's function gives at one point of the tile.
struct Sample {
    /// sRGB-encoded 0..1.
    rgb: [f32; 3],
    /// 0..1.
    height: f32,
    /// 0..1.
    roughness: f32,
}

/// Height range of a kind in units of the tile's width: how strongly its
/// height field bends the normals.
fn relief(kind: ProceduralKind) -> f32 {
    match kind {
        ProceduralKind::Grass => 0.012,
        ProceduralKind::Rock => 0.03,
        ProceduralKind::Snow => 0.006,
        ProceduralKind::Scree => 0.025,
        ProceduralKind::Dirt => 0.02,
    }
}

fn procedural(kind: ProceduralKind, size: u32) -> Layer {
    let noise = Noise { seed: hash(kind as u32, 0x5eed, 0x7e57), nyquist: size / 2 };
    let n = size as usize;
    let mut samples: Vec<Sample> = Vec::with_capacity(n * n);
    (0..n * n)
        .into_par_iter()
        .map(|i| {
            let (u, v) = (((i % n) as f32 + 0.5) / size as f32, ((i / n) as f32 + 0.5) / size as f32);
            sample(kind, u, v, &noise)
        })
        .collect_into_vec(&mut samples);
    let mut albedo = vec![0u8; n * n * 4];
    let mut normal = vec![0u8; n * n * 4];
    // Central differences in tile units, wrapping: the slope across the
    // edge is the slope inside.
    let scale = relief(kind) * size as f32 * 0.5;
    albedo.par_chunks_mut(4).zip(normal.par_chunks_mut(4)).enumerate().for_each(|(i, (a, nrm))| {
        let (x, y) = (i % n, i / n);
        let h = |x: usize, y: usize| samples[(y % n) * n + x % n].height;
        let dhdu = (h(x + 1, y) - h(x + n - 1, y)) * scale;
        let dhdv = (h(x, y + 1) - h(x, y + n - 1)) * scale;
        let s = &samples[i];
        let srgb8 = |c: f32| (c.clamp(0.0, 1.0) * 255.0).round() as u8;
        a.copy_from_slice(&[srgb8(s.rgb[0]), srgb8(s.rgb[1]), srgb8(s.rgb[2]), 255]);
        nrm.copy_from_slice(&encode_normal(normalize([-dhdu, -dhdv, 1.0]), srgb8(s.roughness)));
    });
    let height = samples.iter().map(|s| (s.height.clamp(0.0, 1.0) * 255.0).round() as u8).collect();
    Layer { albedo, normal, height }
}

fn sample(kind: ProceduralKind, u: f32, v: f32, n: &Noise) -> Sample {
    match kind {
        ProceduralKind::Grass => {
            let patch = 0.5 + 0.5 * n.fbm(u, v, [4, 4], 4, 0.5, 1);
            // Blades: thin ridges of noise stretched along v and the two
            // diagonals (whole periods along each keep it tileable).
            let ridge = |x: f32| (1.0 - x.abs() * 2.5).max(0.0).powi(3);
            let b1 = ridge(n.fbm(u, v, [48, 8], 2, 0.5, 2));
            let b2 = ridge(n.fbm(u + v, u - v, [32, 6], 2, 0.5, 3));
            let b3 = ridge(n.fbm(u - v, u + v, [32, 6], 2, 0.5, 4));
            let blades = b1.max(b2).max(b3);
            let mut rgb = mix([0.14, 0.24, 0.06], [0.36, 0.50, 0.15], blades);
            rgb = mix(rgb, [0.50, 0.48, 0.24], 0.4 * smoothstep(0.55, 0.9, patch));
            Sample { rgb, height: 0.3 * patch + 0.7 * blades, roughness: 0.9 - 0.15 * blades }
        }
        ProceduralKind::Rock => {
            let warp = n.fbm(u, v, [3, 3], 3, 0.5, 10);
            let warp2 = n.fbm(u, v, [6, 6], 3, 0.5, 14);
            // Strata: bands along v bent by the warp, each with its own
            // tone and a sharp ledge at its base. Band indices wrap with
            // the tile (15 per repeat).
            let t = (v * 5.0 + 0.35 * warp) * 3.0;
            let stratum = unit(hash((t.floor() as i64).rem_euclid(15) as u32, 7, n.seed));
            let band = 0.5 + 0.5 * (t * TAU / 3.0).sin();
            let ledge = smoothstep(0.0, 0.25, t.rem_euclid(1.0));
            let grain = n.fbm(u, v, [8, 8], 5, 0.55, 11);
            // Cracks: warped cell borders, only where a mask lets them
            // through (all borders would read as paving), plus finer ones.
            let (f1, f2, _) = worley(u + 0.08 * warp2, v + 0.08 * warp, 4, n.seed ^ 12);
            let major =
                (1.0 - smoothstep(0.0, 0.04, f2 - f1)) * smoothstep(-0.15, 0.2, n.fbm(u, v, [5, 5], 2, 0.5, 15));
            let (g1, g2, _) = worley(u + 0.05 * warp, v + 0.05 * warp2, 12, n.seed ^ 16);
            let minor = (1.0 - smoothstep(0.0, 0.05, g2 - g1)) * smoothstep(0.1, 0.4, n.fbm(u, v, [7, 7], 2, 0.5, 17));
            let crack = major.max(0.6 * minor);
            let height = 0.45 + 0.2 * grain + 0.12 * band + 0.08 * ledge - 0.35 * crack;
            let mut rgb = mix([0.33, 0.32, 0.30], [0.60, 0.58, 0.54], 0.5 + 0.6 * grain + 0.5 * (stratum - 0.5));
            rgb = add(rgb, [0.05 * band, 0.03 * band, 0.0]);
            rgb = rgb.map(|c| c * (1.0 - 0.55 * crack));
            let roughness = 0.62 + 0.15 * (0.5 + 0.5 * n.fbm(u, v, [16, 16], 2, 0.5, 13)) + 0.2 * crack;
            Sample { rgb, height, roughness }
        }
        ProceduralKind::Snow => {
            let dunes = n.fbm(u, v, [2, 2], 5, 0.45, 20);
            let fine = n.fbm(u, v, [32, 32], 2, 0.5, 21);
            let height = 0.5 + 0.45 * dunes + 0.04 * fine;
            let rgb = mix([0.82, 0.86, 0.93], [0.95, 0.96, 0.98], smoothstep(0.2, 0.75, height));
            Sample { rgb, height, roughness: 0.45 + 0.1 * fine }
        }
        ProceduralKind::Scree => {
            // Two sizes of stones, domed cells of cellular noise; the higher
            // one shows, the gaps between them are dark grit.
            let stones = |cells: u32, salt: u32, top: f32| {
                let (f1, f2, id) = worley(u, v, cells, n.seed ^ salt);
                let dome = smoothstep(0.0, 0.3, f2 - f1).sqrt();
                (dome * top * (0.75 + 0.25 * unit(id)), unit(hash(id, salt, 1)), dome)
            };
            let (h1, tone1, d1) = stones(10, 30, 0.8);
            let (h2, tone2, d2) = stones(23, 31, 0.55);
            let (h, tone, dome) = if h1 >= h2 { (h1, tone1, d1) } else { (h2, tone2, d2) };
            let grit = n.fbm(u, v, [32, 32], 3, 0.5, 32);
            let stone = mix([0.42, 0.36, 0.29], [0.56, 0.52, 0.46], tone);
            let rgb = mix([0.18, 0.15, 0.11], stone, smoothstep(0.0, 0.35, dome));
            Sample { rgb, height: h + 0.05 * grit, roughness: 0.95 - 0.25 * dome * (0.5 + 0.5 * tone) }
        }
        ProceduralKind::Dirt => {
            let soil = n.fbm(u, v, [4, 4], 6, 0.55, 40);
            let clods = n.fbm(u, v, [16, 16], 3, 0.5, 41);
            let grit = n.fbm(u, v, [64, 64], 1, 0.5, 43);
            // A few small stones in the soil, in a third of the cells.
            let (f1, _, id) = worley(u, v, 10, n.seed ^ 42);
            let pebble = if unit(id) < 0.35 { smoothstep(0.35, 0.15, f1) } else { 0.0 };
            let height = 0.4 + 0.2 * soil + 0.15 * clods + 0.05 * grit + 0.3 * pebble;
            let earth = mix([0.28, 0.20, 0.13], [0.46, 0.35, 0.24], 0.5 + 0.7 * soil + 0.2 * clods + 0.15 * grit);
            let stone = [0.44, 0.40, 0.34].map(|c| c * (0.8 + 0.4 * unit(hash(id, 3, 4))));
            let rgb = mix(earth, stone, 0.8 * pebble);
            Sample { rgb, height, roughness: 0.92 - 0.2 * pebble }
        }
    }
}

fn mix(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    let t = t.clamp(0.0, 1.0);
    [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t]
}

fn add(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// Hermite step from `e0` to `e1` (either order).
fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

fn hash(x: u32, y: u32, seed: u32) -> u32 {
    let mut h = x.wrapping_mul(0x8da6_b343) ^ y.wrapping_mul(0xd816_3841) ^ seed.wrapping_mul(0xcb1a_b31f);
    h ^= h >> 16;
    h = h.wrapping_mul(0x7feb_352d);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846c_a68b);
    h ^ (h >> 16)
}

/// 0..1 from the high bits.
fn unit(h: u32) -> f32 {
    (h >> 8) as f32 / (1u32 << 24) as f32
}

/// Periodic noise: every lattice has a whole number of cells across the
/// tile, and lattices finer than `nyquist` cells are left out (they would
/// only alias at this size).
struct Noise {
    seed: u32,
    nyquist: u32,
}

const GRADIENTS: [[f32; 2]; 8] = [
    [1.0, 0.0],
    [-1.0, 0.0],
    [0.0, 1.0],
    [0.0, -1.0],
    [std::f32::consts::FRAC_1_SQRT_2, std::f32::consts::FRAC_1_SQRT_2],
    [-std::f32::consts::FRAC_1_SQRT_2, std::f32::consts::FRAC_1_SQRT_2],
    [std::f32::consts::FRAC_1_SQRT_2, -std::f32::consts::FRAC_1_SQRT_2],
    [-std::f32::consts::FRAC_1_SQRT_2, -std::f32::consts::FRAC_1_SQRT_2],
];

impl Noise {
    /// Fractal gradient noise, about -1..1: `octaves` lattices from
    /// `cells` up, doubling, each `gain` times weaker.
    fn fbm(&self, u: f32, v: f32, cells: [u32; 2], octaves: u32, gain: f32, salt: u32) -> f32 {
        let (mut sum, mut norm, mut amp) = (0.0, 0.0, 1.0);
        for o in 0..octaves {
            let (px, py) = (cells[0] << o, cells[1] << o);
            if px.max(py) <= self.nyquist {
                sum += amp * gradient(u, v, px, py, hash(self.seed, salt, o));
            }
            norm += amp;
            amp *= gain;
        }
        sum / norm
    }
}

/// Gradient noise with `px` x `py` cells over the unit torus, about -1..1.
fn gradient(u: f32, v: f32, px: u32, py: u32, seed: u32) -> f32 {
    let (x, y) = (u * px as f32, v * py as f32);
    let (xf, yf) = (x.floor(), y.floor());
    let (fx, fy) = (x - xf, y - yf);
    let (x0, y0) = (wrap(xf as i64, px), wrap(yf as i64, py));
    let (x1, y1) = (wrap(x0 as i64 + 1, px), wrap(y0 as i64 + 1, py));
    let dot = |cx: u32, cy: u32, dx: f32, dy: f32| {
        let g = GRADIENTS[(hash(cx, cy, seed) & 7) as usize];
        g[0] * dx + g[1] * dy
    };
    let fade = |t: f32| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
    let (sx, sy) = (fade(fx), fade(fy));
    let (n00, n10) = (dot(x0, y0, fx, fy), dot(x1, y0, fx - 1.0, fy));
    let (n01, n11) = (dot(x0, y1, fx, fy - 1.0), dot(x1, y1, fx - 1.0, fy - 1.0));
    let (a, b) = (n00 + sx * (n10 - n00), n01 + sx * (n11 - n01));
    (a + sy * (b - a)) * 1.4
}

/// `i` modulo `n` in 0..n; lattice indices are nearly always within one
/// period of the tile, where this needs no division (half the noise cost).
fn wrap(i: i64, n: u32) -> u32 {
    let n = n as i64;
    let w = if i < 0 {
        i + n
    } else if i >= n {
        i - n
    } else {
        i
    };
    if (0..n).contains(&w) {
        w as u32
    } else {
        i.rem_euclid(n) as u32
    }
}

/// Cellular noise with `cells` x `cells` jittered points over the unit
/// torus: distances (in cells) to the nearest and second nearest point, and
/// the nearest point's hash.
fn worley(u: f32, v: f32, cells: u32, seed: u32) -> (f32, f32, u32) {
    let (x, y) = (u * cells as f32, v * cells as f32);
    let (cx, cy) = (x.floor(), y.floor());
    let (fx, fy) = (x - cx, y - cy);
    let (cx, cy) = (cx as i64, cy as i64);
    let (mut f1, mut f2, mut id) = (f32::MAX, f32::MAX, 0);
    for dy in -1..=1i64 {
        for dx in -1..=1i64 {
            let (wx, wy) = (wrap(cx + dx, cells), wrap(cy + dy, cells));
            let h = hash(wx, wy, seed);
            let px = dx as f32 + unit(h) - fx;
            let py = dy as f32 + unit(hash(h, 0x9e37_79b9, seed)) - fy;
            let d = px * px + py * py;
            if d < f1 {
                (f2, f1, id) = (f1, d, h);
            } else if d < f2 {
                f2 = d;
            }
        }
    }
    (f1.sqrt(), f2.sqrt(), id)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::materials::tests::temp_dir;
    use crate::effects::materials::TextureSet;

    fn all_kinds() -> MaterialSet {
        let mut set = MaterialSet::default();
        set.textures.push(TextureSet { name: "dirt".into(), source: TextureSource::Procedural(ProceduralKind::Dirt) });
        set
    }

    /// Mean absolute difference of channel `c` between neighbouring
    /// texels across the wrap edge, and across the two pairs of lines next
    /// to it, along x and along y.
    fn seam_and_beside(data: &[u8], size: usize, texel: usize, c: usize) -> [(f64, f64); 2] {
        let at = |x: usize, y: usize| data[(y * size + x) * texel + c] as f64;
        [0, 1].map(|axis| {
            let line = |i: usize| {
                let j = (i + 1) % size;
                let d = |k: usize| if axis == 0 { (at(i, k) - at(j, k)).abs() } else { (at(k, i) - at(k, j)).abs() };
                (0..size).map(d).sum::<f64>() / size as f64
            };
            (line(size - 1), line(size - 2).max(line(0)))
        })
    }

    #[test]
    fn procedural_textures_tile() {
        let size = 128;
        // The measure sees a seam: a ramp does not tile.
        let ramp: Vec<u8> = (0..size * size).map(|i| (i % size * 2) as u8).collect();
        let [(seam, beside), _] = seam_and_beside(&ramp, size, 1, 0);
        assert!(seam > 10.0 * beside, "ramp: seam {seam}, beside {beside}");
        let img = DetailImages::build(&all_kinds(), size as u32).unwrap();
        let n = size * size;
        for layer in 0..img.layers as usize {
            let channels: [(&str, &[u8], usize, usize); 4] = [
                ("albedo.g", &img.albedo[0][layer * n * 4..][..n * 4], 4, 1),
                ("normal.x", &img.normal[0][layer * n * 4..][..n * 4], 4, 0),
                ("normal.y", &img.normal[0][layer * n * 4..][..n * 4], 4, 1),
                ("height", &img.height[0][layer * n..][..n], 1, 0),
            ];
            for (name, data, texel, c) in channels {
                for (seam, beside) in seam_and_beside(data, size, texel, c) {
                    // Features (a crack along the edge) make neighbouring
                    // lines differ alike; a seam stands out from both sides.
                    assert!(seam <= 1.5 * beside + 1.0, "layer {layer} {name}: seam {seam:.2}, beside {beside:.2}");
                }
            }
        }
    }

    #[test]
    fn procedural_functions_are_periodic() {
        let noise = Noise { seed: 99, nyquist: 1024 };
        for kind in ProceduralKind::ALL {
            for i in 0..200 {
                let (u, v) = ((i as f32 * 0.618_034).fract(), (i as f32 * 0.414_214).fract());
                let a = sample(kind, u, v, &noise);
                for (du, dv) in [(1.0, 0.0), (0.0, 1.0), (-1.0, 2.0)] {
                    let b = sample(kind, u + du, v + dv, &noise);
                    // Equal up to f32 rounding of the shifted coordinates
                    // (a sharp crack edge can amplify it a little).
                    assert!((a.height - b.height).abs() < 2e-3, "{kind:?} at ({u}, {v}) + ({du}, {dv})");
                    assert!((0..3).all(|c| (a.rgb[c] - b.rgb[c]).abs() < 2e-3), "{kind:?} at ({u}, {v})");
                }
            }
        }
    }

    #[test]
    fn kinds_look_different() {
        let img = DetailImages::build(&all_kinds(), 64).unwrap();
        let n = 64 * 64;
        let mean: Vec<[f64; 3]> = (0..img.layers as usize)
            .map(|l| {
                let a = &img.albedo[0][l * n * 4..][..n * 4];
                std::array::from_fn(|c| a.chunks(4).map(|t| t[c] as f64).sum::<f64>() / n as f64)
            })
            .collect();
        let [grass, rock, snow, scree, dirt] = [0, 1, 2, 3, 4].map(|i| mean[i]);
        assert!(grass[1] > grass[0] + 15.0 && grass[1] > grass[2] + 30.0, "grass {grass:?}");
        assert!(snow.iter().all(|c| *c > 200.0), "snow {snow:?}");
        assert!((rock[0] - rock[2]).abs() < 20.0, "rock is grey: {rock:?}");
        assert!(dirt[0] > dirt[2] + 25.0, "dirt is brown: {dirt:?}");
        assert!(scree[0] > scree[2] + 15.0, "scree is brown-grey: {scree:?}");
        for i in 0..mean.len() {
            for j in 0..i {
                let d: f64 = (0..3).map(|c| (mean[i][c] - mean[j][c]).abs()).sum();
                assert!(d > 12.0, "layers {i} and {j} look alike: {:?} {:?}", mean[i], mean[j]);
            }
        }
        // Snow is smooth: its normals stay closer to +z than rock's.
        let flat =
            |l: usize| img.normal[0][l * n * 4..][..n * 4].chunks(4).map(|t| t[2] as f64).sum::<f64>() / n as f64;
        assert!(flat(2) > flat(1), "snow {} rock {}", flat(2), flat(1));
    }

    #[test]
    fn mip_chain_shapes_and_sizes() {
        let img = DetailImages::build(&MaterialSet::default(), 64).unwrap();
        assert_eq!((img.size, img.mips, img.layers), (64, 7, 4));
        for m in 0..img.mips {
            let s = (64 >> m) as usize;
            assert_eq!(img.albedo[m as usize].len(), 4 * s * s * 4);
            assert_eq!(img.normal[m as usize].len(), 4 * s * s * 4);
            assert_eq!(img.height[m as usize].len(), 4 * s * s);
        }
        assert_eq!(img.mip_size(6), 1);
        assert!(img.albedo.iter().all(|m| m.chunks(4).all(|t| t[3] == 255)));
        // Every mip's normals are unit length (up to 8-bit encoding).
        for m in &img.normal {
            for t in m.chunks(4) {
                let n = decode_normal(t);
                let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                assert!((len - 1.0).abs() < 0.02, "{t:?}");
            }
        }
        img.check().unwrap();
        for bad in [0, 8, 48, 100, 4096] {
            let e = DetailImages::build(&MaterialSet::default(), bad).unwrap_err().to_string();
            assert!(e.contains("power of two") && !e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn builds_are_deterministic_and_hold_the_full_chain() {
        let a = DetailImages::build(&MaterialSet::default(), 256).unwrap();
        let b = DetailImages::build(&MaterialSet::default(), 256).unwrap();
        assert!(a == b, "two builds of the same set differ");
        // 256 down to 1x1 (mip_chain_shapes_and_sizes checks each level;
        // the speed is for a bench to measure, not a test).
        assert_eq!((a.size, a.mips, a.albedo.len()), (256, 9, 9));
    }

    fn write_set(dir: &Path, side: u32) -> MaterialSet {
        image::RgbImage::from_pixel(side, side, image::Rgb([200, 100, 50])).save(dir.join("a.png")).unwrap();
        image::RgbImage::from_pixel(side, side, image::Rgb([128, 128, 255])).save(dir.join("n.png")).unwrap();
        image::GrayImage::from_fn(side, side, |x, _| image::Luma([(x * 255 / (side - 1)) as u8]))
            .save(dir.join("h.png"))
            .unwrap();
        let text = "[textures]\ngranite = { albedo = \"a.png\", normal = \"n.png\", height = \"h.png\" }\n";
        let t: toml::Table = toml::from_str(text).unwrap();
        MaterialSet::from_toml(&t, dir, "materials.toml").unwrap()
    }

    #[test]
    fn png_sets_load_and_resize() {
        let dir = temp_dir("detail-png");
        let set = write_set(&dir, 40);
        let layer = set.layer_of("granite").unwrap() as usize;
        for size in [16, 64] {
            let img = DetailImages::build(&set, size).unwrap();
            assert_eq!(img.layers, 5);
            let n = (size * size) as usize;
            let a = &img.albedo[0][layer * n * 4..][..n * 4];
            assert!(a.chunks(4).all(|t| t == [200, 100, 50, 255]), "{:?}", &a[..8]);
            let nm = &img.normal[0][layer * n * 4..][..n * 4];
            assert!(nm.chunks(4).all(|t| t[2] == 255 && t[3] == DEFAULT_ROUGHNESS), "{:?}", &nm[..8]);
            let h = &img.height[0][layer * n..][..n];
            assert!(h[0] < 20 && h[size as usize - 1] > 235, "height ramp {:?}", &h[..size as usize]);
            let last = img.mips as usize - 1;
            assert_eq!(&img.albedo[last][layer * 4..][..4], [200, 100, 50, 255]);
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bad_pngs_give_one_line_errors() {
        let dir = temp_dir("detail-bad-png");
        let set = write_set(&dir, 32);
        std::fs::write(dir.join("n.png"), b"\x89PNG\r\n\x1a\nthis is not a png").unwrap();
        let e = DetailImages::build(&set, 32).unwrap_err().to_string();
        assert!(e.contains("normal texture") && e.contains("n.png") && !e.contains('\n'), "{e}");
        image::RgbImage::new(32, 16).save(dir.join("n.png")).unwrap();
        let e = DetailImages::build(&set, 32).unwrap_err().to_string();
        assert!(e.contains("n.png") && e.contains("32x16, must be square") && !e.contains('\n'), "{e}");
        write_set(&dir, 32);
        std::fs::remove_file(dir.join("h.png")).unwrap();
        let e = DetailImages::build(&set, 32).unwrap_err().to_string();
        assert!(e.contains("height texture") && e.contains("h.png") && !e.contains('\n'), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn upload_matches_the_cpu_images() {
        let options = crate::gpu::ContextOptions { validation: true, ..Default::default() };
        let ctx = Context::headless(&options).expect("a Vulkan device (run tools/install-deps)");
        let log = ctx.validation_log();
        let img = DetailImages::build(&MaterialSet::default(), 16).unwrap();
        let tex = DetailTextures::with_usage(&ctx, &img, vk::ImageUsageFlags::TRANSFER_SRC).unwrap();
        assert_eq!(tex.albedo.layout(), vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
        assert!(tex.memory_bytes() >= (16 * 16 * 9 * 4) as u64);
        for (image, data, texel) in
            [(&tex.albedo, &img.albedo, 4), (&tex.normal, &img.normal, 4), (&tex.height, &img.height, 1)]
        {
            for (mip, layer) in [(0, 0), (0, 3), (2, 1), (4, 2)] {
                let n = img.layer_bytes(mip, texel);
                let got = ctx.read_image(image, mip, layer, texel as u64).unwrap();
                assert_eq!(
                    got,
                    data[mip as usize][layer as usize * n..][..n],
                    "{} mip {mip} layer {layer}",
                    image.name
                );
            }
        }
        let mut broken = img.clone();
        broken.height[3].pop();
        assert!(matches!(DetailTextures::new(&ctx, &broken), Err(Error::BadInput(_))));
        drop(tex);
        ctx.wait_idle().unwrap();
        assert_eq!(ctx.live_objects().total(), 0);
        drop(ctx);
        let bad = log.unexpected(&[]);
        assert!(bad.is_empty(), "validation: {bad:#?}");
    }
}
