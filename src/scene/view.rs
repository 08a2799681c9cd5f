//! The view of one frame: camera (world metres in f64, compass yaw, pitch
//! above the horizon), vertical field of view, target size and the accuracy
//! knob; and its GPU form, made relative to the camera in f64 before it is
//! rounded to f32.
//!
//! Conventions (ARCHITECTURE.md): x east, y north, z up; yaw 0 looks toward
//! +y, 90 toward +x; pitch -90 looks straight down; image row 0 is the top.
//! Depth is reversed-Z with an infinite far plane: a point at view depth
//! `d` (metres along the forward axis) stores `near_m / d`.

use crate::error::{Error, Result};
use crate::scene::shading::ShadeRules;
use crate::scene::tonemap::Tonemap;
use crate::terrain::selection::{TraverseCamera, TraverseParams};
use crate::world::{HeightSource, WorldDesc};
use glam::{DMat4, DVec3, DVec4};

/// Near plane distance (m): reversed-Z float depth keeps precision far away,
/// so it can be small enough for a camera standing on the ground.
pub const DEFAULT_NEAR_M: f64 = 0.1;

#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Camera {
    pub position_m: [f64; 3],
    /// Compass heading in degrees: 0 looks toward +y (north), 90 toward +x.
    pub yaw_deg: f64,
    /// Degrees above the horizon: -90 looks straight down.
    pub pitch_deg: f64,
}

impl Camera {
    /// Unit forward, right and up vectors (world axes).
    pub fn basis(&self) -> [DVec3; 3] {
        let (sy, cy) = self.yaw_deg.to_radians().sin_cos();
        let (sp, cp) = self.pitch_deg.to_radians().sin_cos();
        let forward = DVec3::new(sy * cp, cy * cp, sp);
        let right = DVec3::new(cy, -sy, 0.0);
        [forward, right, right.cross(forward)]
    }
}

/// `x,y,z,yaw,pitch` in whole metres and degrees: the form `--camera`
/// takes, so a printed view can be rendered again.
impl std::fmt::Display for Camera {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [x, y, z] = self.position_m;
        write!(f, "{x:.0},{y:.0},{z:.0},{:.0},{:.0}", self.yaw_deg, self.pitch_deg)
    }
}

/// Everything that decides one frame's picture.
#[derive(Debug, Clone, PartialEq)]
pub struct View {
    pub camera: Camera,
    /// Vertical field of view in degrees.
    pub fov_y_deg: f64,
    /// Target width and height in pixels.
    pub size: [u32; 2],
    /// Largest accepted projected vertical error in pixels (the accuracy knob).
    pub target_error_px: f32,
    pub near_m: f64,
}

/// The fields of view the projection is exact for, degrees
/// (`stability::fov`, case 11, measures it). At 1e-7 degrees the default
/// world's ground view still matched 60 degrees' axis; at 3e-8 half the
/// image showed another surface (the f32 focal length 1 / tan(fov / 2) =
/// 3.8e9 no longer separates neighbouring rays): 1e-6 keeps a factor of
/// 10. Above 179.9 the image plane's half-height (tan(fov / 2) > 1146)
/// leaves each pixel a cone wider than most worlds.
pub const MIN_FOV_DEG: f64 = 1e-6;
pub const MAX_FOV_DEG: f64 = 179.9;

impl View {
    /// Checks what a user can get wrong; every renderer entry point calls it.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::BadInput(m));
        let c = &self.camera;
        if !c.position_m.iter().all(|v| v.is_finite()) {
            return bad(format!("camera position {:?} is not finite", c.position_m));
        }
        if !c.yaw_deg.is_finite() || !(-90.0..=90.0).contains(&c.pitch_deg) {
            return bad(format!(
                "camera yaw {} / pitch {} must be finite, pitch within -90..=90",
                c.yaw_deg, c.pitch_deg
            ));
        }
        if !(MIN_FOV_DEG..=MAX_FOV_DEG).contains(&self.fov_y_deg) {
            return bad(format!(
                "field of view {} degrees is outside {MIN_FOV_DEG:e}..={MAX_FOV_DEG}, where the projection is exact \
                 (`vista stability --cases 11`)",
                if self.fov_y_deg.abs() < 1e-3 { format!("{:e}", self.fov_y_deg) } else { self.fov_y_deg.to_string() }
            ));
        }
        if self.size[0] == 0 || self.size[1] == 0 {
            return bad(format!("target size {}x{} is empty", self.size[0], self.size[1]));
        }
        if !(self.target_error_px.is_finite() && self.target_error_px > 0.0) {
            return bad(format!("target error {} px must be a positive number", self.target_error_px));
        }
        if !(self.near_m.is_finite() && self.near_m > 0.0) {
            return bad(format!("near plane {} m must be positive", self.near_m));
        }
        Ok(())
    }

    /// This view with the camera moved from the caller's coordinates into
    /// the world's own (south-west corner at 0, 0), where the world's
    /// south-west corner lies at `origin_m`. In f64, so a camera at UTM
    /// coordinates (millions of metres) loses nothing the renderer needs:
    /// f64 keeps 1e7 m to 2 nm.
    pub fn relative_to(&self, origin_m: [f64; 2]) -> View {
        let [x, y, z] = self.camera.position_m;
        let camera = Camera { position_m: [x - origin_m[0], y - origin_m[1], z], ..self.camera };
        View { camera, ..self.clone() }
    }

    /// Focal length in units of half the target height: 1 / tan(fov / 2).
    pub fn focal(&self) -> f64 {
        1.0 / (self.fov_y_deg.to_radians() / 2.0).tan()
    }

    /// Camera-relative metres -> clip space (reversed-Z, infinite far).
    /// Rows: x = right * f / aspect, y = -up * f (row 0 is the top),
    /// z = near (constant), w = depth along forward.
    pub fn view_proj(&self) -> DMat4 {
        let [forward, right, up] = self.camera.basis();
        let f = self.focal();
        let aspect = f64::from(self.size[0]) / f64::from(self.size[1]);
        let r0 = (right * (f / aspect)).extend(0.0);
        let r1 = (-up * f).extend(0.0);
        let r2 = DVec4::new(0.0, 0.0, 0.0, self.near_m);
        let r3 = forward.extend(0.0);
        DMat4::from_cols(r0, r1, r2, r3).transpose()
    }

    /// Inward planes (xyz unit normal, w) of the left, right, top, bottom and
    /// near sides, camera-relative; the far plane is at infinity.
    pub fn frustum_planes(&self) -> [DVec4; 5] {
        let m = self.view_proj();
        let row = |i: usize| m.row(i);
        let planes = [row(3) + row(0), row(3) - row(0), row(3) + row(1), row(3) - row(1), row(3) - row(2)];
        planes.map(|p| p / p.truncate().length())
    }

    /// Pixel position (x right, y down, pixel centres at +0.5) and view
    /// depth of a world point, or None behind the near plane.
    pub fn project(&self, world_m: [f64; 3]) -> Option<([f64; 2], f64)> {
        let rel = DVec3::from(world_m) - DVec3::from(self.camera.position_m);
        let c = self.view_proj() * rel.extend(1.0);
        if c.w < self.near_m {
            return None;
        }
        let ndc = [c.x / c.w, c.y / c.w];
        let px = [(ndc[0] + 1.0) * 0.5 * f64::from(self.size[0]), (ndc[1] + 1.0) * 0.5 * f64::from(self.size[1])];
        Some((px, c.w))
    }

    /// The world-space ray through pixel (x, y) (pixel centre at +0.5):
    /// unit direction from the camera.
    pub fn ray(&self, px: [f64; 2]) -> DVec3 {
        let [forward, right, up] = self.camera.basis();
        let f = self.focal();
        let aspect = f64::from(self.size[0]) / f64::from(self.size[1]);
        let nx = px[0] / f64::from(self.size[0]) * 2.0 - 1.0;
        let ny = px[1] / f64::from(self.size[1]) * 2.0 - 1.0;
        (forward + right * (nx * aspect / f) - up * (ny / f)).normalize()
    }

    /// This view as the LOD selection sees it.
    pub fn traverse_camera(&self) -> TraverseCamera {
        let forward = self.camera.basis()[0].to_array();
        let mut cam = TraverseCamera::perspective(self.camera.position_m, forward, self.fov_y_deg, self.size);
        // Camera-relative planes to world ones: n . (p - c) + w = n . p + (w - n . c).
        let c = DVec3::from(self.camera.position_m);
        cam.frustum = Some(self.frustum_planes().map(|p| [p.x, p.y, p.z, p.w - p.truncate().dot(c)]));
        cam
    }

    /// The traversal's view of this camera.
    pub fn traverse_params(&self) -> TraverseParams {
        TraverseParams { cameras: vec![self.traverse_camera()], target_error_px: self.target_error_px }
    }

    /// The GPU twin, made relative to the camera in f64.
    pub fn gpu(
        &self,
        world: &WorldDesc,
        lod_map_extent: [u32; 2],
        light: &Lighting,
        shade: &ShadeRules,
    ) -> TerrainViewGpu {
        let p = self.camera.position_m;
        // Grid coordinates (metres from LOD-0 sample (0, 0)) for positions;
        // the world position stays in camera_world.
        let g = [p[0] - world.grid_origin_m[0], p[1] - world.grid_origin_m[1]];
        let s = world.spacing_m;
        let anchor = [(g[0] / s).floor(), (g[1] / s).floor()];
        let [lo, hi] = world.height_range_m;
        let vp = self.view_proj().as_mat4();
        let inv = self.view_proj().inverse().as_mat4();
        let f4 = |v: DVec4| v.as_vec4().to_array();
        let [w, h] = self.size.map(f64::from);
        let (bands, slope, mut flags, control) = shade.gpu();
        // w: the clay albedo's f32 bits, 0 = the G-buffer's albedo.
        flags[3] = light.clay_albedo.map_or(0, f32::to_bits);
        TerrainViewGpu {
            view_proj: vp.to_cols_array_2d(),
            frustum: self.frustum_planes().map(f4),
            sun_dir: light.sun_dir().extend(0.0).as_vec4().to_array(),
            sun_color: [light.sun_color[0], light.sun_color[1], light.sun_color[2], 0.0],
            sky_color: [light.sky_color[0], light.sky_color[1], light.sky_color[2], 0.0],
            camera_sample: anchor.map(|a| a as i32),
            camera_frac: [(g[0] - anchor[0] * s) as f32, (g[1] - anchor[1] * s) as f32],
            camera_z: p[2] as f32,
            spacing_m: s as f32,
            height_lo: lo,
            height_scale: (hi - lo) / 65535.0,
            height_range: hi - lo,
            lod_map_w: lod_map_extent[0],
            lod_map_h: lod_map_extent[1],
            pad: 0,
            inv_view_proj: inv.to_cols_array_2d(),
            viewport: [w as f32, h as f32, (1.0 / w) as f32, (1.0 / h) as f32],
            camera_world: [p[0] as f32, p[1] as f32, p[2] as f32, self.near_m as f32],
            shade_bands: bands,
            shade_slope: slope,
            shade_flags: flags,
            lod_forward: {
                let cam = self.traverse_camera();
                let f = cam.forward;
                [f[0] as f32, f[1] as f32, f[2] as f32, cam.pixels_per_tan as f32]
            },
            lod_params: [self.target_error_px, self.traverse_camera().widest as f32, 0.0, 0.0],
            lod_right: {
                let r = self.camera.basis()[1];
                let tan_x = (self.fov_y_deg.to_radians() / 2.0).tan() * w / h;
                [r.x as f32, r.y as f32, r.z as f32, tan_x as f32]
            },
            lod_up: {
                let u = self.camera.basis()[2];
                [u.x as f32, u.y as f32, u.z as f32, (self.fov_y_deg.to_radians() / 2.0).tan() as f32]
            },
            image: [2f32.powf(light.exposure_ev()), light.tonemap.gpu_id() as f32, 0.0, 0.0],
            control,
        }
    }
}

/// A default view that shows a world's relief: from above the middle of
/// its south edge, looking north and down over the terrain, high enough
/// (a twentieth of the world's size above the ground) to see across it.
pub fn overview_camera(world: &WorldDesc, source: &dyn HeightSource) -> Camera {
    let [ex, ey] = world.extent_m;
    let (x, y) = (ex * 0.5, ey * 0.04);
    let ground =
        f64::from(source.sample(x, y)).clamp(f64::from(world.height_range_m[0]), f64::from(world.height_range_m[1]));
    Camera { position_m: [x, y, ground + 0.05 * ex.max(ey)], yaw_deg: 0.0, pitch_deg: -20.0 }
}

/// The simple lighting of the lit output (sun + sky ambient).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lighting {
    /// Compass direction the sun shines from, degrees.
    pub sun_azimuth_deg: f64,
    /// Sun elevation above the horizon, degrees.
    pub sun_elevation_deg: f64,
    pub sun_color: [f32; 3],
    pub sky_color: [f32; 3],
    /// Lights a uniform albedo (linear, in (0, 1]) instead of the G-buffer's:
    /// the "lighting only" view, where the picture depends on geometry and
    /// normals alone. `vista bench accuracy` uses it to compare the lit
    /// image with its reference, which knows the surface but not the textures.
    pub clay_albedo: Option<f32>,
    /// The display image's transform of the linear image, and the exposure
    /// (stops) applied before it; `None`: the tonemapper's own default
    /// ([`Tonemap::default_exposure_ev`]).
    pub tonemap: Tonemap,
    pub exposure_ev: Option<f32>,
}

impl Default for Lighting {
    /// Afternoon sun from the south-west, low enough to show relief.
    fn default() -> Self {
        Lighting {
            sun_azimuth_deg: 225.0,
            sun_elevation_deg: 30.0,
            sun_color: [1.55, 1.45, 1.3],
            sky_color: [0.35, 0.42, 0.55],
            clay_albedo: None,
            tonemap: Tonemap::default(),
            exposure_ev: None,
        }
    }
}

impl Lighting {
    /// The exposure in stops: the scene's, else the tonemapper's default.
    pub fn exposure_ev(&self) -> f32 {
        self.exposure_ev.unwrap_or(self.tonemap.default_exposure_ev())
    }

    /// Unit vector toward the sun.
    pub fn sun_dir(&self) -> DVec3 {
        let (sa, ca) = self.sun_azimuth_deg.to_radians().sin_cos();
        let (se, ce) = self.sun_elevation_deg.to_radians().sin_cos();
        DVec3::new(sa * ce, ca * ce, se)
    }
}

impl View {
    /// 1 / cos of the angle between the forward axis and the frustum's
    /// corner rays: how much farther than its view depth a pixel can be.
    pub fn corner_secant(&self) -> f64 {
        let tan_h = (self.fov_y_deg.to_radians() * 0.5).tan();
        let tan_w = tan_h * f64::from(self.size[0]) / f64::from(self.size[1].max(1));
        (1.0 + tan_h * tan_h + tan_w * tan_w).sqrt()
    }
}

/// Host twin of `TerrainView` (terrain_view.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TerrainViewGpu {
    pub view_proj: [[f32; 4]; 4],
    pub frustum: [[f32; 4]; 5],
    pub sun_dir: [f32; 4],
    pub sun_color: [f32; 4],
    pub sky_color: [f32; 4],
    pub camera_sample: [i32; 2],
    pub camera_frac: [f32; 2],
    pub camera_z: f32,
    pub spacing_m: f32,
    pub height_lo: f32,
    pub height_scale: f32,
    pub height_range: f32,
    pub lod_map_w: u32,
    pub lod_map_h: u32,
    pub pad: u32,
    pub inv_view_proj: [[f32; 4]; 4],
    pub viewport: [f32; 4],
    pub camera_world: [f32; 4],
    pub shade_bands: [f32; 4],
    pub shade_slope: [f32; 4],
    pub shade_flags: [u32; 4],
    /// The camera's forward axis and pixels per unit of tan.
    pub lod_forward: [f32; 4],
    /// Target error (px), 1 / cos^2 of the frustum's widest angle,
    /// refinement levels allowed, no stitching (tests).
    pub lod_params: [f32; 4],
    /// The camera's right axis and the frustum's half-width tangent.
    pub lod_right: [f32; 4],
    /// The camera's up axis and the frustum's half-height tangent.
    pub lod_up: [f32; 4],
    pub image: [f32; 4],
    /// x: the control-map flavour's tri-planar tighten factor.
    pub control: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<TerrainViewGpu>() == crate::shaders::structs::TERRAIN_VIEW);

/// Linear view depth (m) from a reversed-Z depth value; 0 where nothing was
/// drawn (the clear value).
pub fn linear_depth(depth: f32, near_m: f64) -> f32 {
    if depth > 0.0 {
        (near_m / f64::from(depth)) as f32
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view(yaw: f64, pitch: f64) -> View {
        View {
            camera: Camera { position_m: [100.0, 200.0, 50.0], yaw_deg: yaw, pitch_deg: pitch },
            fov_y_deg: 60.0,
            size: [200, 100],
            target_error_px: 1.0,
            near_m: DEFAULT_NEAR_M,
        }
    }

    #[test]
    fn compass_conventions() {
        // Yaw 0 looks north (+y): a point north of the camera is centred.
        let v = view(0.0, 0.0);
        let (px, d) = v.project([100.0, 300.0, 50.0]).unwrap();
        assert!((px[0] - 100.0).abs() < 1e-9 && (px[1] - 50.0).abs() < 1e-9 && (d - 100.0).abs() < 1e-9);
        // East of that point lies to the right; higher lies toward row 0.
        assert!(v.project([110.0, 300.0, 50.0]).unwrap().0[0] > 100.0);
        assert!(v.project([100.0, 300.0, 60.0]).unwrap().0[1] < 50.0);
        // Yaw 90 looks east.
        assert!((view(90.0, 0.0).project([200.0, 200.0, 50.0]).unwrap().0[0] - 100.0).abs() < 1e-9);
        // Pitch -90 looks straight down, north at the top of the image.
        let down = view(0.0, -90.0);
        let (px, d) = down.project([100.0, 210.0, 0.0]).unwrap();
        assert!((d - 50.0).abs() < 1e-9 && px[1] < 50.0 && (px[0] - 100.0).abs() < 1e-9);
    }

    #[test]
    fn rays_and_projection_agree_and_depth_is_reversed() {
        let v = view(37.0, -20.0);
        for px in [[0.5, 0.5], [199.5, 0.5], [100.0, 50.0], [13.25, 88.5]] {
            let p = DVec3::from(v.camera.position_m) + v.ray(px) * 321.0;
            let (q, _) = v.project(p.to_array()).unwrap();
            assert!((q[0] - px[0]).abs() < 1e-9 && (q[1] - px[1]).abs() < 1e-9, "{px:?} -> {q:?}");
        }
        let c = v.view_proj() * DVec4::new(0.0, 0.0, 0.0, 1.0);
        assert_eq!(c.w, 0.0, "the camera itself is at w = 0");
        let [forward, ..] = v.camera.basis();
        for d in [0.1, 1.0, 1e3, 1e6] {
            let c = v.view_proj() * (forward * d).extend(1.0);
            assert!((c.z / c.w - DEFAULT_NEAR_M / d).abs() < 1e-12);
            assert!((f64::from(linear_depth((c.z / c.w) as f32, DEFAULT_NEAR_M)) - d).abs() < d * 1e-6);
        }
    }

    #[test]
    fn frustum_planes_contain_exactly_the_visible_points() {
        let v = view(200.0, 10.0);
        let planes = v.frustum_planes();
        for (px, inside) in [([0.6, 0.6], true), ([199.4, 99.4], true), ([-2.0, 50.0], false), ([100.0, 103.0], false)]
        {
            let p = v.ray(px) * 500.0;
            let ok = planes.iter().all(|pl| pl.truncate().dot(p) + pl.w >= 0.0);
            assert_eq!(ok, inside, "{px:?}");
        }
        // Behind the near plane is outside.
        let p = v.camera.basis()[0] * 0.05;
        assert!(planes[4].truncate().dot(p) + planes[4].w < 0.0);
    }

    #[test]
    fn cameras_print_as_the_command_line_takes_them() {
        let c = Camera { position_m: [1280.4, -5.0, 627.6], yaw_deg: 270.0, pitch_deg: -15.2 };
        assert_eq!(c.to_string(), "1280,-5,628,270,-15");
    }

    #[test]
    fn bad_views_are_errors() {
        let ok = view(0.0, 0.0);
        assert!(ok.validate().is_ok());
        for bad in [
            View { fov_y_deg: 0.0, ..ok.clone() },
            View { fov_y_deg: 180.0, ..ok.clone() },
            View { size: [0, 10], ..ok.clone() },
            View { target_error_px: f32::NAN, ..ok.clone() },
            View { camera: Camera { pitch_deg: 91.0, ..ok.camera }, ..ok.clone() },
            View { camera: Camera { position_m: [f64::INFINITY, 0.0, 0.0], ..ok.camera }, ..ok.clone() },
        ] {
            assert!(bad.validate().is_err(), "{bad:?}");
        }
    }
}
