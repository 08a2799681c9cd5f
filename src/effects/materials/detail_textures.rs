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

use super::procedural::procedural;
use crate::effects::materials::{MaterialSet, TextureSource, MAX_TEXTURE_SETS};
use crate::error::{Error, Result};
use crate::gpu::{vk, Buffer, BufferDesc, Context, Image, ImageDesc, MemoryLocation};
use image::imageops::FilterType;
use rayon::prelude::*;
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
pub(super) struct Layer {
    pub(super) albedo: Vec<u8>,
    pub(super) normal: Vec<u8>,
    pub(super) height: Vec<u8>,
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

pub(super) fn encode_normal(n: [f32; 3], roughness: u8) -> [u8; 4] {
    let e = |c: f32| (c * 127.5 + 127.5).round().clamp(0.0, 255.0) as u8;
    [e(n[0]), e(n[1]), e(n[2]), roughness]
}

/// Unit length; a zero vector (opposite normals averaged) becomes +z.
pub(super) fn normalize(n: [f32; 3]) -> [f32; 3] {
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if len > 1e-6 {
        [n[0] / len, n[1] / len, n[2] / len]
    } else {
        [0.0, 0.0, 1.0]
    }
}

// ---- procedural ----

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::materials::procedural::*;
    use crate::effects::materials::tests::temp_dir;
    use crate::effects::materials::ProceduralKind;
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
