//! Effect `assets`: the example of other assets grounded in the terrain
//! (seed 000). Rocks and trunks from a scene list, each set on the
//! terrain's height at its origin and blended into the terrain's normal
//! and colour near the ground by `terrain_blend.glsl`, the include an
//! engine's own asset shaders use. Meshes are made here (a lumpy rock, a
//! flared trunk: position and normal); `asset_draw` draws them into the
//! G-buffer, one indexed instanced draw per kind.
//!
//! ```toml
//! [[assets]]
//! kind = "rock"         # or "trunk"
//! at = [5170, 3480]     # world metres (moved by origin like holes)
//! scale = 1.5           # optional (1): the rock is ~1.6 m across, the trunk 5 m tall
//! yaw_deg = 30          # optional (0)
//! [effects]
//! assets = { blend_height_m = 0.6 }
//! ```

pub mod asset_draw;
pub mod frame;
pub mod kind;

use crate::error::{Error, Result};
use crate::gpu::{vk, Buffer, Context};
use glam::Vec3;

/// The meshes the example pass knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AssetKind {
    Rock,
    Trunk,
}

impl AssetKind {
    pub const ALL: [AssetKind; 2] = [AssetKind::Rock, AssetKind::Trunk];

    pub fn name(self) -> &'static str {
        match self {
            AssetKind::Rock => "rock",
            AssetKind::Trunk => "trunk",
        }
    }

    pub fn from_name(name: &str) -> Option<AssetKind> {
        AssetKind::ALL.into_iter().find(|k| k.name() == name)
    }

    /// Its own colour (linear).
    fn albedo(self) -> [f32; 3] {
        match self {
            AssetKind::Rock => [0.16, 0.155, 0.145],
            AssetKind::Trunk => [0.20, 0.13, 0.08],
        }
    }
}

/// One placed asset (world metres, like holes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Asset {
    pub kind: AssetKind,
    pub at_m: [f64; 2],
    pub scale: f64,
    pub yaw_deg: f64,
}

impl Asset {
    /// One-line error for an asset that cannot be drawn.
    pub fn check(&self) -> std::result::Result<(), String> {
        if !self.at_m.iter().all(|v| v.is_finite()) {
            return Err(format!("position {:?} is not finite", self.at_m));
        }
        if !(self.scale.is_finite() && (0.01..=100.0).contains(&self.scale)) {
            return Err(format!("scale {} is outside 0.01..=100", self.scale));
        }
        if !self.yaw_deg.is_finite() {
            return Err(format!("yaw_deg {} is not finite", self.yaw_deg));
        }
        Ok(())
    }

    /// The same asset moved by `-origin_m`.
    pub fn relative_to(&self, origin_m: [f64; 2]) -> Asset {
        Asset { at_m: [self.at_m[0] - origin_m[0], self.at_m[1] - origin_m[1]], ..*self }
    }
}

/// Host twin of `AssetVertex` (asset.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct AssetVertexGpu {
    pub position: [f32; 4],
    pub normal: [f32; 4],
}

/// Host twin of `AssetInstance`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct AssetInstanceGpu {
    /// x, y (world m), yaw (radians), scale.
    pub place: [f32; 4],
    pub albedo: [f32; 4],
}

/// A mesh: vertices and triangle indices (counter-clockwise seen from outside).
#[derive(Debug, Clone, Default)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub indices: Vec<u32>,
}

impl Mesh {
    /// Vertex normals: the area-weighted mean of the faces around each.
    fn smooth_normals(&mut self) {
        let mut n = vec![Vec3::ZERO; self.positions.len()];
        for t in self.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|i| self.positions[t[i] as usize]);
            let face = (b - a).cross(c - a);
            for &i in t {
                n[i as usize] += face;
            }
        }
        self.normals = n.into_iter().map(|v| v.normalize_or(Vec3::Z)).collect();
    }
}

/// A lumpy rock about 1.6 m across and 0.9 m high, its foot 0.25 m below
/// the ground: an octahedron subdivided 3 times onto a sphere, its radius
/// varied by a few smooth waves, flattened.
pub fn rock_mesh() -> Mesh {
    let mut positions = vec![Vec3::X, Vec3::Y, Vec3::NEG_X, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
    let mut tris: Vec<[u32; 3]> =
        vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4], [1, 0, 5], [2, 1, 5], [3, 2, 5], [0, 3, 5]];
    for _ in 0..3 {
        let mut mid = std::collections::HashMap::new();
        let mut split = |a: u32, b: u32, positions: &mut Vec<Vec3>| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                positions.push(((positions[a as usize] + positions[b as usize]) * 0.5).normalize());
                positions.len() as u32 - 1
            })
        };
        tris = tris
            .iter()
            .flat_map(|&[a, b, c]| {
                let (ab, bc, ca) =
                    (split(a, b, &mut positions), split(b, c, &mut positions), split(c, a, &mut positions));
                [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
            })
            .collect();
    }
    let lump =
        |d: Vec3| 1.0 + 0.12 * (3.1 * d.x + 1.3).sin() * (2.3 * d.y).cos() + 0.08 * (4.7 * d.z + 2.9 * d.x).sin();
    let positions = positions.into_iter().map(|d| d * lump(d) * Vec3::new(0.8, 0.7, 0.55) + Vec3::Z * 0.3).collect();
    let mut m = Mesh { positions, normals: Vec::new(), indices: tris.into_flattened() };
    m.smooth_normals();
    m
}

/// A trunk 5 m tall, 0.25 m in radius, flaring to twice that at its foot
/// (which starts 0.3 m below the ground), 16 sides, closed at the top.
pub fn trunk_mesh() -> Mesh {
    const SIDES: u32 = 16;
    const RINGS: u32 = 12;
    let mut m = Mesh::default();
    for r in 0..=RINGS {
        let z = -0.3 + 5.3 * (r as f32 / RINGS as f32).powi(2);
        let radius = 0.25 * (1.0 + (-3.0 * z.max(0.0)).exp());
        for s in 0..SIDES {
            let a = s as f32 / SIDES as f32 * std::f32::consts::TAU;
            m.positions.push(Vec3::new(radius * a.cos(), radius * a.sin(), z));
        }
    }
    for r in 0..RINGS {
        for s in 0..SIDES {
            let (a, b) = (r * SIDES + s, r * SIDES + (s + 1) % SIDES);
            let (c, d) = (a + SIDES, b + SIDES);
            m.indices.extend([a, b, d, a, d, c]);
        }
    }
    let top = m.positions.len() as u32;
    m.positions.push(Vec3::new(0.0, 0.0, 5.0));
    for s in 0..SIDES {
        m.indices.extend([RINGS * SIDES + s, RINGS * SIDES + (s + 1) % SIDES, top]);
    }
    m.smooth_normals();
    m
}

/// Effect `assets`' parameters.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct AssetParams {
    /// The blend into the terrain fades out over this height above it.
    pub blend_height_m: f32,
}

impl Default for AssetParams {
    fn default() -> Self {
        AssetParams { blend_height_m: 0.6 }
    }
}

/// The meshes and instances on the GPU. Teardown: fields drop in
/// declaration order, retired until the frames using them completed.
pub struct AssetResources {
    pub vertices: Buffer,
    /// One index buffer per kind (indices into `vertices`).
    pub indices: Vec<(AssetKind, Buffer, u32)>,
    pub instances: Buffer,
    /// Per kind: its first instance and count (instances grouped by kind).
    pub draws: Vec<(AssetKind, u32, u32)>,
    pub params: AssetParams,
}

/// Most assets one renderer draws (their instances are uploaded once).
pub const MAX_ASSETS: usize = 65536;

impl AssetResources {
    pub fn new(ctx: &Context, assets: &[Asset], params: AssetParams) -> Result<AssetResources> {
        if assets.len() > MAX_ASSETS {
            return Err(Error::BadInput(format!(
                "{} assets; the example asset pass draws at most {MAX_ASSETS}",
                assets.len()
            )));
        }
        for (i, a) in assets.iter().enumerate() {
            a.check().map_err(|e| Error::BadInput(format!("asset {i} ({}): {e}", a.kind.name())))?;
        }
        let buffer = |name: &str, bytes: &[u8], usage| Buffer::with_data(ctx, name, bytes, usage);
        let (mut vertices, mut indices, mut instances, mut draws) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for kind in AssetKind::ALL {
            let mesh = match kind {
                AssetKind::Rock => rock_mesh(),
                AssetKind::Trunk => trunk_mesh(),
            };
            let base = vertices.len() as u32;
            vertices.extend(
                mesh.positions.iter().zip(&mesh.normals).map(|(p, n)| AssetVertexGpu {
                    position: p.extend(1.0).to_array(),
                    normal: n.extend(0.0).to_array(),
                }),
            );
            let idx: Vec<u32> = mesh.indices.iter().map(|i| i + base).collect();
            let name = format!("asset_indices[{}]", kind.name());
            indices.push((
                kind,
                buffer(&name, bytemuck::cast_slice(&idx), vk::BufferUsageFlags::INDEX_BUFFER)?,
                idx.len() as u32,
            ));
            let first = instances.len() as u32;
            let [r, g, b] = kind.albedo();
            instances.extend(assets.iter().filter(|a| a.kind == kind).map(|a| AssetInstanceGpu {
                place: [a.at_m[0] as f32, a.at_m[1] as f32, a.yaw_deg.to_radians() as f32, a.scale as f32],
                albedo: [r, g, b, 1.0],
            }));
            draws.push((kind, first, instances.len() as u32 - first));
        }
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        Ok(AssetResources {
            vertices: buffer("asset_vertices", bytemuck::cast_slice(&vertices), storage)?,
            indices,
            instances: buffer("asset_instances", bytemuck::cast_slice(&instances), storage)?,
            draws,
            params,
        })
    }

    /// Triangles of every instance drawn.
    pub fn triangles(&self) -> u64 {
        let per_kind = |k: AssetKind| self.indices.iter().find(|(i, _, _)| *i == k).map_or(0, |(_, _, n)| n / 3);
        self.draws.iter().map(|(k, _, n)| u64::from(per_kind(*k)) * u64::from(*n)).sum()
    }

    pub fn memory(&self) -> Vec<(String, u64)> {
        [&self.vertices, &self.instances]
            .into_iter()
            .chain(self.indices.iter().map(|(_, b, _)| b))
            .map(|b| (b.name.clone(), b.memory_bytes()))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn twins_have_the_shader_sizes() {
        use crate::shaders::structs;
        assert_eq!(std::mem::size_of::<AssetVertexGpu>(), structs::ASSET_VERTEX);
        assert_eq!(std::mem::size_of::<AssetInstanceGpu>(), structs::ASSET_INSTANCE);
    }

    /// Closed meshes with outward normals and a foot below the ground.
    #[test]
    fn the_meshes_are_closed_and_face_outwards() {
        for (mesh, centre) in [(rock_mesh(), Vec3::Z * 0.3), (trunk_mesh(), Vec3::Z * 2.5)] {
            let mut edges = std::collections::HashMap::new();
            for t in mesh.indices.chunks_exact(3) {
                for k in 0..3 {
                    *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
                }
            }
            let open = edges.keys().filter(|(a, b)| !edges.contains_key(&(*b, *a))).count();
            let min_z = mesh.positions.iter().map(|p| p.z).fold(f32::MAX, f32::min);
            assert!(min_z < -0.2, "foot at {min_z}");
            // The trunk is open at its foot (below the ground), the rock closed.
            assert!(open == 0 || open == 16, "{open} open edges");
            let outward = mesh.positions.iter().zip(&mesh.normals).filter(|(p, n)| {
                let d = **p - centre;
                Vec3::new(d.x, d.y, if centre.z > 1.0 { 0.0 } else { d.z }).dot(**n) > 0.0
            });
            assert!(outward.count() as f32 > 0.95 * mesh.positions.len() as f32);
        }
        let bad = Asset { kind: AssetKind::Rock, at_m: [0.0, f64::NAN], scale: 1.0, yaw_deg: 0.0 };
        assert!(bad.check().unwrap_err().contains("not finite"));
    }
}
