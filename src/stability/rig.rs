//! The small world and frame loop the image cases share: a 2 km procedural
//! world at 2 m spacing (4 LODs) rendered offscreen exactly as `vista
//! render` does, with a magenta background so a missing pixel shows.

use crate::error::Result;
use crate::gpu::Context;
use crate::render::offscreen::{Capture, Offscreen};
use crate::render::{Camera, RendererOptions, TerrainRenderer, View, DEFAULT_NEAR_M};
use crate::terrain::TerrainOptions;
use crate::world::{HeightSource, Hole, ProceduralSource, WorldDesc};
use std::sync::Arc;
use std::time::Duration;

pub const MAGENTA: [f32; 4] = [1.0, 0.0, 1.0, 1.0];

/// Streaming must come to rest within this; a small world settles in a few
/// seconds, so reaching it means something hangs.
const SETTLE_TIMEOUT: Duration = Duration::from_secs(300);

pub fn small_world() -> WorldDesc {
    WorldDesc {
        extent_m: [2048.0, 2048.0],
        height_range_m: [0.0, 400.0],
        spacing_m: 2.0,
        lod_count: 4,
        ..WorldDesc::default()
    }
}

pub struct Rig {
    pub renderer: TerrainRenderer,
    pub off: Offscreen,
    pub world: WorldDesc,
    pub source: Arc<dyn HeightSource>,
}

impl Rig {
    /// The small world with the scene's default effects; `slots` resident
    /// nodes (few make streaming churn under motion).
    pub fn new(ctx: &Context, size: [u32; 2], slots: u32, options: RendererOptions, holes: Vec<Hole>) -> Result<Rig> {
        let world = small_world();
        // Terraced: risers past 60 degrees are the hard case these checks
        // want (the eroded default is gentler).
        let source = ProceduralSource::new(7, world.extent_m, world.height_range_m)?.with_terraces(true);
        let source: Arc<dyn HeightSource> = Arc::new(source);
        let options = RendererOptions {
            terrain: TerrainOptions { slots, loader_threads: 2, ..TerrainOptions::default() },
            ..options
        };
        let renderer = TerrainRenderer::new(ctx, &world, source.clone(), holes, &options)?;
        let off = Offscreen::new(ctx, size, 2, MAGENTA)?;
        Ok(Rig { renderer, off, world, source })
    }

    /// A camera `up` metres above the ground at (x, y), world-relative.
    pub fn camera(&self, x: f64, y: f64, up: f64, yaw_deg: f64, pitch_deg: f64) -> Camera {
        let ground = f64::from(self.source.sample(x, y));
        Camera { position_m: [x, y, ground + up], yaw_deg, pitch_deg }
    }

    pub fn view(&self, camera: Camera) -> View {
        View { camera, fov_y_deg: 60.0, size: self.off.size(), target_error_px: 1.0, near_m: DEFAULT_NEAR_M }
    }

    /// Streams `view` until settled and reads the frame back.
    pub fn settled_shot(&mut self, ctx: &Context, view: &View) -> Result<Capture> {
        let s = self.off.settle(ctx, &mut self.renderer, view, SETTLE_TIMEOUT)?;
        if !s.settled {
            return Err(crate::Error::BadInput(format!("streaming did not settle in {} frames", s.frames)));
        }
        self.off.capture(ctx)
    }

    /// One frame (streaming goes on in the background), read back.
    pub fn shot(&mut self, ctx: &Context, view: &View) -> Result<Capture> {
        self.off.frame(ctx, &mut self.renderer, view)?;
        self.off.capture(ctx)
    }
}

/// A camera path over the small world for `frames` frames: a low pass
/// north-east that climbs to 300 m and comes down again while turning, so
/// LODs change everywhere and streaming crosses node boundaries; always
/// looking 60 degrees down (the top row 30 degrees), so every pixel sees
/// terrain well inside the world.
pub fn fly_through(rig: &Rig, frame: u32, frames: u32) -> Camera {
    let t = f64::from(frame) / f64::from(frames.max(2) - 1);
    let x = 300.0 + 1100.0 * t;
    let y = 300.0 + 1000.0 * t;
    let up = 20.0 + 280.0 * (std::f64::consts::PI * t).sin();
    rig.camera(x, y, up, 30.0 + 60.0 * t, -60.0)
}

/// Every effect a renderer builds over the small world: two assets and a
/// decal at the fly-through's start, where its first cameras look.
pub fn every_effect() -> RendererOptions {
    use crate::effects::assets::{Asset, AssetKind};
    use crate::effects::virtual_texture::decals::{DecalSet, DecalTexture};
    let checker = image::RgbaImage::from_fn(64, 64, |x, y| {
        let on = (x / 8 + y / 8) % 2 == 0;
        image::Rgba(if on { [220, 200, 60, 255] } else { [40, 40, 40, 200] })
    });
    let decals = DecalSet {
        textures: vec![DecalTexture::from_rgba("checker", &checker)].into(),
        decals: vec![script_decal(0.0)],
    };
    let asset = |kind, at_m| Asset { kind, at_m, scale: 1.0, yaw_deg: 0.0 };
    RendererOptions {
        effects: crate::render::Effects::all(),
        decals,
        assets: vec![asset(AssetKind::Rock, [306.0, 318.0]), asset(AssetKind::Trunk, [300.0, 322.0])],
        ..RendererOptions::default()
    }
}

/// The script's decal, turned by `rotation_deg` (the edit).
pub fn script_decal(rotation_deg: f64) -> crate::effects::virtual_texture::decals::Decal {
    use crate::effects::virtual_texture::decals::{Decal, DecalShape};
    let shape = DecalShape::Quad {
        center_m: glam::DVec2::new(306.0, 312.0),
        size_m: glam::DVec2::new(12.0, 8.0),
        rotation_deg,
    };
    Decal { shape, texture: 0, opacity: 1.0, roughness: Some(0.5), displace_m: None }
}

/// Pixels whose colour or depth bits differ.
pub fn differing_pixels(a: &Capture, b: &Capture) -> usize {
    let colour = a.rgba.chunks(4).zip(b.rgba.chunks(4));
    colour
        .zip(a.depth.iter().zip(&b.depth))
        .filter(|((ca, cb), (da, db))| ca != cb || da.to_bits() != db.to_bits())
        .count()
}
