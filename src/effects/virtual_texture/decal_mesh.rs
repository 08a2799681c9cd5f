//! Displacement decals (seed 000's terrain displacement decals, effect
//! `decals`): a quad decal with `displace_m` gets a grid mesh over its
//! quad, each vertex raised above the terrain by `displace_m` x the
//! texture's alpha x opacity, tapering to 0 over the outer two cells so its
//! rim lies on the terrain. The `decal_meshes` pass draws it in the
//! geometry pass, so the tile shading colours it from the same virtual
//! texture pages as the ground around it (the decal's own colours): no
//! seam where mesh and terrain meet.

use super::decals::{Decal, DecalShape, DecalTexture};
use crate::shaders::consts::DECAL_MESH_QUADS;
use glam::{DVec2, Vec2};

/// Host twin of `DecalMeshVertex` (decal_meshes.vert).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct DecalMeshVertex {
    /// x, y (world m), z: height above the terrain (m), w unused.
    pub position: [f32; 4],
    /// xy: the gradient of that height (m per m), zw unused.
    pub gradient: [f32; 4],
}

/// The meshes of every displacement decal: vertices and triangle indices
/// into them.
#[derive(Debug, Clone, Default)]
pub struct DecalMeshes {
    pub vertices: Vec<DecalMeshVertex>,
    pub indices: Vec<u32>,
    /// How many decals have a mesh.
    pub meshes: u32,
}

/// Bilinear alpha (0..1) of `t` at texture coordinates `uv` (0..1, clamped).
fn alpha(t: &DecalTexture, uv: Vec2) -> f32 {
    let n = t.rgba.width() as f32;
    let p = (uv * n - 0.5).clamp(Vec2::ZERO, Vec2::splat(n - 1.0));
    let i = p.floor();
    let f = p - i;
    let at = |x: f32, y: f32| f32::from(t.rgba.get_pixel(x.min(n - 1.0) as u32, y.min(n - 1.0) as u32)[3]) / 255.0;
    let a = at(i.x, i.y) * (1.0 - f.x) + at(i.x + 1.0, i.y) * f.x;
    let b = at(i.x, i.y + 1.0) * (1.0 - f.x) + at(i.x + 1.0, i.y + 1.0) * f.x;
    a * (1.0 - f.y) + b * f.y
}

/// The raise of a displacement decal at grid point (i, j) of its quad.
fn raise(d: &Decal, t: &DecalTexture, i: u32, j: u32) -> f32 {
    let n = DECAL_MESH_QUADS;
    let uv = Vec2::new(i as f32, j as f32) / n as f32;
    // Zero on the rim, full two cells in: the rim lies on the terrain.
    let inside = i.min(j).min(n - i).min(n - j) as f32 / 2.0;
    let taper = {
        let x = inside.min(1.0);
        x * x * (3.0 - 2.0 * x)
    };
    d.displace_m.unwrap_or(0.0) * alpha(t, uv) * d.opacity * taper
}

impl DecalMeshes {
    /// The meshes of `decals` that displace (quads with `displace_m`).
    pub fn build(decals: &[Decal], textures: &[DecalTexture]) -> DecalMeshes {
        let n = DECAL_MESH_QUADS;
        let side = n + 1;
        let mut out = DecalMeshes::default();
        for d in decals {
            let (Some(_), DecalShape::Quad { center_m, size_m, rotation_deg }) = (d.displace_m, &d.shape) else {
                continue;
            };
            let t = &textures[d.texture as usize];
            let u = DVec2::from_angle(rotation_deg.to_radians());
            let (cell_u, cell_v) = (size_m.x / f64::from(n), size_m.y / f64::from(n));
            let base = out.vertices.len() as u32;
            for j in 0..side {
                for i in 0..side {
                    let local =
                        DVec2::new(f64::from(i) / f64::from(n) - 0.5, f64::from(j) / f64::from(n) - 0.5) * *size_m;
                    let p = *center_m + u * local.x + u.perp() * local.y;
                    // Central differences along the quad's axes, turned into world x, y.
                    let (i0, i1, j0, j1) = (i.saturating_sub(1), (i + 1).min(n), j.saturating_sub(1), (j + 1).min(n));
                    let du = f64::from(raise(d, t, i1, j) - raise(d, t, i0, j)) / (f64::from(i1 - i0) * cell_u);
                    let dv = f64::from(raise(d, t, i, j1) - raise(d, t, i, j0)) / (f64::from(j1 - j0) * cell_v);
                    let g = u * du + u.perp() * dv;
                    out.vertices.push(DecalMeshVertex {
                        position: [p.x as f32, p.y as f32, raise(d, t, i, j), 0.0],
                        gradient: [g.x as f32, g.y as f32, 0.0, 0.0],
                    });
                }
            }
            for j in 0..n {
                for i in 0..n {
                    let a = base + j * side + i;
                    // Counter-clockwise seen from above (u east, v north at rotation 0).
                    out.indices.extend([a, a + 1, a + side + 1, a, a + side + 1, a + side]);
                }
            }
            out.meshes += 1;
        }
        out
    }

    /// Triangles of every mesh.
    pub fn triangles(&self) -> u64 {
        self.indices.len() as u64 / 3
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shaders::consts::DECAL_TEXELS;

    #[test]
    fn the_rim_lies_on_the_terrain_and_the_middle_is_raised() {
        let n = DECAL_TEXELS;
        let solid = DecalTexture::from_rgba("solid", &image::RgbaImage::from_pixel(n, n, image::Rgba([9, 9, 9, 255])));
        let quad = |displace_m| Decal {
            shape: DecalShape::Quad {
                center_m: DVec2::new(10.0, 20.0),
                size_m: DVec2::new(8.0, 4.0),
                rotation_deg: 30.0,
            },
            texture: 0,
            opacity: 0.5,
            roughness: None,
            displace_m,
        };
        let m = DecalMeshes::build(&[quad(Some(2.0)), quad(None)], &[solid]);
        let side = DECAL_MESH_QUADS + 1;
        assert_eq!((m.meshes, m.vertices.len() as u32), (1, side * side));
        assert_eq!(m.triangles(), u64::from(2 * DECAL_MESH_QUADS * DECAL_MESH_QUADS));
        let (mut rim, mut top) = (0, 0.0f32);
        for (k, v) in m.vertices.iter().enumerate() {
            let (i, j) = (k as u32 % side, k as u32 / side);
            if i == 0 || j == 0 || i == side - 1 || j == side - 1 {
                assert_eq!(v.position[2], 0.0);
                rim += 1;
            }
            top = top.max(v.position[2]);
        }
        // Alpha 1 x opacity 0.5 x 2 m.
        assert!(rim == 4 * (side - 1) && (top - 1.0).abs() < 1e-6, "{rim} {top}");
        // The centre is where the quad says.
        let c = m.vertices[(side * side / 2) as usize].position;
        assert!((c[0] - 10.0).abs() < 1e-4 && (c[1] - 20.0).abs() < 1e-4, "{c:?}");
    }
}
