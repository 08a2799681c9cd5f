//! What `vista render --out` writes, by output: the display image (`lit`),
//! the linear radiance (`lit`, `hdr`) or what an engine's G-buffer
//! received (`gbuffer`: base colour, normal, roughness), and always the
//! depth, the classification and the JSON reports, as one set of files.

use anyhow::Result;
use glam::Vec3;
use image::ExtendedColorType;
use std::path::Path;
use vista::frame::FrameTimings;
use vista::output::{encode_png, FileSet, OutputWriter};
use vista::render::offscreen::Capture;
use vista::render::stats::RenderStats;
use vista::render::View;
use vista::targets::gbuffer::{classification_colour, GBufferCapture};
use vista::targets::gbuffer_layout::{texel_bytes, DecodedSurface};
use vista::targets::{GbufferLayout, Output};

/// The files of each output, for messages.
pub fn files(output: &Output) -> &'static str {
    match output {
        Output::Lit { .. } => "image.png, lit.exr, depth.exr, classification.png and the JSON reports",
        Output::Hdr { .. } => "lit.exr, depth.exr, classification.png and the JSON reports",
        Output::Gbuffer(_) => {
            "albedo.png, normal.exr, roughness.png, depth.exr, classification.png and the JSON reports"
        }
    }
}

/// What `--out` receives.
pub struct Outputs<'a> {
    pub frames: &'a [FrameTimings],
    pub warmup: usize,
    pub capture: &'a Capture,
    pub gbuffer: &'a GBufferCapture,
    pub stats: &'a RenderStats,
    pub output: &'a Output,
}

impl Outputs<'_> {
    /// All files or none: each is written beside its final name and the
    /// set renamed into place once every one was written, so a full disk
    /// leaves the previous render's files (or no folder) as they were.
    /// timings.json holds the timed frames (what the printed table
    /// summarises); trace.json every frame, warm-up included, for looking
    /// at first-use costs.
    pub fn write(&self, dir: &Path, view: &View, report_json: &str) -> Result<()> {
        let mut set = FileSet::new(dir);
        set.add("timings.json", vista::frame::profiler::to_json(&self.frames[self.warmup..]).as_bytes())?;
        set.add("trace.json", vista::frame::profiler::to_chrome_trace(self.frames).as_bytes())?;
        set.add("stats.json", serde_json::to_string_pretty(self.stats)?.as_bytes())?;
        set.add("report.json", report_json.as_bytes())?;
        let [w, h] = self.capture.size;
        let size = [w as usize, h as usize];
        match self.output {
            Output::Lit { .. } => {
                set.add_with("image.png", |f| encode_png(f, &self.capture.rgba, [w, h], ExtendedColorType::Rgba8))?;
                set.add_with("lit.exr", |f| write_rgb_exr(f, size, "lit", &self.gbuffer.hdr))?;
            }
            Output::Hdr { .. } => set.add_with("lit.exr", |f| write_rgb_exr(f, size, "lit", &self.capture.hdr))?,
            Output::Gbuffer(layout) => {
                // Where vista drew nothing (depth 0) the images hold the clear.
                let background = DecodedSurface { base: Vec3::ZERO, normal: Vec3::ZERO, roughness: 0.0, material: 0 };
                let mut s = decode(layout, self.capture);
                s.iter_mut().zip(&self.capture.depth).filter(|(_, d)| **d == 0.0).for_each(|(p, _)| *p = background);
                let albedo: Vec<u8> = s.iter().flat_map(|p| p.base.to_array().map(srgb8)).collect();
                set.add_with("albedo.png", |f| encode_png(f, &albedo, [w, h], ExtendedColorType::Rgb8))?;
                let normal: Vec<[f32; 4]> = s.iter().map(|p| p.normal.extend(0.0).to_array()).collect();
                set.add_with("normal.exr", |f| write_normal_exr(f, size, &normal))?;
                let rough: Vec<u8> = s.iter().map(|p| (p.roughness.clamp(0.0, 1.0) * 255.0).round() as u8).collect();
                set.add_with("roughness.png", |f| encode_png(f, &rough, [w, h], ExtendedColorType::L8))?;
            }
        }
        let depth = self.capture.linear_depth(view.near_m);
        set.add_with("depth.exr", |f| write_depth_exr(f, size, depth))?;
        let class: Vec<u8> = self.gbuffer.classification.iter().flat_map(|&b| classification_colour(b)).collect();
        set.add_with("classification.png", |f| encode_png(f, &class, [w, h], ExtendedColorType::Rgb8))?;
        set.commit()?;
        println!("wrote {} into {}", files(self.output), dir.display());
        Ok(())
    }
}

/// Each pixel of the engine's images as the layout says to read it.
fn decode(layout: &GbufferLayout, capture: &Capture) -> Vec<DecodedSurface> {
    let n = capture.size[0] as usize * capture.size[1] as usize;
    let sizes: Vec<usize> = layout.attachments.iter().map(|a| texel_bytes(a.format)).collect();
    (0..n)
        .map(|i| {
            let texels: Vec<&[u8]> =
                capture.gbuffer.iter().zip(&sizes).map(|(bytes, &b)| &bytes[i * b..(i + 1) * b]).collect();
            layout.decode(&texels)
        })
        .collect()
}

fn srgb8(linear: f32) -> u8 {
    (vista::reference::tonemap::srgb_encode(f64::from(linear.clamp(0.0, 1.0))) * 255.0).round() as u8
}

fn exr_io(e: exr::error::Error) -> std::io::Error {
    match e {
        exr::error::Error::Io(io) => io,
        other => std::io::Error::other(other),
    }
}

fn write_layer(
    w: &mut OutputWriter,
    size: [usize; 2],
    name: &str,
    channels: Vec<exr::prelude::AnyChannel<exr::prelude::FlatSamples>>,
) -> std::io::Result<()> {
    use exr::prelude::*;
    let layer = Layer::new(
        (size[0], size[1]),
        LayerAttributes::named(name),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(SmallVec::from_vec(channels)),
    );
    Image::from_layer(layer).write().non_parallel().to_buffered(w).map_err(exr_io)
}

/// Linear RGB radiance before display encoding (float16 channels R, G,
/// B), row 0 at the top.
fn write_rgb_exr(w: &mut OutputWriter, size: [usize; 2], name: &str, rgb: &[[f32; 4]]) -> std::io::Result<()> {
    use exr::prelude::*;
    let channel = |name: &str, i: usize| {
        AnyChannel::new(name, FlatSamples::F16(rgb.iter().map(|p| f16::from_f32(p[i])).collect()))
    };
    write_layer(w, size, name, vec![channel("R", 0), channel("G", 1), channel("B", 2)])
}

/// The world-space unit shading normal (z up) an engine's G-buffer holds,
/// float32 channels X, Y, Z (0 where no terrain).
fn write_normal_exr(w: &mut OutputWriter, size: [usize; 2], n: &[[f32; 4]]) -> std::io::Result<()> {
    use exr::prelude::*;
    let channel = |name: &str, i: usize| AnyChannel::new(name, FlatSamples::F32(n.iter().map(|p| p[i]).collect()));
    write_layer(w, size, "normal", vec![channel("X", 0), channel("Y", 1), channel("Z", 2)])
}

/// One float32 channel `Z`: linear view depth in metres along the camera's
/// forward axis, 0 where no terrain; row 0 is the top of the image.
fn write_depth_exr(w: &mut OutputWriter, size: [usize; 2], depth: Vec<f32>) -> std::io::Result<()> {
    use exr::prelude::*;
    write_layer(w, size, "depth", vec![AnyChannel::new("Z", FlatSamples::F32(depth))])
}
