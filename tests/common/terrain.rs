//! Analytic height sources with closed-form ray intersections, and a rig
//! that renders them through `TerrainRenderer` + `Offscreen` exactly as
//! `vista render` does.

use std::sync::Arc;
use std::time::Duration;
use vista::gpu::Context;
use vista::passes::cull_patches::CullStages;
use vista::render::offscreen::{Capture, Offscreen, OffscreenDesc};
use vista::render::{Camera, RendererOptions, TerrainRenderer, View, DEFAULT_NEAR_M};
use vista::terrain::TerrainOptions;
use vista::world::{GridSource, HeightSource, Hole, WorldDesc};

/// Background of the test images: no lit terrain colour is magenta.
pub const MAGENTA: [f32; 4] = [1.0, 0.0, 1.0, 1.0];
pub const MAGENTA_RGBA: [u8; 4] = [255, 0, 255, 255];

#[derive(Clone, Copy, Debug)]
pub enum Surface {
    Plane(f64),
    Tilted {
        z0: f64,
        gx: f64,
        gy: f64,
    },
    /// z0 + a * |p - c|^2
    Paraboloid {
        z0: f64,
        a: f64,
        c: [f64; 2],
    },
    /// A plane at z0 with a cone of height h and radius r at c.
    Bump {
        z0: f64,
        c: [f64; 2],
        r: f64,
        h: f64,
    },
    /// Rolling hills with steep flanks (both ridge sides face the camera somewhere).
    Hills,
    /// A V-shaped gorge with near-vertical walls along x = c.
    Gorge {
        c: f64,
        slope: f64,
    },
    /// A sphere's cap rising from a plane at z0: the sphere (centre c,
    /// radius r) has its centre below z0, so the rim slope stays finite.
    SphereCap {
        z0: f64,
        c: [f64; 3],
        r: f64,
    },
    /// Flat terraces `width` m wide with vertical steps of `step` m, the
    /// step lines at 30 degrees to the y axis: no sample grid lines up with
    /// them.
    Terraces {
        z0: f64,
        step: f64,
        width: f64,
    },
    /// A sawtooth ridge: ramps rising `amp` m over `period` m along y, each
    /// ending in a vertical drop, crossed by a gentle wave along x.
    Sawtooth {
        z0: f64,
        amp: f64,
        period: f64,
    },
}

impl Surface {
    pub fn height(&self, x: f64, y: f64) -> f64 {
        match *self {
            Surface::Plane(z) => z,
            Surface::Tilted { z0, gx, gy } => z0 + gx * x + gy * y,
            Surface::Paraboloid { z0, a, c } => z0 + a * ((x - c[0]).powi(2) + (y - c[1]).powi(2)),
            Surface::Bump { z0, c, r, h } => z0 + h * (1.0 - (x - c[0]).hypot(y - c[1]) / r).max(0.0),
            Surface::Hills => 300.0 + 120.0 * (x / 97.0).sin() * (y / 131.0).cos() + 40.0 * (x / 23.0 + y / 31.0).sin(),
            Surface::Gorge { c, slope } => 500.0 + slope * (x - c).abs(),
            Surface::SphereCap { z0, c, r } => {
                let d2 = (x - c[0]).powi(2) + (y - c[1]).powi(2);
                if d2 < r * r {
                    z0.max(c[2] + (r * r - d2).sqrt())
                } else {
                    z0
                }
            }
            Surface::Terraces { z0, step, width } => {
                let (s, c) = 30f64.to_radians().sin_cos();
                z0 + step * ((x * c + y * s) / width).floor()
            }
            Surface::Sawtooth { z0, amp, period } => {
                z0 + amp * (y / period).rem_euclid(1.0) + 0.1 * amp * (x / (0.7 * period)).sin()
            }
        }
    }

    /// Distance along the unit ray `d` from `o` to the surface (None: no hit
    /// ahead), closed form for the planes and the paraboloid.
    pub fn intersect(&self, o: [f64; 3], d: [f64; 3]) -> Option<f64> {
        let t = match *self {
            Surface::Plane(z) => (z - o[2]) / d[2],
            Surface::Tilted { z0, gx, gy } => (z0 + gx * o[0] + gy * o[1] - o[2]) / (d[2] - gx * d[0] - gy * d[1]),
            Surface::Paraboloid { z0, a, c } => {
                let (px, py) = (o[0] - c[0], o[1] - c[1]);
                let qa = a * (d[0] * d[0] + d[1] * d[1]);
                let qb = 2.0 * a * (px * d[0] + py * d[1]) - d[2];
                let qc = a * (px * px + py * py) + z0 - o[2];
                if qa.abs() < 1e-15 {
                    -qc / qb
                } else {
                    let disc = qb * qb - 4.0 * qa * qc;
                    if disc < 0.0 {
                        return None;
                    }
                    let q = -0.5 * (qb + qb.signum() * disc.sqrt());
                    let (t0, t1) = (q / qa, qc / q);
                    let (lo, hi) = (t0.min(t1), t0.max(t1));
                    if lo > 0.0 {
                        lo
                    } else {
                        hi
                    }
                }
            }
            Surface::SphereCap { z0, c, r } => {
                // The sphere's first entry above the plane, else the plane
                // outside the cap's rim.
                let oc = [o[0] - c[0], o[1] - c[1], o[2] - c[2]];
                let b = oc[0] * d[0] + oc[1] * d[1] + oc[2] * d[2];
                let disc = b * b - (oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - r * r);
                let sphere = (disc >= 0.0).then(|| -b - disc.sqrt()).filter(|&t| t > 0.0 && o[2] + t * d[2] >= z0);
                let rim2 = r * r - (z0 - c[2]).powi(2);
                let plane = Some((z0 - o[2]) / d[2]).filter(|&t| {
                    let (x, y) = (o[0] + t * d[0] - c[0], o[1] + t * d[1] - c[1]);
                    t > 0.0 && x * x + y * y >= rim2
                });
                match (sphere, plane) {
                    (Some(a), Some(b)) => a.min(b),
                    (a, b) => a.or(b)?,
                }
            }
            _ => panic!("no closed-form intersection for {self:?}"),
        };
        (t.is_finite() && t > 0.0).then_some(t)
    }

    /// Height gradient (dz/dx, dz/dy).
    pub fn gradient(&self, x: f64, y: f64) -> [f64; 2] {
        match *self {
            Surface::Plane(_) => [0.0, 0.0],
            Surface::Tilted { gx, gy, .. } => [gx, gy],
            Surface::Paraboloid { a, c, .. } => [2.0 * a * (x - c[0]), 2.0 * a * (y - c[1])],
            _ => panic!("no gradient for {self:?}"),
        }
    }
}

impl HeightSource for Surface {
    fn sample(&self, x: f64, y: f64) -> f32 {
        self.height(x, y) as f32
    }
    fn id_hash(&self) -> u64 {
        let s = format!("{self:?}");
        s.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3))
    }
}

pub fn view(position: [f64; 3], yaw: f64, pitch: f64, size: [u32; 2], target_error_px: f32) -> View {
    View {
        camera: Camera { position_m: position, yaw_deg: yaw, pitch_deg: pitch },
        fov_y_deg: 60.0,
        size,
        target_error_px,
        near_m: DEFAULT_NEAR_M,
    }
}

/// The adversarial surfaces' world: 2 km at 1 m spacing over 0..600 m, 5 LODs.
pub fn adversarial_world() -> WorldDesc {
    WorldDesc {
        extent_m: [2048.0, 2048.0],
        height_range_m: [0.0, 600.0],
        spacing_m: 1.0,
        lod_count: 5,
        ..WorldDesc::default()
    }
}

/// Vertical terrace steps and a sawtooth ridge.
pub const ADVERSARIAL: [Surface; 2] = [
    Surface::Terraces { z0: 100.0, step: 6.0, width: 40.0 },
    Surface::Sawtooth { z0: 150.0, amp: 30.0, period: 120.0 },
];

/// Views (position, yaw, pitch) over `surface`: 60, 250 and 15 m above it.
pub fn adversarial_views(surface: Surface) -> Vec<([f64; 3], f64, f64)> {
    let at = |x: f64, y: f64, up: f64| [x, y, surface.height(x, y) + up];
    vec![
        (at(1024.0, 300.0, 60.0), 0.0, -12.0),
        (at(700.0, 700.0, 250.0), 45.0, -35.0),
        (at(1500.0, 1200.0, 15.0), 200.0, -8.0),
    ]
}

/// The GPU tests' small world: 1024 m at 1 m spacing over 100..500 m with
/// 4 LODs. Its one 1024 m root tiles it exactly (so without hole regions
/// the hole path has nothing to cut), and every node a view wants stays
/// resident in the default slots (so two renderers can share a resident
/// set).
pub fn small_world() -> WorldDesc {
    WorldDesc {
        extent_m: [1024.0, 1024.0],
        height_range_m: [100.0, 500.0],
        spacing_m: 1.0,
        lod_count: 4,
        ..WorldDesc::default()
    }
}

/// The sun shadow tests' world: 512 m at 1 m spacing, 3 LODs, heights
/// 100..140 m (a 40 m shadow at 5 degrees stays inside).
pub fn shadow_world() -> WorldDesc {
    WorldDesc {
        extent_m: [512.0, 512.0],
        height_range_m: [100.0, 140.0],
        spacing_m: 1.0,
        lod_count: 3,
        ..WorldDesc::default()
    }
}

/// `surface` sampled as the GPU samples LOD 0 of [`shadow_world`]:
/// bilinear between 1 m posts; None off the world.
pub fn shadow_world_height(surface: Surface, p: glam::DVec2) -> Option<f64> {
    if p.x < 0.0 || p.y < 0.0 || p.x >= 512.0 || p.y >= 512.0 {
        return None;
    }
    let (i, f) = (p.floor(), p - p.floor());
    let z = |dx: f64, dy: f64| surface.height(i.x + dx, i.y + dy);
    let a = z(0.0, 0.0) * (1.0 - f.x) + z(1.0, 0.0) * f.x;
    let b = z(0.0, 1.0) * (1.0 - f.x) + z(1.0, 1.0) * f.x;
    Some(a * (1.0 - f.y) + b * f.y)
}

pub struct Rig {
    pub renderer: TerrainRenderer,
    pub off: Offscreen,
    pub world: WorldDesc,
}

impl Rig {
    /// `rings`: keep the families around the camera too; off, only the LOD
    /// criterion decides what is resident (an exact, view-driven set).
    pub fn new(
        ctx: &Context,
        world: WorldDesc,
        surface: Surface,
        holes: Vec<Hole>,
        size: [u32; 2],
        rings: bool,
    ) -> Rig {
        Rig::with_options(ctx, world, surface, holes, size, rings, RendererOptions::default())
    }

    /// As `new`, with the effects (and test overrides) of `options`; its
    /// terrain options are replaced by the rig's.
    pub fn with_options(
        ctx: &Context,
        world: WorldDesc,
        surface: Surface,
        holes: Vec<Hole>,
        size: [u32; 2],
        rings: bool,
        options: RendererOptions,
    ) -> Rig {
        Rig::with_source(ctx, world, Arc::new(surface), holes, size, rings, options)
    }

    /// As `with_options`, for any height source; `options.terrain.slots`
    /// is kept when it is not the default, and its error tree if given.
    pub fn with_source(
        ctx: &Context,
        world: WorldDesc,
        source: Arc<dyn HeightSource>,
        holes: Vec<Hole>,
        size: [u32; 2],
        rings: bool,
        options: RendererOptions,
    ) -> Rig {
        let slots = match options.terrain.slots {
            s if s == TerrainOptions::default().slots => 400,
            s => s,
        };
        let options = RendererOptions {
            terrain: TerrainOptions {
                slots,
                loader_threads: 2,
                ring_prefetch: rings,
                errors: options.terrain.errors.clone(),
                ..TerrainOptions::default()
            },
            ..options
        };
        let renderer = TerrainRenderer::new(ctx, &world, source, holes, &options).expect("renderer");
        let desc = OffscreenDesc {
            depth_format: options.depth.format,
            output: options.output.clone(),
            ..OffscreenDesc::new(size, MAGENTA)
        };
        let off = Offscreen::with_desc(ctx, &desc).expect("targets");
        Rig { renderer, off, world }
    }

    /// Streams until settled, renders `view` with `stages`, reads it back.
    pub fn shot(&mut self, ctx: &Context, view: &View, stages: CullStages) -> Capture {
        self.renderer.stages = stages;
        let s = self.off.settle(ctx, &mut self.renderer, view, Duration::from_secs(300)).expect("frames");
        assert!(s.settled, "streaming did not settle");
        self.off.capture(ctx).expect("capture")
    }

    /// One more frame of the same view (same resident set) with `stages`.
    pub fn again(&mut self, ctx: &Context, view: &View, stages: CullStages) -> Capture {
        self.renderer.stages = stages;
        self.off.frame(ctx, &mut self.renderer, view).expect("frame");
        self.off.capture(ctx).expect("capture")
    }
}

/// 1 km at 1 m samples, 4 LODs, from a 129 x 129 grid of posts with
/// hashed heights (steep random relief at every scale the LODs see).
pub fn rough_posts() -> (WorldDesc, Arc<dyn HeightSource>) {
    let n = 129usize;
    let heights: Vec<f32> = (0..n * n)
        .map(|i| {
            let (x, y) = ((i % n) as f32, (i / n) as f32);
            let h = ((i as u64).wrapping_mul(2654435761) % 1000) as f32 / 1000.0;
            180.0 + 40.0 * (x / 9.0).sin() * (y / 13.0).cos() + 25.0 * h
        })
        .collect();
    let world = WorldDesc {
        extent_m: [1024.0, 1024.0],
        height_range_m: [100.0, 300.0],
        spacing_m: 1.0,
        lod_count: 4,
        ..WorldDesc::default()
    };
    (world, Arc::new(GridSource::new(n, n, heights, [1024.0, 1024.0])))
}
