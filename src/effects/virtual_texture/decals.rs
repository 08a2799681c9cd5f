//! Decals composited into the virtual texture's pages (effect `decals`;
//! seed 000: a decal drawn once into the cached page costs nothing per
//! frame). A decal is a textured quad or a road (a polyline with a width,
//! its texture repeating along it) in world metres. `vt_pages` alpha-blends
//! every decal touching a page over the material, in list order, when it
//! renders the page; an edit drops exactly the resident pages the old or
//! the new shape touches, and they are rendered again. No Vulkan here.

use crate::error::{Error, Result};
use crate::shaders::consts::{
    DECAL_KIND_QUAD, DECAL_KIND_ROAD, DECAL_MAX, DECAL_MAX_POINTS, DECAL_MAX_TEXTURES, DECAL_TEXELS,
};
use glam::DVec2;
use image::imageops::FilterType;
use std::path::Path;
use std::sync::Arc;

/// Where a decal lies (world metres, x east, y north).
#[derive(Debug, Clone, PartialEq)]
pub enum DecalShape {
    /// The texture stretched over a rectangle: u along the rotated x axis,
    /// v along the rotated y axis.
    Quad { center_m: DVec2, size_m: DVec2, rotation_deg: f64 },
    /// A road: `width_m` wide along the polyline, square at its two ends and
    /// round at its bends; u runs across it (0 on the left), v along it, one
    /// texture repeat every `repeat_m`.
    Road { points_m: Vec<DVec2>, width_m: f64, repeat_m: f64 },
}

/// One decal: a shape, the texture it shows (an index into the set's
/// textures) and how it blends: its texture's alpha times `opacity`;
/// roughness towards `roughness` when given, else the material's kept.
/// `displace_m` (quads only) makes it a displacement decal: a mesh over the
/// quad raised by `displace_m` x alpha x opacity above the terrain,
/// shaded from the same pages (decal_mesh.rs).
#[derive(Debug, Clone, PartialEq)]
pub struct Decal {
    pub shape: DecalShape,
    pub texture: u32,
    pub opacity: f32,
    pub roughness: Option<f32>,
    pub displace_m: Option<f32>,
}

/// An oriented rectangle: centre, unit axes, half sizes along them.
#[derive(Debug, Clone, Copy)]
struct Obb {
    c: DVec2,
    u: DVec2,
    half: DVec2,
}

impl Obb {
    /// Whether it overlaps the axis-aligned `rect` (x0, y0, x1, y1):
    /// separating axes x, y, u and v.
    fn overlaps(self, rect: [f64; 4]) -> bool {
        let v = self.u.perp();
        let bc = DVec2::new(rect[0] + rect[2], rect[1] + rect[3]) * 0.5;
        let bh = DVec2::new(rect[2] - rect[0], rect[3] - rect[1]) * 0.5;
        let d = self.c - bc;
        let reach = |axis: DVec2| self.half.x * self.u.dot(axis).abs() + self.half.y * v.dot(axis).abs();
        let box_reach = |axis: DVec2| bh.x * axis.x.abs() + bh.y * axis.y.abs();
        d.x.abs() <= bh.x + reach(DVec2::X)
            && d.y.abs() <= bh.y + reach(DVec2::Y)
            && d.dot(self.u).abs() <= self.half.x + box_reach(self.u)
            && d.dot(v).abs() <= self.half.y + box_reach(v)
    }
}

fn disc_overlaps(c: DVec2, r: f64, rect: [f64; 4]) -> bool {
    let q = c.clamp(DVec2::new(rect[0], rect[1]), DVec2::new(rect[2], rect[3]));
    q.distance_squared(c) <= r * r
}

impl Decal {
    /// Whether any point within `margin` m of the decal lies in `rect`
    /// (x0, y0, x1, y1 m): the pages whose texels it may colour. A quad is
    /// one rectangle grown by `margin`; a road is a rectangle per segment
    /// and a disc per bend.
    pub fn touches(&self, rect: [f64; 4], margin: f64) -> bool {
        match &self.shape {
            DecalShape::Quad { center_m, size_m, rotation_deg } => {
                let u = DVec2::from_angle(rotation_deg.to_radians());
                Obb { c: *center_m, u, half: *size_m * 0.5 + margin }.overlaps(rect)
            }
            DecalShape::Road { points_m, width_m, .. } => {
                let half = width_m * 0.5 + margin;
                let segment = |s: &[DVec2]| {
                    let along = s[1] - s[0];
                    let h = DVec2::new(along.length() * 0.5 + margin, half);
                    Obb { c: (s[0] + s[1]) * 0.5, u: along.normalize(), half: h }.overlaps(rect)
                };
                let bends = &points_m[1..points_m.len() - 1];
                points_m.windows(2).any(segment) || bends.iter().any(|&p| disc_overlaps(p, half, rect))
            }
        }
    }

    /// Its footprint as shapes (a quad's rectangle; a road's rectangle per
    /// segment and disc per bend): what `clear_vegetation` keeps clear.
    pub fn outline(&self) -> Vec<crate::world::Hole> {
        use crate::world::Hole;
        let rect = |c: DVec2, u: DVec2, half: DVec2| {
            let v = u.perp();
            let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
            Hole::Polygon(corners.iter().map(|(a, b)| (c + u * half.x * *a + v * half.y * *b).to_array()).collect())
        };
        match &self.shape {
            DecalShape::Quad { center_m, size_m, rotation_deg } => {
                vec![rect(*center_m, DVec2::from_angle(rotation_deg.to_radians()), *size_m * 0.5)]
            }
            DecalShape::Road { points_m, width_m, .. } => {
                let half = width_m * 0.5;
                let segments = points_m.windows(2).map(|s| {
                    let along = s[1] - s[0];
                    rect((s[0] + s[1]) * 0.5, along.normalize(), DVec2::new(along.length() * 0.5, half))
                });
                let bends = points_m[1..points_m.len() - 1]
                    .iter()
                    .map(|p| Hole::Circle { center_m: p.to_array(), radius_m: half });
                segments.chain(bends).collect()
            }
        }
    }

    /// Moved by `by` m (a caller's coordinates into the world's).
    pub fn translated(&self, by: DVec2) -> Decal {
        let shape = match &self.shape {
            DecalShape::Quad { center_m, size_m, rotation_deg } => {
                DecalShape::Quad { center_m: *center_m + by, size_m: *size_m, rotation_deg: *rotation_deg }
            }
            DecalShape::Road { points_m, width_m, repeat_m } => DecalShape::Road {
                points_m: points_m.iter().map(|p| *p + by).collect(),
                width_m: *width_m,
                repeat_m: *repeat_m,
            },
        };
        Decal { shape, ..self.clone() }
    }

    /// A one-line reason when it cannot be drawn with `textures` textures.
    pub fn check(&self, textures: usize) -> std::result::Result<(), String> {
        if self.texture as usize >= textures {
            return Err(format!("texture {} is not one of the {textures} loaded", self.texture));
        }
        if !(0.0..=1.0).contains(&self.opacity) {
            return Err(format!("opacity {} is not in 0..=1", self.opacity));
        }
        if self.roughness.is_some_and(|r| !(0.0..=1.0).contains(&r)) {
            return Err(format!("roughness {:?} is not in 0..=1", self.roughness.unwrap_or_default()));
        }
        if let Some(d) = self.displace_m {
            // Drawn over the terrain, depth-tested: a mesh below it would never show.
            if !(d > 0.0 && d <= 50.0) {
                return Err(format!("displace_m {d} is not in 0..=50 (above 0: the mesh rises from the terrain)"));
            }
            if !matches!(self.shape, DecalShape::Quad { .. }) {
                return Err("displace_m needs a quad decal (a road has no displacement mesh)".into());
            }
        }
        match &self.shape {
            DecalShape::Quad { center_m, size_m, rotation_deg } => {
                if !center_m.is_finite() || !rotation_deg.is_finite() {
                    return Err("the quad's center and rotation must be finite".into());
                }
                if !(size_m.min_element() > 0.0 && size_m.is_finite()) {
                    return Err(format!("the quad's size {size_m} must be positive"));
                }
            }
            DecalShape::Road { points_m, width_m, repeat_m } => {
                if points_m.len() < 2 || points_m.iter().any(|p| !p.is_finite()) {
                    return Err("a road needs at least 2 points of finite numbers".into());
                }
                if let Some(w) = points_m.windows(2).position(|s| s[0].distance(s[1]) < 1e-3) {
                    return Err(format!("road points {} and {} are the same point", w + 1, w + 2));
                }
                if !(width_m.is_finite() && *width_m > 0.0 && repeat_m.is_finite() && *repeat_m > 0.0) {
                    return Err(format!("width {width_m} and repeat {repeat_m} must be positive"));
                }
            }
        }
        Ok(())
    }
}

/// A decal texture, resampled to `DECAL_TEXELS` a side (one layer of the
/// decal array). RGB is sRGB, alpha the coverage.
#[derive(Debug, Clone, PartialEq)]
pub struct DecalTexture {
    pub name: String,
    pub rgba: image::RgbaImage,
}

/// Largest side of a decal image file, checked before it is decoded.
pub const MAX_FILE_SIDE: u32 = 8192;

impl DecalTexture {
    pub fn from_rgba(name: &str, rgba: &image::RgbaImage) -> DecalTexture {
        let rgba = if rgba.dimensions() == (DECAL_TEXELS, DECAL_TEXELS) {
            rgba.clone()
        } else {
            image::imageops::resize(rgba, DECAL_TEXELS, DECAL_TEXELS, FilterType::Triangle)
        };
        DecalTexture { name: name.to_string(), rgba }
    }

    /// Reads an image file (PNG, ...); one-line errors name it.
    pub fn load(path: &Path) -> Result<DecalTexture> {
        let fail = |why: String| Error::Scene(format!("decal texture {}: {why}", path.display()));
        let reader = crate::world::require_regular_file(path)
            .and_then(|()| image::ImageReader::open(path))
            .and_then(|r| r.with_guessed_format())
            .map_err(|e| fail(format!("cannot read it: {e}")))?;
        let (w, h) = reader.into_dimensions().map_err(|e| fail(format!("cannot decode it: {e}")))?;
        if w.max(h) > MAX_FILE_SIDE {
            return Err(fail(format!("is {w}x{h}; decal textures are at most {MAX_FILE_SIDE} a side")));
        }
        let img = image::ImageReader::open(path)
            .and_then(|r| r.with_guessed_format())
            .map_err(|e| fail(format!("cannot read it: {e}")))?
            .decode()
            .map_err(|e| fail(format!("cannot decode it: {}", e.to_string().lines().next().unwrap_or(""))))?;
        Ok(DecalTexture::from_rgba(&path.display().to_string(), &img.into_rgba8()))
    }

    /// Mips of the layer, mip 0 first, down to 1 x 1.
    pub fn mips(&self) -> Vec<Vec<u8>> {
        let mut out = vec![self.rgba.as_raw().clone()];
        let mut side = DECAL_TEXELS / 2;
        while side >= 1 {
            out.push(image::imageops::resize(&self.rgba, side, side, FilterType::Triangle).into_raw());
            side /= 2;
        }
        out
    }
}

/// A decal as `vt_pages` reads it (`Decal` in vt_pages.comp).
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct DecalGpu {
    /// Quad: its centre (m).
    pub origin: [f32; 2],
    /// Quad: u and v per metre along the world axes' projections.
    pub axis_u: [f32; 2],
    pub axis_v: [f32; 2],
    pub kind: u32,
    pub layer: u32,
    pub opacity: f32,
    /// Negative: the material's roughness is kept.
    pub roughness: f32,
    /// Road: its points (x, y, metres along the road, 0) in the point list.
    pub first_point: u32,
    pub point_count: u32,
    pub half_width: f32,
    pub repeat_m: f32,
}

/// The scene's decals and the textures they show.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DecalSet {
    pub textures: Arc<[DecalTexture]>,
    pub decals: Vec<Decal>,
}

impl DecalSet {
    /// One-line errors for a set the renderer cannot hold.
    pub fn check(&self) -> Result<()> {
        let bad = |s: String| Err(Error::BadInput(s));
        if self.decals.len() > DECAL_MAX as usize {
            return bad(format!("{} decals; at most {DECAL_MAX}", self.decals.len()));
        }
        if self.textures.len() > DECAL_MAX_TEXTURES as usize {
            return bad(format!("{} decal textures; at most {DECAL_MAX_TEXTURES}", self.textures.len()));
        }
        let points: usize = self.decals.iter().map(|d| road_points(d).len()).sum();
        if points > DECAL_MAX_POINTS as usize {
            return bad(format!("the roads have {points} points in all; at most {DECAL_MAX_POINTS}"));
        }
        for (i, d) in self.decals.iter().enumerate() {
            if let Err(why) = d.check(self.textures.len()) {
                return bad(format!("decal {}: {why}", i + 1));
            }
        }
        Ok(())
    }

    /// The decal list and the road point list as `vt_pages` reads them.
    pub fn gpu_words(&self) -> (Vec<DecalGpu>, Vec<[f32; 4]>) {
        let mut points = Vec::new();
        let decals = self
            .decals
            .iter()
            .map(|d| {
                let mut g = DecalGpu {
                    origin: [0.0; 2],
                    axis_u: [0.0; 2],
                    axis_v: [0.0; 2],
                    kind: DECAL_KIND_QUAD,
                    layer: d.texture,
                    opacity: d.opacity,
                    roughness: d.roughness.unwrap_or(-1.0),
                    first_point: points.len() as u32,
                    point_count: 0,
                    half_width: 0.0,
                    repeat_m: 1.0,
                };
                match &d.shape {
                    DecalShape::Quad { center_m, size_m, rotation_deg } => {
                        let u = DVec2::from_angle(rotation_deg.to_radians());
                        g.origin = center_m.as_vec2().to_array();
                        g.axis_u = (u / size_m.x).as_vec2().to_array();
                        g.axis_v = (u.perp() / size_m.y).as_vec2().to_array();
                    }
                    DecalShape::Road { points_m, width_m, repeat_m } => {
                        g.kind = DECAL_KIND_ROAD;
                        g.point_count = points_m.len() as u32;
                        g.half_width = (width_m * 0.5) as f32;
                        g.repeat_m = *repeat_m as f32;
                        let mut along = 0.0;
                        for (i, p) in points_m.iter().enumerate() {
                            if i > 0 {
                                along += p.distance(points_m[i - 1]);
                            }
                            points.push([p.x as f32, p.y as f32, along as f32, 0.0]);
                        }
                    }
                }
                g
            })
            .collect();
        (decals, points)
    }

    /// The decals that touch `rect` with a margin of `margin` m, in order.
    pub fn touching(&self, rect: [f64; 4], margin: f64) -> impl Iterator<Item = u32> + '_ {
        (0..self.decals.len() as u32).filter(move |&i| self.decals[i as usize].touches(rect, margin))
    }
}

fn road_points(d: &Decal) -> &[DVec2] {
    match &d.shape {
        DecalShape::Road { points_m, .. } => points_m,
        DecalShape::Quad { .. } => &[],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(c: [f64; 2], size: [f64; 2], rot: f64) -> Decal {
        Decal {
            shape: DecalShape::Quad { center_m: c.into(), size_m: size.into(), rotation_deg: rot },
            texture: 0,
            opacity: 1.0,
            roughness: None,
            displace_m: None,
        }
    }

    /// Whether a point lies in the shape (grown by `margin`), by brute force.
    fn inside(d: &Decal, p: DVec2, margin: f64) -> bool {
        match &d.shape {
            DecalShape::Quad { center_m, size_m, rotation_deg } => {
                let u = DVec2::from_angle(rotation_deg.to_radians());
                let q = p - *center_m;
                q.dot(u).abs() <= size_m.x * 0.5 + margin && q.dot(u.perp()).abs() <= size_m.y * 0.5 + margin
            }
            DecalShape::Road { points_m, width_m, .. } => points_m.windows(2).enumerate().any(|(i, s)| {
                let ab = s[1] - s[0];
                let t = (p - s[0]).dot(ab) / ab.length_squared();
                let end = (i == 0 && t < 0.0) || (i == points_m.len() - 2 && t > 1.0);
                let beyond = if t < 0.0 { -t } else { t - 1.0 } * ab.length();
                let line = (p - s[0]).perp_dot(ab.normalize()).abs();
                let near = (p - (s[0] + ab * t.clamp(0.0, 1.0))).length();
                if end {
                    line <= width_m * 0.5 + margin && beyond <= margin
                } else {
                    near <= width_m * 0.5 + margin
                }
            }),
        }
    }

    /// `touches` agrees with point sampling: a rectangle holding a point of
    /// the shape is touched; one touched holds a point within a small
    /// extra margin (the grown rectangles' corners).
    #[test]
    fn touches_matches_point_sampling() {
        let road = Decal {
            shape: DecalShape::Road {
                points_m: vec![[0.0, 0.0].into(), [20.0, 5.0].into(), [25.0, 30.0].into()],
                width_m: 4.0,
                repeat_m: 8.0,
            },
            ..quad([0.0; 2], [1.0; 2], 0.0)
        };
        let decals = [quad([10.0, 10.0], [12.0, 4.0], 37.0), road];
        let mut rng = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            (rng >> 11) as f64 / (1u64 << 53) as f64
        };
        for d in &decals {
            for _ in 0..400 {
                let (x, y, s) = (next() * 50.0 - 10.0, next() * 50.0 - 10.0, 0.5 + next() * 6.0);
                let rect = [x, y, x + s, y + s];
                let n = 24;
                let grid = (0..=n).flat_map(|i| (0..=n).map(move |j| (i, j)));
                let pts: Vec<DVec2> = grid
                    .map(|(i, j)| DVec2::new(x + s * f64::from(i) / f64::from(n), y + s * f64::from(j) / f64::from(n)))
                    .collect();
                let hit = pts.iter().any(|&p| inside(d, p, 0.0));
                let near = pts.iter().any(|&p| inside(d, p, 0.45 * s / f64::from(n) + 0.2));
                let t = d.touches(rect, 0.1);
                assert!(!hit || t, "{rect:?} holds a point of {d:?} but is not touched");
                assert!(!t || near, "{rect:?} is touched by {d:?} but holds no point near it");
            }
        }
        // The quad's corner (+-6, +-2 rotated by 37 degrees) reaches x = 16.0
        // from its centre's 10: just beyond it nothing is touched.
        let far_x = 10.0 + 6.0 * 37f64.to_radians().cos() + 2.0 * 37f64.to_radians().sin();
        assert!(decals[0].touches([far_x - 0.01, 0.0, far_x + 1.0, 20.0], 0.0));
        assert!(!decals[0].touches([far_x + 0.01, 0.0, far_x + 1.0, 20.0], 0.0));
    }

    #[test]
    fn bad_decals_say_why_in_one_line() {
        let set = |d: Decal| DecalSet {
            textures: vec![DecalTexture::from_rgba("t", &image::RgbaImage::new(4, 4))].into(),
            decals: vec![d],
        };
        let road = |pts: Vec<DVec2>, w: f64| Decal {
            shape: DecalShape::Road { points_m: pts, width_m: w, repeat_m: 1.0 },
            ..quad([0.0; 2], [1.0; 2], 0.0)
        };
        let bad = [
            Decal { texture: 1, ..quad([0.0; 2], [1.0; 2], 0.0) },
            Decal { opacity: 1.5, ..quad([0.0; 2], [1.0; 2], 0.0) },
            quad([f64::NAN, 0.0], [1.0; 2], 0.0),
            quad([0.0; 2], [0.0, 1.0], 0.0),
            road(vec![DVec2::ZERO], 1.0),
            road(vec![DVec2::ZERO, DVec2::ZERO], 1.0),
            road(vec![DVec2::ZERO, DVec2::ONE], -1.0),
        ];
        for d in bad {
            let e = set(d.clone()).check().expect_err(&format!("{d:?}")).to_string();
            assert!(!e.contains('\n') && e.contains("decal 1"), "{e}");
        }
        set(quad([0.0; 2], [1.0; 2], 0.0)).check().unwrap();
    }
}
